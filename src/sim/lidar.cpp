#include "door_state_recognition/sim/lidar.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "ray_random.hpp"

namespace dsr {
namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

void requireOption(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("lidar: " + what);
}

// A free spot for a robot's mast: 0.35 m clear of every box at the head's
// height and at 1 m, inside the room and clear of inward door swings.
Eigen::Vector3d freeMastPosition(const Scene& scene, RayRandom& rnd, double height) {
  const RoomSpec& r = scene.spec;
  const double margin = 0.35;
  for (int attempt = 0; attempt < 5000; ++attempt) {
    const Eigen::Vector3d q((rnd.uniform() - 0.5) * (r.width - 2 * margin), (rnd.uniform() - 0.5) * (r.depth - 2 * margin), height);
    const Eigen::Vector3d p = scene.room_to_world * q;
    if (scene.isFree(p, std::min(margin, height - 0.01)) && scene.isFree(Eigen::Vector3d(p.x(), p.y(), 1.0), margin)) return p;
  }
  throw std::invalid_argument("lidar: no free position for the sensor in this room");
}

}  // namespace

LidarOptions LidarOptions::preset(int beams) {
  LidarOptions o;
  o.beams = beams;
  switch (beams) {
    case 16:
      o.min_elevation_deg = -15;
      o.max_elevation_deg = 15;
      o.azimuth_steps = 1800;
      o.range_sigma = 0.02;
      break;
    case 32:
      o.min_elevation_deg = -25;
      o.max_elevation_deg = 15;
      o.azimuth_steps = 1800;
      o.range_sigma = 0.02;
      break;
    case 64:
      o.min_elevation_deg = -22.5;
      o.max_elevation_deg = 22.5;
      o.azimuth_steps = 1024;
      o.range_sigma = 0.015;
      break;
    case 128:
      o.min_elevation_deg = -45;
      o.max_elevation_deg = 45;
      o.azimuth_steps = 1024;
      o.range_sigma = 0.015;
      o.max_range = 50;
      break;
    default:
      throw std::invalid_argument("lidar: no preset for " + std::to_string(beams) + " beams (16, 32, 64, 128)");
  }
  return o;
}

int lidarBeamsOf(const std::string& s) {
  for (int b : {16, 32, 64, 128})
    if (s == "lidar" + std::to_string(b)) return b;
  return 0;
}

double lidarBeamElevation(const LidarOptions& o, int row) {
  if (o.beams < 2) return 0.5 * (o.min_elevation_deg + o.max_elevation_deg) * kDeg;
  return (o.max_elevation_deg - (o.max_elevation_deg - o.min_elevation_deg) * row / (o.beams - 1)) * kDeg;
}

