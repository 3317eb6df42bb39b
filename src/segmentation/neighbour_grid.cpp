#include "door_state_recognition/segmentation/neighbour_grid.hpp"

#include "door_state_recognition/preprocess/cell_map.hpp"

namespace dsr {
namespace segmentation {

using preprocess::CellMap;
using preprocess::cellOf;
using preprocess::packCell;

NeighbourGrid::NeighbourGrid(const std::vector<Eigen::Vector3f>& points, float cell)
    : cell_(cell), inv_(1.0 / cell) {
  const std::size_t n = points.size();
  CellMap map(std::max<std::size_t>(n, 1));
  std::vector<std::uint32_t> cell_of(n);
  std::vector<std::uint32_t> count;
  std::uint64_t last_key = ~std::uint64_t(0);  // no packed key
  std::uint32_t last_id = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3i c = cellOf(points[i], inv_);
    // Points come in scan order: runs of them share a cell.
    const std::uint64_t key = packCell(c.x(), c.y(), c.z());
    const std::uint32_t id = key == last_key ? last_id : map.insert(key);
    last_key = key;
    last_id = id;
    if (id == count.size()) {
      count.push_back(0);
      coord_.push_back(c);
    }
    ++count[id];
    cell_of[i] = id;
  }
  begin_.assign(count.size() + 1, 0);
  for (std::size_t c = 0; c < count.size(); ++c) begin_[c + 1] = begin_[c] + count[c];
  std::vector<std::uint32_t> fill(begin_.begin(), begin_.end() - 1);
  order_.resize(n);
  slot_.resize(n);
  pos_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t s = fill[cell_of[i]]++;
    order_[s] = static_cast<int>(i);
    slot_[i] = static_cast<int>(s);
    pos_[s] = points[i];
  }
  map_ = std::move(map);
}

std::uint32_t NeighbourGrid::findCell(int x, int y, int z) const { return map_.find(packCell(x, y, z)); }

void NeighbourGrid::neighbourCells(std::size_t c, int ring, std::vector<std::uint32_t>& cells) const {
  cells.clear();
  const Eigen::Vector3i& k = coord_[c];
  for (int dz = -ring; dz <= ring; ++dz)
    for (int dy = -ring; dy <= ring; ++dy)
      for (int dx = -ring; dx <= ring; ++dx) {
        const std::uint32_t o = findCell(k.x() + dx, k.y() + dy, k.z() + dz);
        if (o != CellMap::kNone) cells.push_back(o);
      }
}

void NeighbourGrid::within(int i, float r, std::vector<int>& idx, std::vector<float>& d2) const {
  idx.clear();
  d2.clear();
  const Eigen::Vector3f& q = point(i);
  const int ring = r <= cell_ ? 1 : 2;
  const float r2 = r * r;
  const Eigen::Vector3i k = cellOf(q, inv_);
  for (int dz = -ring; dz <= ring; ++dz)
    for (int dy = -ring; dy <= ring; ++dy)
      for (int dx = -ring; dx <= ring; ++dx) {
        const std::uint32_t o = findCell(k.x() + dx, k.y() + dy, k.z() + dz);
        if (o == CellMap::kNone) continue;
        for (std::uint32_t s = begin_[o]; s < begin_[o + 1]; ++s) {
          const float d = (pos_[s] - q).squaredNorm();
          if (d <= r2 && order_[s] != i) {
            idx.push_back(order_[s]);
            d2.push_back(d);
          }
        }
      }
}

}  // namespace segmentation
}  // namespace dsr
