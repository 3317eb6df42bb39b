// A simulated cloud's points without their labels (the truth), as the
// pipeline takes them: organized layout kept. Shared by the gtest suites.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

inline pcl::PointCloud<pcl::PointXYZ> xyz(const pcl::PointCloud<pcl::PointXYZL>& in) {
  pcl::PointCloud<pcl::PointXYZ> out;
  out.width = in.width;
  out.height = in.height;
  out.points.resize(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) out.points[i] = pcl::PointXYZ(in[i].x, in[i].y, in[i].z);
  return out;
}
