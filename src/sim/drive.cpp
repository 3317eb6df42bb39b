#include "door_state_recognition/sim/drive.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <stdexcept>

#include "door_state_recognition/sim/ground_truth.hpp"
#include "ray_random.hpp"

namespace dsr {
namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
// A leaf cell a terrestrial scanner sees at a steeper incidence gets a few
// points at most (leafInViewShare).
constexpr double kTlsMaxIncidenceDeg = 80.0;

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("drive: " + what);
}

double wrapAngle(double a) { return std::atan2(std::sin(a), std::cos(a)); }

// Occupancy grid of the floor in the room frame: a cell is free when the
// robot's footprint (a disc of robot_radius, Chebyshev-expanded) meets no box
// of any scene of the drive at the heights of its body, and it lies inside
// the room, or inside the room behind the wall of `through_wall` (-1: none).
struct Grid {
  double x0 = 0, y0 = 0, res = 0.05;
  int nx = 0, ny = 0;
  std::vector<char> free;
  bool ok(int i, int j) const { return i >= 0 && j >= 0 && i < nx && j < ny && free[static_cast<std::size_t>(j) * nx + i]; }
  Eigen::Vector2d centre(int i, int j) const { return {x0 + (i + 0.5) * res, y0 + (j + 0.5) * res}; }
  std::pair<int, int> cell(const Eigen::Vector2d& q) const {
    return {static_cast<int>(std::floor((q.x() - x0) / res)), static_cast<int>(std::floor((q.y() - y0) / res))};
  }
};

struct PreparedBox {
  Eigen::Isometry3d inv;
  Eigen::Vector3d half;
};

Grid buildGrid(const std::vector<Scene>& scenes, double radius, int through_wall, double sensor_top) {
  const Scene& s = scenes.front();
  const RoomSpec& r = s.spec;
  const double ext = r.wall_thickness + r.adjacent_depth;
  Grid g;
  g.x0 = -r.width / 2 - ext;
  g.y0 = -r.depth / 2 - ext;
  g.nx = static_cast<int>(std::ceil((r.width + 2 * ext) / g.res));
  g.ny = static_cast<int>(std::ceil((r.depth + 2 * ext) / g.res));
  g.free.assign(static_cast<std::size_t>(g.nx) * g.ny, 0);
  std::vector<PreparedBox> boxes;
  for (const Scene& sc : scenes)
    for (const Box& b : sc.boxes)
      if (b.surface != Surface::Floor && b.surface != Surface::Ceiling) boxes.push_back({b.pose.inverse(), b.half});
  const std::vector<double> heights = {0.1, 0.45, 0.8, std::min(sensor_top, s.ceiling_z - 0.05)};
  const double t = r.wall_thickness;
#pragma omp parallel for schedule(dynamic, 4)
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) {
      const Eigen::Vector2d q = g.centre(i, j);
      bool inside = std::abs(q.x()) <= r.width / 2 && std::abs(q.y()) <= r.depth / 2;
      if (!inside && through_wall >= 0) {
        // Wall frame: s along the wall's axis, d along its inward normal.
        const WallTruth& w = s.walls[through_wall];
        const Eigen::Vector3d qw = s.room_to_world * Eigen::Vector3d(q.x(), q.y(), 0);
        const double sa = (qw - w.origin).dot(w.axis), d = (qw - w.origin).dot(w.normal);
        inside = std::abs(sa) <= w.length / 2 && d <= 0 && d >= -t - r.adjacent_depth;
      }
      if (!inside) continue;
      bool clear = true;
      for (const double z : heights) {
        const Eigen::Vector3d p = s.room_to_world * Eigen::Vector3d(q.x(), q.y(), z);
        for (const PreparedBox& b : boxes)
          if (((b.inv * p).cwiseAbs() - b.half).maxCoeff() <= radius) {
            clear = false;
            break;
          }
        if (!clear) break;
      }
      g.free[static_cast<std::size_t>(j) * g.nx + i] = clear;
    }
  return g;
}

