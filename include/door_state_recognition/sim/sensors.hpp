// Simulated sensors: a terrestrial laser scanner (TLS) and an RGB-D camera,
// both ray casting into a sim::Scene. ROS-free; deterministic for a seed
// whatever the number of threads.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "door_state_recognition/sim/scene.hpp"

namespace dsr {
namespace sim {

struct TlsOptions {
  std::size_t points = 400000;     // rays over all viewpoints (returns are fewer with dropout)
  int viewpoints = 1;              // scan positions inside the room
  bool beyond_doors = false;       // one more scan position beyond each door, in the room behind it
  double range_sigma = 0.005;      // Gaussian range noise, metres (0: none)
  double dropout = 0.0;            // probability that a return is lost
  double min_elevation_deg = -60;  // below that the tripod hides the floor
  double max_range = 80.0;
  std::uint64_t seed = 1;
};

// The depth error model of an RGB-D camera's family (src/sim/depth_models.cpp
// gives each its published behaviour and sources).
enum class DepthModel {
  Default,          // axial noise sigma(z) of a Kinect v1 (Nguyen et al. 2012), random dropout: the frames of old
  StructuredLight,  // Kinect v1-like: disparity quantized to 1/8 px, projector shadows, holes on dark surfaces
  TimeOfFlight,     // Kinect v2 / Azure-like: flying pixels at edges, multipath in concave corners, range to 10 m
  ActiveStereo,     // RealSense D435-like: RMS error ~ z^2, speckle, imager shadows, holes on dark/glossy surfaces
};
// "default" | "structured" | "tof" | "stereo"; throws std::invalid_argument otherwise.
DepthModel parseDepthModel(const std::string& name);
const char* toString(DepthModel m);

struct RgbdOptions {
  int width = 640, height = 480;
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;  // Kinect-like intrinsics
  double min_range = 0.5, max_range = 4.5;                // along the optical axis, metres
  bool noise = true;               // depth noise sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2
  double dropout = 0.02;           // random missing returns
  double max_incidence_deg = 80;   // steeper grazing angles return nothing
  int target_door = -1;            // door the camera looks at (-1: chosen by the seed)
  bool avoid_ceiling = true;       // pitch so that no ceiling is in view
  // Pose of the optical frame in the world (a camera on a robot); unset:
  // placed in front of a door by the seed as above (target_door, avoid_ceiling).
  std::optional<Eigen::Isometry3d> camera_to_world;
  std::uint64_t seed = 1;
  DepthModel depth_model = DepthModel::Default;
  // The same camera at another image size (a fraction of 640 x 480): the
  // intrinsics scaled with it, the principal point in the image's middle.
  void resize(int w, int h) {
    fx = fy = 525.0 * w / 640.0;
    width = w, height = h;
    cx = (w - 1) / 2.0, cy = (h - 1) / 2.0;
  }
  // Not the default model: the share of leaves and of furniture pieces that
  // are dark (or glossy), drawn per piece by the seed.
  double dark_fraction = 0.35;
  // The camera's pose; each one unset is drawn by the seed as before (height
  // 0.9-1.5 m, pitched at the door and below the ceiling, roll within 3 deg,
  // 1.6-3.5 m in front of the door). pitch: of the optical axis above the
  // horizontal; a pitch given (or robot_camera) lets the ceiling into view.
  std::optional<double> camera_height, pitch_deg, roll_deg, door_distance;
  // A camera as robots carry it, drawn by the seed: height 0.3-1.6 m, pitch
  // -20..+10 deg, roll within 5 deg, 1-6 m from the door (as deep as the
  // room allows). Options given above win.
  bool robot_camera = false;
};

struct SimulatedCloud {
  // Points in the sensor frame. TLS: unorganized, finite points only.
  // RGB-D: organized width x height, NaN where no return. LiDAR: organized
  // azimuth steps x beams, NaN (or zeros) where no return.
  // label = sim::Surface of the surface hit (ground truth, never an input).
  pcl::PointCloud<pcl::PointXYZL> cloud;
  Eigen::Isometry3d sensor_to_world = Eigen::Isometry3d::Identity();  // pose of the cloud frame
  std::string sensor;    // "tls" | "rgbd" | "lidar16" | "lidar32" | "lidar64" | "lidar128"
  std::string frame_id;  // "tls_scanner" | "camera_depth_optical_frame" | "lidar"
  std::vector<Eigen::Vector3d> viewpoints_world;
  std::vector<int> station;  // TLS: index into viewpoints_world of the scan position each point was seen from
  RgbdOptions rgbd;      // intrinsics used (RGB-D only)
  // Rotating LiDAR only (sim/lidar.hpp): the vertical field of view swept and the range.
  int lidar_beams = 0;
  double lidar_min_elevation_deg = 0, lidar_max_elevation_deg = 0, lidar_max_range = 0;
};

struct RayHit {
  bool hit = false;
  double t = 0.0;
  Surface surface = Surface::None;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // of the face hit, world
  int owner = -1;  // Box::owner of the box hit
};

// Nearest hit of the ray origin + t * dir (dir unit), t in (0, max_t].
RayHit castRay(const Scene& scene, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_t);

// Throws std::invalid_argument on absurd options or when no free scan
// position exists.
SimulatedCloud scanTls(const Scene& scene, const TlsOptions& options);
SimulatedCloud captureRgbd(const Scene& scene, const RgbdOptions& options);

}  // namespace sim
}  // namespace dsr
