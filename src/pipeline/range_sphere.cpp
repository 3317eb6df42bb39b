// The occluders of the range sphere (range_sphere.hpp): a cloud's points,
// thinned, as small oriented disks.
#include "range_sphere.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "door_state_recognition/segmentation/neighbour_grid.hpp"
#include "door_state_recognition/segmentation/segmentation.hpp"

namespace dsr {
namespace sight {
namespace detail {

Occluders disks(Points p, double voxel, const Parameters& prm) {
  Occluders o;
  o.p = std::move(p);
  o.radius = static_cast<float>(voxel);
  if (o.p.size() < 20) return o;
  const segmentation::NeighbourGrid grid(o.p, static_cast<float>(1.5 * voxel));
  o.n = segmentation::estimateNormals(o.p, grid, prm.normal_k, Eigen::Vector3f::Zero()).n;
  // Sampling spacing: the median distance to the nearest thinned neighbour
  // over a sample (the voxel for dense clouds; a mesh export's vertex
  // spacing when that is coarser).
  std::vector<float> nearest;
  std::vector<int> idx;
  std::vector<float> d2;
  const std::size_t stride = std::max<std::size_t>(1, o.p.size() / 2000);
  for (std::size_t i = 0; i < o.p.size(); i += stride) {
    grid.within(static_cast<int>(i), static_cast<float>(3 * voxel), idx, d2);
    if (!d2.empty()) nearest.push_back(std::sqrt(*std::min_element(d2.begin(), d2.end())));
  }
  float spacing = static_cast<float>(voxel);
  if (!nearest.empty()) {
    std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
    spacing = std::max(spacing, nearest[nearest.size() / 2]);
  }
  o.radius = 0.9f * spacing;
  return o;
}

Occluders occluders(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Parameters& prm) {
  return disks(preprocess::sanitizeAndDownsample(cloud, prm.max_abs_coordinate, kOccluderVoxel), kOccluderVoxel, prm);
}

}  // namespace detail
}  // namespace sight
}  // namespace dsr