// The free cell nearest to q (room frame) within `reach`, or nothing.
std::optional<std::pair<int, int>> nearestFree(const Grid& g, const Eigen::Vector2d& q, double reach,
                                                const std::function<bool(const Eigen::Vector2d&)>& accept) {
  const auto [ci, cj] = g.cell(q);
  const int k = static_cast<int>(std::ceil(reach / g.res));
  std::optional<std::pair<int, int>> best;
  double best_d = std::numeric_limits<double>::infinity();
  for (int j = cj - k; j <= cj + k; ++j)
    for (int i = ci - k; i <= ci + k; ++i) {
      if (!g.ok(i, j)) continue;
      const Eigen::Vector2d c = g.centre(i, j);
      const double d = (c - q).norm();
      if (d < best_d && d <= reach && accept(c)) {
        best_d = d;
        best = std::make_pair(i, j);
      }
    }
  return best;
}

// A* on the 8-connected grid; empty when unreachable.
std::vector<std::pair<int, int>> aStar(const Grid& g, std::pair<int, int> a, std::pair<int, int> b) {
  const std::size_t n = g.free.size();
  auto id = [&](int i, int j) { return static_cast<std::size_t>(j) * g.nx + i; };
  std::vector<double> cost(n, std::numeric_limits<double>::infinity());
  std::vector<std::size_t> from(n, n);
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  auto h = [&](int i, int j) {
    const double dx = std::abs(i - b.first), dy = std::abs(j - b.second);
    return std::max(dx, dy) + (std::sqrt(2.0) - 1) * std::min(dx, dy);
  };
  cost[id(a.first, a.second)] = 0;
  open.push({h(a.first, a.second), id(a.first, a.second)});
  const std::size_t goal = id(b.first, b.second);
  while (!open.empty()) {
    const auto [f, u] = open.top();
    open.pop();
    if (u == goal) break;
    const int ui = static_cast<int>(u % g.nx), uj = static_cast<int>(u / g.nx);
    if (f - h(ui, uj) > cost[u] + 1e-9) continue;
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        if (!di && !dj) continue;
        const int vi = ui + di, vj = uj + dj;
        if (!g.ok(vi, vj) || (di && dj && (!g.ok(ui + di, uj) || !g.ok(ui, uj + dj)))) continue;
        const double c = cost[u] + ((di && dj) ? std::sqrt(2.0) : 1.0);
        const std::size_t v = id(vi, vj);
        if (c < cost[v]) {
          cost[v] = c;
          from[v] = u;
          open.push({c + h(vi, vj), v});
        }
      }
  }
  std::vector<std::pair<int, int>> out;
  if (!std::isfinite(cost[goal])) return out;
  for (std::size_t v = goal; v != n; v = from[v]) out.push_back({static_cast<int>(v % g.nx), static_cast<int>(v / g.nx)});
  std::reverse(out.begin(), out.end());
  return out;
}

// Whether the straight segment between two cell centres stays on free cells.
bool clearLine(const Grid& g, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() / (0.25 * g.res))));
  for (int k = 0; k <= steps; ++k) {
    const auto [i, j] = g.cell(a + (b - a) * (static_cast<double>(k) / steps));
    if (!g.ok(i, j)) return false;
  }
  return true;
}

// A grid path shortened to the vertices that line of sight needs.
std::vector<Eigen::Vector2d> shortcut(const Grid& g, const std::vector<std::pair<int, int>>& cells) {
  std::vector<Eigen::Vector2d> out;
  if (cells.empty()) return out;
  std::size_t i = 0;
  out.push_back(g.centre(cells[0].first, cells[0].second));
  while (i + 1 < cells.size()) {
    std::size_t j = cells.size() - 1;
    while (j > i + 1 && !clearLine(g, g.centre(cells[i].first, cells[i].second), g.centre(cells[j].first, cells[j].second))) --j;
    out.push_back(g.centre(cells[j].first, cells[j].second));
    i = j;
  }
  return out;
}

// Camera-frame check of one point: in front, within range, inside the image.
bool inImage(const RgbdOptions& o, const Eigen::Vector3d& p) {
  if (p.z() < o.min_range || p.z() > o.max_range) return false;
  const double u = o.fx * p.x() / p.z() + o.cx, v = o.fy * p.y() / p.z() + o.cy;
  return u >= 0 && u < o.width && v >= 0 && v < o.height;
}

}  // namespace

