// Recognition: the evidence grid of findDoorways on a wall: every point
// taken along its ray from the sensor to the wall's plane marks the face,
// what is seen through it, a recess or an occluder; the face's tolerance
// from the wall's own noise; the columns' shares over a door's body.
#include "doorway_search.hpp"

#include "door_state_recognition/util/both_halves.hpp"
#include "door_state_recognition/util/floor.hpp"
#include "door_state_recognition/util/radix_sort.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

namespace dsr {
namespace recognition {
namespace detail {

namespace {

// Rows (5 cm) above and below an empty cell between a LiDAR's rings looked at for the rings next to it.
constexpr int kRingRows = 6;
// Elevation margin (tan) inside a camera frame's view for an empty cell to count as looked at.
constexpr float kInViewMargin = 0.01f;
// Points of a cloud from which findDoorways reads them in two halves at once.
constexpr std::size_t kSplitPoints = 20000;

}  // namespace

bool DoorwaySearch::buildGrid() {
  cell = p.grid_cell, row_h = 0.05;
  s_lo = wall.s_min - 0.3, s_hi = wall.s_max + 0.3;
  cols = std::max(1, static_cast<int>(std::ceil((s_hi - s_lo) / cell)));
  const double z_span = std::min(top_z - floor_z, 2.6);
  rows = std::max(1, static_cast<int>(std::ceil(z_span / row_h)));
  if (cols > 20000) return false;
  grid.resize(static_cast<std::size_t>(cols) * rows);
  std::vector<int> front_diff(static_cast<std::size_t>(cols + 1) * (rows + 1), 0);
  // Trim is sought on sub-columns of half a cell, summed over the body.
  sub = 2 * cols;
  face_d_out.assign(sub, 0), face_d_n.assign(sub, 0);
  face_d_sum.assign(sub, 0.0);
  d_view = wall.signedDistance(viewpoint);
  if (d_view <= 0) return false;
  auto cellIndex = [&](double s, double z) -> std::ptrdiff_t {  // the cell at (s, z), as an index; -1 for none
    const int c = util::floorToInt((s - s_lo) / cell), r = util::floorToInt((z - floor_z) / row_h);
    if (c < 0 || c >= cols || r < 0 || r >= rows) return -1;
    return static_cast<std::ptrdiff_t>(r) * cols + c;
  };
  const double footprint = std::max(p.voxel_size, 0.01);
  body0 = static_cast<int>(0.25 / row_h), body1 = std::min(rows, static_cast<int>(1.75 / row_h));
  // The lower body, below a window's sill (0.8 m and up): a doorway seen
  // through is seen through here too, where the floor runs on beyond it.
  low1 = std::min(body1, static_cast<int>(0.8 / row_h));
  // Face and trim counts above the body in rows a fifth as high (a 5 cm row
  // slid in 1 cm steps over them): a head's trim only 7 cm high fills no
  // 5 cm row of the grid when it straddles two.
  fine0 = body1 * kFine, fine_n = (rows - body1) * kFine;
  head_fine.assign(static_cast<std::size_t>(std::max(0, fine_n)) * cols, {0, 0});  // face, out
  // The face points' offsets summed in the same fine rows, in a camera
  // frame only: a depth camera's trim stands out of the wall by less than
  // its noise point by point, but clearly in the mean (rule (5) below).
  head_fine_d.assign(view ? head_fine.size() : 0, 0.0);
  // The wall's own noise sets how thick its face is: laser scans are
  // millimetre-sharp, depth-camera returns spread with range. The tolerance
  // is local: 2.5 sigma of the wall's inliers within half a metre along it.
  col_tol.assign(cols, p.face_tolerance);
  // The noise itself (sigma, from the same median deviation): what a mean
  // offset of n face points must exceed to stand out of the wall (trim legs).
  col_sigma.assign(cols, p.face_tolerance / 2.5);
  {
    // The median deviation of the inliers within `win` columns: the deviations
    // ranked once, the window slid over the columns with its ranks counted
    // in blocks of kRankBlock (adding or removing a rank is two increments;
    // the k-th smallest is found by walking the blocks, then one block's
    // ranks): the same value as selecting from the pooled window each time.
    std::vector<std::pair<float, int>> dev;  // deviation, column
    dev.reserve(wall.inliers.size());
    for (int i : wall.inliers) {
      const int c = util::floorToInt((wall.along(points[i]) - s_lo) / cell);
      if (c >= 0 && c < cols) dev.push_back({static_cast<float>(std::abs(wall.signedDistance(points[i]))), c});
    }
    util::sortPairs(dev);  // std::sort's order, in linear time
    const int n = static_cast<int>(dev.size());
    std::vector<std::vector<int>> ranks(cols);
    for (int r = 0; r < n; ++r) ranks[dev[r].second].push_back(r);
    constexpr int kRankBlock = 256;
    std::vector<unsigned char> in_window(n, 0);
    std::vector<int> block(n / kRankBlock + 1, 0);
    int size = 0;
    auto addColumn = [&](int k, int v) {
      for (int r : ranks[k]) in_window[r] = static_cast<unsigned char>(in_window[r] + v), block[r / kRankBlock] += v;
      size += v * static_cast<int>(ranks[k].size());
    };
    auto kth = [&](int k) {  // rank of the k-th smallest (from 0) in the window; k < size
      int b = 0;
      while (block[b] <= k) k -= block[b++];
      int r = b * kRankBlock;
      for (;; ++r) {
        if (in_window[r] > k) break;
        k -= in_window[r];
      }
      return r;
    };
    const int win = std::max(1, static_cast<int>(0.5 / cell));
    for (int k = 0; k <= std::min(cols - 1, win); ++k) addColumn(k, 1);
    for (int c = 0; c < cols; ++c) {
      if (c > 0 && c + win <= cols - 1) addColumn(c + win, 1);
      if (c - win - 1 >= 0) addColumn(c - win - 1, -1);
      if (size < 20) continue;
      col_sigma[c] = 1.4826 * dev[kth(size / 2)].first;
      col_tol[c] = std::max(p.face_tolerance, 2.5 * col_sigma[c]);
    }
  }
  // Points at the wall's body height within its face and 0.6 m behind it
  // (near the wall), where the jambs and the wall's thickness are read
  // below, in point order: those within the face (tolAt) as positions
  // along the wall; those behind it by tolAt to 0.6 m as (position, depth).
  const double max_tol = *std::max_element(col_tol.begin(), col_tol.end());
  // A point off the face band whose ray from the sensor meets the wall's
  // line outside the grid (with 6 cells of shadow and 0.5 m to spare) adds
  // nothing below: the wedge from the sensor over the grid tells it cheaply.
  const Eigen::Vector2d v2(viewpoint.x(), viewpoint.y());
  const Eigen::Vector2d wa = wall.point + (s_lo - 6 * cell - 0.5) * wall.direction - v2;
  const Eigen::Vector2d wb = wall.point + (s_lo + (cols + 6) * cell + 0.5) * wall.direction - v2;
  const double wedge_sign = wa.x() * wb.y() - wa.y() * wb.x() >= 0 ? 1.0 : -1.0;
  const bool cull = d_view > 0.05;
  const double band_lo = -std::max(0.6, max_tol);
  auto outsideWedge = [&](const Eigen::Vector3f& pt) {
    const Eigen::Vector2d q = Eigen::Vector2d(pt.x(), pt.y()) - v2;
    return wedge_sign * (wa.x() * q.y() - wa.y() * q.x()) < 0 || wedge_sign * (q.x() * wb.y() - q.y() * wb.x()) < 0;
  };
  // The evidence of points [i0, i1) counted into the grid g, the arrays
  // fd (front_diff), hf (head_fine), fo and fn (face_d_out, face_d_n), fa
  // and bh (face_along, behind_face); each face offset d of sub-column col
  // goes to addD(col, d).
  // fa and bh are filled as lists of the scan's own, moved out when done:
  // the ends of the halves' lists, written at every point, would otherwise
  // share cache lines between the cores (false sharing).
  auto scan = [&](std::size_t i0, std::size_t i1, Cell* g, int* fd, std::pair<int, int>* hf, double* hd, int* fo, int* fn,
                  std::vector<double>& fa_out, std::vector<std::pair<double, double>>& bh_out, auto&& addD) {
    std::vector<double> fa;
    std::vector<std::pair<double, double>> bh;
    for (std::size_t i = i0; i < i1; ++i) {
      const auto& pt = points[i];
      const double d = wall.signedDistance(pt);
      if (d >= -0.6 && d <= max_tol && pt.z() >= floor_z + 0.25 && pt.z() <= floor_z + 1.75) {
        const double a = wall.along(pt), tol = tolAt(a);
        if (std::abs(d) <= tol) fa.push_back(a);
        if (-d >= tol && -d <= 0.6) bh.push_back({a, -d});
      }
      if (d >= d_view) continue;  // beside or behind the sensor
      if (cull && (d < band_lo || d > max_tol) && outsideWedge(pt)) continue;
      const double s_pt = wall.along(pt);
      if (std::abs(d) <= tolAt(s_pt)) {
        const double s = s_pt;
        const std::ptrdiff_t ci = cellIndex(s, pt.z());
        if (ci >= 0) {
          Cell* c = g + ci;
          ++c->face;
          c->out += d > p.casing_min_offset;
          const double frf = std::floor((pt.z() - floor_z) / (row_h / kFine)) - fine0;
          if (frf >= 0 && frf < fine_n) {
            const std::size_t k = static_cast<std::size_t>(frf) * cols + static_cast<std::size_t>(ci) % cols;
            auto& h = hf[k];
            ++h.first;
            h.second += d > p.casing_min_offset;
            if (hd) hd[k] += d;
          }
          if (pt.z() > floor_z + 0.3 && pt.z() < floor_z + 1.9) {
            const int col = std::min(sub - 1, static_cast<int>((s - s_lo) / (cell / 2)));
            fo[col] += d > p.casing_min_offset;
            addD(col, d);
            ++fn[col];
          }
        }
        continue;
      }
      // Where the ray from the sensor to this point crosses the wall's plane.
      const double lambda = d_view / (d_view - d);
      const Eigen::Vector3f x = viewpoint + static_cast<float>(lambda) * (pt - viewpoint);
      const double s = wall.along(x);
      if (d < 0) {
        const std::ptrdiff_t ci = cellIndex(s, x.z());
        if (ci >= 0) (d < -0.3 ? g[ci].through : g[ci].recess)++;
      } else {
        // An occluder shadows a patch that grows with lambda: a rectangle of
        // cells, added to a difference array (summed once below).
        // lambda grows without bound as the ray runs parallel to the wall, so the
        // crossing may lie far off the grid: clamp and test in double before any
        // cast to int (found by fuzz_pipeline; off-grid patches were skipped anyway).
        const int r = static_cast<int>(std::min(5.0, std::ceil(0.5 * footprint * lambda / cell)));
        const double cf = std::floor((s - s_lo) / cell);
        const double r0f = std::floor((x.z() - r * cell - floor_z) / row_h);
        const double r1f = std::floor((x.z() + r * cell - floor_z) / row_h);
        if (!(cf >= -r && cf <= cols - 1 + r && r1f >= 0 && r0f <= rows - 1)) continue;  // also NaN
        const int c = static_cast<int>(cf), r0 = static_cast<int>(r0f), r1 = static_cast<int>(r1f);
        const int ca = std::max(0, c - r), cb = std::min(cols - 1, c + r), ra = std::max(0, r0), rb = std::min(rows - 1, r1);
        if (ca > cb || ra > rb) continue;
        fd[static_cast<std::size_t>(ra) * (cols + 1) + ca] += 1;
        fd[static_cast<std::size_t>(ra) * (cols + 1) + cb + 1] -= 1;
        fd[static_cast<std::size_t>(rb + 1) * (cols + 1) + ca] -= 1;
        fd[static_cast<std::size_t>(rb + 1) * (cols + 1) + cb + 1] += 1;
      }
    }
    fa_out.swap(fa);
    bh_out.swap(bh);
  };
  // Over both cores for a large cloud: the first half into the arrays
  // above, the second (a task) into arrays of its own, added after (counts
  // add up the same in any order); its face offsets, kept in point order,
  // are summed after the first half's, as one pass in point order sums them.
  const std::size_t half_at = points.size() >= kSplitPoints ? points.size() / 2 : points.size();
  struct Second {
    std::vector<Cell> grid;
    std::vector<int> front_diff, face_d_out, face_d_n;
    std::vector<double> face_along;
    std::vector<std::pair<double, double>> behind_face;
    std::vector<std::pair<int, int>> head_fine;
    std::vector<double> head_fine_d;
    std::vector<std::pair<int, double>> face_d;  // (sub-column, offset) in point order
  } second;
  util::bothHalves(half_at < points.size(), [&](int h) {
    if (h == 0) {
      scan(0, half_at, grid.data(), front_diff.data(), head_fine.data(), head_fine_d.empty() ? nullptr : head_fine_d.data(), face_d_out.data(), face_d_n.data(), face_along, behind_face,
           [&](int col, double d) { face_d_sum[col] += d; });
      return;
    }
    second.grid.resize(grid.size());
    second.front_diff.assign(front_diff.size(), 0);
    second.head_fine.assign(head_fine.size(), {0, 0});
    second.head_fine_d.assign(head_fine_d.size(), 0.0);
    second.face_d_out.assign(sub, 0);
    second.face_d_n.assign(sub, 0);
    std::vector<std::pair<int, double>> face_d;  // this task's own, as above
    scan(half_at, points.size(), second.grid.data(), second.front_diff.data(), second.head_fine.data(),
         second.head_fine_d.empty() ? nullptr : second.head_fine_d.data(),
         second.face_d_out.data(), second.face_d_n.data(), second.face_along, second.behind_face,
         [&](int col, double d) { face_d.push_back({col, d}); });
    second.face_d.swap(face_d);
  });
  if (half_at < points.size()) {
    for (std::size_t k = 0; k < grid.size(); ++k) {
      grid[k].face += second.grid[k].face, grid[k].out += second.grid[k].out;
      grid[k].through += second.grid[k].through, grid[k].recess += second.grid[k].recess;
    }
    for (std::size_t k = 0; k < front_diff.size(); ++k) front_diff[k] += second.front_diff[k];
    for (std::size_t k = 0; k < head_fine.size(); ++k)
      head_fine[k].first += second.head_fine[k].first, head_fine[k].second += second.head_fine[k].second;
    // Summed per half, then added: a split run rounds these sums otherwise
    // than one pass would (deterministically; only rule (5) reads them).
    for (std::size_t k = 0; k < head_fine_d.size(); ++k) head_fine_d[k] += second.head_fine_d[k];
    for (int k = 0; k < sub; ++k) face_d_out[k] += second.face_d_out[k], face_d_n[k] += second.face_d_n[k];
    for (const auto& cd : second.face_d) face_d_sum[cd.first] += cd.second;
    face_along.insert(face_along.end(), second.face_along.begin(), second.face_along.end());
    behind_face.insert(behind_face.end(), second.behind_face.begin(), second.behind_face.end());
  }
  // Occluder shadows: 2-D prefix sums of the difference array.
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * (cols + 1) + c;
      if (r > 0) front_diff[i] += front_diff[i - (cols + 1)];
      if (c > 0) front_diff[i] += front_diff[i - 1];
      if (r > 0 && c > 0) front_diff[i] -= front_diff[i - (cols + 1) - 1];
      grid[static_cast<std::size_t>(r) * cols + c].front = front_diff[i];
    }
  // A camera frame: a cell on the wall's plane without any return whose
  // centre lies inside the view (between the lowest and the highest return
  // on its bearing) was looked at and nothing was there in range.
  if (no_return_is_free && view && !view->max_tan.empty())
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        Cell& g = grid[static_cast<std::size_t>(r) * cols + c];
        if (g.face || g.through || g.recess || g.front) continue;
        const Eigen::Vector3f q = cellCentre(c, r);
        g.empty_in_view = view->inView(q, -kInViewMargin) && sampled(q, c, r);
      }

