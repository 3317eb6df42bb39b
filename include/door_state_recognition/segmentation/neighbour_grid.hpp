// NeighbourGrid: the one search structure of the pipeline. Points are bucketed
// in cubic cells of edge `cell`; a query visits the 27 cells around it (or
// 125 for a radius up to twice the cell). Built in O(n) with a flat hash, it
// replaces a k-d tree: after voxel thinning every neighbourhood the pipeline
// asks for is a few centimetres wide, which a grid answers without a tree
// walk. Normals and region growing work on whole cells (neighbourCells).
// Stores indices and its own cell-ordered copy of the points (for locality);
// distances are rotation-invariant, so a grid built before levelling serves
// the levelled points as well. ROS-free.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "door_state_recognition/preprocess/cell_map.hpp"

namespace dsr {
namespace segmentation {

class NeighbourGrid {
 public:
  NeighbourGrid() = default;
  NeighbourGrid(const std::vector<Eigen::Vector3f>& points, float cell);

  float cell() const { return cell_; }
  std::size_t size() const { return pos_.size(); }
  std::size_t cells() const { return coord_.size(); }
  // Integer coordinates of cell c (floor of position / cell).
  const Eigen::Vector3i& coord(std::size_t c) const { return coord_[c]; }
  // Points of cell c, as indices into the points the grid was built on.
  const int* cellBegin(std::size_t c) const { return order_.data() + begin_[c]; }
  const int* cellEnd(std::size_t c) const { return order_.data() + begin_[c + 1]; }
  // The points of cell c as stored, in cellBegin's order: point(*(cellBegin(c) + k)) is cellPoints(c)[k].
  const Eigen::Vector3f* cellPoints(std::size_t c) const { return pos_.data() + begin_[c]; }
  // The point of index i as stored (in the frame the grid was built in).
  const Eigen::Vector3f& point(int i) const { return pos_[slot_[i]]; }

  // Every point within distance r of point i (itself excluded), r <= 2 cell:
  // index and squared distance appended to idx and d2 (cleared first).
  void within(int i, float r, std::vector<int>& idx, std::vector<float>& d2) const;
  // The occupied cells of the (2 ring + 1)^3 block around c, c included.
  void neighbourCells(std::size_t c, int ring, std::vector<std::uint32_t>& cells) const;
  // f(o) for each cell neighbourCells(c, 1, ...) lists, in its order, without the list.
  template <class F>
  void forEachNeighbourCell(std::size_t c, const F& f) const {
    const Eigen::Vector3i& k = coord_[c];
    if (dense_.empty()) {
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const std::uint32_t o = findCell(k.x() + dx, k.y() + dy, k.z() + dz);
            if (o != preprocess::CellMap::kNone) f(o);
          }
      return;
    }
    // As neighbourCells walks the dense index: a row of coarse cells at a time.
    std::size_t ox[3], oy[3], oz[3];
    int px[3], pyz[3][3];
    for (int d = -1; d <= 1; ++d) {
      const int x = k.x() + d, y = k.y() + d, z = k.z() + d;
      ox[d + 1] = static_cast<std::size_t>(half(x) - lo_.x());
      oy[d + 1] = static_cast<std::size_t>(half(y) - lo_.y()) * dims_.x();
      oz[d + 1] = static_cast<std::size_t>(half(z) - lo_.z()) * dims_.y() * dims_.x();
      px[d + 1] = x & 1;
    }
    for (int iz = 0; iz < 3; ++iz)
      for (int iy = 0; iy < 3; ++iy) pyz[iz][iy] = 2 * ((k.y() + iy - 1) & 1) + 4 * ((k.z() + iz - 1) & 1);
    for (int iz = 0; iz < 3; ++iz)
      for (int iy = 0; iy < 3; ++iy) {
        const std::size_t row = oz[iz] + oy[iy];
        const int parity_yz = pyz[iz][iy];
        for (int ix = 0; ix < 3; ++ix) {
          const std::uint32_t kc = dense_[row + ox[ix]];
          if (kc == preprocess::CellMap::kNone) continue;
          const std::uint32_t o = children_[8 * static_cast<std::size_t>(kc) + px[ix] + parity_yz];
          if (o != preprocess::CellMap::kNone) f(o);
        }
      }
  }

  // Coarse cells (twice the edge: cell coordinates halved, rounded down),
  // indexed densely over their bounding box when that box is small (and
  // within +-2^20 cells, where no packed key wraps). Then every lookup is two
  // loads (the coarse cell in the box, the cell among its 8) instead of a
  // hash probe, and coarseCells() > 0; otherwise the hash map serves and the
  // coarse level is not built (coarseCells() == 0). Numbering does not
  // depend on which serves: cells are numbered in order of first point.
  std::size_t coarseCells() const { return coarse_coord_.size(); }
  std::uint32_t coarseOf(std::size_t c) const { return coarse_of_[c]; }
  const Eigen::Vector3i& coarseCoord(std::size_t k) const { return coarse_coord_[k]; }
  // The coarse cell at coarse coordinates (x, y, z), or CellMap::kNone; only
  // when coarseCells() > 0.
  std::uint32_t findCoarse(int x, int y, int z) const {
    const long long rx = static_cast<long long>(x) - lo_.x(), ry = static_cast<long long>(y) - lo_.y(),
                    rz = static_cast<long long>(z) - lo_.z();
    if (rx < 0 || ry < 0 || rz < 0 || rx >= dims_.x() || ry >= dims_.y() || rz >= dims_.z())
      return preprocess::CellMap::kNone;
    return dense_[(static_cast<std::size_t>(rz) * dims_.y() + static_cast<std::size_t>(ry)) * dims_.x() +
                  static_cast<std::size_t>(rx)];
  }
  // floor(v / 2): an arithmetic shift (as g++ and clang shift, and C++20 requires).
  static int half(int v) { return v >> 1; }

 private:
  std::uint32_t findCell(int x, int y, int z) const;
  bool buildDense(const std::vector<Eigen::Vector3i>& cell, const Eigen::Vector3i& lo, const Eigen::Vector3i& hi,
                  std::vector<std::uint32_t>& count, std::vector<std::uint32_t>& cell_of, std::size_t mid,
                  std::vector<std::uint32_t>& count_mid);
  float cell_ = 1;
  double inv_ = 1;
  std::vector<Eigen::Vector3f> pos_;   // points in cell order
  std::vector<int> order_;             // cell order -> point index
  std::vector<int> slot_;              // point index -> cell order
  std::vector<std::uint32_t> begin_;   // cell -> first slot; cells() + 1 entries
  std::vector<Eigen::Vector3i> coord_; // cell -> integer coordinates
  preprocess::CellMap map_{1};         // packed cell key -> cell (when not dense)
  // Dense coarse index (see coarseCells).
  Eigen::Vector3i lo_ = Eigen::Vector3i::Zero(), dims_ = Eigen::Vector3i::Zero();
  std::vector<std::uint32_t> dense_;         // coarse box -> coarse cell
  std::vector<std::uint32_t> children_;      // coarse cell x 8 -> cell (x&1 + 2 (y&1) + 4 (z&1))
  std::vector<std::uint32_t> coarse_of_;     // cell -> coarse cell
  std::vector<Eigen::Vector3i> coarse_coord_;// coarse cell -> coarse coordinates
};

}  // namespace segmentation
}  // namespace dsr
