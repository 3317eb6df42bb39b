// Preprocessing stage: drop garbage points, level the cloud so that z is up,
// voxel-downsample. ROS-free.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "door_state_recognition/preprocess/camera.hpp"
#include "door_state_recognition/preprocess/levelling.hpp"

namespace dsr {
namespace preprocess {

// Finite points with every |coordinate| <= max_abs, as float vectors.
Points sanitize(const pcl::PointCloud<pcl::PointXYZ>& cloud, double max_abs);

// One point (the centroid) per occupied cubic voxel of edge `leaf`; the
// output order is deterministic. leaf <= 0 returns the input.
Points voxelDownsample(const Points& points, double leaf);

// voxelDownsample(sanitize(cloud, max_abs), leaf) in one pass, without the
// copy; `kept` (if given) receives the number of points sanitize keeps.
Points sanitizeAndDownsample(const pcl::PointCloud<pcl::PointXYZ>& cloud, double max_abs, double leaf,
                             std::size_t* kept = nullptr);

}  // namespace preprocess
}  // namespace dsr
