// Input that cannot be a scene, told before any stage runs: the pipeline then
// reports zero doors with a warning naming the likely cause, rather than
// finding structure in it. ROS-free.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace dsr {

// A warning when the cloud, seen from `viewpoint`, cannot be a scene:
//  - every return at the sensor itself (a depth image of zeros: no returns);
//  - a camera frame (organized) whose every pixel has one depth (a constant
//    depth image);
//  - ranges beyond any sensor's reach indoors (median range above 30 m for a
//    camera frame, 1000 m for a scan): depth in millimetres read as metres.
// nullopt for a cloud that may be a scene (including an empty one).
std::optional<std::string> implausibleInput(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& viewpoint);

// The same for a cloud with no viewpoint: its points spread (median distance
// from their middle) more than a camera frame (30 m) or a building's
// indoors (1000 m) spans: millimetres read as metres.
std::optional<std::string> implausibleExtent(const pcl::PointCloud<pcl::PointXYZ>& cloud);

// A warning when one plane holds nearly all the (levelled) points: only a
// floor in view, only a ceiling, or one surface close up (a wall within
// 1.5 m), too little of a scene to tell a doorway. `normals` pairs with
// `points`, both levelled (z up); `up_given`: the up axis was given, not
// estimated from the points (a single plane levels itself as a floor).
std::optional<std::string> singleSurface(const std::vector<Eigen::Vector3f>& points,
                                         const std::vector<Eigen::Vector3f>& normals, const Eigen::Vector3f& viewpoint,
                                         bool up_given);

}  // namespace dsr
