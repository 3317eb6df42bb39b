// Viewpoint credibility and stations inferred from geometry (sight.hpp).
//
// Both rest on one test: from a position o, is point x the first surface of
// the cloud on the ray o -> x? The cloud, thinned to kOccluderVoxel, is cast
// into a range sphere around o as small oriented disks (each thinned point
// with its PCA normal, radius a little over the sampling spacing so that a
// sparse surface stays closed): every angular bin keeps the nearest range at
// which its ray meets a disk. A disk is met exactly where its plane is, so a
// surface seen at a grazing angle does not hide itself; x is hidden when
// the bin's nearest range is shorter than x's by more than the noise.
#include "door_state_recognition/pipeline/sight.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "door_state_recognition/preprocess/preprocess.hpp"
#include "door_state_recognition/segmentation/neighbour_grid.hpp"
#include "door_state_recognition/segmentation/segmentation.hpp"

namespace dsr {
namespace sight {
namespace {

using Points = preprocess::Points;

constexpr double kPi = 3.14159265358979323846;
// Occluders: the cloud thinned to this (m); a room's surfaces then hold some
// 10^4-10^5 disks.
constexpr double kOccluderVoxel = 0.05;
// Angular bin of the range sphere: 0.5 deg (4.4 cm at 5 m).
constexpr double kBin = 0.5 * kPi / 180;
// A point is behind a surface when it is farther than that surface's disk on
// its ray by this much plus a share of its range (range noise of scanners and
// the thickness of thinned surfaces: a leaf's two faces, 4 cm apart, are
// not told apart; a wall's two faces, 10 cm or more, are).
constexpr float kHiddenAbs = 0.05f, kHiddenRel = 0.01f;
// Disks closer than this to the position are its own surroundings (a
// tripod, the robot): they hide nothing.
constexpr float kMinRange = 0.25f;

struct Occluders {
  Points p, n;    // thinned points and unit normals (zero: isolated)
  float radius;   // disk radius
};

// Disks of the points `p` (thinned to `voxel`) with their normals.
Occluders disks(Points p, double voxel, const Parameters& prm) {
  Occluders o;
  o.p = std::move(p);
  o.radius = static_cast<float>(voxel);
  if (o.p.size() < 20) return o;
  const segmentation::NeighbourGrid grid(o.p, static_cast<float>(1.5 * voxel));
  o.n = segmentation::estimateNormals(o.p, grid, prm.normal_k, Eigen::Vector3f::Zero()).n;
  // Sampling spacing: the median distance to the nearest thinned neighbour
  // over a sample (the voxel for dense clouds; a mesh export's vertex
  // spacing when that is coarser).
  std::vector<float> nearest;
  std::vector<int> idx;
  std::vector<float> d2;
  const std::size_t stride = std::max<std::size_t>(1, o.p.size() / 2000);
  for (std::size_t i = 0; i < o.p.size(); i += stride) {
    grid.within(static_cast<int>(i), static_cast<float>(3 * voxel), idx, d2);
    if (!d2.empty()) nearest.push_back(std::sqrt(*std::min_element(d2.begin(), d2.end())));
  }
  float spacing = static_cast<float>(voxel);
  if (!nearest.empty()) {
    std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
    spacing = std::max(spacing, nearest[nearest.size() / 2]);
  }
  o.radius = 0.9f * spacing;
  return o;
}

Occluders occluders(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Parameters& prm) {
  return disks(preprocess::sanitizeAndDownsample(cloud, prm.max_abs_coordinate, kOccluderVoxel), kOccluderVoxel, prm);
}

// Nearest range per angular bin around an origin, in a frame whose z is up
// (any frame works; bins are finest at the horizon).
// atan2 to within 1e-5 rad (a polynomial on [0, 1]; bins are 1e-2 rad).
inline float fastAtan2(float y, float x) {
  const float ax = std::abs(x), ay = std::abs(y), hi = std::max(ax, ay);
  if (hi == 0) return 0;
  const float a = std::min(ax, ay) / hi, s = a * a;
  float r = ((-0.0464964749f * s + 0.15931422f) * s - 0.327622764f) * s * a + a;
  if (ay > ax) r = 1.57079637f - r;
  if (x < 0) r = 3.14159274f - r;
  return y < 0 ? -r : r;
}

class RangeSphere {
 public:
  // Rows are even steps of sin(elevation) (no asin per point; as fine as
  // `bin` at the horizon, coarser towards the poles), columns even steps of
  // azimuth.
  RangeSphere(const Eigen::Vector3f& origin, double bin)
      : o_(origin), bin_(static_cast<float>(bin)),
        na_(static_cast<int>(std::ceil(2 * kPi / bin))), ne_(static_cast<int>(std::ceil(2 / bin))),
        z_(static_cast<std::size_t>(na_) * ne_, std::numeric_limits<float>::infinity()) {
    // The ray through the middle of every bin, from two small tables.
    cos_el_.resize(ne_);
    sin_el_.resize(ne_);
    for (int e = 0; e < ne_; ++e) {
      const double z = std::min(1.0, (e + 0.5) * bin - 1);
      cos_el_[e] = static_cast<float>(std::sqrt(std::max(0.0, 1 - z * z)));
      sin_el_[e] = static_cast<float>(z);
    }
    cos_az_.resize(na_);
    sin_az_.resize(na_);
    for (int a = 0; a < na_; ++a) {
      const double az = (a + 0.5) * bin - kPi;
      cos_az_[a] = static_cast<float>(std::cos(az));
      sin_az_[a] = static_cast<float>(std::sin(az));
    }
  }

