// Internal to the simulator: the depth error models of RGB-D camera families
// (sim::DepthModel other than Default), rendered over a frame's rays.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>

#include "door_state_recognition/sim/sensors.hpp"

namespace dsr {
namespace sim {
namespace detail {

// Counter-based random numbers: the value for (seed, stream, index) does not
// depend on the order rays are processed in, so threads keep results exact.
inline std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
struct RayRandom {
  std::uint64_t state;
  RayRandom(std::uint64_t seed, std::uint64_t stream, std::uint64_t index)
      : state(splitmix(seed ^ splitmix(stream * 0x100000001B3ull ^ splitmix(index)))) {}
  double uniform() {
    state = splitmix(state);
    return ((state >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  }
  double gaussian() { return std::sqrt(-2.0 * std::log(uniform())) * std::cos(2 * 3.14159265358979323846 * uniform()); }
};

// Nearest hit along origin + t * dir (world, dir unit), t in (0, max_t].
using RayCaster = std::function<RayHit(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_t)>;

// Fills `cloud` (organized o.width x o.height, NaN where no return, label =
// the surface hit) with the frame of a camera at camera_to_world (optical
// frame: x right, y down, z forward) under o.depth_model.
void renderDepthModel(const Scene& scene, const RgbdOptions& o, const Eigen::Isometry3d& camera_to_world,
                      const RayCaster& cast, pcl::PointCloud<pcl::PointXYZL>& cloud);

}  // namespace detail
}  // namespace sim
}  // namespace dsr