int DrivePlan::sceneIndexAt(double t) const {
  int k = 0;
  for (std::size_t i = 1; i < scene_from_t.size(); ++i)
    if (t >= scene_from_t[i]) k = static_cast<int>(i);
  return k;
}

Eigen::Isometry3d DrivePlan::baseToMap(double t) const {
  const Scene& s = scenes.front();
  auto pose = [&](const Eigen::Vector2d& xy, double yaw) {
    const Eigen::Vector3d p = s.room_to_world * Eigen::Vector3d(xy.x(), xy.y(), 0.0);
    return Eigen::Isometry3d(Eigen::Translation3d(p.x(), p.y(), s.floor_z) *
                             Eigen::AngleAxisd(yaw + std::atan2(s.room_to_world.linear()(1, 0), s.room_to_world.linear()(0, 0)),
                                               Eigen::Vector3d::UnitZ()));
  };
  t = std::clamp(t, 0.0, options.seconds);
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Eigen::Vector2d a = path[i].head<2>(), b = path[i + 1].head<2>();
    if (t < arrive_t[i]) break;
    if (t < vertex_t[i]) {  // turning in place at path[i] from the previous heading to this segment's
      const double prev = i == 0 ? path[i].z() : path[i - 1].z();
      const double d = wrapAngle(path[i].z() - prev), f = (t - arrive_t[i]) / std::max(1e-9, vertex_t[i] - arrive_t[i]);
      return pose(a, prev + d * f);
    }
    if (t <= arrive_t[i + 1]) {
      const double f = (t - vertex_t[i]) / std::max(1e-9, arrive_t[i + 1] - vertex_t[i]);
      return pose(a + (b - a) * f, path[i].z());
    }
  }
  const std::size_t last = path.size() - 1;
  return pose(path[last].head<2>(), path[last > 0 ? last - 1 : 0].z());
}

