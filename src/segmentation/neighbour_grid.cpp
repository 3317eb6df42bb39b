#include "door_state_recognition/segmentation/neighbour_grid.hpp"

#include "door_state_recognition/preprocess/cell_map.hpp"

#include <limits>

namespace dsr {
namespace segmentation {

using preprocess::CellMap;
using preprocess::cellOf;
using preprocess::packCell;

// The cells of the points through the dense coarse index, when the coarse
// cells' bounding box (one coarse cell of margin) is small: at most 16
// entries a point plus 1M, within +-2^20 cells. Cells are numbered in order
// of first point, as the hash map numbers them. False (nothing built): too large.
bool NeighbourGrid::buildDense(const std::vector<Eigen::Vector3f>& points, std::vector<std::uint32_t>& count,
                               std::vector<std::uint32_t>& cell_of) {
  const std::size_t n = points.size();
  if (n == 0) return false;
  Eigen::Vector3i lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max()), hi = -lo;
  for (const Eigen::Vector3f& p : points) {
    const Eigen::Vector3i c = cellOf(p, inv_);
    lo = lo.cwiseMin(c), hi = hi.cwiseMax(c);
  }
  // Fine coordinates (and a ring of 2 around) within +-2^20: packed keys do not wrap.
  constexpr int kLimit = (1 << 20) - 4;
  if (lo.minCoeff() < -kLimit || hi.maxCoeff() > kLimit) return false;
  const Eigen::Vector3i clo(half(lo.x()) - 1, half(lo.y()) - 1, half(lo.z()) - 1);
  const Eigen::Vector3i chi(half(hi.x()) + 1, half(hi.y()) + 1, half(hi.z()) + 1);
  const Eigen::Vector3i dims = chi - clo + Eigen::Vector3i::Ones();
  const double volume = static_cast<double>(dims.x()) * dims.y() * dims.z();
  if (volume > 16.0 * static_cast<double>(n) + (1 << 20)) return false;
  lo_ = clo;
  dims_ = dims;
  dense_.assign(static_cast<std::size_t>(volume), CellMap::kNone);
  children_.clear();
  coarse_coord_.clear();
  Eigen::Vector3i last = Eigen::Vector3i::Constant(std::numeric_limits<int>::min());
  std::uint32_t last_id = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3i c = cellOf(points[i], inv_);
    // Points come in scan order: runs of them share a cell.
    if (c != last) {
      const Eigen::Vector3i q(half(c.x()), half(c.y()), half(c.z()));
      std::uint32_t& k = dense_[(static_cast<std::size_t>(q.z() - clo.z()) * dims.y() + (q.y() - clo.y())) * dims.x() +
                                (q.x() - clo.x())];
      if (k == CellMap::kNone) {
        k = static_cast<std::uint32_t>(coarse_coord_.size());
        coarse_coord_.push_back(q);
        children_.resize(children_.size() + 8, CellMap::kNone);
      }
      std::uint32_t& id = children_[8 * static_cast<std::size_t>(k) + (c.x() & 1) + 2 * (c.y() & 1) + 4 * (c.z() & 1)];
      if (id == CellMap::kNone) {
        id = static_cast<std::uint32_t>(count.size());
        count.push_back(0);
        coord_.push_back(c);
        coarse_of_.push_back(k);
      }
      last = c;
      last_id = id;
    }
    ++count[last_id];
    cell_of[i] = last_id;
  }
  return true;
}

NeighbourGrid::NeighbourGrid(const std::vector<Eigen::Vector3f>& points, float cell)
    : cell_(cell), inv_(1.0 / cell) {
  const std::size_t n = points.size();
  std::vector<std::uint32_t> cell_of(n);
  std::vector<std::uint32_t> count;
  if (!buildDense(points, count, cell_of)) {
    CellMap map(std::max<std::size_t>(n, 1));
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
    map_ = std::move(map);
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
}

std::uint32_t NeighbourGrid::findCell(int x, int y, int z) const {
  if (dense_.empty()) return map_.find(packCell(x, y, z));
  const std::uint32_t k = findCoarse(half(x), half(y), half(z));
  return k == CellMap::kNone ? k : children_[8 * static_cast<std::size_t>(k) + (x & 1) + 2 * (y & 1) + 4 * (z & 1)];
}

void NeighbourGrid::neighbourCells(std::size_t c, int ring, std::vector<std::uint32_t>& cells) const {
  cells.clear();
  const Eigen::Vector3i& k = coord_[c];
  if (!dense_.empty() && ring <= 2) {
    // The same cells in the same order as below, a row of coarse cells at a
    // time: a cell's coarse cell lies a coarse cell or more inside the box,
    // so 2 cells around it stay inside. Each axis's offsets into the box and
    // child parities are worked out once, for the 2 ring + 1 steps.
    std::size_t ox[5], oy[5], oz[5];
    int px[5], py[5], pz[5];
    for (int d = -ring; d <= ring; ++d) {
      const int x = k.x() + d, y = k.y() + d, z = k.z() + d;
      ox[d + ring] = static_cast<std::size_t>(half(x) - lo_.x());
      oy[d + ring] = static_cast<std::size_t>(half(y) - lo_.y()) * dims_.x();
      oz[d + ring] = static_cast<std::size_t>(half(z) - lo_.z()) * dims_.y() * dims_.x();
      px[d + ring] = x & 1, py[d + ring] = 2 * (y & 1), pz[d + ring] = 4 * (z & 1);
    }
    const int n = 2 * ring + 1;
    for (int iz = 0; iz < n; ++iz)
      for (int iy = 0; iy < n; ++iy) {
        const std::size_t row = oz[iz] + oy[iy];
        const int parity_yz = py[iy] + pz[iz];
        for (int ix = 0; ix < n; ++ix) {
          const std::uint32_t kc = dense_[row + ox[ix]];
          if (kc == CellMap::kNone) continue;
          const std::uint32_t o = children_[8 * static_cast<std::size_t>(kc) + px[ix] + parity_yz];
          if (o != CellMap::kNone) cells.push_back(o);
        }
      }
    return;
  }
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
