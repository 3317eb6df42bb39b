#include "door_state_recognition/segmentation/segmentation.hpp"

#include "door_state_recognition/preprocess/cell_map.hpp"
#include "door_state_recognition/util/both_halves.hpp"
#include "door_state_recognition/util/first_error.hpp"
#include "door_state_recognition/util/radix_sort.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstddef>
#include <limits>
#include <memory>
#include <cmath>
#include <exception>
#include <random>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#endif

#ifdef _OPENMP
#include <omp.h>
#endif

namespace dsr {
namespace segmentation {

// Curvature of a coarse neighbourhood above which a cell's normal is taken
// from its fine neighbourhood: a plane with centimetre noise stays far below.
constexpr float kRefineCurvature = 0.02f;

// Vertical structure this far above a horizontal level (m), in more than
// 2% of the vertical points (and at least this many), says the level is
// not the ceiling.
constexpr double kAboveCeiling = 0.3;
constexpr std::size_t kAboveCeilingPoints = 50;

// A gap in a wall's inliers with more than this share unseen splits it.
constexpr double kGapUnknown = 0.1;

// cos 15 deg: planes closer to parallel than this may shadow one another.
constexpr double kNearParallel = 0.966;

// sin 5 deg: a plane passing closer than this share of the range of its
// nearest point to the viewpoint is seen at more than 85 deg incidence
// everywhere. Range sensors return almost nothing from a surface that
// grazing: such a "wall" is a sheet of mixed (flying) pixels strung along
// the rays past a depth edge, not a surface.
constexpr double kEdgeOnShare = 0.087;

// Of a wall's surface not hidden from the viewpoint (by what stands in
// front of it), at least this share holds points: each point within
// kFillBand of its plane taken for the patch of surface a sensor's ray (or
// the voxel grid, where coarser) gives one point on. A wall is one
// continuous surface: on the tuning camera frames the walls holding a true
// door covered 0.78 or more of what they show; a "wall" joined from
// scattered pieces (the edges of furniture and of the room beyond seen
// through a doorway, flying pixels between them) covers down to a sixth.
constexpr double kMinWallFill = 0.5;
// Points this close to the plane count for it (depth noise of a few
// centimetres at a few metres spreads a wall's points that far).
constexpr double kFillBand = 0.1;
// The lowest this high above the floor are left out (the floor's own points).
constexpr double kFillAboveFloor = 0.15;

namespace {

// SelfAdjointEigenSolver<Matrix3d>::computeDirect as Eigen 3.4 runs it (its
// own computeRoots and extract_kernel, step for step), split in two and
// trimmed to what the normals read: values() the eigenvalues (eivals), then
// vector0() the eigenvector of the smallest (eivecs.col(0)), the same bits
// as computeDirect's. Not computed: column 1 (Eigen's cross product of the
// others, normalised, last) and, where column 0 comes first (its eigenvalue
// the most distinct), column 2, which Eigen works out after it without
// changing it.
struct Eigen3 {
  using Direct = Eigen::internal::direct_selfadjoint_eigenvalues<Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>, 3, false>;
  Eigen::Matrix3d scaled, eivecs;
  Eigen::Vector3d roots, eivals;  // of scaled; of the matrix
  void values(const Eigen::Matrix3d& mat) {
    const double shift = mat.trace() / 3.0;
    scaled = mat.template selfadjointView<Eigen::Lower>();
    scaled.diagonal().array() -= shift;
    const double scale = scaled.cwiseAbs().maxCoeff();
    if (scale > 0) scaled /= scale;
    Direct::computeRoots(scaled, roots);
    eivals = roots;
    eivals *= scale;
    eivals.array() += shift;
  }
  void vector0() {
    const Eigen::Vector3d& ev = roots;
    if ((ev(2) - ev(0)) <= Eigen::NumTraits<double>::epsilon()) {
      eivecs.setIdentity();
      return;
    }
    Eigen::Matrix3d tmp;
    tmp = scaled;
    double d0 = ev(2) - ev(1);
    const double d1 = ev(1) - ev(0);
    Eigen::Index k(0), l(2);
    if (d0 > d1) {
      std::swap(k, l);
      d0 = d1;
    }
    tmp.diagonal().array() -= ev(k);
    Direct::extract_kernel(tmp, eivecs.col(k), eivecs.col(l));
    if (k == 0) return;
    if (d0 <= 2 * Eigen::NumTraits<double>::epsilon() * d1) {
      eivecs.col(l) -= eivecs.col(k).dot(eivecs.col(l)) * eivecs.col(l);
      eivecs.col(l).normalize();
    } else {
      tmp = scaled;
      tmp.diagonal().array() -= ev(l);
      Eigen::Vector3d dummy;
      Direct::extract_kernel(tmp, eivecs.col(l), dummy);
    }
  }
};

}  // namespace

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DSR_NEIGHBOUR_MOMENTS_AVX2 1
// To acc (10 doubles) the 10 doubles of each cell around cell c (m + 10 o
// for cell o), in forEachNeighbourCell's order, with AVX2 (no FMA): each
// lane adds as the scalar loop adds, in the same order, the same sums.
__attribute__((target("avx2"))) void addNeighbourMomentsAvx2(const NeighbourGrid& grid, std::size_t c, const double* m,
                                                              double* acc) {
  std::uint32_t around[27];
  int count = 0;
  grid.forEachNeighbourCell(c, [&](std::uint32_t o) { around[count++] = o; });
  __m256d a0 = _mm256_loadu_pd(acc), a1 = _mm256_loadu_pd(acc + 4);
  __m128d a2 = _mm_loadu_pd(acc + 8);
  for (int k = 0; k < count; ++k) {
    const double* b = m + 10 * static_cast<std::size_t>(around[k]);
    a0 = _mm256_add_pd(a0, _mm256_loadu_pd(b));
    a1 = _mm256_add_pd(a1, _mm256_loadu_pd(b + 4));
    a2 = _mm_add_pd(a2, _mm_loadu_pd(b + 8));
  }
  _mm256_storeu_pd(acc, a0);
  _mm256_storeu_pd(acc + 4, a1);
  _mm_storeu_pd(acc + 8, a2);
  // Upper halves of the vector registers cleared before returning to SSE code.
  _mm256_zeroupper();
}
#endif

Normals estimateNormals(const Points& points, const NeighbourGrid& grid, int k, const Eigen::Vector3f& viewpoint) {
  Normals out;
  out.n.assign(points.size(), Eigen::Vector3f::Zero());
  out.curvature.assign(points.size(), 1.0f);
  if (points.size() < 3 || k < 3) return out;
  // Moments of every cell, once: count, sum and sum of outer products, about
  // one origin in the cloud (in double, exact enough for centimetre spreads
  // up to max_abs_coordinate away), so that cells' moments simply add.
  // The sum of outer products is kept as its upper triangle (xx xy xz yy yz
  // zz): the lower one mirrors it exactly (d_i d_j = d_j d_i, and sums of
  // equal terms in the same order are equal), and 80 bytes a cell read 27
  // times over where 104 were.
  struct Moments {
    double n = 0;
    double s[3] = {0, 0, 0};
    double q[6] = {0, 0, 0, 0, 0, 0};
    void add(const Moments& b) {
      n += b.n;
      for (int k = 0; k < 3; ++k) s[k] += b.s[k];
      for (int k = 0; k < 6; ++k) q[k] += b.q[k];
    }
    void addPoint(const Eigen::Vector3d& d) {
      n += 1;
      for (int k = 0; k < 3; ++k) s[k] += d[k];
      q[0] += d.x() * d.x(), q[1] += d.x() * d.y(), q[2] += d.x() * d.z();
      q[3] += d.y() * d.y(), q[4] += d.y() * d.z(), q[5] += d.z() * d.z();
    }
  };
  // n, s and q side by side: ten doubles (read as such by addNeighbourMomentsAvx2).
  static_assert(sizeof(Moments) == 10 * sizeof(double) && offsetof(Moments, s) == sizeof(double) &&
                    offsetof(Moments, q) == 4 * sizeof(double),
                "moments: ten doubles");
  const std::size_t cells = grid.cells();
  const Eigen::Vector3d origin = points.front().cast<double>();
  std::vector<Moments> m(cells);
#pragma omp parallel for schedule(static, 1024)
  for (long long c = 0; c < static_cast<long long>(cells); ++c) {
    const Eigen::Vector3f* q = grid.cellPoints(c);
    for (const int* it = grid.cellBegin(c); it != grid.cellEnd(c); ++it, ++q) m[c].addPoint(q->cast<double>() - origin);
  }
  // A coarse level (cells twice as wide) for sparse surroundings: 27 coarse
  // cells reach as far as 125 fine ones at a fifth of the lookups.
  auto coarseOf = [&](std::size_t c) {
    const Eigen::Vector3i& k3 = grid.coord(c);
    auto half = [](int v) { return v >= 0 ? v / 2 : -((-v + 1) / 2); };
    return Eigen::Vector3i(half(k3.x()), half(k3.y()), half(k3.z()));
  };
  // The grid's own coarse level when it has one (a dense index, see
  // NeighbourGrid::coarseCells), else a hash map of coarse cells here. Either
  // way a coarse cell's moments are its cells' added in cell order.
  const bool grid_coarse = grid.coarseCells() > 0;
  preprocess::CellMap coarse_map(grid_coarse ? 1 : cells / 4 + 1);
  std::vector<Moments> cm;
  std::vector<std::uint32_t> coarse_of(cells);
  std::vector<Eigen::Vector3i> ccoord;
  if (grid_coarse) {
    cm.resize(grid.coarseCells());
    ccoord.resize(grid.coarseCells());
    for (std::size_t c = 0; c < cells; ++c) {
      coarse_of[c] = grid.coarseOf(c);
      cm[coarse_of[c]].add(m[c]);
    }
    for (std::size_t q = 0; q < ccoord.size(); ++q) ccoord[q] = grid.coarseCoord(q);
  } else {
    cm.reserve(cells / 4 + 1);
    std::uint64_t last_key = ~std::uint64_t(0);  // no packed key
    std::uint32_t last_id = 0;
    for (std::size_t c = 0; c < cells; ++c) {
      const Eigen::Vector3i q = coarseOf(c);
      // Cells come in scan order: runs of them share a coarse cell.
      const std::uint64_t key = preprocess::packCell(q.x(), q.y(), q.z());
      const std::uint32_t id = key == last_key ? last_id : coarse_map.insert(key);
      last_key = key;
      last_id = id;
      if (id == cm.size()) cm.emplace_back();
      cm[id].add(m[c]);
      coarse_of[c] = id;
    }
    ccoord.resize(cm.size());
    for (std::size_t c = 0; c < cells; ++c) ccoord[coarse_of[c]] = coarseOf(c);
  }
  const int need = std::min(k, 8);
  struct Pca {
    Eigen::Vector3f n = Eigen::Vector3f::Zero();
    float curvature = 1.0f;
    bool ok = false;
  };
  // The covariance of a neighbourhood's moments and its eigenvalues, then
  // (where needed) the normal: the eigenvector of the smallest.
  auto eigenvalues = [](const Moments& acc, Eigen3& e) {
    const Eigen::Vector3d mean = Eigen::Vector3d(acc.s[0], acc.s[1], acc.s[2]) / acc.n;
    Eigen::Matrix3d ss;
    ss << acc.q[0], acc.q[1], acc.q[2], acc.q[1], acc.q[3], acc.q[4], acc.q[2], acc.q[4], acc.q[5];
    const Eigen::Matrix3d C = ss / acc.n - mean * mean.transpose();
    e.values(C);
  };
  auto curvatureOf = [](const Eigen3& e) {
    const double sum = e.eivals.sum();
    return sum > 0 ? static_cast<float>(std::max(0.0, e.eivals(0)) / sum) : 0.0f;
  };
  auto finish = [&](Eigen3& e) {
    Pca r;
    e.vector0();
    r.n = e.eivecs.col(0).cast<float>().normalized();
    if (!r.n.allFinite()) return Pca();
    r.curvature = curvatureOf(e);
    r.ok = true;
    return r;
  };
  auto pca = [&](const Moments& acc) {
    if (acc.n < 3) return Pca();  // isolated: no normal (zero), curvature 1
    Eigen3 e;
    eigenvalues(acc, e);
    return finish(e);
  };
  // Coarse normals first: the 3 x 3 x 3 coarse cells around each coarse cell.
  auto coarseMoments = [&](std::size_t i) {
    Moments acc;
    const Eigen::Vector3i& q = ccoord[i];
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const std::uint32_t o = grid_coarse ? grid.findCoarse(q.x() + dx, q.y() + dy, q.z() + dz)
                                              : coarse_map.find(preprocess::packCell(q.x() + dx, q.y() + dy, q.z() + dz));
          if (o != preprocess::CellMap::kNone) acc.add(cm[o]);
        }
    return acc;
  };
  // A coarse neighbourhood curved beyond kRefineCurvature (by its
  // eigenvalues) sends its cells to their fine neighbourhoods whether or not
  // its normal exists: the normal is not worked out (unknown) and is found
  // only for a cell whose fine neighbourhood holds too few points.
  std::vector<Pca> coarse(cm.size());
  std::vector<char> coarse_unknown(cm.size(), 0);
#pragma omp parallel for schedule(dynamic, 256)
  for (long long i = 0; i < static_cast<long long>(cm.size()); ++i) {
    const Moments acc = coarseMoments(static_cast<std::size_t>(i));
    if (acc.n < 3) continue;  // Pca(): no normal, curvature 1
    Eigen3 e;
    eigenvalues(acc, e);
    const float curvature = curvatureOf(e);
    if (curvature > kRefineCurvature) {
      coarse[i].curvature = curvature;
      coarse_unknown[i] = 1;
    } else {
      coarse[i] = finish(e);
    }
  }
#ifdef DSR_NEIGHBOUR_MOMENTS_AVX2
  static const bool avx2 = __builtin_cpu_supports("avx2");
#endif
  // Fine cells take the coarse normal where it is planar (most of a room);
  // near edges, corners and thin parts the 3 x 3 x 3 fine cells around.
#pragma omp parallel
  {
#pragma omp for schedule(dynamic, 256)
    for (long long c = 0; c < static_cast<long long>(cells); ++c) {
      Pca r = coarse[coarse_of[c]];
      if (!r.ok || r.curvature > kRefineCurvature) {
        Moments acc;
#ifdef DSR_NEIGHBOUR_MOMENTS_AVX2
        if (avx2)
          addNeighbourMomentsAvx2(grid, static_cast<std::size_t>(c), &m[0].n, &acc.n);
        else
#endif
          grid.forEachNeighbourCell(static_cast<std::size_t>(c), [&](std::uint32_t o) { acc.add(m[o]); });
        if (acc.n >= need) {
          r = pca(acc);
        } else if (coarse_unknown[coarse_of[c]]) {
          r = pca(coarseMoments(coarse_of[c]));
        }
      }
      if (!r.ok) continue;
      for (const int* it = grid.cellBegin(c); it != grid.cellEnd(c); ++it) {
        out.n[*it] = r.n.dot(viewpoint - points[*it]) < 0 ? Eigen::Vector3f(-r.n) : r.n;
        out.curvature[*it] = r.curvature;
      }
    }
  }
  return out;
}

FloorCeiling findFloorCeiling(const Points& points, const Normals& normals, const Parameters& p, double viewpoint_z) {
  FloorCeiling fc;
  std::vector<float> z;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (std::abs(normals.n[i].z()) > p.horizontal_normal_z) z.push_back(points[i].z());
  if (z.size() < 50) return fc;
  const auto [mn, mx] = std::minmax_element(z.begin(), z.end());
  const double z0 = *mn, bin = std::max(p.histogram_bin, (*mx - z0) / 100000.0);
  const std::size_t bins = static_cast<std::size_t>((*mx - z0) / bin) + 1;
  std::vector<int> hist(bins, 0);
  for (float v : z) ++hist[std::min(bins - 1, static_cast<std::size_t>((v - z0) / bin))];
  const int peak = *std::max_element(hist.begin(), hist.end());
  const int threshold = std::max(30, peak / 8);
  // Significant local maxima, low to high.
  std::vector<std::size_t> peaks;
  for (std::size_t b = 0; b < bins; ++b) {
    const int left = b > 0 ? hist[b - 1] : 0, right = b + 1 < bins ? hist[b + 1] : 0;
    if (hist[b] >= threshold && hist[b] >= left && hist[b] >= right) peaks.push_back(b);
  }
  if (peaks.empty()) return fc;
  auto refine = [&](std::size_t b) {  // mean z of the points in the peak's neighbourhood
    double s = 0;
    int n = 0;
    for (float v : z)
      if (std::abs(v - (z0 + (b + 0.5) * bin)) <= 1.5 * bin) s += v, ++n;
    return n ? s / n : z0 + (b + 0.5) * bin;
  };
  const double lo = refine(peaks.front()), hi = refine(peaks.back());
  // A ceiling closes the room: walls do not rise above it. A horizontal
  // level with much vertical structure above it is the top of a desk or a
  // cupboard, or the underside of a shelf, seen by a sensor that does not
  // see the ceiling (a camera frame rarely does).
  std::size_t vertical = 0, above = 0;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (std::abs(normals.n[i].z()) < p.vertical_normal_z) {
      ++vertical;
      above += points[i].z() > hi + kAboveCeiling;
    }
  const bool closes = above < std::max<std::size_t>(kAboveCeilingPoints, vertical / 50);
  if (hi - lo >= p.min_room_height && closes) {
    fc.floor = lo;
    fc.ceiling = hi;
  } else if (lo < viewpoint_z) {
    fc.floor = lo;  // one horizontal level below the sensor: the floor
  } else if (closes) {
    fc.ceiling = hi;
  }
  return fc;
}

namespace {

// Total least squares line of 2-D points: centroid and unit direction.
void fitLine(const std::vector<Eigen::Vector2d>& pts, Eigen::Vector2d& c, Eigen::Vector2d& dir) {
  c.setZero();
  for (const auto& q : pts) c += q;
  c /= static_cast<double>(pts.size());
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  for (const auto& q : pts) C += (q - c) * (q - c).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  dir = es.eigenvectors().col(1);
}

}  // namespace

namespace {
constexpr int kViewTopBins = 1440;  // bearing bins (pseudo-angle), about 0.25 deg
// A wall's top within this of the view's top (tan of elevation) was cut by the view.
constexpr float kViewTopSlack = 0.02f;
}  // namespace

int ViewTop::bin(const Eigen::Vector3f& q) const {
  // Pseudo-angle in [0, 4): monotonic in the bearing, no atan2.
  const float dx = q.x() - viewpoint.x(), dy = q.y() - viewpoint.y();
  const float den = std::abs(dx) + std::abs(dy);
  if (den <= 0) return -1;
  const float r = dy / den;  // [-1, 1]
  const float a = dx >= 0 ? (dy >= 0 ? r : 4 + r) : 2 - r;
  return std::min(kViewTopBins - 1, static_cast<int>(a * (kViewTopBins / 4)));
}

float ViewTop::tanElevation(const Eigen::Vector3f& q) const {
  const float h = std::hypot(q.x() - viewpoint.x(), q.y() - viewpoint.y());
  return h > 1e-3f ? (q.z() - viewpoint.z()) / h : 0.0f;
}

namespace {
// tanElevation(q) lies below hi for sure, told without hypot: the quotient
// in double by sqrt in double is within a few parts in 1e7 of it (both
// roundings to float included), far inside the margin of 1e-5 of it; near
// the viewpoint's vertical, or near hi, false (then the caller works
// tanElevation out). Nothing lies below -infinity (an empty bin).
inline bool surelyBelow(const ViewTop& v, const Eigen::Vector3f& q, float hi) {
  const float dx = q.x() - v.viewpoint.x(), dy = q.y() - v.viewpoint.y();
  const double h2 = static_cast<double>(dx) * dx + static_cast<double>(dy) * dy;
  if (!(h2 > 4e-6)) return false;  // h within 2 mm: tanElevation's cut-off at 1 mm is near
  const double t = static_cast<double>(q.z() - v.viewpoint.z()) / std::sqrt(h2);
  return t + 1e-5 * std::abs(t) + 1e-30 < hi;
}
}  // namespace

ViewTop viewTop(const Points& points, const Eigen::Vector3f& viewpoint) {
  ViewTop v;
  v.viewpoint = viewpoint;
  v.max_tan.assign(kViewTopBins, -std::numeric_limits<float>::infinity());
  v.min_tan.assign(kViewTopBins, std::numeric_limits<float>::infinity());
  // Over the cores, each into bins of its own, then merged: a least or
  // greatest value is the same whatever the order it is taken in.
  const long long n = static_cast<long long>(points.size());
#pragma omp parallel if (n >= 20000)
  {
    std::vector<float> hi(kViewTopBins, -std::numeric_limits<float>::infinity());
    std::vector<float> lo(kViewTopBins, std::numeric_limits<float>::infinity());
#pragma omp for schedule(static) nowait
    for (long long i = 0; i < n; ++i) {
      const auto& q = points[i];
      const int b = v.bin(q);
      if (b < 0) continue;
      const float t = v.tanElevation(q);
      hi[b] = std::max(hi[b], t);
      lo[b] = std::min(lo[b], t);
    }
#pragma omp critical(dsr_view_top)
    for (int b = 0; b < kViewTopBins; ++b) {
      v.max_tan[b] = std::max(v.max_tan[b], hi[b]);
      v.min_tan[b] = std::min(v.min_tan[b], lo[b]);
    }
  }
  return v;
}

bool ViewTop::inView(const Eigen::Vector3f& q, float slack) const {
  if (max_tan.empty()) return true;
  const int b = bin(q);
  if (b < 0) return true;
  const float t = tanElevation(q);
  return t >= min_tan[b] - slack && t <= max_tan[b] + slack;
}

namespace {
// Lists of at least this many points are read in two halves at once by addWallSegments.
constexpr std::size_t kSplitSegment = 10000;
}  // namespace

void addWallSegments(const Points& points, const std::vector<int>& inliers, const Eigen::Vector2d& point,
                     const Eigen::Vector2d& direction, const Eigen::Vector2d& normal, double floor_z, double height_top,
                     bool ceiling_known, const Parameters& p, std::vector<WallPlane>& walls,
                     const ViewTop* view, const Eigen::Vector2d* viewpoint) {
  const double room_h = height_top - floor_z;
  // What the sensor saw across a gap (a, b) in the inliers, in 5 cm bins at
  // a door's body height: each hidden by something in front, seen through
  // (returns behind the plane, or rays of a camera's pixels without a
  // return), showing points near the plane, or nothing at all (unknown).
  auto gapSeen = [&](double a, double b, double& through, double& unknown) {
    through = 0;
    unknown = 1;
    if (!viewpoint) return;
    const double vs = (*viewpoint - point).dot(direction), vd = (*viewpoint - point).dot(normal);
    if (vd <= 0.1) return;
    const int bins = std::max(1, static_cast<int>(std::ceil((b - a) / 0.05)));
    std::vector<char> sh(bins, 0), th(bins, 0), any(bins, 0);
    auto binOf = [&](double s) { return s > a && s < b ? std::min(bins - 1, static_cast<int>((s - a) / 0.05)) : -1; };
    for (const auto& q : points) {
      if (q.z() < floor_z + 0.25 || q.z() > floor_z + 1.75) continue;
      const Eigen::Vector2d r(q.x() - point.x(), q.y() - point.y());
      const double d = r.dot(normal);
      if (d >= vd) continue;
      const int k = binOf(vs + vd / (vd - d) * (r.dot(direction) - vs));
      if (k < 0) continue;
      any[k] = 1;
      if (std::abs(d) > p.wall_distance) (d > 0 ? sh : th)[k] = 1;
    }
    if (view) {
      const Eigen::Vector3f v3(static_cast<float>(viewpoint->x()), static_cast<float>(viewpoint->y()), view->viewpoint.z());
      for (const Eigen::Vector3f& u : view->no_return) {
        const double un = u.x() * normal.x() + u.y() * normal.y();
        if (un >= -1e-6) continue;
        const Eigen::Vector3f x = v3 + static_cast<float>(vd / -un) * u;
        if (x.z() < floor_z + 0.25 || x.z() > floor_z + 1.75) continue;
        const int k = binOf((Eigen::Vector2d(x.x(), x.y()) - point).dot(direction));
        if (k >= 0) th[k] = 1;
      }
    }
    int nt = 0, nu = 0;
    for (int k = 0; k < bins; ++k) {
      nt += !sh[k] && th[k];
      nu += !sh[k] && !th[k] && !any[k];
    }
    through = nt * 0.05;
    unknown = static_cast<double>(nu) / bins;
  };
  // Seen edge-on from the viewpoint along all its length (kEdgeOnShare).
  auto edgeOn = [&](const WallPlane& w) {
    if (!viewpoint) return false;
    const double vd = std::abs((*viewpoint - point).dot(normal));
    double nearest = std::numeric_limits<double>::infinity();
    for (const int i : w.inliers)
      nearest = std::min(nearest, (Eigen::Vector2d(points[i].x(), points[i].y()) - *viewpoint).squaredNorm());
    return vd < kEdgeOnShare * std::sqrt(nearest);
  };
  // Too few points on the surface it shows (kMinWallFill), where the
  // sensor's ray spacing is known (an organized cloud: one return per ray,
  // on the plane, in front of it or beyond).
  auto sparse = [&](const WallPlane& w) {
    if (!view || view->ray_spacing <= 0) return false;
    const double z0 = floor_z + kFillAboveFloor, area = (w.s_max - w.s_min) * (w.z_max - z0);
    if (area <= 0) return false;
    const double voxel2 = p.voxel_size * p.voxel_size, spacing = view->ray_spacing;
    const Eigen::Vector3d v = view->viewpoint.cast<double>();
    const double vd = (Eigen::Vector2d(v.x(), v.y()) - point).dot(normal);
    // The patch a ray meets the plane in, at x (t: x's range over the range
    // of the point that stands for it, whose voxel it spreads by t).
    auto patch = [&](const Eigen::Vector3d& x, double t) {
      const Eigen::Vector3d r = x - v;
      const double range = r.norm();
      const double cos_inc = std::max(0.1, std::abs(r.x() * normal.x() + r.y() * normal.y()) / std::max(range, 1e-6));
      return std::max(voxel2 * t * t, range * spacing * range * spacing / cos_inc);
    };
    auto inBox = [&](const Eigen::Vector3d& x) {
      const double sv = (Eigen::Vector2d(x.x(), x.y()) - point).dot(direction);
      return sv >= w.s_min && sv <= w.s_max && x.z() >= z0 && x.z() <= w.z_max;
    };
    // Its inliers alone often suffice (they lie within the band, none hidden).
    double covered = 0;
    for (const int i : w.inliers) {
      const Eigen::Vector3d x = points[i].cast<double>();
      if (inBox(x)) covered += patch(x, 1.0);
    }
    if (covered >= kMinWallFill * area) return false;
    covered = 0;
    double hidden = 0;
    for (const auto& q : points) {
      const double d = (Eigen::Vector2d(q.x(), q.y()) - point).dot(normal);
      if (std::abs(d) <= kFillBand) {
        const Eigen::Vector3d x = q.cast<double>();
        if (inBox(x)) covered += patch(x, 1.0);
      } else if (d > kFillBand && d < vd) {  // in front: hides where its ray meets the plane
        const double t = vd / (vd - d);
        const Eigen::Vector3d x = v + t * (q.cast<double>() - v);
        if (inBox(x)) hidden += patch(x, t);
      }
    }
    return covered < kMinWallFill * std::max(area - hidden, 0.0);
  };
  // Split along the wall at gaps wider than wall_gap.
  // (Many inliers: in two halves at once.)
  std::vector<std::pair<double, int>> along(inliers.size());
  {
    const std::size_t n = inliers.size(), mid = n >= kSplitSegment ? n / 2 : n;
    util::bothHalves(mid < n, [&](int h) {
      for (std::size_t k = h ? mid : 0, end = h ? n : mid; k < end; ++k) {
        const int i = inliers[k];
        along[k] = {(Eigen::Vector2d(points[i].x(), points[i].y()) - point).dot(direction), i};
      }
    });
  }
  util::sortPairs(along);  // std::sort's order, in linear time
  std::size_t start = 0;
  for (std::size_t k = 1; k <= along.size(); ++k) {
    if (k < along.size() && along[k].first - along[k - 1].first <= p.wall_gap) continue;
    // A gap the sensor could not see the wall across (hidden by what stands
    // in front, and seen through no wider than a doorway) does not split it.
    if (k < along.size()) {
      double through, unknown;
      gapSeen(along[k - 1].first, along[k].first, through, unknown);
      if (unknown <= kGapUnknown && through <= p.door_max_width + 0.1) continue;
    }
    WallPlane w;
    w.point = point;
    w.direction = direction;
    w.normal = normal;
    w.s_min = along[start].first;
    w.s_max = along[k - 1].first;
    w.z_min = 1e9;
    w.z_max = -1e9;
    w.inliers.reserve(k - start);
    for (std::size_t j = start; j < k; ++j) {
      w.inliers.push_back(along[j].second);
      w.z_min = std::min<double>(w.z_min, points[along[j].second].z());
      w.z_max = std::max<double>(w.z_max, points[along[j].second].z());
    }
    start = k;
    const double h = w.z_max - floor_z;

    // Or the view's top: the highest points of the wall are the highest seen
    // on most of its bearings (a camera frame cuts a near wall below the ceiling).
    auto cutByView = [&]() {
      if (!view || view->max_tan.empty()) return false;
      // Each bearing's highest (a greatest value, whatever the order it is
      // taken in): many inliers in two halves at once, each into bins of its own.
      std::vector<float> top(view->max_tan.size(), -std::numeric_limits<float>::infinity()), top_second;
      const std::size_t n = w.inliers.size(), mid = n >= kSplitSegment ? n / 2 : n;
      util::bothHalves(mid < n, [&](int h) {
        std::vector<float>& t = h ? top_second : top;
        if (h) t.assign(top.size(), -std::numeric_limits<float>::infinity());
        for (std::size_t k = h ? mid : 0, end = h ? n : mid; k < end; ++k) {
          const auto& q = points[w.inliers[k]];
          const int b = view->bin(q);
          // A camera's rows come top down: a bearing's first point is mostly its highest.
          if (b >= 0 && !surelyBelow(*view, q, t[b])) t[b] = std::max(t[b], view->tanElevation(q));
        }
      });
      for (std::size_t b = 0; b < top_second.size(); ++b) top[b] = std::max(top[b], top_second[b]);
      int bins = 0, cut = 0;
      for (std::size_t b = 0; b < top.size(); ++b)
        if (std::isfinite(top[b])) ++bins, cut += top[b] >= view->max_tan[b] - kViewTopSlack;
      return bins > 0 && cut >= 0.5 * bins;
    };
    const bool cut = cutByView();
    const bool reaches_top = !ceiling_known || w.z_max > height_top - 0.25 || cut;
    // Tall: from near the floor up to the share of the room a wall spans, or
    // (cut by the view) as high as a door at least.
    const bool tall = (h >= p.wall_height_ratio * room_h || (cut && h >= p.door_min_height)) && w.z_min < floor_z + 0.5;
    // A plane parallel to a stronger wall and close behind or before it
    // (a recessed leaf, trim, a cupboard front) is not another wall; nor is
    // one a few degrees off a stronger wall and close to it all along (a
    // second hypothesis of a noisy face): walls do not meet at such angles.
    bool shadowed = false;
    for (const WallPlane& o : walls) {
      const double c = std::abs(o.normal.dot(w.normal));
      if (c < kNearParallel) continue;
      const Eigen::Vector2d a = w.point + w.s_min * w.direction, b = w.point + w.s_max * w.direction;
      const double off = std::abs((0.5 * (a + b) - o.point).dot(o.normal));
      const double off_ends = std::max(std::abs((a - o.point).dot(o.normal)), std::abs((b - o.point).dot(o.normal)));
      const double s0 = std::min((a - o.point).dot(o.direction), (b - o.point).dot(o.direction));
      const double s1 = std::max((a - o.point).dot(o.direction), (b - o.point).dot(o.direction));
      // Off parallel, only along the stronger wall: not a wall meeting it at a shallow corner.
      const bool along = c >= 0.995 ? s0 < o.s_max && s1 > o.s_min : off_ends < 0.5 && s0 > o.s_min - 0.3 && s1 < o.s_max + 0.3;
      shadowed |= off < 0.3 && along;
    }
    // Without a ceiling to reach, a door leaf is as tall as a wall: then a
    // wall must also be longer than any door.
    const double min_length = ceiling_known ? p.min_wall_length : std::max(p.min_wall_length, p.door_max_width + 0.1);
    if (static_cast<int>(w.inliers.size()) >= p.min_wall_points && w.s_max - w.s_min >= min_length && tall &&
        reaches_top && !shadowed && !edgeOn(w) && !sparse(w))
      walls.push_back(std::move(w));
  }
}

namespace {

// RANSAC never stops before this many draws.
constexpr int kMinRansacIterations = 20;
// Below these (sample points scored, a plane's inliers) the work of a RANSAC
// round is too small to hand to the other thread: waiting for it could cost
// more (a thread of a loaded machine waits for its turn on a core).
constexpr std::size_t kTaskSample = 4000, kTaskInliers = 1000;
// A pool of this many points or more has its inliers found in two halves at once.
constexpr std::size_t kTaskPool = 20000;

// Of the n sample points (x, y, normal nx_i, ny_i), those within wd of the
// line through (qx, qy) with normal (nx, ny) whose normal agrees (|n . n_i|
// > agree), without branches.
std::size_t countInliersScalar(const float* x, const float* y, const float* nxs, const float* nys, std::size_t n,
                               double qx, double qy, double nx, double ny, double wd, double agree) {
  std::size_t count = 0, j = 0;
#if defined(__SSE2__)
  {  // two at a time: the same double operations, in the same order
    const __m128d vqx = _mm_set1_pd(qx), vqy = _mm_set1_pd(qy), vnx = _mm_set1_pd(nx), vny = _mm_set1_pd(ny);
    const __m128d vwd = _mm_set1_pd(wd), vag = _mm_set1_pd(agree);
    const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
    auto load2 = [](const float* f) { return _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(f)))); };
    for (; j + 2 <= n; j += 2) {
      const __m128d dist = _mm_add_pd(_mm_mul_pd(_mm_sub_pd(load2(&x[j]), vqx), vnx),
                                      _mm_mul_pd(_mm_sub_pd(load2(&y[j]), vqy), vny));
      const __m128d dot = _mm_add_pd(_mm_mul_pd(vnx, load2(&nxs[j])), _mm_mul_pd(vny, load2(&nys[j])));
      const __m128d in = _mm_and_pd(_mm_cmplt_pd(_mm_and_pd(dist, abs_mask), vwd),
                                    _mm_cmpgt_pd(_mm_and_pd(dot, abs_mask), vag));
      const int bits = _mm_movemask_pd(in);
      count += static_cast<std::size_t>((bits & 1) + (bits >> 1));
    }
  }