  void cast(const Occluders& occ) {
    for (std::size_t i = 0; i < occ.p.size(); ++i) disk(occ.p[i], occ.n[i], occ.radius);
  }

  // Range of x's first surface along its ray (infinity: none).
  float nearest(const Eigen::Vector3f& x) const {
    const Eigen::Vector3f d = x - o_;
    return nearestAt(d, d.norm());
  }
  bool hidden(const Eigen::Vector3f& x) const {
    const Eigen::Vector3f d = x - o_;
    const float r = d.norm();
    return nearestAt(d, r) < r - (kHiddenAbs + kHiddenRel * r);
  }

 private:
  // The same for d = x - origin, r = |d|.
  float nearestAt(const Eigen::Vector3f& d, float r) const {
    if (!(r > 1e-6f)) return std::numeric_limits<float>::infinity();
    return z_[index(bins(d / r))];
  }
  std::pair<int, int> bins(const Eigen::Vector3f& u) const {
    const float az = fastAtan2(u.y(), u.x());
    int a = static_cast<int>(std::floor((az + static_cast<float>(kPi)) / bin_));
    int e = static_cast<int>(std::floor((u.z() + 1) / bin_));
    if (a >= na_ && a < 2 * na_) a -= na_;  // az = pi: the first column again
    else if (a < 0 || a >= na_) a = ((a % na_) + na_) % na_;
    e = std::clamp(e, 0, ne_ - 1);
    return {a, e};
  }
  std::size_t index(std::pair<int, int> ae) const { return static_cast<std::size_t>(ae.second) * na_ + ae.first; }

