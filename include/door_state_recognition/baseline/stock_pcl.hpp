// The stock-PCL baseline: the paper's method as a user would write it with
// PCL's own classes, for the benchmark (issue 5) to compare against.
//
//   preprocess     pcl::VoxelGrid (same voxel size) after levelling to the
//                  given up axis, refined by the largest horizontal plane
//                  found by pcl::SACSegmentation (SACMODEL_PERPENDICULAR_PLANE)
//   normals        pcl::NormalEstimationOMP, k = normal_k, every core
//   floor_ceiling  z histogram of horizontal-normal points (paper 3.1)
//   walls          iterative pcl::SACSegmentation (SACMODEL_PARALLEL_PLANE
//                  to the up axis: vertical planes), pcl::ExtractIndices to
//                  remove the inliers, repeat; a plane is split at gaps along
//                  it and kept by the same height/length rules as ours
//   doors          our recognition::findDoorways and state::fitLeaf on those
//                  walls (so that both are scored by the same evaluation)
//   segments       pcl::RegionGrowing on what is not wall, leaf, floor or
//                  ceiling, pcl::MomentOfInertiaEstimation (AABB and OBB) of
//                  every region and wall
//   boundary       pcl::BoundaryEstimation on the wall and leaf points
//                  (paper 3.3.1; our pipeline has no such stage)
//
// The result is a PipelineResult in the input frame, so io::reportJson and
// eval::evaluate score it like ours. ROS-free.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include "door_state_recognition/pipeline/parameters.hpp"
#include "door_state_recognition/pipeline/pipeline.hpp"

namespace dsr {
namespace baseline {

struct StockOptions {
  int sac_max_iterations = 1000;   // per plane
  double sac_axis_eps_deg = 5.0;   // vertical planes: normal within this of horizontal
  int normal_threads = 0;          // NormalEstimationOMP threads, 0: every core
  double up_refine_deg = 15.0;     // largest horizontal plane within this refines the up axis
};

// Runs the stock-PCL pipeline. `p.up_axis` must be an axis (+x ... -z), not
// "auto". timing_ms holds preprocess, normals, floor_ceiling, walls, doors,
// segments, boundary and total.
PipelineResult runStockPcl(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Parameters& p,
                           const StockOptions& options = StockOptions(),
                           const Eigen::Vector3d& viewpoint = Eigen::Vector3d::Zero());

}  // namespace baseline
}  // namespace dsr
