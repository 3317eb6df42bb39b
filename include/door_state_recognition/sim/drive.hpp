// A simulated robot drive through a room: a path past every door (and
// through one open doorway into the room behind, when one is passable), a
// rotating LiDAR or an RGB-D camera on the robot, clouds at a fixed rate,
// doors that change during the drive. ROS-free; deterministic for a seed.
//
// Frames (REP 105): "map" = the scene's world frame; "base_link" on the floor
// under the robot's centre, x forward, z up; the sensor frame ("lidar": REP
// 103, x forward, z up; "camera_depth_optical_frame": z forward, x right,
// y down) rigidly on base_link.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "door_state_recognition/sim/lidar.hpp"
#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/sim/sensors.hpp"

namespace dsr {
namespace sim {

// Door `door` is at `angle_deg` from `t` (seconds after the start) on: the
// scene is rebuilt with it for every later cloud.
struct DoorChange {
  int door = 0;
  double angle_deg = 0;
  double t = 0;
};

struct DriveOptions {
  std::string sensor = "lidar64";  // lidar16 | lidar32 | lidar64 | lidar128 | rgbd
  double seconds = 0;              // duration of the drive; 0: the path at `speed`
  double rate_hz = 0;              // clouds per second; 0: 10 (LiDAR), 15 (RGB-D)
  double speed = 0.5;              // m/s, when seconds = 0
  double turn_rate_deg_s = 60;     // the robot turns in place at the path's corners
  double door_distance = 1.4;      // passes each door this far from its wall's face, [1, 3] m
  bool through_door = true;        // ends 1.8 m beyond an open doorway, if one is passable
  double robot_radius = 0.25;      // clearance kept from every surface
  // Sensor height above the floor; unset: drawn by the seed in [0.4, 1.2] m
  // (LiDAR) or [0.3, 1.5] m (RGB-D).
  std::optional<double> mount_height;
  // RGB-D pitch, degrees, negative down; unset: drawn in [-20, 10].
  std::optional<double> camera_pitch_deg;
  // Sensor models; unset: LidarOptions::preset(beams), or a 320x240 RGB-D
  // (Kinect intrinsics scaled). Their pose and seed are set per cloud.
  std::optional<LidarOptions> lidar;
  std::optional<RgbdOptions> rgbd;
  std::vector<DoorChange> changes;
  // LiDAR: each sweep lasts 1 / rate_hz and ends at its cloud's stamp; the
  // robot moves during it and the cloud is not deskewed (each column cast
  // from where the head was when it fired, all in the frame at the stamp).
  bool lidar_motion = false;
  std::uint64_t seed = 1;
};

// The drive, planned: scenes, path and timing. Cheap to keep; clouds are
// simulated from it one at a time (simulateFrame).
struct DrivePlan {
  DriveOptions options;                 // with seconds and rate_hz resolved
  std::vector<Scene> scenes;            // scenes[k] holds from scene_from_t[k] on
  std::vector<double> scene_from_t;     // 0, then each change's time (sorted)
  std::vector<DoorChange> changes;      // sorted by time
  std::vector<Eigen::Vector3d> path;    // the polyline driven: x, y in the room frame, yaw (room frame) of the segment leaving it
  std::vector<double> vertex_t;         // time the robot leaves path[i] (after turning there)
  std::vector<double> arrive_t;         // time the robot reaches path[i]
  double speed = 0;                     // m/s along the path
  double path_length = 0;
  int through_door = -1;                // door driven through at the end (-1: none)
  std::vector<Eigen::Vector3d> door_waypoints;  // where each door is passed (map, -1 z: unreachable)
  Eigen::Isometry3d sensor_to_base = Eigen::Isometry3d::Identity();
  std::string sensor_frame, base_frame = "base_link", map_frame = "map";
  std::size_t frame_count = 0;          // round(seconds x rate_hz)

  double frameTime(std::size_t i) const { return static_cast<double>(i) / options.rate_hz; }
  Eigen::Isometry3d baseToMap(double t) const;  // clamped to [0, seconds]
  int sceneIndexAt(double t) const;
};

struct DriveFrame {
  std::size_t index = 0;
  double t = 0;                        // seconds after the start
  SimulatedCloud cloud;                // points in the sensor frame; sensor_to_world = sensor -> map
  Eigen::Isometry3d base_to_map = Eigen::Isometry3d::Identity();
  int scene_index = 0;
};

// Throws std::invalid_argument for absurd options (unknown sensor, rate or
// seconds out of range, a change naming no door or outside the drive,
// seconds too short for the turns) or a room no path fits in.
DrivePlan planDrive(const RoomSpec& spec, const DriveOptions& options);
DriveFrame simulateFrame(const DrivePlan& plan, std::size_t index);
// Every frame in order, one at a time (a 64-beam minute is ~1 GB held at once).
void simulateDrive(const DrivePlan& plan, const std::function<void(const DriveFrame&)>& each);
// Every frame, held in memory: for short drives.
std::vector<DriveFrame> simulateDrive(const RoomSpec& spec, const DriveOptions& options);

// Whether the sensor of `cloud` (only its pose and sensor fields are used)
// sees door `door` of `scene`: LiDAR as lidarSeesDoor; RGB-D when a point of
// the doorway projects into the image within range with a clear sight line.
bool sensorSeesDoor(const Scene& scene, const SimulatedCloud& cloud, int door);
// RGB-D and TLS (else 0): the share, 0..1, of door `door`'s leaf the sensor
// of `cloud` sees: 8 x 16 points on the leaf's face turned to the sensor
// (cell centres of the rectangle leaf_corners span), each counted when the
// ray to it first hits that door's leaf or handle at an incidence the sensor
// returns (a camera's max_incidence_deg, 80 deg for a TLS) and, for a
// camera, it projects into the image within range. A TLS cloud of several
// stations (a survey, a merged or mesh-like export) counts a point seen from
// any of its viewpoints_world.
double leafInViewShare(const Scene& scene, const SimulatedCloud& cloud, int door);

// Ground truth of the drive, every coordinate in map: groundTruthJson of the
// final scene in map ("doors" hold the states at the end of the drive, each
// with "initial_opening_angle_deg"/"initial_state", "frames_in_view",
// "first_in_view_t", "last_in_view_t", "min_distance_m" (sensor path to the
// doorway's middle, horizontal), "passed_within_3m"; "in_view" = seen in some
// frame), plus "drive": sensor, frames, rate, seconds, start_stamp,
// sensor_to_base, through_door, "changes" (door, t, stamp, from/to angle and
// state, first frame after and first frame that shows the door after), and
// "path" (per frame: i, t, stamp, x, y, yaw of base_link, doors in view).
nlohmann::json driveTruthJson(const DrivePlan& plan, double start_stamp = 0.0);

}  // namespace sim
}  // namespace dsr