  void disk(const Eigen::Vector3f& q, const Eigen::Vector3f& n, float radius) {
    const Eigen::Vector3f d = q - o_;
    const float r = d.norm();
    if (r < kMinRange) return;
    const Eigen::Vector3f u = d / r;
    const auto [a0, e0] = bins(u);
    const float alpha = std::atan(radius / r);
    const float cos_el = std::sqrt(std::max(0.0f, 1 - u.z() * u.z()));
    // Rows the disk spans: d(sin el) = cos el d(el), plus the curvature near a pole.
    const int ke = static_cast<int>(std::ceil((alpha * cos_el + alpha * alpha) / bin_)) + 1;
    const int ka = std::min(na_ / 2, static_cast<int>(std::ceil(alpha / (bin_ * std::max(cos_el, 0.02f)))));
    const bool oriented = n.squaredNorm() > 0.5f;
    const float dn_d = d.dot(n), r2 = radius * radius;
    // Columns a0 - ka .. a0 + ka (ka <= na_ / 2) as at most three runs
    // without wrapping (a bin met twice keeps its minimum). Without
    // branches: every bin's test is worked out, and the bin takes t where
    // the disk is met nearer than its nearest range so far.
    auto run = [&](float* row, float ce, float se, int from, int to) {
      if (oriented) {
        for (int a = from; a <= to; ++a) {
          const Eigen::Vector3f ray(ce * cos_az_[a], ce * sin_az_[a], se);
          const float dn = ray.dot(n);
          const float t = dn_d / dn;
          // not edge-on (there the disk covers no area of the bin), ahead, nearer, on the disk
          const bool met = !(std::abs(dn) < 0.05f) & (t > 0) & (t < row[a]) & !((ray * t - d).squaredNorm() > r2);
          row[a] = met ? t : row[a];
        }
      } else {
        for (int a = from; a <= to; ++a) {
          const Eigen::Vector3f ray(ce * cos_az_[a], ce * sin_az_[a], se);
          const bool met = (r < row[a]) & !((ray * r - d).squaredNorm() > r2);
          row[a] = met ? r : row[a];
        }
      }
    };
    // Of those rows, only the ones a ray meeting the disk can lie in: such
    // a ray is within beta = asin(radius / r) of u, so its z (the row's
    // sin el) within beta cos el + beta^2 / 2 of u's (with a margin for
    // rounding); the rows beyond hold no bin the disk is met in.
    const float beta = radius < r ? 1.0001f * std::asin(radius / r) : 4.0f;
    const float dz = beta * cos_el + 0.5f * beta * beta + 1e-4f;
    // And in a row of cos el c, only the columns such a ray can lie in: its
    // azimuth differs from u's by D with sin(D / 2) <= sin(beta / 2) /
    // sqrt(cos el c) <= s, so D <= 2 asin(s) <= 2 s / sqrt(1 - s^2); u lies
    // at `frac` of its column a0.
    const float pos = (fastAtan2(u.y(), u.x()) + static_cast<float>(kPi)) / bin_, frac = pos - std::floor(pos);
    for (int de = -ke; de <= ke; ++de) {
      const int e = e0 + de;
      if (e < 0 || e >= ne_ || std::abs(sin_el_[e] - u.z()) > dz) continue;
      float* row = z_.data() + static_cast<std::size_t>(e) * na_;
      int lo = a0 - ka, hi = a0 + ka;
      const float cc = cos_el * cos_el_[e];
      if (cc > 1e-6f) {
        const float s = 0.5f * beta / std::sqrt(cc);
        if (s < 0.5f) {
          const float reach = (2 * s / std::sqrt(1 - s * s) + 1e-3f) / bin_;
          lo = std::max(lo, a0 + static_cast<int>(std::ceil(frac - 0.5f - reach)));
          hi = std::min(hi, a0 + static_cast<int>(std::floor(frac - 0.5f + reach)));
          if (lo > hi) continue;
        }
      }
      if (lo < 0) run(row, cos_el_[e], sin_el_[e], lo + na_, na_ - 1), lo = 0;
      if (hi >= na_) run(row, cos_el_[e], sin_el_[e], 0, hi - na_), hi = na_ - 1;
      run(row, cos_el_[e], sin_el_[e], lo, hi);
    }
  }

