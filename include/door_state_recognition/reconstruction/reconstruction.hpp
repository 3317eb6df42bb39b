// Reconstruction stage (paper 3.4): every wall is rebuilt as points
// up-sampled along the edges of its corner box, in the plane fitted to its
// points, with its doorways left open and each leaf placed at its recognised
// angle. Levelled frame. ROS-free.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <vector>

namespace dsr {
namespace reconstruction {

struct WallPatch {       // a wall as a rectangle in its fitted plane
  Eigen::Vector2d point, direction;  // line on the floor plane (x, y), unit direction
  double s_min, s_max, z_min, z_max;
};
struct Opening {         // a doorway in a wall, and its leaf as it stands
  int wall;
  double s0, s1, z_top;
  Eigen::Vector2d hinge, leaf_direction;  // x, y; unit
  double leaf_length, leaf_bottom, leaf_top;
};

// Label 1: wall, 2: leaf. Points `spacing` apart, each turned by
// `to_output` (levelled frame -> the input's) as it is made.
pcl::PointCloud<pcl::PointXYZL> reconstruct(const std::vector<WallPatch>& walls,
                                            const std::vector<Opening>& openings, double spacing,
                                            const Eigen::Matrix3f& to_output = Eigen::Matrix3f::Identity());

}  // namespace reconstruction
}  // namespace dsr