SimulatedCloud scanLidar(const Scene& scene, const LidarOptions& o) {
  requireOption(o.beams >= 1 && o.beams <= 1024, "beams must lie in [1, 1024]");
  requireOption(o.azimuth_steps >= 8 && o.azimuth_steps <= 16384, "azimuth steps must lie in [8, 16384]");
  requireOption(o.min_elevation_deg >= -89 && o.max_elevation_deg <= 89 && o.min_elevation_deg <= o.max_elevation_deg,
                "elevations must satisfy -89 <= min <= max <= 89 deg");
  requireOption(o.range_sigma >= 0 && o.range_sigma < 1, "range noise must lie in [0, 1) m");
  requireOption(o.min_range >= 0 && o.max_range > o.min_range && o.max_range <= 1000, "need 0 <= min range < max range <= 1000 m");
  requireOption(o.dropout >= 0 && o.dropout < 1, "dropout must lie in [0, 1)");
  requireOption(o.max_incidence_deg > 0 && o.max_incidence_deg <= 90, "max incidence must lie in (0, 90] deg");
  requireOption(o.mast_height < 0 || (o.mast_height >= 0.4 && o.mast_height <= 1.2), "mast height must lie in [0.4, 1.2] m");
  requireOption(!o.sensor_to_world || o.sensor_to_world->matrix().allFinite(), "sensor pose must be finite");
  requireOption(!o.sweep_start_to_world || (o.sensor_to_world && o.sweep_start_to_world->matrix().allFinite()),
                "a sweep's start pose needs a finite pose and sensor_to_world");

  SimulatedCloud out;
  out.sensor = "lidar" + std::to_string(o.beams);
  out.frame_id = "lidar";
  out.lidar_beams = o.beams;
  out.lidar_min_elevation_deg = o.min_elevation_deg;
  out.lidar_max_elevation_deg = o.max_elevation_deg;
  out.lidar_max_range = o.max_range;
  if (o.sensor_to_world) {
    out.sensor_to_world = *o.sensor_to_world;
  } else {
    RayRandom placement(o.seed, 0x11DA, 0);
    const double h = o.mast_height >= 0 ? o.mast_height : 0.4 + 0.8 * placement.uniform();
    const Eigen::Vector3d p = freeMastPosition(scene, placement, scene.floor_z + h);
    out.sensor_to_world = Eigen::Translation3d(p) * Eigen::AngleAxisd(2 * kPi * placement.uniform(), Eigen::Vector3d::UnitZ());
  }
  const Eigen::Vector3d origin = out.sensor_to_world.translation();
  const Eigen::Matrix3d R = out.sensor_to_world.linear();
  out.viewpoints_world.push_back(origin);
  // Pose of each column's rays relative to the cloud frame (identity: no motion).
  std::vector<Eigen::Isometry3d> column(o.azimuth_steps, Eigen::Isometry3d::Identity());
  if (o.sweep_start_to_world) {
    const Eigen::Isometry3d start = out.sensor_to_world.inverse() * *o.sweep_start_to_world;  // in the end frame
    const Eigen::Quaterniond q0(start.linear()), q1 = Eigen::Quaterniond::Identity();
    for (int c = 0; c < o.azimuth_steps; ++c) {
      const double f = (c + 0.5) / o.azimuth_steps;
      column[c].linear() = q0.slerp(f, q1).toRotationMatrix();
      column[c].translation() = (1 - f) * start.translation();
    }
  }

  const int W = o.azimuth_steps, H = o.beams;
  out.cloud.width = W;
  out.cloud.height = H;
  out.cloud.is_dense = false;
  out.cloud.points.resize(static_cast<std::size_t>(W) * H);
  const float none = o.zeros_for_no_return ? 0.0f : std::numeric_limits<float>::quiet_NaN();
  const double cos_max = std::cos(o.max_incidence_deg * kDeg);
#pragma omp parallel for schedule(dynamic, 1)
  for (int r = 0; r < H; ++r) {
    const double el = lidarBeamElevation(o, r);
    for (int c = 0; c < W; ++c) {
      const double az = kPi - 2 * kPi * (c + 0.5) / W;
      const Eigen::Vector3d d_s(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const std::size_t idx = static_cast<std::size_t>(r) * W + c;
      pcl::PointXYZL& q = out.cloud.points[idx];
      q.x = q.y = q.z = none;
      q.label = 0;
      const Eigen::Vector3d d_c = column[c].linear() * d_s;  // the ray in the cloud frame
      const Eigen::Vector3d dir = R * d_c;
      const RayHit hit = castRay(scene, origin + R * column[c].translation(), dir, o.max_range);
      if (!hit.hit || hit.t < o.min_range || std::abs(hit.normal.dot(dir)) < cos_max) continue;
      RayRandom rnd(o.seed, 11, idx);
      if (o.dropout > 0 && rnd.uniform() < o.dropout) continue;
      const double range = hit.t + (o.range_sigma > 0 ? o.range_sigma * rnd.gaussian() : 0.0);
      // As the head measured it: range along its beam, whatever it moved since.
      q.x = static_cast<float>(range * d_s.x());
      q.y = static_cast<float>(range * d_s.y());
      q.z = static_cast<float>(range * d_s.z());
      q.label = static_cast<std::uint32_t>(hit.surface);
    }
  }
  return out;
}

bool lidarSeesDoor(const Scene& scene, const SimulatedCloud& cloud, int door) {
  if (door < 0 || door >= static_cast<int>(scene.doors.size())) return false;
  const DoorTruth& d = scene.doors[door];
  const Eigen::Isometry3d W2S = cloud.sensor_to_world.inverse();
  const Eigen::Vector3d origin = cloud.sensor_to_world.translation();
  // Half a beam spacing beyond the outer beams still meets a surface between them.
  const double half_gap =
      cloud.lidar_beams > 1 ? 0.5 * (cloud.lidar_max_elevation_deg - cloud.lidar_min_elevation_deg) / (cloud.lidar_beams - 1) : 0.5;
  const double el0 = (cloud.lidar_min_elevation_deg - half_gap) * kDeg, el1 = (cloud.lidar_max_elevation_deg + half_gap) * kDeg;
  for (const double s : {0.0, -d.width / 3, d.width / 3})
    for (const double z : {0.3, d.height / 2, d.height - 0.3}) {
      const Eigen::Vector3d p = d.opening_center + d.wall_axis * s + Eigen::Vector3d::UnitZ() * z;
      const Eigen::Vector3d ps = W2S * p;
      const double dist = ps.norm(), el = std::atan2(ps.z(), ps.head<2>().norm());
      if (dist < 1e-6 || dist > cloud.lidar_max_range || el < el0 || el > el1) continue;
      const RayHit hit = castRay(scene, origin, (p - origin) / dist, dist - 0.01);
      if (!hit.hit || hit.surface == Surface::Leaf || hit.surface == Surface::Handle || hit.surface == Surface::Casing)
        return true;
    }
  return false;
}

}  // namespace sim
}  // namespace dsr