DrivePlan planDrive(const RoomSpec& spec, const DriveOptions& options) {
  DriveOptions o = options;
  const int beams = lidarBeamsOf(o.sensor);
  require(beams > 0 || o.sensor == "rgbd", "sensor must be lidar16, lidar32, lidar64, lidar128 or rgbd, got '" + o.sensor + "'");
  if (o.rate_hz == 0) o.rate_hz = beams > 0 ? 10.0 : 15.0;
  require(o.rate_hz > 0 && o.rate_hz <= 100, "rate must lie in (0, 100] Hz");
  require(o.seconds >= 0 && o.seconds <= 3600, "seconds must lie in [0, 3600]");
  require(o.speed > 0.05 && o.speed <= 3, "speed must lie in (0.05, 3] m/s");
  require(o.turn_rate_deg_s >= 5 && o.turn_rate_deg_s <= 360, "turn rate must lie in [5, 360] deg/s");
  require(o.door_distance >= 1 && o.door_distance <= 3, "door distance must lie in [1, 3] m");
  require(o.robot_radius >= 0.1 && o.robot_radius <= 0.6, "robot radius must lie in [0.1, 0.6] m");
  require(!o.camera_pitch_deg || (*o.camera_pitch_deg >= -20 && *o.camera_pitch_deg <= 10), "camera pitch must lie in [-20, 10] deg");
  if (o.mount_height) {
    if (beams > 0) require(*o.mount_height >= 0.4 && *o.mount_height <= 1.2, "LiDAR height must lie in [0.4, 1.2] m");
    else require(*o.mount_height >= 0.3 && *o.mount_height <= 1.5, "camera height must lie in [0.3, 1.5] m");
  }

  DrivePlan plan;
  RayRandom rnd(o.seed, 0xD71E, 0);
  plan.scenes.push_back(buildScene(spec));
  plan.scene_from_t.push_back(0.0);
  plan.changes = o.changes;
  std::stable_sort(plan.changes.begin(), plan.changes.end(), [](const DoorChange& a, const DoorChange& b) { return a.t < b.t; });
  RoomSpec changed = spec;
  for (const DoorChange& c : plan.changes) {
    require(c.door >= 0 && c.door < static_cast<int>(spec.doors.size()),
            "change names door " + std::to_string(c.door) + " but the room has " + std::to_string(spec.doors.size()));
    require(c.angle_deg >= 0 && c.angle_deg <= 180, "a changed angle must lie in [0, 180] deg");
    require(c.t >= 0 && std::isfinite(c.t), "a change's time must be >= 0 s");
    changed.doors[c.door].angle_deg = c.angle_deg;
    plan.scenes.push_back(buildScene(changed));
    plan.scene_from_t.push_back(c.t);
  }
  const Scene& s0 = plan.scenes.front();

  // The sensor on the robot.
  const double height = o.mount_height ? *o.mount_height : (beams > 0 ? 0.4 + 0.8 * rnd.uniform() : 0.3 + 1.2 * rnd.uniform());
  const double pitch = o.camera_pitch_deg ? *o.camera_pitch_deg : -20 + 30 * rnd.uniform();
  if (beams > 0) {
    plan.sensor_frame = "lidar";
    plan.sensor_to_base = Eigen::Translation3d(0, 0, height);
    if (!o.lidar) o.lidar = LidarOptions::preset(beams);
    require(o.lidar->beams == beams, "LiDAR options of " + std::to_string(o.lidar->beams) + " beams for sensor " + o.sensor);
  } else {
    plan.sensor_frame = "camera_depth_optical_frame";
    const double p = pitch * kDeg;
    Eigen::Matrix3d R;
    R.col(2) = Eigen::Vector3d(std::cos(p), 0, std::sin(p));  // optical axis
    R.col(0) = Eigen::Vector3d(0, -1, 0);                      // image right
    R.col(1) = R.col(2).cross(R.col(0));                       // image down
    plan.sensor_to_base.linear() = R;
    plan.sensor_to_base.translation() = Eigen::Vector3d(0.1, 0, height);
    if (!o.rgbd) {
      RgbdOptions r;
      r.resize(320, 240);
      o.rgbd = r;
    }
  }
  o.mount_height = height;
  if (beams == 0) o.camera_pitch_deg = pitch;

  // Where each door is passed, and the doorway driven through at the end.
  const RoomSpec& r = s0.spec;
  const Eigen::Isometry3d world_to_room = s0.room_to_world.inverse();
  auto toRoom = [&](const Eigen::Vector3d& w) -> Eigen::Vector2d { return (world_to_room * w).head<2>(); };
  const double t_wall = r.wall_thickness;
  const int n_doors = static_cast<int>(s0.doors.size());
  auto passable = [&](int k) {
    for (const Scene& sc : plan.scenes)
      if (sc.doors[k].angle_deg < 75) return false;
    return true;
  };
  std::vector<int> order;
  for (int k = 0; k < n_doors; ++k) order.push_back(k);
  // Candidates for the passage: open in every scene, tried in a seeded order.
  std::vector<int> candidates;
  if (o.through_door)
    for (int k = 0; k < n_doors; ++k)
      if (passable(k)) candidates.push_back(k);
  for (std::size_t i = candidates.size(); i > 1; --i) std::swap(candidates[i - 1], candidates[static_cast<std::size_t>(rnd.uniform() * i) % i]);

  const double sensor_top = height + 0.15;
  Grid grid;
  std::vector<std::optional<std::pair<int, int>>> front(n_doors);
  std::optional<std::pair<int, int>> beyond;
  auto frontOf = [&](const Grid& g, int k) {
    const DoorTruth& d = s0.doors[k];
    const Eigen::Vector3d n = s0.walls[d.wall].normal;
    const Eigen::Vector2d want = toRoom(d.opening_center + n * (t_wall / 2 + o.door_distance));
    const Eigen::Vector2d c = toRoom(d.opening_center);
    return nearestFree(g, want, 1.5, [&](const Eigen::Vector2d& q) {
      const double dist = (q - c).norm();
      return std::abs(q.x()) <= r.width / 2 && std::abs(q.y()) <= r.depth / 2 && dist >= 1.0 && dist <= 3.0;
    });
  };
  for (std::size_t ci = 0; ci <= candidates.size(); ++ci) {
    const int k = ci < candidates.size() ? candidates[ci] : -1;
    grid = buildGrid(plan.scenes, o.robot_radius, k >= 0 ? s0.doors[k].wall : -1, sensor_top);
    if (k < 0) break;
    const DoorTruth& d = s0.doors[k];
    const Eigen::Vector2d want = toRoom(d.opening_center - s0.walls[d.wall].normal * (t_wall / 2 + 1.8));
    const Eigen::Vector2d c = toRoom(d.opening_center);
    const WallTruth& w = s0.walls[d.wall];
    beyond = nearestFree(grid, want, 0.8, [&](const Eigen::Vector2d& q) {
      const Eigen::Vector3d qw = s0.room_to_world * Eigen::Vector3d(q.x(), q.y(), 0);
      return (qw - w.origin).dot(w.normal) < -t_wall - 0.5 && (q - c).norm() <= 3.0;
    });
    const auto f = frontOf(grid, k);
    if (beyond && f && !aStar(grid, *f, *beyond).empty()) {
      plan.through_door = k;
      break;
    }
    beyond.reset();
  }
  for (int k = 0; k < n_doors; ++k) front[k] = frontOf(grid, k);

  // Start: the free cell nearest the room's middle; doors in order around it,
  // the one driven through last.
  const auto start = nearestFree(grid, Eigen::Vector2d::Zero(), std::max(r.width, r.depth),
                                 [&](const Eigen::Vector2d& q) { return std::abs(q.x()) <= r.width / 2 && std::abs(q.y()) <= r.depth / 2; });
  require(start.has_value(), "no free floor in the room for the robot");
  auto bearing = [&](int k) {
    const Eigen::Vector2d c = toRoom(s0.doors[k].opening_center);
    return std::atan2(c.y(), c.x());
  };
  const double first = plan.through_door >= 0 ? bearing(plan.through_door) : -kPi;
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    auto key = [&](int k) {
      double v = bearing(k) - first;
      while (v <= 1e-9) v += 2 * kPi;
      return v;
    };
    return key(a) < key(b);
  });
  if (plan.through_door >= 0) {  // it is last: its bearing minus itself wrapped to 2 pi
    order.erase(std::find(order.begin(), order.end(), plan.through_door));
    order.push_back(plan.through_door);
  }
  std::vector<std::pair<int, int>> stops = {*start};
  plan.door_waypoints.assign(n_doors, Eigen::Vector3d(0, 0, -1));
  for (int k : order) {
    if (!front[k] || aStar(grid, stops.back(), *front[k]).empty()) continue;  // unreachable: left out
    stops.push_back(*front[k]);
    const Eigen::Vector2d q = grid.centre(front[k]->first, front[k]->second);
    plan.door_waypoints[k] = s0.room_to_world * Eigen::Vector3d(q.x(), q.y(), 0);
  }
  if (plan.through_door >= 0) stops.push_back(*beyond);

  std::vector<Eigen::Vector2d> poly;
  for (std::size_t i = 0; i + 1 < stops.size(); ++i) {
    const std::vector<Eigen::Vector2d> leg = shortcut(grid, aStar(grid, stops[i], stops[i + 1]));
    for (const Eigen::Vector2d& q : leg)
      if (poly.empty() || (q - poly.back()).norm() > 1e-6) poly.push_back(q);
  }
  if (poly.empty()) poly.push_back(grid.centre(start->first, start->second));
  if (poly.size() == 1) {  // nothing to visit: turn once around on the spot's neighbour
    poly.push_back(poly[0] + Eigen::Vector2d(0.05, 0));
  }

  // Timing: straight segments at one speed, turns in place at the vertices.
  plan.path.clear();
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Eigen::Vector2d dir = i + 1 < poly.size() ? Eigen::Vector2d(poly[i + 1] - poly[i]) : Eigen::Vector2d(poly[i] - poly[i - 1]);
    plan.path.emplace_back(poly[i].x(), poly[i].y(), std::atan2(dir.y(), dir.x()));
  }
  double turn = 0, length = 0;
  for (std::size_t i = 0; i + 1 < plan.path.size(); ++i) {
    length += (poly[i + 1] - poly[i]).norm();
    if (i > 0) turn += std::abs(wrapAngle(plan.path[i].z() - plan.path[i - 1].z()));
  }
  const double w = o.turn_rate_deg_s * kDeg, turn_s = turn / w;
  if (o.seconds == 0) o.seconds = turn_s + length / o.speed;
  require(o.seconds > turn_s + 0.1 * length, "seconds must exceed " + std::to_string(turn_s + 0.1 * length) +
                                                  " for this path (its turns take " + std::to_string(turn_s) + " s)");
  plan.speed = length / (o.seconds - turn_s);
  plan.path_length = length;
  plan.arrive_t.assign(plan.path.size(), 0);
  plan.vertex_t.assign(plan.path.size(), 0);
  double t = 0;
  for (std::size_t i = 0; i < plan.path.size(); ++i) {
    plan.arrive_t[i] = t;
    if (i > 0 && i + 1 < plan.path.size()) t += std::abs(wrapAngle(plan.path[i].z() - plan.path[i - 1].z())) / w;
    plan.vertex_t[i] = t;
    if (i + 1 < plan.path.size()) t += (poly[i + 1] - poly[i]).norm() / plan.speed;
  }
  // The path's xy in map from here on (yaw stays in the room frame: baseToMap adds the room's yaw).
  for (const DoorChange& c : plan.changes) require(c.t < o.seconds, "a change at " + std::to_string(c.t) + " s lies beyond the drive");
  plan.options = o;
  plan.frame_count = static_cast<std::size_t>(std::llround(o.seconds * o.rate_hz));
  require(plan.frame_count >= 1, "the drive holds no cloud (seconds x rate < 0.5)");
  return plan;
}

