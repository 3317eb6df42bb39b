// Viewpoint credibility (sight.hpp): an organized cloud by its pixels'
// rays, any other by the share of its points hidden from the viewpoint in
// the range sphere (range_sphere.hpp). Stations inferred from geometry:
// inferred_stations.cpp.
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
#include "range_sphere.hpp"

namespace dsr {
namespace sight {

using namespace detail;

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

}  // namespace sight
}  // namespace dsr
