#include "door_state_recognition/tracking/drive_tracker.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_set>

namespace dsr {

void DriveTrackerOptions::validate() const {
  fusion.validate();
  if (!(max_sensor_speed >= 0) || !std::isfinite(max_sensor_speed))
    throw std::invalid_argument("max_sensor_speed must be a finite number of m/s >= 0 (0: no relocalisation check)");
  if (!(jump_slack_m >= 0) || !std::isfinite(jump_slack_m))
    throw std::invalid_argument("jump_slack_m must be a finite number of metres >= 0");
  if (confirm_clouds < 1) throw std::invalid_argument("confirm_clouds must be >= 1");
  if (!(confirm_spread_m >= 0) || !std::isfinite(confirm_spread_m))
    throw std::invalid_argument("confirm_spread_m must be a finite number of metres >= 0");
}

DriveTracker::DriveTracker(const DriveTrackerOptions& options) : options_(options), fusion_(options.fusion) {
  options_.validate();
}

PipelineResult DriveTracker::run(const Pipeline& pipeline, pcl::PointCloud<pcl::PointXYZ>& cloud,
                                 const std::optional<Eigen::Isometry3d>& sensor_to_fixed, bool with_reconstruction,
                                 bool without_viewpoint) {
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();
  if (sensor_to_fixed) {
    const Eigen::Matrix3f R = sensor_to_fixed->linear().cast<float>();
    const Eigen::Vector3f t = sensor_to_fixed->translation().cast<float>();
    for (auto& p : cloud.points) p.getVector3fMap() = R * p.getVector3fMap() + t;
    viewpoint = sensor_to_fixed->translation();
  }
  return without_viewpoint ? pipeline.runWithoutViewpoint(cloud, with_reconstruction)
                           : pipeline.run(cloud, with_reconstruction, viewpoint);
}

DriveTracker::Step DriveTracker::fuse(const PipelineResult& result, double stamp, const Parameters& params,
                                      const std::optional<Eigen::Vector3d>& sensor,
                                      const pcl::PointCloud<pcl::PointXYZ>* cloud) {
  Step s;
  if (sensor && last_sensor_ && options_.max_sensor_speed > 0 && stamp >= last_sensor_stamp_) {
    s.moved_m = (*sensor - *last_sensor_).norm();
    s.dt_s = stamp - last_sensor_stamp_;
    if (s.moved_m > options_.jump_slack_m + options_.max_sensor_speed * s.dt_s) {
      s.relocalised = true;
      fusion_.reset();
    }
  }
  if (sensor && std::isfinite(stamp)) {
    last_sensor_ = sensor;
    last_sensor_stamp_ = stamp;
  }
  FusionOptions fo = fusion_.options();
  fo.closed_below_deg = params.closed_below_deg;
  fo.open_from_deg = params.open_from_deg;
  fo.leaf_thickness = params.leaf_thickness;
  fusion_.setOptions(fo);  // the pipeline's thresholds, validated with it
  s.newest_before = fusion_.newestStamp();
  s.fusion = fusion_.update(result.doors, stamp, result.up);
  confirm(s, sensor);
  if (options_.disprove && cloud && sensor && s.fusion.outcome == DoorFusion::Outcome::Fused)
    s.disproved = disprove(*cloud, *sensor);
  return s;
}

void DriveTracker::confirm(const Step& s, const std::optional<Eigen::Vector3d>& sensor) {
  if (s.fusion.outcome == DoorFusion::Outcome::Reset) sights_.clear();
  std::unordered_set<std::uint32_t> alive;  // forget the tracks gone (forgotten, joined, reset)
  for (const TrackedDoor& t : fusion_.tracks()) alive.insert(t.id);
  for (auto it = sights_.begin(); it != sights_.end();) it = alive.count(it->first) ? std::next(it) : sights_.erase(it);
  for (const TrackedDoor& t : fusion_.tracks()) {
    Sight& g = sights_[t.id];
    if (t.seen_now && sensor) {
      const Eigen::Vector2d p = sensor->head<2>();
      if (!g.known) g.first = p, g.known = true;
      g.spread = std::max(g.spread, (p - g.first).norm());
    }
    const bool far = !g.known || g.spread >= options_.confirm_spread_m;
    if (t.observations >= static_cast<std::uint32_t>(options_.confirm_clouds) && far) g.confirmed = true;
  }
  standing();  // a withdrawn track seen again may be back
}

bool DriveTracker::confirmed(std::uint32_t id) const {
  const auto it = sights_.find(id);
  return it != sights_.end() && it->second.confirmed && !it->second.withdrawn;
}

double DriveTracker::spread(std::uint32_t id) const {
  const auto it = sights_.find(id);
  return it == sights_.end() ? 0.0 : it->second.spread;
}

std::vector<TrackedDoor> DriveTracker::published() const {
  std::vector<TrackedDoor> out;
  for (const TrackedDoor& t : fusion_.tracks())
    if (confirmed(t.id)) out.push_back(t);
  return out;
}

DriveTracker::Processed DriveTracker::process(const Pipeline& pipeline, pcl::PointCloud<pcl::PointXYZ>& cloud,
                                              const std::optional<Eigen::Isometry3d>& sensor_to_fixed, double stamp,
                                              bool with_reconstruction, bool without_viewpoint) {
  Processed p;
  const auto t0 = std::chrono::steady_clock::now();
  p.result = run(pipeline, cloud, sensor_to_fixed, with_reconstruction, without_viewpoint);
  const auto t1 = std::chrono::steady_clock::now();
  std::optional<Eigen::Vector3d> sensor;
  if (sensor_to_fixed) sensor = sensor_to_fixed->translation();
  p.step = fuse(p.result, stamp, pipeline.parameters(), sensor, &cloud);
  p.run_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  p.fuse_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();
  return p;
}

namespace {

constexpr double kDisproveRange = 4.0;  // m, sensor to opening centre, horizontal
constexpr float kOnPlane = 0.05f;       // m
constexpr int kMinRays = 30;            // rays reaching a doorway for a cloud to have looked at it
constexpr int kMinMisses = 3;
// Clouds that looked at a doorway without showing its door, per cloud that
// showed it: set on the tuning drives 1000-1019 (doc/results.md): 3 withdrew
// 4 true doors of the 320x240 camera (it finds some doors in few of the
// frames that see them), 6 one, 10 none but kept more false doors.
constexpr double kMissRatio = 6.0;

// The doorway of a track as a rectangle on its wall's plane, in float (one
// pass over every point of the cloud for each doorway still counting).
struct Doorway {
  std::uint32_t id;
  float nx, ny, c;       // the plane: n.p = c (n unit, horizontal)
  float ex, ey;          // along the wall (horizontal)
  float centre, half;    // of the rectangle along e (e.p), half its width
  float floor;           // z of the doorway's floor
  float side;            // +1 or -1: the sensor's side of the plane
  float dsn;             // the sensor's signed distance to the plane
  int reached = 0;       // rays that ended on the doorway's rectangle or passed through it (counted to kMinRays)
};

}  // namespace

std::size_t DriveTracker::disprove(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& sensor) {
  std::vector<Doorway> ds;
  const Eigen::Vector2d s2 = sensor.head<2>();
  for (const TrackedDoor& t : fusion_.tracks()) {
    const DoorResult& d = t.door;
    if (t.seen_now || !d.opening_center.allFinite() || (d.opening_center.head<2>() - s2).norm() > kDisproveRange) continue;
    Eigen::Vector2d n = d.wall_normal.head<2>();
    if (!(n.norm() > 0.5) || !d.wall_line_point.allFinite() || !(d.width > 0.3)) continue;
    n.normalize();
    const Eigen::Vector2d q = d.wall_line_point.head<2>(), e(-n.y(), n.x());
    const double dsn = (s2 - q).dot(n);
    if (std::abs(dsn) < 0.2) continue;  // the sensor in the wall's plane: no sight across it
    Doorway w;
    w.id = t.id;
    w.nx = static_cast<float>(n.x()), w.ny = static_cast<float>(n.y()), w.c = static_cast<float>(q.dot(n));
    w.ex = static_cast<float>(e.x()), w.ey = static_cast<float>(e.y());
    w.centre = static_cast<float>(d.opening_center.head<2>().dot(e)), w.half = static_cast<float>(0.4 * d.width);
    w.floor = static_cast<float>(d.opening_center.z());
    w.side = dsn > 0 ? 1.0f : -1.0f, w.dsn = static_cast<float>(dsn);
    ds.push_back(w);
  }
  const float sx = static_cast<float>(sensor.x()), sy = static_cast<float>(sensor.y()), sz = static_cast<float>(sensor.z());
  std::size_t counting = ds.size();  // ds[0, counting) still below kMinRays
  for (std::size_t k = 0; k < cloud.points.size() && counting > 0; ++k) {
    const auto& p = cloud.points[k];
    for (std::size_t i = 0; i < counting; ++i) {
      Doorway& w = ds[i];
      const float dpn = p.x * w.nx + p.y * w.ny - w.c;
      // Positive forms throughout: a NaN or infinite point fails every test.
      if (!(w.side * dpn <= kOnPlane)) continue;  // ended before the plane
      float x = p.x, y = p.y, z = p.z;
      if (!(std::abs(dpn) <= kOnPlane)) {  // passed through it: where
        const float lambda = w.dsn / (w.dsn - dpn);
        x = sx + lambda * (p.x - sx), y = sy + lambda * (p.y - sy), z = sz + lambda * (p.z - sz);
      }
      const float along = x * w.ex + y * w.ey - w.centre, h = z - w.floor;
      if (!(std::abs(along) <= w.half && h >= 0.3f && h <= 1.8f)) continue;
      if (++w.reached >= kMinRays) std::swap(ds[i--], ds[--counting]);  // looked at: no need to count on
    }
  }
  for (auto it = misses_.begin(); it != misses_.end();) {  // forget the tracks gone (forgotten, joined)
    bool alive = false;
    for (const TrackedDoor& t : fusion_.tracks()) alive = alive || t.id == it->first;
    it = alive ? std::next(it) : misses_.erase(it);
  }
  for (const Doorway& w : ds)
    if (w.reached >= kMinRays) ++misses_[w.id];  // looked at, not shown
  return standing();
}

// Every track's standing from its misses and observations: withdrawn while
// they stand at kMissRatio or more, published again once its observations
// catch up. Returns how many it withdrew.
std::size_t DriveTracker::standing() {
  std::size_t withdrawn = 0;
  for (const TrackedDoor& t : fusion_.tracks()) {
    const auto m = misses_.find(t.id);
    const bool out = m != misses_.end() && m->second >= kMinMisses && m->second >= kMissRatio * t.observations;
    Sight& g = sights_[t.id];
    withdrawn += out && !g.withdrawn;
    g.withdrawn = out;
  }
  return withdrawn;
}

void DriveTracker::reset() {
  misses_.clear();
  sights_.clear();
  fusion_.reset();
  last_sensor_.reset();
}

}  // namespace dsr