DriveFrame simulateFrame(const DrivePlan& plan, std::size_t index) {
  if (index >= plan.frame_count) throw std::invalid_argument("drive: frame " + std::to_string(index) + " out of range");
  DriveFrame f;
  f.index = index;
  f.t = plan.frameTime(index);
  f.scene_index = plan.sceneIndexAt(f.t);
  f.base_to_map = plan.baseToMap(f.t);
  const Scene& scene = plan.scenes[f.scene_index];
  const std::uint64_t seed = splitmix(plan.options.seed ^ splitmix(0xD21E0000ull + index));
  const Eigen::Isometry3d sensor_to_map = f.base_to_map * plan.sensor_to_base;
  if (plan.options.lidar) {
    LidarOptions o = *plan.options.lidar;
    o.sensor_to_world = sensor_to_map;
    if (plan.options.lidar_motion) o.sweep_start_to_world = plan.baseToMap(f.t - 1.0 / plan.options.rate_hz) * plan.sensor_to_base;
    o.seed = seed;
    f.cloud = scanLidar(scene, o);
  } else {
    RgbdOptions o = *plan.options.rgbd;
    o.camera_to_world = sensor_to_map;
    o.seed = seed;
    f.cloud = captureRgbd(scene, o);
  }
  return f;
}

void simulateDrive(const DrivePlan& plan, const std::function<void(const DriveFrame&)>& each) {
  for (std::size_t i = 0; i < plan.frame_count; ++i) each(simulateFrame(plan, i));
}

