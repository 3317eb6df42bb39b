// Internal to the sight step (sight.hpp): the range sphere and the
// occluders cast into it, shared by checkViewpoint (sight.cpp) and
// inferStations (inferred_stations.cpp).
//
// Both rest on one test: from a position o, is point x the first surface of
// the cloud on the ray o -> x? The cloud, thinned to kOccluderVoxel, is cast
// into a range sphere around o as small oriented disks (each thinned point
// with its PCA normal, radius a little over the sampling spacing so that a
// sparse surface stays closed): every angular bin keeps the nearest range at
// which its ray meets a disk. A disk is met exactly where its plane is, so a
// surface seen at a grazing angle does not hide itself; x is hidden when
// the bin's nearest range is shorter than x's by more than the noise.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "door_state_recognition/pipeline/parameters.hpp"
#include "door_state_recognition/preprocess/preprocess.hpp"

namespace dsr {
namespace sight {
namespace detail {

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
Occluders disks(Points p, double voxel, const Parameters& prm);
// The cloud thinned to kOccluderVoxel, as disks.
Occluders occluders(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Parameters& prm);

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

}  // namespace detail
}  // namespace sight
}  // namespace dsr
