// Segmentation: region growing on normals and curvature over the
// neighbour grid's cells (growRegions).
#include "door_state_recognition/segmentation/segmentation.hpp"

#include "door_state_recognition/util/radix_sort.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace dsr {
namespace segmentation {

std::vector<std::vector<int>> growRegions(const Points& points, const Normals& normals, const NeighbourGrid& grid,
                                         const std::vector<char>& mask, const Parameters& p) {
  // Cell by cell: the points of a grid cell share one normal (estimateNormals),
  // so regions grow over neighbouring cells with agreeing normals.
  const float cos_thr = static_cast<float>(std::cos(p.region_angle_deg * M_PI / 180.0));
  const std::size_t cells = grid.cells();
  std::vector<char> live(cells, 0);
  std::vector<Eigen::Vector3f> cn(cells);
  std::vector<float> curv(cells, 1.0f);
  std::vector<int> order;
  for (std::size_t c = 0; c < cells; ++c) {
    const int first = *grid.cellBegin(c);
    cn[c] = normals.n[first];
    curv[c] = normals.curvature[first];
    for (const int* it = grid.cellBegin(c); it != grid.cellEnd(c); ++it) live[c] |= mask[*it] != 0;
    if (live[c] && curv[c] <= p.region_curvature && cn[c].squaredNorm() > 0.25f) order.push_back(static_cast<int>(c));
  }
  // By curvature, ties in cell order: a stable sort, by radix.
  util::radixSortBy(order, [&](int c) { return static_cast<std::uint64_t>(util::orderedBits(curv[c])); });
  std::vector<int> label(cells, -1);
  std::vector<std::vector<int>> regions;
  std::vector<int> members, stack, region;
  for (int seed : order) {
    if (label[seed] != -1) continue;
    const int id = static_cast<int>(regions.size());
    members.assign(1, seed);
    stack.assign(1, seed);
    label[seed] = id;
    while (!stack.empty()) {
      const int cur = stack.back();
      stack.pop_back();
      grid.forEachNeighbourCell(static_cast<std::size_t>(cur), [&](std::uint32_t nb) {
        if (!live[nb] || label[nb] != -1) return;
        if (std::abs(cn[cur].dot(cn[nb])) < cos_thr) return;
        label[nb] = id;
        members.push_back(static_cast<int>(nb));
        if (curv[nb] <= p.region_curvature) stack.push_back(static_cast<int>(nb));
      });
    }
    region.clear();
    for (int c : members)
      for (const int* it = grid.cellBegin(c); it != grid.cellEnd(c); ++it)
        if (mask[*it]) region.push_back(*it);
    if (static_cast<int>(region.size()) >= p.min_region_points) {
      std::sort(region.begin(), region.end());
      regions.push_back(region);
    } else {
      for (int c : members) label[c] = -2;  // too small: never reused as a seed
    }
  }
  return regions;
}

}  // namespace segmentation
}  // namespace dsr