std::vector<DriveFrame> simulateDrive(const RoomSpec& spec, const DriveOptions& options) {
  const DrivePlan plan = planDrive(spec, options);
  std::vector<DriveFrame> out;
  out.reserve(plan.frame_count);
  simulateDrive(plan, [&](const DriveFrame& f) { out.push_back(f); });
  return out;
}

bool sensorSeesDoor(const Scene& scene, const SimulatedCloud& cloud, int door) {
  if (cloud.lidar_beams > 0) return lidarSeesDoor(scene, cloud, door);
  if (door < 0 || door >= static_cast<int>(scene.doors.size())) return false;
  const DoorTruth& d = scene.doors[door];
  const Eigen::Isometry3d W2S = cloud.sensor_to_world.inverse();
  const Eigen::Vector3d origin = cloud.sensor_to_world.translation();
  for (const double s : {0.0, -d.width / 3, d.width / 3})
    for (const double z : {0.3, d.height / 2, d.height - 0.3}) {
      const Eigen::Vector3d p = d.opening_center + d.wall_axis * s + Eigen::Vector3d::UnitZ() * z;
      if (!inImage(cloud.rgbd, W2S * p)) continue;
      const double dist = (p - origin).norm();
      const RayHit hit = castRay(scene, origin, (p - origin) / dist, dist - 0.01);
      if (!hit.hit || hit.surface == Surface::Leaf || hit.surface == Surface::Handle || hit.surface == Surface::Casing)
        return true;
    }
  return false;
}