#endif
  for (; j < n; ++j) {
    const double dist = (static_cast<double>(x[j]) - qx) * nx + (static_cast<double>(y[j]) - qy) * ny;
    const double dot = nx * static_cast<double>(nxs[j]) + ny * static_cast<double>(nys[j]);
    count += static_cast<std::size_t>((std::abs(dist) < wd) & (std::abs(dot) > agree));
  }
  return count;
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DSR_COUNT_INLIERS_AVX2 1
// countInliersScalar four at a time on a CPU with AVX2: the same double
// operations in each lane (AVX2 alone, no FMA: no multiply-add is fused),
// the same count. The rest as countInliersScalar counts it.
// The inlier test of countInliersScalar on points [j, j + 4), for every
// whole block of four of the n: on(j, bits), bit k set when point j + k is
// an inlier. Returns where the blocks end (the rest is the scalar code's).
template <class F>
__attribute__((target("avx2"))) inline std::size_t inlierBlocksAvx2(const float* x, const float* y, const float* nxs,
                                                                    const float* nys, std::size_t n, double qx,
                                                                    double qy, double nx, double ny, double wd,
                                                                    double agree, const F& on) {
  std::size_t j = 0;
  const __m256d vqx = _mm256_set1_pd(qx), vqy = _mm256_set1_pd(qy), vnx = _mm256_set1_pd(nx), vny = _mm256_set1_pd(ny);
  const __m256d vwd = _mm256_set1_pd(wd), vag = _mm256_set1_pd(agree);
  const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL));
  for (; j + 4 <= n; j += 4) {
    const __m256d px = _mm256_cvtps_pd(_mm_loadu_ps(&x[j])), py = _mm256_cvtps_pd(_mm_loadu_ps(&y[j]));
    const __m256d pnx = _mm256_cvtps_pd(_mm_loadu_ps(&nxs[j])), pny = _mm256_cvtps_pd(_mm_loadu_ps(&nys[j]));
    const __m256d dist = _mm256_add_pd(_mm256_mul_pd(_mm256_sub_pd(px, vqx), vnx), _mm256_mul_pd(_mm256_sub_pd(py, vqy), vny));
    const __m256d dot = _mm256_add_pd(_mm256_mul_pd(vnx, pnx), _mm256_mul_pd(vny, pny));
    const __m256d in = _mm256_and_pd(_mm256_cmp_pd(_mm256_and_pd(dist, abs_mask), vwd, _CMP_LT_OQ),
                                     _mm256_cmp_pd(_mm256_and_pd(dot, abs_mask), vag, _CMP_GT_OQ));
    on(j, static_cast<unsigned>(_mm256_movemask_pd(in)));
  }
  // Upper halves of the vector registers cleared before returning to SSE
  // code: left dirty, every SSE instruction after would wait on them.
  _mm256_zeroupper();
  return j;
}

