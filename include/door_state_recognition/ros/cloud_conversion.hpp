// sensor_msgs/PointCloud2 -> pcl::PointCloud<pcl::PointXYZ>, validating the
// message first: nothing in it is trusted (sizes, offsets, types, endianness).
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <sensor_msgs/PointCloud2.h>

#include <string>

namespace dsr {
namespace ros_io {

// Empty string when the cloud can be read; otherwise what is wrong, one line.
// Accepts x, y, z as FLOAT32 or FLOAT64, little-endian, COUNT 1, inside
// point_step, not overlapping; requires row_step >= width*point_step (rows
// may be padded) and data.size() == row_step*height, with no overflow.
std::string validate(const sensor_msgs::PointCloud2& msg, std::size_t max_points);

// Converts a cloud that validate() accepted. NaN points are kept.
void toPcl(const sensor_msgs::PointCloud2& msg, pcl::PointCloud<pcl::PointXYZ>& out);

}  // namespace ros_io
}  // namespace dsr
