// Camera frames: the pinhole camera of an organized cloud, fitted to its
// pixels. ROS-free.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace dsr {
namespace preprocess {

using Points = std::vector<Eigen::Vector3f>;

// The pinhole camera of an organized frame seen from `viewpoint`, fitted to
// the pixels with a return (direct linear transform, pixel column and row
// against the point): within a pixel at nine in ten of the sampled pixels.
struct Pinhole {
  Eigen::Matrix3d Mi = Eigen::Matrix3d::Identity();  // (u, v, 1) -> a ray in front, u and v scaled as below
  double cu = 0, cv = 0, sc = 1;                      // u = (col - cu) / sc, v = (row - cv) / sc
  int width = 0, height = 0;
  // The unit ray of pixel (col, row), in the cloud's frame.
  Eigen::Vector3d ray(double col, double row) const;
  // The unit direction, across the optical axis, towards the image's top
  // row (row 0 is the top of an image), in the cloud's frame.
  Eigen::Vector3d imageUp() const;
};

// Nullopt when the cloud is not organized or no pinhole camera fits its
// pixels (an organized scan of another kind, e.g. a rotating LiDAR's rings).
std::optional<Pinhole> fitPinhole(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3f& viewpoint);

// The unit rays of the pixels without a return (every `step`-th row and
// column), in the cloud's frame: empty when the camera is not of this cloud.
Points noReturnRays(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Pinhole& camera, int step = 2);

// The angle (rad) between neighbouring rays of an organized cloud, seen from
// `viewpoint`: the median angle between pixels next to each other in a row
// and in a column (each where both returned), the larger of the two. A depth
// camera's pixels lie 0.1-0.2 deg apart; a rotating LiDAR's rings 0.35-2 deg.
// 0 for an unorganized cloud or too few neighbours.
double raySpacing(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3f& viewpoint);
// The same with the camera fitted here (empty when none fits).
Points noReturnRays(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3f& viewpoint, int step = 2);

}  // namespace preprocess
}  // namespace dsr