__attribute__((target("avx2"))) std::size_t countInliersAvx2(const float* x, const float* y, const float* nxs,
                                                              const float* nys, std::size_t n, double qx, double qy,
                                                              double nx, double ny, double wd, double agree) {
  std::size_t count = 0;
  const std::size_t j = inlierBlocksAvx2(x, y, nxs, nys, n, qx, qy, nx, ny, wd, agree, [&](std::size_t, unsigned bits) {
    count += static_cast<std::size_t>(__builtin_popcount(bits));
  });
  return count + countInliersScalar(x + j, y + j, nxs + j, nys + j, n - j, qx, qy, nx, ny, wd, agree);
}
#endif

// Of the n pool points (x, y, normal nx_i, ny_i; pool indices idx), those
// countInliersScalar counts, appended in order: index to in, (x, y) in
// double to q.
void collectInliersScalar(const float* x, const float* y, const float* nxs, const float* nys, const int* idx,
                          std::size_t n, double qx, double qy, double nx, double ny, double wd, double agree,
                          std::vector<int>& in, std::vector<Eigen::Vector2d>& q) {
  for (std::size_t j = 0; j < n; ++j) {
    const double rx = x[j], ry = y[j];
    const double dist = (rx - qx) * nx + (ry - qy) * ny;
    const double dot = nx * static_cast<double>(nxs[j]) + ny * static_cast<double>(nys[j]);
    if (std::abs(dist) < wd && std::abs(dot) > agree) {
      in.push_back(idx[j]);
      q.emplace_back(rx, ry);
    }
  }
}

