// Internal to the simulator: the depth error models of RGB-D camera families
// (sim::DepthModel other than Default), rendered over a frame's rays.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>

#include "door_state_recognition/sim/sensors.hpp"
#include "ray_random.hpp"

namespace dsr {
namespace sim {
namespace detail {

using sim::RayRandom;  // src/sim/ray_random.hpp

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
