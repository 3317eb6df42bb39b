// Simulated rotating multi-beam LiDAR (Velodyne/Ouster-like): one sweep of
// `beams` rings x `azimuth_steps` columns cast into a sim::Scene. ROS-free;
// deterministic for a seed whatever the number of threads.
//
// The cloud is organized: height = beams, width = azimuth steps, row r is
// the r-th beam from the top (row 0: highest elevation), column c looks at
// azimuth pi - 2 pi (c + 0.5) / width (clockwise seen from above, as the
// head spins; the middle column looks along +x). No return: NaN (or 0, 0, 0
// with zeros_for_no_return). Frame: REP 103, x forward, y left, z up, at
// the optical centre of the head.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>

#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/sim/sensors.hpp"

namespace dsr {
namespace sim {

struct LidarOptions {
  int beams = 64;
  double min_elevation_deg = -22.5, max_elevation_deg = 22.5;  // lowest and highest beam, evenly spaced
  int azimuth_steps = 1024;
  double range_sigma = 0.015;      // Gaussian range noise, metres (0: none)
  double min_range = 0.3;          // closer returns are lost (the robot's own body)
  double max_range = 100.0;
  double dropout = 0.01;           // probability that a return is lost
  double max_incidence_deg = 88;   // steeper grazing angles return nothing
  bool zeros_for_no_return = false;  // (0, 0, 0) instead of NaN where no return
  // Height of the head above the floor when the scan position is drawn
  // (sensor_to_world unset): [0.4, 1.2] m; < 0: drawn in that range.
  double mast_height = -1;
  // Pose of the sensor frame in the world (e.g. on a robot); unset: a free
  // position in the room drawn by the seed, level, yawed arbitrarily.
  std::optional<Eigen::Isometry3d> sensor_to_world;
  // A head moving during its sweep (a driving robot, clouds not deskewed):
  // the pose where the sweep began; column c is cast from the pose
  // interpolated at (c + 0.5) / width between it and sensor_to_world (the
  // sweep's end: the cloud's frame and stamp; translation linear, rotation
  // slerp) and written as that head measured it (range along its beam), as
  // a driver that does not deskew delivers it. Unset: the head stands still.
  std::optional<Eigen::Isometry3d> sweep_start_to_world;
  std::uint64_t seed = 1;

  // 16: +-15 deg, 1800 columns (VLP-16 at 10 Hz), 2 cm noise; 32: -25..+15 deg,
  // 1800 columns (VLP-32C-like), 2 cm; 64: +-22.5 deg, 1024 columns (OS1-64),
  // 1.5 cm; 128: +-45 deg, 1024 columns (OS0-128), 1.5 cm, 50 m range.
  // Throws std::invalid_argument for another beam count.
  static LidarOptions preset(int beams);
};

// "lidar16" | "lidar32" | "lidar64" | "lidar128" -> beam count; 0 otherwise.
int lidarBeamsOf(const std::string& sensor_name);

// One sweep. cloud.sensor = "lidarN", frame_id = "lidar". Throws
// std::invalid_argument on absurd options or when no free position exists.
SimulatedCloud scanLidar(const Scene& scene, const LidarOptions& options);

// Elevation (rad) of beam `row` (row 0: the highest).
double lidarBeamElevation(const LidarOptions& options, int row);

// Whether a rotating LiDAR at the cloud's pose can see door `door`: a
// sight line to some point of its doorway (middle and sides, three heights)
// lies within the vertical field of view and range, and meets nothing but
// that door's leaf, handle or casing (walls, furniture: occluded).
bool lidarSeesDoor(const Scene& scene, const SimulatedCloud& cloud, int door);

}  // namespace sim
}  // namespace dsr