#ifdef DSR_COUNT_INLIERS_AVX2
// collectInliersScalar four at a time with AVX2 (no FMA): the same double
// operations in each lane, the same inliers in the same order.
__attribute__((target("avx2"))) void collectInliersAvx2(const float* x, const float* y, const float* nxs,
                                                         const float* nys, const int* idx, std::size_t n, double qx,
                                                         double qy, double nx, double ny, double wd, double agree,
                                                         std::vector<int>& in, std::vector<Eigen::Vector2d>& q) {
  const std::size_t j = inlierBlocksAvx2(x, y, nxs, nys, n, qx, qy, nx, ny, wd, agree, [&](std::size_t b, unsigned bits) {
    while (bits) {
      const int k = __builtin_ctz(bits);
      bits &= bits - 1;
      in.push_back(idx[b + k]);
      q.emplace_back(static_cast<double>(x[b + k]), static_cast<double>(y[b + k]));
    }
  });
  collectInliersScalar(x + j, y + j, nxs + j, nys + j, idx + j, n - j, qx, qy, nx, ny, wd, agree, in, q);
}
#endif

void collectInliers(const float* x, const float* y, const float* nxs, const float* nys, const int* idx, std::size_t n,
                    double qx, double qy, double nx, double ny, double wd, double agree, std::vector<int>& in,
                    std::vector<Eigen::Vector2d>& q) {
#ifdef DSR_COUNT_INLIERS_AVX2
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return collectInliersAvx2(x, y, nxs, nys, idx, n, qx, qy, nx, ny, wd, agree, in, q);
#endif
  collectInliersScalar(x, y, nxs, nys, idx, n, qx, qy, nx, ny, wd, agree, in, q);
}