  Eigen::Vector3f o_;
  float bin_;
  int na_, ne_;
  std::vector<float> z_;
  std::vector<float> cos_el_, sin_el_, cos_az_, sin_az_;
};

}  // namespace

namespace {

// An organized cloud's pixels are rays from one point: seen from there, the
// angle between the rays of two neighbouring pixels of a row is the
// sensor's pitch (a camera's changes slowly across its image) whatever
// their depths, so two such angles side by side are alike. Seen from
// elsewhere (a frame moved into another frame, VIEWPOINT left at 0) each
// angle follows the depths and neighbours differ. The share of neighbouring
// angles more than kRayRatio apart, over every second row.
struct RayCheck {
  std::size_t pairs = 0;
  double off = 0;
};
constexpr double kRayRatio = 1.0 / 0.7, kMaxRayOffShare = 0.05;
constexpr std::size_t kMinRayPairs = 1000;
// raysMeet: a row or column of at least kMinPlanePoints points spread over
// kPlaneMinSpread (m, standard deviation) in its plane, and flat within
// kPlaneFlat of that (variance ratio: rays of one plane, exactly so); at
// least kMinPlanes of them; a direction is fixed where the planes' normals
// hold kFixedShare of the strongest direction's weight.
constexpr std::size_t kMinPlanePoints = 12, kMinPlanes = 20;
constexpr double kPlaneMinSpread = 0.01, kPlaneFlat = 1e-4, kFixedShare = 0.01;

// A pixel that holds a return: finite, and not (0,0,0), which some drivers
// write where there is none.
bool isReturn(const pcl::PointXYZ& q) { return q.getVector3fMap().allFinite() && !q.getVector3fMap().isZero(); }

RayCheck rayCheck(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& viewpoint) {
  RayCheck out;
  const Eigen::Vector3f v = viewpoint.cast<float>();
  std::size_t off = 0;
  for (std::uint32_t r = 0; r < cloud.height; r += 2) {
    Eigen::Vector3f prev;
    float prev_angle = -1;
    bool have = false;
    for (std::uint32_t k = 0; k < cloud.width; ++k) {
      const pcl::PointXYZ& q = cloud.points[static_cast<std::size_t>(r) * cloud.width + k];
      Eigen::Vector3f d = q.getVector3fMap() - v;
      const float n = d.norm();
      if (!isReturn(q) || !d.allFinite() || n < 1e-3f) {
        have = false, prev_angle = -1;
        continue;
      }
      d /= n;
      if (have) {
        const float angle = std::acos(std::clamp(prev.dot(d), -1.0f, 1.0f));
        if (prev_angle > 0 && angle > 0) {
          ++out.pairs;
          const double ratio = angle / prev_angle;
          off += ratio > kRayRatio || ratio < 1 / kRayRatio;
        }
        prev_angle = angle;
      }
      prev = d, have = true;
    }
  }
  if (out.pairs > 0) out.off = static_cast<double>(off) / static_cast<double>(out.pairs);
  return out;
}

// Where an organized cloud's rays meet: the points of one column (a
// camera's, or a rotating LiDAR's scan line at one azimuth) lie in one plane
// through the sensor, and so do a camera's rows; a LiDAR's rows are cones
// and fail the flatness test. The point nearest every such plane whose
// points span it (not one line, as a single flat wall gives), least squares;
// along a direction no plane fixes (a LiDAR's columns all hold its vertical
// axis) it stays at `start`.
std::optional<Eigen::Vector3d> raysMeet(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& start) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  std::size_t planes = 0;
  auto addLine = [&](std::uint32_t count, const auto& at) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d sq = Eigen::Matrix3d::Zero();
    std::size_t n = 0;
    for (std::uint32_t k = 0; k < count; ++k) {
      const pcl::PointXYZ& q = at(k);
      if (!isReturn(q)) continue;
      const Eigen::Vector3d x = q.getVector3fMap().cast<double>();
      sum += x, sq += x * x.transpose(), ++n;
    }
    if (n < kMinPlanePoints) return;
    const Eigen::Vector3d m = sum / static_cast<double>(n);
    const Eigen::Matrix3d C = sq / static_cast<double>(n) - m * m.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
    const Eigen::Vector3d l = es.eigenvalues();
    if (l(1) < kPlaneMinSpread * kPlaneMinSpread || l(0) > kPlaneFlat * l(1)) return;
    const Eigen::Vector3d nrm = es.eigenvectors().col(0);
    A += nrm * nrm.transpose(), b += nrm * nrm.dot(m), ++planes;
  };
  for (std::uint32_t c = 0; c < cloud.width; c += 2)
    addLine(cloud.height, [&](std::uint32_t r) -> const pcl::PointXYZ& { return cloud.points[static_cast<std::size_t>(r) * cloud.width + c]; });
  for (std::uint32_t r = 0; r < cloud.height; r += 2)
    addLine(cloud.width, [&](std::uint32_t c) -> const pcl::PointXYZ& { return cloud.points[static_cast<std::size_t>(r) * cloud.width + c]; });
  if (planes < kMinPlanes) return std::nullopt;
  // Solved in the directions the planes fix, `start` kept in the others.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(A);
  Eigen::Vector3d c = start;
  const Eigen::Vector3d r = b - A * start;
  int free_dirs = 0;
  for (int k = 0; k < 3; ++k) {
    if (es.eigenvalues()(k) > kFixedShare * es.eigenvalues()(2))
      c += es.eigenvectors().col(k) * (es.eigenvectors().col(k).dot(r) / es.eigenvalues()(k));
    else
      ++free_dirs;
  }
  if (!c.allFinite()) return std::nullopt;
  // One direction free: a rotating LiDAR, its columns' planes all holding
  // its axis u. Each ring is a cone about that axis, its apex the sensor: a
  // ring's points rise along u by a fixed slope per metre out from the axis,
  // h = h0 + slope * rho, and the apex is at h0 (the median over rings whose
  // points lie at several distances from the axis).
  if (free_dirs == 1) {
    const Eigen::Vector3d u = es.eigenvectors().col(0);
    std::vector<double> apex;
    for (std::uint32_t row = 0; row < cloud.height; ++row) {
      double n = 0, sr = 0, sh = 0, srr = 0, srh = 0;
      for (std::uint32_t k = 0; k < cloud.width; ++k) {
        const pcl::PointXYZ& q = cloud.points[static_cast<std::size_t>(row) * cloud.width + k];
        if (!isReturn(q)) continue;
        const Eigen::Vector3d d = q.getVector3fMap().cast<double>() - c;
        const double h = d.dot(u), rho = (d - h * u).norm();
        n += 1, sr += rho, sh += h, srr += rho * rho, srh += rho * h;
      }
      const double var = n > 0 ? srr / n - (sr / n) * (sr / n) : 0;
      if (n < kMinPlanePoints || var < kPlaneMinSpread * kPlaneMinSpread) continue;
      const double slope = (srh / n - (sr / n) * (sh / n)) / var;
      apex.push_back(sh / n - slope * sr / n);
    }
    if (apex.size() >= 3) {
      std::nth_element(apex.begin(), apex.begin() + apex.size() / 2, apex.end());
      c += apex[apex.size() / 2] * u;
    }
  }
  return c;
}

}  // namespace

