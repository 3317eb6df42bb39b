#include "door_state_recognition/sim/sensors.hpp"

#include "depth_models.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "ray_random.hpp"

namespace dsr {
namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A box prepared for ray tests: world-to-local rotation and centre.
struct PreparedBox {
  Eigen::Matrix3d Rt;
  Eigen::Vector3d c, half;
  Surface surface;
  int owner;
};

std::vector<PreparedBox> prepare(const Scene& scene) {
  std::vector<PreparedBox> out;
  out.reserve(scene.boxes.size());
  for (const Box& b : scene.boxes) out.push_back({b.pose.linear().transpose(), b.pose.translation(), b.half, b.surface, b.owner});
  return out;
}

RayHit cast(const std::vector<PreparedBox>& boxes, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_t) {
  RayHit best;
  best.t = max_t;
  for (const PreparedBox& b : boxes) {
    const Eigen::Vector3d ol = b.Rt * (o - b.c), dl = b.Rt * d;
    double t0 = 1e-9, t1 = best.t;
    int axis = -1;
    double sign = 0;
    bool miss = false;
    for (int i = 0; i < 3 && !miss; ++i) {
      if (std::abs(dl[i]) < 1e-12) {
        miss = std::abs(ol[i]) > b.half[i];
        continue;
      }
      const double inv = 1.0 / dl[i];
      double ta = (-b.half[i] - ol[i]) * inv, tb = (b.half[i] - ol[i]) * inv;
      double s = -1.0;  // entering through the -half face
      if (ta > tb) {
        std::swap(ta, tb);
        s = 1.0;
      }
      if (ta > t0) {
        t0 = ta;
        axis = i;
        sign = s;
      }
      t1 = std::min(t1, tb);
      miss = t0 > t1;
    }
    if (miss || axis < 0 || t0 >= best.t) continue;  // axis < 0: origin inside the box
    best.hit = true;
    best.t = t0;
    best.surface = b.surface;
    best.owner = b.owner;
    best.normal = b.Rt.row(axis).transpose() * sign;
  }
  return best;
}

void requireOption(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("sensor: " + what);
}

Eigen::Vector3d freePoint(const Scene& scene, RayRandom& rnd, double margin, double z0, double z1) {
  const RoomSpec& r = scene.spec;
  for (int attempt = 0; attempt < 5000; ++attempt) {
    const Eigen::Vector3d q((rnd.uniform() - 0.5) * (r.width - 2 * margin), (rnd.uniform() - 0.5) * (r.depth - 2 * margin),
                            z0 + (z1 - z0) * rnd.uniform());
    const Eigen::Vector3d p = scene.room_to_world * q;
    if (scene.isFree(p, margin)) return p;
  }
  throw std::invalid_argument("sensor: no free position for the sensor in this room");
}

// A scan position in the room behind a door, as a surveyor sets one up after
// walking through: 1.2-2.0 m beyond the wall, within a third of the doorway's
// width of its axis, clear of every box and of the leaf's swing.
Eigen::Vector3d beyondDoor(const Scene& scene, const DoorTruth& door, RayRandom& rnd) {
  const WallTruth& wall = scene.walls[door.wall];
  const double t = scene.spec.wall_thickness;
  for (int attempt = 0; attempt < 5000; ++attempt) {
    const double depth = 1.2 + 0.8 * rnd.uniform(), side = (rnd.uniform() - 0.5) * 2.0 / 3.0 * door.width;
    const double z = 1.2 + 0.5 * rnd.uniform();
    const Eigen::Vector3d p = door.opening_center - wall.normal * (t / 2 + depth) + wall.axis * side + Eigen::Vector3d::UnitZ() * z;
    bool free = true;
    for (const Box& b : scene.boxes) free = free && !b.contains(p, 0.3);
    const Eigen::Vector3d h = p - door.hinge;
    if (!door.swing_into_room && Eigen::Vector2d(h.x(), h.y()).norm() < door.width + 0.3) free = false;
    if (free) return p;
  }
  throw std::invalid_argument("sensor: no free position beyond a door");
}

}  // namespace

RayHit castRay(const Scene& scene, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_t) {
  return cast(prepare(scene), origin, dir, max_t);
}

