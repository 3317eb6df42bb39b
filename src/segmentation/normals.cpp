// Segmentation: PCA normals and curvature from the moments of the
// neighbour grid's cells (estimateNormals).
#include "door_state_recognition/segmentation/segmentation.hpp"

#include "door_state_recognition/preprocess/cell_map.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#endif

namespace dsr {
namespace segmentation {

// Curvature of a coarse neighbourhood above which a cell's normal is taken
// from its fine neighbourhood: a plane with centimetre noise stays far below.
constexpr float kRefineCurvature = 0.02f;

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

}  // namespace segmentation
}  // namespace dsr