double leafInViewShare(const Scene& scene, const SimulatedCloud& cloud, int door) {
  const bool camera = cloud.sensor == "rgbd" && cloud.lidar_beams == 0, tls = cloud.sensor == "tls";
  if (!camera && !tls) return 0.0;
  if (door < 0 || door >= static_cast<int>(scene.doors.size())) return 0.0;
  const DoorTruth& d = scene.doors[door];
  const Eigen::Isometry3d W2S = cloud.sensor_to_world.inverse();
  // A camera's one origin; a terrestrial scanner's every station (a merged
  // or mesh-like export keeps them in viewpoints_world).
  std::vector<Eigen::Vector3d> origins = tls ? cloud.viewpoints_world : std::vector<Eigen::Vector3d>{};
  if (origins.empty()) origins.push_back(cloud.sensor_to_world.translation());
  const auto& c = d.leaf_corners;  // mid-thickness: hinge-bottom, latch-bottom, latch-top, hinge-top
  const Eigen::Vector3d across = c[1] - c[0], up = c[3] - c[0];
  const Eigen::Vector3d n = across.cross(up).normalized();
  const double cos_max = std::cos((camera ? cloud.rgbd.max_incidence_deg : kTlsMaxIncidenceDeg) * kDeg);
  constexpr int kAcross = 8, kUp = 16;  // cells of about 11 x 13 cm on a 0.9 x 2 m leaf
  int seen = 0;
  for (int i = 0; i < kAcross; ++i)
    for (int j = 0; j < kUp; ++j) {
      const Eigen::Vector3d mid = c[0] + across * ((i + 0.5) / kAcross) + up * ((j + 0.5) / kUp);
      for (const Eigen::Vector3d& origin : origins) {
        // The point on the face turned to the sensor.
        const Eigen::Vector3d p = mid + n * (n.dot(origin - mid) >= 0 ? 0.5 : -0.5) * scene.spec.leaf_thickness;
        if (camera && !inImage(cloud.rgbd, W2S * p)) continue;
        const double dist = (p - origin).norm();
        const Eigen::Vector3d dir = (p - origin) / dist;
        if (std::abs(n.dot(dir)) < cos_max) continue;  // too grazing: the sensor returns (next to) nothing there
        const RayHit hit = castRay(scene, origin, dir, dist + 0.01);
        if (hit.hit && (hit.surface == Surface::Leaf || hit.surface == Surface::Handle) && hit.owner == door) {
          ++seen;
          break;
        }
      }
    }
  return static_cast<double>(seen) / (kAcross * kUp);
}