std::size_t countInliers(const float* x, const float* y, const float* nxs, const float* nys, std::size_t n, double qx,
                         double qy, double nx, double ny, double wd, double agree) {
#ifdef DSR_COUNT_INLIERS_AVX2
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return countInliersAvx2(x, y, nxs, nys, n, qx, qy, nx, ny, wd, agree);
#endif
  return countInliersScalar(x, y, nxs, nys, n, qx, qy, nx, ny, wd, agree);
}

}  // namespace

std::vector<WallPlane> findWalls(const Points& points, const Normals& normals, double floor_z, double height_top,
                                 bool ceiling_known, const Eigen::Vector2d& viewpoint, const Parameters& p,
                                 const ViewTop* view, const OnWall& on_wall) {
  std::vector<int> pool;
  pool.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    if (std::abs(normals.n[i].z()) < p.vertical_normal_z && points[i].z() > floor_z + 0.05) pool.push_back(static_cast<int>(i));
  // The pool's x, y and normal x, y side by side (kept in the pool's order
  // as it shrinks): the sample and the inlier passes read them in turn
  // instead of gathering them.
  std::vector<float> px(pool.size()), py(pool.size()), pnx(pool.size()), pny(pool.size());
  for (std::size_t j = 0; j < pool.size(); ++j) {
    const int i = pool[j];
    px[j] = points[i].x(), py[j] = points[i].y();
    pnx[j] = normals.n[i].x(), pny[j] = normals.n[i].y();
  }
  std::vector<WallPlane> walls;
  std::mt19937 rng(static_cast<unsigned>(p.random_seed));
  std::vector<float> sx, sy, snx, sny;  // the scored sample, side by side
  // A round's wall rules (addWallSegments) run as a task on the other core
  // while this one draws the next rounds' planes, which need only the pool
  // and the generator, not the walls. The rules of consecutive rounds still
  // run in turn (task dependences: the shadow test reads the walls before),
  // and a round is kept only if the walls found before it leave room
  // (max_walls), as in a loop that waited for them: rounds drawn past the
  // last are dropped unused.
  util::FirstError error;
  int threads = 1;
#ifdef _OPENMP
  threads = std::min(2, omp_get_max_threads());
#endif
  // The rounds drawn on the master thread (the other takes the tasks at the
  // region's end): libgomp keeps the dependences of the tasks a thread makes
  // in that thread's implicit task, and a pool thread's (where a single
  // construct may put the rounds) can be set up afresh for the next region
  // before it is freed (LeakSanitizer saw it leak); the master's is freed as
  // its region ends.
#pragma omp parallel num_threads(threads) if (threads > 1)
#pragma omp master
  try {
    for (int round = 0; round < 4 * p.max_walls; ++round) {
      if (static_cast<int>(pool.size()) < p.min_wall_points) break;
      // 1-point RANSAC: a point with its (horizontal) normal proposes a plane.
      std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
      std::size_t best_count = 0;
      Eigen::Vector2d best_pt, best_n;
      const std::size_t stride = std::max<std::size_t>(1, pool.size() / 20000);
      const double sampled = static_cast<double>((pool.size() + stride - 1) / stride);
      // Adaptive: stop once a plane larger than the best would have been drawn
      // with probability 0.999 (capped by ransac_iterations).
      int needed = p.ransac_iterations;
      // The scored sample (every stride-th point of the pool) in arrays of
      // x, y and the normal's x, y, read in turn instead of gathered.
      // Every point of the pool (stride 1): the pool's own arrays.
      const float *sxp = px.data(), *syp = py.data(), *snxp = pnx.data(), *snyp = pny.data();
      if (stride > 1) {
        sx.clear(), sy.clear(), snx.clear(), sny.clear();
        for (std::size_t j = 0; j < pool.size(); j += stride) {
          sx.push_back(px[j]), sy.push_back(py[j]);
          snx.push_back(pnx[j]), sny.push_back(pny[j]);
        }
        sxp = sx.data(), syp = sy.data(), snxp = snx.data(), snyp = sny.data();
      }
      const std::size_t ns = (pool.size() + stride - 1) / stride;
      const double wd = p.wall_distance, agree = p.wall_normal_agreement;
      // The plane of pool point s scored on the sample (0 if s has no normal).
      auto score = [&](int s) -> std::size_t {
        Eigen::Vector2d n(normals.n[s].x(), normals.n[s].y());
        if (n.norm() < 0.5) return 0;
        n.normalize();
        return countInliers(sxp, syp, snxp, snyp, ns, points[s].x(), points[s].y(), n.x(), n.y(), wd, agree);
      };
      // The first kMinRansacIterations draws are scored whatever they score
      // (needed never falls below): drawn in turn as the loop draws them, and
      // scored as tasks, two at once (a small sample here: no tasks, no wait
      // on the other thread).
      const int always = std::min(kMinRansacIterations, p.ransac_iterations);
      std::vector<int> drawn(always);
      std::vector<std::size_t> counts(always, 0);
      for (int it = 0; it < always; ++it) drawn[it] = pool[pick(rng)];
#pragma omp taskloop default(shared) num_tasks(2) if (ns >= kTaskSample)
      for (int it = 0; it < always; ++it) counts[it] = score(drawn[it]);
      for (int it = 0; it < std::min(needed, p.ransac_iterations); ++it) {
        const int s = it < always ? drawn[it] : pool[pick(rng)];
        Eigen::Vector2d n(normals.n[s].x(), normals.n[s].y());
        if (n.norm() < 0.5) continue;
        n.normalize();
        const Eigen::Vector2d q(points[s].x(), points[s].y());
        const std::size_t count = it < always ? counts[it] : score(s);
        if (count > best_count) {
          best_count = count, best_pt = q, best_n = n;
          const double w = std::min(0.999, best_count / sampled);
          needed = std::max(kMinRansacIterations, static_cast<int>(std::ceil(std::log(0.001) / std::log(1.0 - w))));
        }
      }
      if (best_count * stride < static_cast<std::size_t>(p.min_wall_points)) break;
      // Refine twice by TLS on the inliers.
      std::vector<int> inl;
      std::vector<Eigen::Vector2d> q2;
      inl.reserve(pool.size());
      q2.reserve(pool.size());
      // The inliers of pool[j0, j1) in pool order.
      // (Those within wall_distance of the line whose normal agrees: |(r -
      // best_pt) . best_n| and |best_n . n_i| in double, from the pool's arrays.)
      auto inliersOf = [&](std::size_t j0, std::size_t j1, std::vector<int>& in, std::vector<Eigen::Vector2d>& q) {
        collectInliers(px.data() + j0, py.data() + j0, pnx.data() + j0, pny.data() + j0, pool.data() + j0, j1 - j0,
                       best_pt.x(), best_pt.y(), best_n.x(), best_n.y(), p.wall_distance, p.wall_normal_agreement, in,
                       q);
      };
      // The inliers of the whole pool: a large pool in two halves at once,
      // the second as a task into lists of its own (moved out when done: the
      // ends of lists side by side would share cache lines between the
      // cores), appended after the first's: the lists of one pass. A task
      // group waits for that task alone, not for the rounds' rules (tasks).
      std::vector<int> inl_second;
      std::vector<Eigen::Vector2d> q2_second;
      auto allInliers = [&] {
        inl.clear();
        q2.clear();
        if (pool.size() < kTaskPool) {
          inliersOf(0, pool.size(), inl, q2);
          return;
        }
        const std::size_t mid = pool.size() / 2;
        util::FirstError failed;  // an exception must not leave the task
#pragma omp taskgroup
        {
#pragma omp task default(shared)
          failed.run([&] {
            std::vector<int> in;
            std::vector<Eigen::Vector2d> q;
            in.reserve(pool.size() - mid);
            q.reserve(pool.size() - mid);
            inliersOf(mid, pool.size(), in, q);
            inl_second.swap(in);
            q2_second.swap(q);
          });
          failed.run([&] { inliersOf(0, mid, inl, q2); });
        }
        failed.rethrow();
        inl.insert(inl.end(), inl_second.begin(), inl_second.end());
        q2.insert(q2.end(), q2_second.begin(), q2_second.end());
      };
      for (int pass = 0; pass < 3; ++pass) {
        allInliers();
        if (q2.size() < 3 || pass == 2) break;
        Eigen::Vector2d c, dir;
        fitLine(q2, c, dir);
        best_pt = c;
        best_n = Eigen::Vector2d(-dir.y(), dir.x());
      }
      // Remove the inliers from the pool whatever becomes of them (they are
      // a part of it, in its order).
      {
        std::size_t k = 0, kept = 0;
        for (std::size_t j = 0; j < pool.size(); ++j) {
          const int i = pool[j];
          if (k < inl.size() && inl[k] == i) {
            ++k;
            continue;
          }
          pool[kept] = i;
          px[kept] = px[j], py[kept] = py[j], pnx[kept] = pnx[j], pny[kept] = pny[j];
          ++kept;
        }
        pool.resize(kept);
        px.resize(kept), py.resize(kept), pnx.resize(kept), pny.resize(kept);
      }
      const Eigen::Vector2d dir(best_n.y(), -best_n.x());
      if ((viewpoint - best_pt).dot(best_n) < 0) best_n = -best_n;
      // The round's rules after the previous round's (depend), each with its
      // own inliers; skipped once a round failed or max_walls walls are
      // found, where a loop that waited for them would have stopped.
      auto round_inl = std::make_shared<std::vector<int>>(std::move(inl));
      const bool defer = round_inl->size() >= kTaskInliers;
#pragma omp task default(shared) firstprivate(best_pt, best_n, dir, round_inl) depend(inout : walls) if (defer)
      error.run([&] {
        if (!error.failed() && static_cast<int>(walls.size()) < p.max_walls) {
          const std::size_t before = walls.size();
          addWallSegments(points, *round_inl, best_pt, dir, best_n, floor_z, height_top, ceiling_known, p, walls, view,
                          &viewpoint);
          if (on_wall)
            for (std::size_t i = before; i < walls.size(); ++i) on_wall(i, walls[i]);
        }
      });
    }
  } catch (...) {
    // Kept after the rules of the rounds drawn before it, whose exception comes first.
#pragma omp taskwait
    error.keep(std::current_exception());
  }
  error.rethrow();
  return walls;
}

