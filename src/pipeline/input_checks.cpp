#include "door_state_recognition/pipeline/input_checks.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#endif

namespace dsr {

namespace {
// The farthest a depth camera measures (time of flight to ~12 m, stereo to
// ~20 m with errors of metres): a camera frame whose median range is beyond
// it is in another unit. A terrestrial scanner reaches hundreds of metres,
// but no room is a kilometre across.
constexpr double kCameraMedianRangeMax = 30.0, kScanMedianRangeMax = 1000.0;
constexpr std::size_t kSample = 20000;  // points sampled for the ranges

bool finitePoint(const pcl::PointXYZ& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

// The points of [p, p + n) with x, y and z finite, counted.
std::size_t countFiniteScalar(const pcl::PointXYZ* p, std::size_t n) {
  std::size_t finite = 0;
  for (std::size_t i = 0; i < n; ++i) finite += finitePoint(p[i]);
  return finite;
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DSR_COUNT_FINITE_AVX2 1
// Two points (x, y, z and the padding) at a time with AVX2: a float is
// finite exactly where its magnitude is at most FLT_MAX (a NaN compares false).
__attribute__((target("avx2"))) std::size_t countFiniteAvx2(const pcl::PointXYZ* p, std::size_t n) {
  static_assert(sizeof(pcl::PointXYZ) == 4 * sizeof(float), "PointXYZ: x, y, z and a float of padding");
  const __m256 magnitude = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 largest = _mm256_set1_ps(std::numeric_limits<float>::max());
  std::size_t finite = 0, i = 0;
  for (; i + 2 <= n; i += 2) {
    const __m256 v = _mm256_loadu_ps(p[i].data);
    const int bits = _mm256_movemask_ps(_mm256_cmp_ps(_mm256_and_ps(v, magnitude), largest, _CMP_LE_OQ));
    finite += static_cast<std::size_t>((bits & 0x7) == 0x7) + static_cast<std::size_t>((bits & 0x70) == 0x70);
  }
  return finite + countFiniteScalar(p + i, n - i);
}
#endif

std::size_t countFinite(const pcl::PointCloud<pcl::PointXYZ>& cloud) {
#ifdef DSR_COUNT_FINITE_AVX2
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return countFiniteAvx2(cloud.points.data(), cloud.points.size());
#endif
  return countFiniteScalar(cloud.points.data(), cloud.points.size());
}
}  // namespace

std::optional<std::string> implausibleInput(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& viewpoint) {
  const bool organized = cloud.height > 1;
  const Eigen::Vector3f vp = viewpoint.cast<float>();
  const std::size_t finite = countFinite(cloud);
  if (finite < 20) return std::nullopt;  // too few points: the pipeline says so
  const std::size_t stride = std::max<std::size_t>(1, finite / kSample);
  std::vector<double> range;
  range.reserve(finite / stride + 1);
  float z_min = std::numeric_limits<float>::max(), z_max = -z_min;
  std::size_t skip = 0, at_sensor = 0;  // skip: finite points before the next sampled one
  for (const auto& p : cloud.points) {
    if (!finitePoint(p)) continue;
    // The range's root only where it is used: a point at the sensor (below
    // 1 mm, so its square below 1e-5) and a sampled one.
    const float r2 = (p.getVector3fMap() - vp).squaredNorm();
    if (r2 < 1e-5f) at_sensor += static_cast<double>(std::sqrt(r2)) < 1e-3;
    z_min = std::min(z_min, p.z);
    z_max = std::max(z_max, p.z);
    if (skip-- == 0) {
      range.push_back(std::sqrt(r2));
      skip = stride - 1;
    }
  }
  char buf[300];
  if (at_sensor * 100 >= finite * 99) {
    std::snprintf(buf, sizeof buf,
                  "%zu of %zu points lie at the sensor (depth 0 everywhere): a depth image without returns "
                  "(0 is 'no return'); no doors",
                  at_sensor, finite);
    return std::string(buf);
  }
  if (organized && z_max - z_min <= 1e-6f * std::max(1.0f, std::abs(z_max))) {
    std::snprintf(buf, sizeof buf,
                  "every pixel of the frame has the same depth (%.3f m): a constant depth image, not a scene; no doors",
                  z_max);
    return std::string(buf);
  }
  std::nth_element(range.begin(), range.begin() + range.size() / 2, range.end());
  const double median = range[range.size() / 2], limit = organized ? kCameraMedianRangeMax : kScanMedianRangeMax;
  if (median > limit) {
    std::snprintf(buf, sizeof buf,
                  "median range %.0f m, beyond what a %s reaches indoors (%.0f m): depth in millimetres read as "
                  "metres? (REP 103: metres); no doors",
                  median, organized ? "depth camera" : "scanner", limit);
    return std::string(buf);
  }
  return std::nullopt;
}

std::optional<std::string> implausibleExtent(const pcl::PointCloud<pcl::PointXYZ>& cloud) {
  std::vector<Eigen::Vector3f> pts;
  std::size_t finite = 0;
  for (const auto& p : cloud.points) finite += std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  if (finite < 20) return std::nullopt;
  const std::size_t stride = std::max<std::size_t>(1, finite / kSample);
  std::size_t k = 0;
  for (const auto& p : cloud.points)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && k++ % stride == 0) pts.push_back(p.getVector3fMap());
  // The points' spread about their middle (the median of each coordinate):
  // the median distance to it, whatever frame or offset the cloud is in.
  Eigen::Vector3f mid;
  std::vector<float> c(pts.size());
  for (int a = 0; a < 3; ++a) {
    for (std::size_t i = 0; i < pts.size(); ++i) c[i] = pts[i][a];
    std::nth_element(c.begin(), c.begin() + c.size() / 2, c.end());
    mid[a] = c[c.size() / 2];
  }
  std::vector<double> d(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) d[i] = (pts[i] - mid).norm();
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  const double spread = d[d.size() / 2], limit = cloud.height > 1 ? kCameraMedianRangeMax : kScanMedianRangeMax;
  if (spread <= limit) return std::nullopt;
  char buf[300];
  std::snprintf(buf, sizeof buf,
                "the points lie %.0f m from their middle (median), more than any %s scene spans (%.0f m): "
                "millimetres read as metres? (REP 103: metres); no doors",
                spread, cloud.height > 1 ? "camera's" : "indoor", limit);
  return std::string(buf);
}

std::optional<std::string> singleSurface(const std::vector<Eigen::Vector3f>& points,
                                         const std::vector<Eigen::Vector3f>& normals, const Eigen::Vector3f& viewpoint,
                                         bool up_given) {
  // The dominant direction of the normals (sign-free), and the share of
  // points whose normal lies within 10 deg of it.
  // (The six sums of the symmetric matrix as scalars: each product of two
  // floats is exact in double, so these are the sums of C += n n^T.)
  double cxx = 0, cxy = 0, cxz = 0, cyy = 0, cyz = 0, czz = 0;
  std::size_t n = 0;
  for (const auto& nf : normals)
    if (nf.norm() > 0.5f) {
      const double x = nf.x(), y = nf.y(), z = nf.z();
      cxx += x * x, cxy += x * y, cxz += x * z, cyy += y * y, cyz += y * z, czz += z * z;
      ++n;
    }
  if (n < 100) return std::nullopt;
  Eigen::Matrix3d C;
  C << cxx, cxy, cxz, cxy, cyy, cyz, cxz, cyz, czz;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  const Eigen::Vector3f e = es.eigenvectors().col(2).cast<float>();
  const float cos10 = std::cos(10.0f * 3.14159265f / 180.0f);
  std::vector<float> offset;  // of the plane's points from the viewpoint, along e
  for (std::size_t i = 0; i < normals.size(); ++i)
    if (normals[i].norm() > 0.5f && std::abs(normals[i].dot(e)) > cos10) offset.push_back((points[i] - viewpoint).dot(e));
  const double share = static_cast<double>(offset.size()) / n;
  if (share < 0.9) return std::nullopt;
  std::nth_element(offset.begin(), offset.begin() + offset.size() / 2, offset.end());
  const double d = offset[offset.size() / 2];  // signed, along e
  char buf[300];
  if (std::abs(e.z()) > 0.9f) {
    const double below = e.z() > 0 ? -d : d;  // the plane's depth below the viewpoint
    std::snprintf(buf, sizeof buf, "only a %s in view (one plane holds %.0f%% of the points, %.2f m %s the sensor)%s: no walls, no doors",
                  below > 0 ? "floor" : "ceiling", 100 * share, std::abs(below), below > 0 ? "below" : "above",
                  up_given ? "" : ", or one surface close up levelled as a floor (the up axis was estimated from it: give the sensor's)");
    return std::string(buf);
  }
  if (std::abs(e.z()) < 0.25f && std::abs(d) < 1.5) {
    std::snprintf(buf, sizeof buf,
                  "only one surface close up (one wall-like plane holds %.0f%% of the points, %.2f m from the sensor): "
                  "too little of the scene to tell a doorway",
                  100 * share, std::abs(d));
    return std::string(buf);
  }
  if (std::abs(e.z()) >= 0.25f) {  // neither floor nor wall: the up axis is off
    std::snprintf(buf, sizeof buf,
                  "only one surface in view (one plane holds %.0f%% of the points, tilted %.0f deg from the up axis): "
                  "no walls, no doors; is the up axis right?",
                  100 * share, std::acos(std::min(1.0f, std::abs(e.z()))) * 180 / 3.14159265);
    return std::string(buf);
  }
  return std::nullopt;
}

}  // namespace dsr