SimulatedCloud scanTls(const Scene& scene, const TlsOptions& o) {
  requireOption(o.points >= 100 && o.points <= 100000000, "TLS points must lie in [100, 1e8]");
  requireOption(o.viewpoints >= 1 && o.viewpoints <= 64, "TLS viewpoints must lie in [1, 64]");
  requireOption(o.range_sigma >= 0 && o.range_sigma < 1, "range noise must lie in [0, 1) m");
  requireOption(o.dropout >= 0 && o.dropout < 1, "dropout must lie in [0, 1)");
  requireOption(o.min_elevation_deg > -90 && o.min_elevation_deg < 80, "min elevation must lie in (-90, 80) deg");

  SimulatedCloud out;
  out.sensor = "tls";
  out.frame_id = "tls_scanner";
  RayRandom placement(o.seed, 0xF00D, 0);
  for (int v = 0; v < o.viewpoints; ++v)
    out.viewpoints_world.push_back(v == 0 && scene.spec.scanner ? Eigen::Vector3d(scene.room_to_world * *scene.spec.scanner)
                                                                 : freePoint(scene, placement, 0.6, 1.2, 1.7));
  // The scanner's frame: at the first viewpoint, z up, yawed arbitrarily.
  out.sensor_to_world = Eigen::Translation3d(out.viewpoints_world[0]) *
                        Eigen::AngleAxisd(2 * kPi * placement.uniform(), Eigen::Vector3d::UnitZ());
  const Eigen::Isometry3d world_to_sensor = out.sensor_to_world.inverse();
  if (o.beyond_doors) {
    RayRandom beyond(o.seed, 0xD00B, 0);  // its own stream: the positions inside stay as without it
    for (const DoorTruth& d : scene.doors) out.viewpoints_world.push_back(beyondDoor(scene, d, beyond));
  }
  const int n_views = static_cast<int>(out.viewpoints_world.size());

  const std::vector<PreparedBox> boxes = prepare(scene);
  const double el0 = o.min_elevation_deg * kPi / 180, el1 = 0.5 * kPi;
  const double per_view = static_cast<double>(o.points) / n_views;
  const int n_el = std::max(2, static_cast<int>(std::lround(std::sqrt(per_view * (el1 - el0) / (2 * kPi)))));
  const int n_az = std::max(4, static_cast<int>(std::lround(per_view / n_el)));
  const std::size_t per = static_cast<std::size_t>(n_el) * n_az;

  std::vector<pcl::PointXYZL> slots(per * n_views);
  std::vector<char> valid(slots.size(), 0);
#pragma omp parallel for schedule(dynamic, 4096)
  for (long long idx = 0; idx < static_cast<long long>(slots.size()); ++idx) {
    const std::size_t v = idx / per, k = idx % per;
    const int ie = static_cast<int>(k / n_az), ia = static_cast<int>(k % n_az);
    const double el = el0 + (el1 - el0) * (ie + 0.5) / n_el, az = 2 * kPi * (ia + 0.5) / n_az;
    const Eigen::Vector3d dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const Eigen::Vector3d& origin = out.viewpoints_world[v];
    const RayHit hit = cast(boxes, origin, dir, o.max_range);
    if (!hit.hit) continue;
    RayRandom rnd(o.seed, 1 + v, k);
    if (o.dropout > 0 && rnd.uniform() < o.dropout) continue;
    const double range = hit.t + (o.range_sigma > 0 ? o.range_sigma * rnd.gaussian() : 0.0);
    const Eigen::Vector3d p = world_to_sensor * (origin + range * dir);
    pcl::PointXYZL& q = slots[idx];
    q.x = static_cast<float>(p.x());
    q.y = static_cast<float>(p.y());
    q.z = static_cast<float>(p.z());
    q.label = static_cast<std::uint32_t>(hit.surface);
    valid[idx] = 1;
  }
  out.cloud.reserve(slots.size());
  out.station.reserve(slots.size());
  for (std::size_t i = 0; i < slots.size(); ++i)
    if (valid[i]) {
      out.cloud.push_back(slots[i]);
      out.station.push_back(static_cast<int>(i / per));
    }
  out.cloud.is_dense = true;
  return out;
}

