// door_state_fusion_bench: the time fusion adds to a processed cloud (issue
// 20: at most 1 ms), figures on stdout.
//  1. DoorFusion::update over a long drive: 60 doors tracked, 6 doors per
//     cloud, 20000 clouds.
//  2. DriveTracker::fuse with the withdrawal pass (a pass over the cloud's
//     points for each track within 4 m that this cloud does not show) on the
//     clouds of simulated drive 1000, lidar64 and rgbd, every 10th frame
//     moved into the map frame. Three track sets per cloud: the scene's true
//     doors (the pass stops counting a doorway at 30 rays reaching it), and
//     4 and 8 doorways within 4 m that no ray reaches (their floor 5 m up,
//     above any ceiling: the whole cloud is read for each, the worst case).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/sim/drive.hpp"
#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/tracking/door_fusion.hpp"
#include "door_state_recognition/tracking/drive_tracker.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

void report(const char* what, std::vector<double> v) {
  if (v.empty()) return;
  std::sort(v.begin(), v.end());
  std::printf("%-34s clouds %4zu  median %.3f ms  p90 %.3f ms  max %.3f ms\n", what, v.size(), v[v.size() / 2],
              v[v.size() * 9 / 10], v.back());
}

void updateOnly() {
  dsr::DoorFusion f;
  std::vector<double> t;
  for (int k = 0; k < 20000; ++k) {
    std::vector<dsr::DoorResult> doors;
    for (int i = 0; i < 6; ++i) {
      dsr::DoorResult d;
      const int door = (k / 50 + i) % 60;
      d.opening_center = Eigen::Vector3d(door * 2.0 + 0.05 * ((k * 7 + i) % 5), (door % 2) * 5.0, 0);
      d.wall_line_direction = Eigen::Vector3d::UnitX();
      d.opening_angle_deg = (k % 13 == 0) ? 80 : 30;
      d.confidence = 0.6;
      d.width = 0.9;
      doors.push_back(d);
    }
    const auto t0 = Clock::now();
    f.update(doors, 0.1 * k);
    t.push_back(ms(t0, Clock::now()));
  }
  std::printf("DoorFusion::update, %zu tracks:\n", f.tracks().size());
  report("  update", t);
}

dsr::DoorResult doorway(const Eigen::Vector3d& centre, const Eigen::Vector3d& normal) {
  dsr::DoorResult d;
  d.opening_center = centre;
  d.wall_normal = normal;
  d.wall_line_point = centre;
  d.wall_line_direction = Eigen::Vector3d(-normal.y(), normal.x(), 0);
  d.width = 0.9;
  d.height = 2.0;
  d.confidence = 0.6;
  d.state = dsr::DoorStateKind::Closed;
  return d;
}

// The timed call: tracks made of `doors` at t = 0, then the cloud at t = 0.1
// showing none of them.
double withdrawalPass(const std::vector<dsr::DoorResult>& doors, const pcl::PointCloud<pcl::PointXYZ>& cloud,
                      const Eigen::Vector3d& sensor, const dsr::Parameters& params) {
  dsr::DriveTracker t;
  dsr::PipelineResult seen, none;
  seen.doors = doors;
  t.fuse(seen, 0.0, params, sensor);
  const auto t0 = Clock::now();
  t.fuse(none, 0.1, params, sensor, &cloud);
  return ms(t0, Clock::now());
}

void withdrawal(const char* sensor_name) {
  dsr::sim::DriveOptions o;
  o.sensor = sensor_name;
  o.seed = 1000;
  const dsr::sim::DrivePlan plan = dsr::sim::planDrive(dsr::sim::randomRoom(1000), o);
  const dsr::Parameters params;
  std::vector<double> truth, four, eight;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  std::size_t points = 0;
  for (std::size_t i = 0; i < plan.frame_count; i += 10) {
    const dsr::sim::DriveFrame f = dsr::sim::simulateFrame(plan, i);
    const Eigen::Isometry3f to_map = f.cloud.sensor_to_world.cast<float>();
    cloud.clear();
    for (const auto& q : f.cloud.cloud.points) cloud.push_back(pcl::PointXYZ(q.x, q.y, q.z));
    for (auto& p : cloud.points) p.getVector3fMap() = to_map * p.getVector3fMap();
    points = std::max(points, cloud.size());
    const Eigen::Vector3d s = f.cloud.sensor_to_world.translation();
    std::vector<dsr::DoorResult> real;
    for (const auto& d : plan.scenes[f.scene_index].doors) real.push_back(doorway(d.opening_center, d.wall_normal));
    truth.push_back(withdrawalPass(real, cloud, s, params));
    std::vector<dsr::DoorResult> hidden;  // within 4 m, facing the sensor, above any ceiling
    for (int k = 0; k < 8; ++k) {
      const double a = 2 * M_PI * k / 8;
      const Eigen::Vector3d dir(std::cos(a), std::sin(a), 0);
      hidden.push_back(doorway(Eigen::Vector3d(s.x() + 2.5 * dir.x(), s.y() + 2.5 * dir.y(), 5.0), -dir));
    }
    eight.push_back(withdrawalPass(hidden, cloud, s, params));
    hidden.resize(4);
    four.push_back(withdrawalPass(hidden, cloud, s, params));
  }
  std::printf("DriveTracker::fuse with the withdrawal pass, %s drive 1000 (up to %zu points a cloud):\n", sensor_name,
              points);
  report("  the scene's doors as tracks", truth);
  report("  4 doorways no ray reaches", four);
  report("  8 doorways no ray reaches", eight);
}

}  // namespace

int main() {
  updateOnly();
  withdrawal("lidar64");
  withdrawal("rgbd");
}