ViewpointCheck checkViewpoint(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& viewpoint,
                              const Parameters& p, pcl::PointCloud<pcl::PointXYZ>* visible) {
  ViewpointCheck c;
  if (cloud.height > 1) {
    // Organized: one sensor's frame, if its rays meet at the viewpoint (a
    // frame moved into another frame keeps its pixels but not their origin).
    const RayCheck j = rayCheck(cloud, viewpoint);
    c.tested = j.pairs;
    char buf[260];
    if (j.pairs >= kMinRayPairs && j.off > kMaxRayOffShare) {
      // Where do they meet? Taken only if they are alike seen from there.
      if (const std::optional<Eigen::Vector3d> at = raysMeet(cloud, viewpoint)) {
        const RayCheck there = rayCheck(cloud, *at);
        if (there.off <= kMaxRayOffShare) {
          c.rays_meet = at;
          std::snprintf(buf, sizeof buf,
                        "organized cloud whose pixels' rays do not meet there but at (%.3f, %.3f, %.3f) (%.0f %% "
                        "of neighbouring angles apart against %.1f %%): moved out of its sensor's frame",
                        at->x(), at->y(), at->z(), 100 * j.off, 100 * there.off);
          c.reason = buf;
          return c;
        }
      }
      std::snprintf(buf, sizeof buf,
                    "organized cloud whose pixels' rays do not meet there: the angles between neighbouring "
                    "pixels' rays differ along its rows (%.0f %% of them by more than %.0f %%; from the sensor's "
                    "own origin none): moved out of its sensor's frame?",
                    100 * j.off, 100 * (kRayRatio - 1));
      c.reason = buf;
      return c;
    }
    c.credible = true;
    std::snprintf(buf, sizeof buf,
                  "organized cloud: one sensor's frame, its pixels' rays meeting at its viewpoint (%.1f %% of "
                  "neighbouring angles apart)",
                  100 * j.off);
    c.reason = buf;
    return c;
  }
  const Occluders occ = occluders(cloud, p);
  if (occ.p.size() < 20) {
    c.credible = true;
    c.reason = "too few points to test the viewpoint; taken as given";
    return c;
  }
  RangeSphere sphere(viewpoint.cast<float>(), kBin);
  sphere.cast(occ);
  std::size_t hidden = 0;
  for (const auto& x : occ.p) hidden += sphere.hidden(x);
  c.tested = occ.p.size();
  c.hidden_share = static_cast<double>(hidden) / static_cast<double>(c.tested);
  c.credible = c.hidden_share <= kMaxHiddenShare;
  c.take_visible = !c.credible && c.hidden_share <= kTakeVisibleUpTo;
  if (visible && c.take_visible) {
    visible->clear();
    const float lim = static_cast<float>(p.max_abs_coordinate);
    for (const auto& q : cloud.points) {
      const Eigen::Vector3f x = q.getVector3fMap();
      if (x.allFinite() && !(x.cwiseAbs().maxCoeff() > lim) && !sphere.hidden(x)) visible->push_back(q);
    }
    visible->width = static_cast<std::uint32_t>(visible->size());
    visible->height = 1;
    visible->is_dense = true;
    visible->sensor_origin_ = cloud.sensor_origin_;
    visible->sensor_orientation_ = cloud.sensor_orientation_;
  }
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "%.1f %% of the points lie behind other surfaces seen from it (one sensor's own: <= %.0f %%; "
                "up to %.0f %%, a cluttered room's depth edges, those left out)",
                100 * c.hidden_share, 100 * kMaxHiddenShare, 100 * kTakeVisibleUpTo);
  c.reason = buf;
  return c;
}

