#include "door_state_recognition/segmentation/neighbour_grid.hpp"

#include "door_state_recognition/preprocess/cell_map.hpp"
#include "door_state_recognition/util/first_error.hpp"

#include <exception>
#include <limits>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace dsr {
namespace segmentation {

using preprocess::CellMap;
using preprocess::cellOf;
using preprocess::packCell;

namespace {

// body() with a team of two threads for its tasks: the caller's team when it
// runs inside a parallel region (its tasks go to that team's threads), else
// a team of its own (two threads, when there are two). An exception from
// body() is rethrown here.
template <class F>
void withTasks(const F& body) {
  util::FirstError error;
  auto guarded = [&] { error.run(body); };
#ifdef _OPENMP
  if (!omp_in_parallel() && omp_get_max_threads() >= 2) {
#pragma omp parallel num_threads(2)
#pragma omp single
    guarded();
  } else {
    guarded();
  }
#else
  guarded();
#endif
  error.rethrow();
}

}  // namespace

// The cells of the points through the dense coarse index, when the coarse
// cells' bounding box (one coarse cell of margin) is small: at most 16
// entries a point plus 1M, within +-2^20 cells. Cells are numbered in order
// of first point, as the hash map numbers them. False (nothing built): too large.
// cell[i] is point i's cell coordinates (cellOf), lo and hi their bounds;
// the points' counts of each cell come back in count (all) and count_mid
// (those before mid), each cell's number in cell_of.
bool NeighbourGrid::buildDense(const std::vector<Eigen::Vector3i>& cell, const Eigen::Vector3i& lo,
                               const Eigen::Vector3i& hi, std::vector<std::uint32_t>& count,
                               std::vector<std::uint32_t>& cell_of, std::size_t mid,
                               std::vector<std::uint32_t>& count_mid) {
  const std::size_t n = cell.size();
  if (n == 0) return false;
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
  // Each point's key: its coarse cell's place in the box, times 8, plus its
  // place among the coarse cell's 8 (two halves at once).
  std::vector<std::uint64_t> key(n);
  auto keysOf = [&](std::size_t i0, std::size_t i1) {
    for (std::size_t i = i0; i < i1; ++i) {
      const Eigen::Vector3i& c = cell[i];
      const std::size_t box = (static_cast<std::size_t>(half(c.z()) - clo.z()) * dims.y() + (half(c.y()) - clo.y())) *
                                  dims.x() +
                              (half(c.x()) - clo.x());
      key[i] = 8 * static_cast<std::uint64_t>(box) + static_cast<std::uint64_t>((c.x() & 1) + 2 * (c.y() & 1) + 4 * (c.z() & 1));
    }
  };
  if (mid < n) {
#pragma omp task default(shared)
    keysOf(mid, n);
  }
  keysOf(0, mid);
  dense_.assign(static_cast<std::size_t>(volume), CellMap::kNone);
  children_.clear();
#pragma omp taskwait
  // Numbered in point order: a coarse cell when first met (its 8 children
  // made), a cell when first met; each remembers its first point.
  std::vector<std::uint32_t> first, coarse_first;
  std::uint64_t last = ~std::uint64_t(0);  // no key
  std::uint32_t last_id = 0;
  constexpr std::size_t kAhead = 16;  // points ahead whose coarse entry is fetched into cache
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t k = key[i];
    if (i + kAhead < n) __builtin_prefetch(&dense_[key[i + kAhead] >> 3]);
    // Points come in scan order: runs of them share a cell.
    if (k != last) {
      std::uint32_t& kc = dense_[k >> 3];
      if (kc == CellMap::kNone) {
        kc = static_cast<std::uint32_t>(coarse_first.size());
        coarse_first.push_back(static_cast<std::uint32_t>(i));
        children_.resize(children_.size() + 8, CellMap::kNone);
      }
      std::uint32_t& id = children_[8 * static_cast<std::size_t>(kc) + (k & 7)];
      if (id == CellMap::kNone) {
        id = static_cast<std::uint32_t>(first.size());
        first.push_back(static_cast<std::uint32_t>(i));
        coarse_of_.push_back(kc);
      }
      last = k;
      last_id = id;
    }
    cell_of[i] = last_id;
  }
  const std::size_t cells = first.size();
  coord_.resize(cells);
  for (std::size_t c = 0; c < cells; ++c) coord_[c] = cell[first[c]];
  coarse_coord_.resize(coarse_first.size());
  for (std::size_t k = 0; k < coarse_first.size(); ++k) {
    const Eigen::Vector3i& c = cell[coarse_first[k]];
    coarse_coord_[k] = Eigen::Vector3i(half(c.x()), half(c.y()), half(c.z()));
  }
  // Points of each cell, in the two halves at once.
  count.assign(cells, 0);
  if (mid < n) count_mid.assign(cells, 0);
  std::vector<std::uint32_t>& count0 = mid < n ? count_mid : count;
  auto tally = [&](std::size_t i0, std::size_t i1, std::vector<std::uint32_t>& cnt) {
    for (std::size_t i = i0; i < i1; ++i) ++cnt[cell_of[i]];
  };
  if (mid < n) {
#pragma omp task default(shared)
    tally(mid, n, count);
  }
  tally(0, mid, count0);
#pragma omp taskwait
  if (mid < n)
    for (std::size_t c = 0; c < cells; ++c) count[c] += count_mid[c];
  return true;
}