  // Column shares over the body of a door.
  const int nbody = std::max(1, body1 - body0);
  face.assign(cols, 0.0), expl.assign(cols, 0.0), casing_share.assign(sub, 0.0);
  col_seen.assign(cols, 0), col_through.assign(cols, 0);
  // Shares among the observed cells of a column: a camera may see nothing
  // at all through the upper part of a doorway (the room beyond out of range).
  for (int c = 0; c < cols; ++c) {
    int f = 0, e = 0, t = 0;
    for (int r = body0; r < body1; ++r) {
      const Cell& g = grid[static_cast<std::size_t>(r) * cols + c];
      if (g.face) ++f;
      else if (g.through || g.front || g.recess || g.empty_in_view) ++e, t += g.through || g.recess || g.empty_in_view;
    }
    const int observed = f + e;
    col_seen[c] = observed, col_through[c] = t;
    const bool enough = observed >= std::max(4.0, 0.15 * nbody);
    face[c] = enough ? static_cast<double>(f) / observed : (f > 0 ? 1.0 : 0.0);
    expl[c] = enough ? static_cast<double>(e) / observed : 0.0;
  }
  return true;
}

double DoorwaySearch::tolAt(double s) const {
  const int c = util::floorToInt((s - s_lo) / cell);
  return col_tol[std::clamp(c, 0, cols - 1)];
}

// Rays of an organized cloud cross every cell near enough: at most one
// cell size apart there. Farther, a cell without a return may lie between
// two of them (a 64-beam LiDAR's rings are 7 cm apart 6 m off, a 16-beam's
// 20 cm): not looked at, nothing told of it (lidar64 drive 1008: a plain
// wall 6 m off, its cells between rings taken as seen through, made a doorway).
// Between rings, a cell next to a ring that met the wall's face (in the
// rows within one ring spacing above and below, at most kRingRows) is that
// face, unsampled: not seen through.
bool DoorwaySearch::sampled(const Eigen::Vector3f& q, int c, int r) const {
  if (!view || view->ray_spacing <= 0) return true;
  const double gap = (q - view->viewpoint).norm() * view->ray_spacing;
  if (gap <= std::min(row_h, cell)) return true;
  const int k = std::min(kRingRows, static_cast<int>(std::ceil(gap / row_h)));
  for (int rr = std::max(0, r - k); rr <= std::min(rows - 1, r + k); ++rr)
    if (grid[static_cast<std::size_t>(rr) * cols + c].face) return false;
  return true;
}

Eigen::Vector3f DoorwaySearch::cellCentre(int c, int r) const {
  const Eigen::Vector2d xy = wall.point + (s_lo + (c + 0.5) * cell) * wall.direction;
  return Eigen::Vector3f(static_cast<float>(xy.x()), static_cast<float>(xy.y()),
                         static_cast<float>(floor_z + (r + 0.5) * row_h));
}

}  // namespace detail
}  // namespace recognition
}  // namespace dsr