InferredStations inferStations(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Parameters& p) {
  InferredStations out;
  auto t_last = std::chrono::steady_clock::now();
  auto mark = [&](const char* stage) {
    const auto now = std::chrono::steady_clock::now();
    out.timing_ms.emplace_back(stage, std::chrono::duration<double, std::milli>(now - t_last).count());
    t_last = now;
  };
  const Occluders occ = occluders(cloud, p);
  mark("sight_disks");
  if (occ.p.size() < 50) return out;

  // Up: given, or estimated as the pipeline does; positions are placed in
  // the levelled frame.
  std::optional<Eigen::Vector3d> up = preprocess::parseUpAxis(p.up_axis);
  if (!up) up = preprocess::estimateUp(occ.p, occ.n, static_cast<unsigned>(p.random_seed));
  if (!up) up = Eigen::Vector3d::UnitZ();
  out.up = up->normalized();
  const Eigen::Matrix3f R = preprocess::levellingRotation(out.up).cast<float>();
  Occluders lev = occ;
  for (std::size_t i = 0; i < lev.p.size(); ++i) {
    lev.p[i] = R * lev.p[i];
    lev.n[i] = R * lev.n[i];
  }

  // Extent: robust percentiles (a few stray points do not stretch it).
  auto percentile = [&](int axis, double q) {
    std::vector<float> v;
    v.reserve(lev.p.size());
    for (const auto& x : lev.p) v.push_back(x(axis));
    const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())));
    std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
    return v[k];
  };
  const float x0 = percentile(0, 0.005), x1 = percentile(0, 0.995);
  const float y0 = percentile(1, 0.005), y1 = percentile(1, 0.995);
  const float z0 = percentile(2, 0.01), z1 = percentile(2, 0.99);
  // A scanner's height: 1.3 m above the floor, or half the room where lower.
  const float zs = z0 + std::min(1.3f, 0.5f * (z1 - z0));
  // A horizontal grid of about 1 m, at most ~100 positions.
  const double area = std::max(1e-3, static_cast<double>(x1 - x0) * (y1 - y0));
  const float g = static_cast<float>(std::max(1.0, std::sqrt(area / 100)));
  std::vector<Eigen::Vector3f> cand;
  for (float x = x0 + g / 2; x < x1; x += g)
    for (float y = y0 + g / 2; y < y1; y += g) cand.emplace_back(x, y, zs);

  // Positions a scanner could stand at: free (nothing of the cloud within
  // kClearance) and enclosed (walls all around: of 36 horizontal rays,
  // kMinEnclosed meet the cloud's structure at the scanner's height within
  // the extent; a position outside a room, or in a corridor's open end,
  // sees its walls on one side only). On a 2D occupancy grid of the band
  // +-0.6 m around that height.
  {
    constexpr float kCell = 0.1f, kClearance = 0.3f;
    constexpr int kRays = 36, kMinEnclosed = 31;
    const int nx = static_cast<int>(std::ceil((x1 - x0) / kCell)) + 1, ny = static_cast<int>(std::ceil((y1 - y0) / kCell)) + 1;
    std::vector<char> occupied(static_cast<std::size_t>(nx) * ny, 0);
    auto cellOf = [&](float x, float y, int& i, int& j) {
      i = static_cast<int>(std::floor((x - x0) / kCell));
      j = static_cast<int>(std::floor((y - y0) / kCell));
      return i >= 0 && j >= 0 && i < nx && j < ny;
    };
    for (const auto& x : lev.p) {
      int i, j;
      if (std::abs(x.z() - zs) <= 0.6f && cellOf(x.x(), x.y(), i, j)) occupied[static_cast<std::size_t>(j) * nx + i] = 1;
    }
    // Free: only points in a band a little wider than kClearance around
    // the height can be that close; they are bucketed in columns of that
    // width, and a candidate tests the 3x3 columns around it.
    constexpr float kReach = kClearance + 0.01f;
    std::vector<Eigen::Vector3f> band;
    Eigen::Vector2f blo = Eigen::Vector2f::Constant(std::numeric_limits<float>::max()), bhi = -blo;
    for (const auto& x : lev.p)
      if (std::abs(x.z() - zs) <= kReach) {
        band.push_back(x);
        blo = blo.cwiseMin(x.head<2>());
        bhi = bhi.cwiseMax(x.head<2>());
      }
    const int bx = band.empty() ? 1 : static_cast<int>((bhi.x() - blo.x()) / kReach) + 1;
    const int by = band.empty() ? 1 : static_cast<int>((bhi.y() - blo.y()) / kReach) + 1;
    auto column = [&](const Eigen::Vector3f& x, int& i, int& j) {
      i = static_cast<int>(std::floor((x.x() - blo.x()) / kReach));
      j = static_cast<int>(std::floor((x.y() - blo.y()) / kReach));
    };
    std::vector<std::size_t> start(static_cast<std::size_t>(bx) * by + 1, 0);
    std::vector<Eigen::Vector3f> bucketed(band.size());
    {
      std::vector<std::size_t> col(band.size());
      for (std::size_t k = 0; k < band.size(); ++k) {
        int i, j;
        column(band[k], i, j);
        col[k] = static_cast<std::size_t>(std::clamp(j, 0, by - 1)) * bx + std::clamp(i, 0, bx - 1);
        ++start[col[k] + 1];
      }
      for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
      std::vector<std::size_t> fill(start.begin(), start.end() - 1);
      for (std::size_t k = 0; k < band.size(); ++k) bucketed[fill[col[k]]++] = band[k];
    }
    auto clearAt = [&](const Eigen::Vector3f& c) {
      int ci, cj;
      column(c, ci, cj);
      for (int j = std::max(0, cj - 1); j <= std::min(by - 1, cj + 1); ++j)
        for (int i = std::max(0, ci - 1); i <= std::min(bx - 1, ci + 1); ++i) {
          const std::size_t b = static_cast<std::size_t>(j) * bx + i;
          for (std::size_t k = start[b]; k < start[b + 1]; ++k)
            if (!((bucketed[k] - c).squaredNorm() > kClearance * kClearance)) return false;
        }
      return true;
    };
    std::vector<Eigen::Vector3f> kept;
    for (const auto& c : cand) {
      if (!clearAt(c)) continue;
      int enclosed = 0;
      for (int r = 0; r < kRays; ++r) {
        const float a = static_cast<float>(2 * kPi * r / kRays), dx = std::cos(a) * kCell / 2, dy = std::sin(a) * kCell / 2;
        int i, j;
        for (float x = c.x(), y = c.y(); cellOf(x, y, i, j); x += dx, y += dy)
          if (occupied[static_cast<std::size_t>(j) * nx + i]) {
            ++enclosed;
            break;
          }
      }
      if (enclosed >= kMinEnclosed) kept.push_back(c);
    }
    cand.swap(kept);
  }
  mark("sight_candidates");
  if (cand.empty()) return out;

  // Score on a sample of the thinned points: which each position sees,
  // against coarser disks (kScoreVoxel) in coarser bins.
  constexpr double kScoreVoxel = 0.1;
  const Occluders coarse = disks(preprocess::voxelDownsample(lev.p, kScoreVoxel), kScoreVoxel, p);
  const std::size_t stride = std::max<std::size_t>(1, lev.p.size() / 20000);
  std::vector<int> sample;
  for (std::size_t i = 0; i < lev.p.size(); i += stride) sample.push_back(static_cast<int>(i));
  std::vector<std::vector<char>> sees(cand.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (long c = 0; c < static_cast<long>(cand.size()); ++c) {
    RangeSphere sphere(cand[c], 4 * kBin);
    sphere.cast(coarse);
    sees[c].resize(sample.size());
    for (std::size_t k = 0; k < sample.size(); ++k) sees[c][k] = !sphere.hidden(lev.p[sample[k]]);
  }

  mark("sight_score");
  // Greedy cover: the position seeing most of what no chosen one sees, while
  // it adds a station's worth (kMinGain of the sample: main stations), then
  // while it adds kMinGainMinor (minor stations, whose doors only refine).
  constexpr double kMinGain = 0.08, kMinGainMinor = 0.03;
  constexpr int kMaxStations = 6;
  std::vector<char> covered(sample.size(), 0);
  std::vector<std::size_t> chosen;
  std::size_t main_count = 0;
  while (static_cast<int>(chosen.size()) < kMaxStations) {
    std::size_t best = cand.size(), best_gain = 0;
    for (std::size_t c = 0; c < cand.size(); ++c) {
      std::size_t gain = 0;
      for (std::size_t k = 0; k < sample.size(); ++k) gain += sees[c][k] && !covered[k];
      if (gain > best_gain) best_gain = gain, best = c;
    }
    if (best == cand.size() || static_cast<double>(best_gain) < kMinGainMinor * static_cast<double>(sample.size())) break;
    if (static_cast<double>(best_gain) >= kMinGain * static_cast<double>(sample.size()) && main_count == chosen.size())
      ++main_count;
    chosen.push_back(best);
    for (std::size_t k = 0; k < sample.size(); ++k) covered[k] |= sees[best][k];
  }
  if (main_count == 0) return out;
  out.main = main_count;

  // Every input point to each chosen station that sees it (a point seen from
  // two stations is in both scans, as in a survey).
  const Eigen::Matrix3f Rt = R.transpose();
  std::vector<RangeSphere> spheres;
  for (std::size_t c : chosen) {
    spheres.emplace_back(cand[c], kBin);
    out.viewpoints.push_back((Rt * cand[c]).cast<double>());
  }
#pragma omp parallel for schedule(dynamic, 1)
  for (long k = 0; k < static_cast<long>(spheres.size()); ++k) spheres[static_cast<std::size_t>(k)].cast(lev);
  out.clouds.resize(chosen.size());
  const float lim = static_cast<float>(p.max_abs_coordinate);
  const long n = static_cast<long>(cloud.size());
  // Bit s of seen_by[i]: station s sees point i (0: none, or not a point).
  std::vector<std::uint8_t> seen_by(cloud.size(), 0);
#pragma omp parallel for schedule(static, 4096)
  for (long i = 0; i < n; ++i) {
    const Eigen::Vector3f x = cloud.points[static_cast<std::size_t>(i)].getVector3fMap();
    if (!x.allFinite() || x.cwiseAbs().maxCoeff() > lim) continue;
    const Eigen::Vector3f xl = R * x;
    std::uint8_t bits = 0;
    for (std::size_t k = 0; k < spheres.size(); ++k)
      if (!spheres[k].hidden(xl)) bits |= static_cast<std::uint8_t>(1u << k);
    seen_by[static_cast<std::size_t>(i)] = bits ? bits : 0x80;
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const std::uint8_t bits = seen_by[i];
    if (bits == 0x80) ++out.unseen;
    if (bits & 0x80) continue;
    for (std::size_t k = 0; k < spheres.size(); ++k)
      if (bits & (1u << k)) out.clouds[k].push_back(cloud.points[i]);
  }
  mark("sight_assign");
  for (auto& c : out.clouds) {
    c.width = static_cast<std::uint32_t>(c.size());
    c.height = 1;
    c.is_dense = true;
  }
  return out;
}

}  // namespace sight
}  // namespace dsr