nlohmann::json driveTruthJson(const DrivePlan& plan, double start_stamp) {
  const DriveOptions& o = plan.options;
  auto vec = [](const Eigen::Vector3d& v) { return nlohmann::json{v.x(), v.y(), v.z()}; };
  // A cloud without points at the map's origin: the final scene's truth in map.
  SimulatedCloud in_map;
  in_map.sensor = o.sensor;
  in_map.frame_id = plan.map_frame;
  nlohmann::json j = groundTruthJson(plan.scenes.back(), in_map);
  j.erase("ceiling_in_view");
  j.erase("sensor_origins");
  for (auto& d : j["doors"]) d.erase("leaf_in_view");  // a camera's, per frame
  const int n = static_cast<int>(plan.scenes.front().doors.size());
  std::vector<int> seen(n, 0);
  std::vector<double> first(n, -1), last(n, -1), min_dist(n, std::numeric_limits<double>::infinity());
  nlohmann::json path = nlohmann::json::array();
  std::vector<std::vector<int>> in_view_of(plan.frame_count);
  for (std::size_t i = 0; i < plan.frame_count; ++i) {
    const double t = plan.frameTime(i);
    const Eigen::Isometry3d base = plan.baseToMap(t);
    const Scene& scene = plan.scenes[plan.sceneIndexAt(t)];
    SimulatedCloud pose;  // sensor fields and pose only
    pose.sensor_to_world = base * plan.sensor_to_base;
    if (o.lidar) {
      pose.lidar_beams = o.lidar->beams;
      pose.lidar_min_elevation_deg = o.lidar->min_elevation_deg;
      pose.lidar_max_elevation_deg = o.lidar->max_elevation_deg;
      pose.lidar_max_range = o.lidar->max_range;
    } else {
      pose.rgbd = *o.rgbd;
    }
    nlohmann::json doors = nlohmann::json::array();
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d c = scene.doors[k].opening_center, p = pose.sensor_to_world.translation();
      min_dist[k] = std::min(min_dist[k], std::hypot(c.x() - p.x(), c.y() - p.y()));
      if (!sensorSeesDoor(scene, pose, k)) continue;
      doors.push_back(k);
      in_view_of[i].push_back(k);
      ++seen[k];
      if (first[k] < 0) first[k] = t;
      last[k] = t;
    }
    const double yaw = std::atan2(base.linear()(1, 0), base.linear()(0, 0));
    path.push_back({{"i", i}, {"t", t}, {"stamp", start_stamp + t}, {"x", base.translation().x()},
                    {"y", base.translation().y()}, {"yaw", yaw}, {"doors_in_view", doors}});
  }
  for (int k = 0; k < n; ++k) {
    nlohmann::json& d = j["doors"][k];
    d["initial_opening_angle_deg"] = plan.scenes.front().doors[k].angle_deg;
    d["initial_state"] = plan.scenes.front().doors[k].state();
    d["frames_in_view"] = seen[k];
    d["first_in_view_t"] = seen[k] ? nlohmann::json(first[k]) : nlohmann::json(nullptr);
    d["last_in_view_t"] = seen[k] ? nlohmann::json(last[k]) : nlohmann::json(nullptr);
    d["min_distance_m"] = min_dist[k];
    d["passed_within_3m"] = min_dist[k] <= 3.0;
    d["in_view"] = seen[k] > 0;
  }
  nlohmann::json changes = nlohmann::json::array();
  for (std::size_t c = 0; c < plan.changes.size(); ++c) {
    const DoorChange& ch = plan.changes[c];
    const DoorTruth &before = plan.scenes[c].doors[ch.door], &after = plan.scenes[c + 1].doors[ch.door];
    nlohmann::json e = {{"door", ch.door}, {"t", ch.t}, {"stamp", start_stamp + ch.t},
                        {"from_deg", before.angle_deg}, {"to_deg", after.angle_deg},
                        {"from_state", before.state()}, {"to_state", after.state()}};
    const std::size_t after_i = static_cast<std::size_t>(std::ceil(ch.t * o.rate_hz - 1e-9));
    e["first_frame_after"] = after_i < plan.frame_count ? nlohmann::json(after_i) : nlohmann::json(nullptr);
    e["first_frame_showing"] = nullptr;
    for (std::size_t i = after_i; i < plan.frame_count; ++i)
      if (std::find(in_view_of[i].begin(), in_view_of[i].end(), ch.door) != in_view_of[i].end()) {
        e["first_frame_showing"] = i;
        break;
      }
    changes.push_back(e);
  }
  const Eigen::Quaterniond q(plan.sensor_to_base.linear());
  nlohmann::json waypoints = nlohmann::json::array();
  for (const Eigen::Vector3d& w : plan.door_waypoints) waypoints.push_back(w.z() < 0 ? nlohmann::json(nullptr) : vec(w));
  j["drive"] = {{"sensor", o.sensor},
                {"sensor_frame", plan.sensor_frame},
                {"base_frame", plan.base_frame},
                {"map_frame", plan.map_frame},
                {"frames", plan.frame_count},
                {"rate_hz", o.rate_hz},
                {"seconds", o.seconds},
                {"start_stamp", start_stamp},
                {"speed_mps", plan.speed},
                {"path_length_m", plan.path_length},
                {"mount_height_m", *o.mount_height},
                {"sensor_to_base", {{"translation", vec(plan.sensor_to_base.translation())},
                                    {"rotation_xyzw", {q.x(), q.y(), q.z(), q.w()}}}},
                {"through_door", plan.through_door},
                {"lidar_motion", o.lidar && o.lidar_motion},
                {"door_waypoints", waypoints},
                {"changes", changes},
                {"path", path}};
  if (!o.lidar) j["drive"]["camera_pitch_deg"] = *o.camera_pitch_deg;
  return j;
}

}  // namespace sim
}  // namespace dsr
