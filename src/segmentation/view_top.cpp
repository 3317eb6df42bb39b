// Segmentation: the top (and bottom) of what a sensor saw, by bearing from
// its viewpoint (ViewTop, viewTop).
#include "door_state_recognition/segmentation/segmentation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace dsr {
namespace segmentation {

namespace {
constexpr int kViewTopBins = 1440;  // bearing bins (pseudo-angle), about 0.25 deg
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

int ViewTop::binsWithin(float angle) const {
  return angle > 0 ? static_cast<int>(angle / (2 * static_cast<float>(M_PI) / kViewTopBins)) : 0;
}

bool ViewTop::inViewNear(const Eigen::Vector3f& q, int bins, float slack) const {
  if (max_tan.empty()) return true;
  const int b = bin(q);
  if (b < 0) return true;
  const float t = tanElevation(q);
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (int k = -bins; k <= bins; ++k) {
    const int j = ((b + k) % kViewTopBins + kViewTopBins) % kViewTopBins;
    lo = std::min(lo, min_tan[j]), hi = std::max(hi, max_tan[j]);
  }
  return t >= lo - slack && t <= hi + slack;
}

bool ViewTop::inView(const Eigen::Vector3f& q, float slack) const { return inViewNear(q, 0, slack); }

}  // namespace segmentation
}  // namespace dsr