SimulatedCloud captureRgbd(const Scene& scene, const RgbdOptions& o) {
  requireOption(o.width >= 8 && o.width <= 4096 && o.height >= 8 && o.height <= 4096, "image size must lie in [8, 4096]");
  requireOption(o.fx > 0 && o.fy > 0, "focal lengths must be positive");
  requireOption(o.min_range > 0 && o.max_range > o.min_range, "need 0 < min range < max range");
  requireOption(o.dropout >= 0 && o.dropout < 1, "dropout must lie in [0, 1)");
  requireOption(!scene.doors.empty() || o.target_door < 0, "target door given but the scene has no door");
  requireOption(o.target_door < static_cast<int>(scene.doors.size()), "target door out of range");
  requireOption(!o.camera_to_world || o.camera_to_world->matrix().allFinite(), "camera pose must be finite");

  SimulatedCloud out;
  out.sensor = "rgbd";
  out.frame_id = "camera_depth_optical_frame";
  out.rgbd = o;
  RayRandom rnd(o.seed, 0xCAFE, 0);
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();

  requireOption(!o.camera_height || (*o.camera_height >= 0.1 && *o.camera_height <= 3.0), "camera height must lie in [0.1, 3] m");
  requireOption(!o.pitch_deg || std::abs(*o.pitch_deg) <= 60, "pitch must lie in [-60, 60] deg");
  requireOption(!o.roll_deg || std::abs(*o.roll_deg) <= 30, "roll must lie in [-30, 30] deg");
  requireOption(!o.door_distance || (*o.door_distance >= 0.5 && *o.door_distance <= 50), "door distance must lie in [0.5, 50] m");
  requireOption(o.dark_fraction >= 0 && o.dark_fraction <= 1, "dark fraction must lie in [0, 1]");

  // Place the camera in front of a door, looking at it.
  Eigen::Vector3d cam, target;
  double robot_pitch = 0, robot_roll = 0;
  if (o.camera_to_world) {  // placed by the caller
    cam = o.camera_to_world->translation();
    target = cam + o.camera_to_world->linear().col(2);
  } else if (scene.doors.empty()) {
    cam = freePoint(scene, rnd, 0.5, 0.9, 1.5);
    target = scene.walls[0].origin + up * 1.0;
  } else {
    const int di = o.target_door >= 0 ? o.target_door
                                      : static_cast<int>(rnd.uniform() * scene.doors.size()) % scene.doors.size();
    const DoorTruth& door = scene.doors[di];
    const WallTruth& wall = scene.walls[door.wall];
    const Eigen::Vector3d face_center = door.opening_center + wall.normal * (scene.spec.wall_thickness / 2);
    const double room_depth = (door.wall % 2 == 0) ? scene.spec.depth : scene.spec.width;
    bool placed = false;
    for (int attempt = 0; attempt < 2000 && !placed; ++attempt) {
      double dist = 1.6 + (std::min(3.5, room_depth - 0.4) - 1.6) * rnd.uniform();
      const double lateral = (rnd.uniform() - 0.5) * 1.6;
      double height = 0.9 + 0.6 * rnd.uniform();
      if (o.robot_camera) {  // its own stream: the draws above stay as they were
        RayRandom pose(o.seed, 0x20B07, attempt);
        height = 0.3 + 1.3 * pose.uniform();
        dist = 1.0 + (std::max(1.0, std::min(6.0, room_depth - 0.4)) - 1.0) * pose.uniform();
        robot_pitch = (-20.0 + 30.0 * pose.uniform()) * kPi / 180;
        robot_roll = (pose.uniform() - 0.5) * 10.0 * kPi / 180;
      }
      if (o.door_distance) dist = *o.door_distance;
      if (o.camera_height) height = *o.camera_height;
      cam = face_center + wall.normal * dist + wall.axis * lateral + up * (scene.floor_z + height);
      placed = scene.isFree(cam, std::min(0.3, height - 0.02));
    }
    if (!placed) throw std::invalid_argument("sensor: no free camera position in front of door " + std::to_string(di));
    target = face_center + wall.axis * ((rnd.uniform() - 0.5) * 0.6) + up * (0.8 + 0.5 * rnd.uniform());
  }
  Eigen::Vector3d f = (target - cam).normalized();
  const std::optional<double> pitch_given =
      o.pitch_deg ? std::optional<double>(*o.pitch_deg * kPi / 180) : o.robot_camera ? std::optional<double>(robot_pitch) : std::nullopt;
  if (pitch_given && !o.camera_to_world) {
    const Eigen::Vector3d flat = Eigen::Vector3d(f.x(), f.y(), 0).normalized();
    f = (flat * std::cos(*pitch_given) + up * std::sin(*pitch_given)).normalized();
  } else if (o.avoid_ceiling && !o.camera_to_world) {
    // Lower the pitch until the top image row meets the far wall below the ceiling.
    const double horiz = std::hypot(f.x(), f.y());
    double pitch = std::atan2(f.z(), horiz);
    const double half_v = std::atan((o.height / 2.0) / o.fy), half_h = std::atan((o.width / 2.0) / o.fx);
    const double reach = (target - cam).head<2>().norm() / std::cos(half_h) + 0.3;
    const double max_pitch = std::atan2(scene.ceiling_z - 0.15 - cam.z(), reach) - half_v;
    if (pitch > max_pitch) {
      pitch = max_pitch;
      const Eigen::Vector3d flat = Eigen::Vector3d(f.x(), f.y(), 0).normalized();
      f = (flat * std::cos(pitch) + up * std::sin(pitch)).normalized();
    }
  }
  double roll = (rnd.uniform() - 0.5) * 6.0 * kPi / 180;
  if (o.robot_camera) roll = robot_roll;
  if (o.roll_deg) roll = *o.roll_deg * kPi / 180;
  Eigen::Vector3d x = f.cross(up).normalized(), y = f.cross(x);
  const Eigen::AngleAxisd R_roll(roll, f);
  x = R_roll * x;
  y = R_roll * y;
  out.sensor_to_world.linear().col(0) = x;
  out.sensor_to_world.linear().col(1) = y;
  out.sensor_to_world.linear().col(2) = f;
  out.sensor_to_world.translation() = cam;
  if (o.camera_to_world) out.sensor_to_world = *o.camera_to_world;
  out.viewpoints_world.push_back(cam);

  const std::vector<PreparedBox> boxes = prepare(scene);
  if (o.depth_model != DepthModel::Default) {
    detail::renderDepthModel(scene, o, out.sensor_to_world,
                             [&boxes](const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_t) {
                               return cast(boxes, origin, dir, max_t);
                             },
                             out.cloud);
    return out;
  }
  out.cloud.width = o.width;
  out.cloud.height = o.height;
  out.cloud.is_dense = false;
  out.cloud.points.resize(static_cast<std::size_t>(o.width) * o.height);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double cos_max = std::cos(o.max_incidence_deg * kPi / 180);
  const Eigen::Matrix3d R = out.sensor_to_world.linear();
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < o.height; ++v) {
    for (int u = 0; u < o.width; ++u) {
      const Eigen::Vector3d ray_cam((u - o.cx) / o.fx, (v - o.cy) / o.fy, 1.0);
      const Eigen::Vector3d dir = (R * ray_cam).normalized();
      pcl::PointXYZL& q = out.cloud.points[static_cast<std::size_t>(v) * o.width + u];
      q.x = q.y = q.z = static_cast<float>(nan);
      q.label = 0;
      const double max_t = o.max_range * ray_cam.norm();
      const RayHit hit = cast(boxes, cam, dir, max_t);
      if (!hit.hit) continue;
      RayRandom r(o.seed, 7, static_cast<std::uint64_t>(v) * o.width + u);
      const double z = hit.t / ray_cam.norm();
      if (z < o.min_range || std::abs(hit.normal.dot(dir)) < cos_max) continue;
      if (o.dropout > 0 && r.uniform() < o.dropout) continue;
      const double sigma = 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4);
      const double zn = o.noise ? z + sigma * r.gaussian() : z;
      q.x = static_cast<float>(ray_cam.x() * zn);
      q.y = static_cast<float>(ray_cam.y() * zn);
      q.z = static_cast<float>(zn);
      q.label = static_cast<std::uint32_t>(hit.surface);
    }
  }
  return out;
}

}  // namespace sim
}  // namespace dsr