NeighbourGrid::NeighbourGrid(const std::vector<Eigen::Vector3f>& points, float cell)
    : cell_(cell), inv_(1.0 / cell) {
  const std::size_t n = points.size();
  // Two halves of the points at once (tasks) where it pays: the cells of
  // the points and their bounds, the dense index's keys and counts, then
  // the points sorted into cell order.
  const std::size_t mid = n >= 20000 ? n / 2 : n;
  withTasks([&] {
    std::vector<std::uint32_t> cell_of(n);
    std::vector<std::uint32_t> count, count_mid;
    {
      std::vector<Eigen::Vector3i> cells(n);
      struct Bounds {
        Eigen::Vector3i lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max()), hi = -lo;
      } b[2];
      // The bounds kept in the task's own variables, stored when done: the
      // two halves' bounds lie side by side (false sharing if written per point).
      auto cellsOf = [&](std::size_t i0, std::size_t i1, Bounds& bd) {
        Bounds own;
        for (std::size_t i = i0; i < i1; ++i) {
          const Eigen::Vector3i c = cellOf(points[i], inv_);
          cells[i] = c;
          own.lo = own.lo.cwiseMin(c), own.hi = own.hi.cwiseMax(c);
        }
        bd = own;
      };
      if (mid < n) {
#pragma omp task default(shared)
        cellsOf(mid, n, b[1]);
      }
      cellsOf(0, mid, b[0]);
#pragma omp taskwait
      const Eigen::Vector3i lo = b[0].lo.cwiseMin(b[1].lo), hi = b[0].hi.cwiseMax(b[1].hi);
      if (!buildDense(cells, lo, hi, count, cell_of, mid, count_mid)) {
        CellMap map(std::max<std::size_t>(n, 1));
        std::uint64_t last_key = ~std::uint64_t(0);  // no packed key
        std::uint32_t last_id = 0;
        for (std::size_t i = 0; i < n; ++i) {
          if (i == mid) count_mid = count;  // the cells' counts over points [0, mid)
          const Eigen::Vector3i& c = cells[i];
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
    }
    begin_.assign(count.size() + 1, 0);
    for (std::size_t c = 0; c < count.size(); ++c) begin_[c + 1] = begin_[c] + count[c];
    order_.resize(n);
    slot_.resize(n);
    pos_.resize(n);
    // Each cell's points in point order: those of [0, mid) from its first
    // slot on, those of [mid, n) after them.
    std::vector<std::uint32_t> fill0(begin_.begin(), begin_.end() - 1), fill1;
    if (mid < n) {
      fill1 = fill0;
      for (std::size_t c = 0; c < count_mid.size(); ++c) fill1[c] += count_mid[c];
    }
    auto place = [&](std::size_t i0, std::size_t i1, std::vector<std::uint32_t>& fill) {
      for (std::size_t i = i0; i < i1; ++i) {
        const std::uint32_t s = fill[cell_of[i]]++;
        order_[s] = static_cast<int>(i);
        slot_[i] = static_cast<int>(s);
        pos_[s] = points[i];
      }
    };
    if (mid < n) {
#pragma omp task default(shared)
      place(mid, n, fill1);
    }
    place(0, mid, fill0);
#pragma omp taskwait
  });
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