std::vector<std::vector<int>> growRegions(const Points& points, const Normals& normals, const NeighbourGrid& grid,
                                         const std::vector<char>& mask, const Parameters& p) {
  // Cell by cell: the points of a grid cell share one normal (estimateNormals),
  // so regions grow over neighbouring cells with agreeing normals.
  const float cos_thr = static_cast<float>(std::cos(p.region_angle_deg * M_PI / 180.0));
  const std::size_t cells = grid.cells();
  std::vector<char> live(cells, 0);
  std::vector<Eigen::Vector3f> cn(cells);
  std::vector<float> curv(cells, 1.0f);
  std::vector<int> order;
  for (std::size_t c = 0; c < cells; ++c) {
    const int first = *grid.cellBegin(c);
    cn[c] = normals.n[first];
    curv[c] = normals.curvature[first];
    for (const int* it = grid.cellBegin(c); it != grid.cellEnd(c); ++it) live[c] |= mask[*it] != 0;
    if (live[c] && curv[c] <= p.region_curvature && cn[c].squaredNorm() > 0.25f) order.push_back(static_cast<int>(c));
  }
  // By curvature, ties in cell order: a stable sort, by radix.
  util::radixSortBy(order, [&](int c) { return static_cast<std::uint64_t>(util::orderedBits(curv[c])); });
  std::vector<int> label(cells, -1);
  std::vector<std::vector<int>> regions;
  std::vector<int> members, stack, region;
  for (int seed : order) {
    if (label[seed] != -1) continue;
    const int id = static_cast<int>(regions.size());
    members.assign(1, seed);
    stack.assign(1, seed);
    label[seed] = id;
    while (!stack.empty()) {
      const int cur = stack.back();
      stack.pop_back();
      grid.forEachNeighbourCell(static_cast<std::size_t>(cur), [&](std::uint32_t nb) {
        if (!live[nb] || label[nb] != -1) return;
        if (std::abs(cn[cur].dot(cn[nb])) < cos_thr) return;
        label[nb] = id;
        members.push_back(static_cast<int>(nb));
        if (curv[nb] <= p.region_curvature) stack.push_back(static_cast<int>(nb));
      });
    }
    region.clear();
    for (int c : members)
      for (const int* it = grid.cellBegin(c); it != grid.cellEnd(c); ++it)
        if (mask[*it]) region.push_back(*it);
    if (static_cast<int>(region.size()) >= p.min_region_points) {
      std::sort(region.begin(), region.end());
      regions.push_back(region);
    } else {
      for (int c : members) label[c] = -2;  // too small: never reused as a seed
    }
  }
  return regions;
}

}  // namespace segmentation
}  // namespace dsr
