#include "door_state_recognition/recognition/recognition.hpp"
#include "door_state_recognition/util/floor.hpp"
#include "door_state_recognition/util/radix_sort.hpp"
#include "door_state_recognition/util/both_halves.hpp"
#include "door_state_recognition/util/first_error.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <exception>
#include <limits>

namespace dsr {
namespace recognition {

BoxCorners boundingBox(const Points& points, const std::vector<int>& idx) {
  BoxCorners b;
  if (idx.empty()) return b;
  // Principal horizontal axis of the segment.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int i : idx) mean += points[i].head<2>().cast<double>();
  mean /= static_cast<double>(idx.size());
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  for (int i : idx) {
    const Eigen::Vector2d d = points[i].head<2>().cast<double>() - mean;
    C += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  Eigen::Vector2d a = es.eigenvectors().col(1);
  const double ang = std::atan2(a.y(), a.x());
  const double to_axis = std::abs(std::remainder(ang, M_PI / 2));
  b.oriented = to_axis > 2.0 * M_PI / 180.0;
  // Gram-Schmidt: the axes are the principal horizontal axis, its
  // orthogonal complement in the horizontal plane, and z (levelled frame).
  Eigen::Vector3d e1 = b.oriented ? Eigen::Vector3d(a.x(), a.y(), 0).normalized() : Eigen::Vector3d::UnitX();
  Eigen::Vector3d e3 = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d e2 = e3.cross(e1);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  for (int i : idx) {
    const Eigen::Vector3d p = points[i].cast<double>();
    const Eigen::Vector3d q(p.dot(e1), p.dot(e2), p.dot(e3));
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  b.extents = hi - lo;
  b.volume = b.extents.prod();
  b.height = b.extents.z();
  const Eigen::Vector3d c = (lo + hi) / 2;
  b.center = c.x() * e1 + c.y() * e2 + c.z() * e3;
  b.corners = boxCorners(lo, hi, e1, e2, e3);
  return b;
}

std::array<Eigen::Vector3d, 8> boxCorners(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3d& e1,
                                          const Eigen::Vector3d& e2, const Eigen::Vector3d& e3) {
  std::array<Eigen::Vector3d, 8> corners;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d q((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
    corners[k] = q.x() * e1 + q.y() * e2 + q.z() * e3;
  }
  return corners;
}

std::vector<char> boundaryPoints(const Points& points, const segmentation::Normals& normals,
                                 const segmentation::NeighbourGrid& grid, float radius,
                                 const std::vector<int>& indices, int k, double angle_deg) {
  std::vector<char> out(indices.size(), 0);
  const double thr = angle_deg * M_PI / 180.0;
  if (k < 3) return out;
  std::vector<int> within;
  std::vector<float> d2;
  std::vector<std::pair<float, int>> near;
  std::vector<double> angles;
  for (std::size_t j = 0; j < indices.size(); ++j) {
    const int i = indices[j];
    const Eigen::Vector3d p = points[i].cast<double>(), n = normals.n[i].cast<double>();
    // Tangent basis (u, v) of the plane perpendicular to n.
    Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
    // The k nearest within the radius.
    grid.within(i, radius, within, d2);
    near.clear();
    for (std::size_t m = 0; m < within.size(); ++m) near.push_back({d2[m], within[m]});
    if (static_cast<int>(near.size()) > k - 1) {
      std::nth_element(near.begin(), near.begin() + (k - 1), near.end());
      near.resize(k - 1);
    }
    angles.clear();
    for (const auto& nb : near) {
      const Eigen::Vector3d d = points[nb.second].cast<double>() - p;
      const Eigen::Vector3d proj = d - d.dot(n) * n;  // onto the tangent plane
      if (proj.squaredNorm() < 1e-12) continue;
      angles.push_back(std::atan2(proj.dot(v), proj.dot(u)));
    }
    if (angles.size() < 2) {
      out[j] = 1;
      continue;
    }
    std::sort(angles.begin(), angles.end());
    double gap = 2 * M_PI - (angles.back() - angles.front());
    for (std::size_t m = 1; m < angles.size(); ++m) gap = std::max(gap, angles[m] - angles[m - 1]);
    out[j] = gap > thr;
  }
  return out;
}

namespace {

// Evidence counts of one cell of a wall's grid.
struct Cell {
  int face = 0, out = 0, through = 0, front = 0, recess = 0;  // out: face points standing out (trim)
  bool empty_in_view = false;  // no return at all, inside a camera frame's view: nothing there in range
};

// d values near 0 towards -t at a jamb: the run of depths from the face
// inwards without a gap of more than 3 cm is the wall's thickness.
double thicknessFrom(std::vector<double> depth, double start) {
  if (depth.size() < 5) return 0;
  std::sort(depth.begin(), depth.end());
  double last = start;
  for (double d : depth) {
    if (d - last > 0.03) break;
    last = d;
  }
  return last;
}

// (3) of findDoorways: panels set back from the wall around them. Where a
// face is noisy at the scale of a door's recess (a depth camera at range:
// depth steps of several centimetres, and a face that bends by as much),
// the face is read column by column against the same column's wall above
// a door's head: a run of columns a door wide whose body lies at least
// max(0.1 m, 2 tolerances) behind it, with the wall level again beside it
// on both sides, is a doorway with its leaf (or nothing) set back. Returns
// (s0, s1, depth) of each run. Needs the wall seen above a door's head.
struct SetBack {
  double s0, s1, depth;
};
std::vector<SetBack> setBackPanels(const Points& points, const segmentation::WallPlane& wall, double floor_z,
                                   double top_z, double d_view, double s_lo, double cell,
                                   const std::vector<double>& col_tol, const Parameters& p) {
  constexpr double kHead0 = 2.3, kReach = 0.5;
  // Below the ceiling (or the top of what was seen) and its points.
  const double kHead1 = std::min(2.8, top_z - floor_z - 0.1);
  const int cols = static_cast<int>(col_tol.size());
  if (kHead1 < kHead0 + 0.1 || cols < 3) return {};
  std::vector<std::vector<float>> body(cols), head(cols);
  for (const auto& pt : points) {
    const double d = wall.signedDistance(pt);
    if (d < -kReach || d > kReach || d >= d_view) continue;
    const double h = pt.z() - floor_z;
    const bool in_body = h >= 0.25 && h <= 1.75, in_head = h >= kHead0 && h <= kHead1;
    if (!in_body && !in_head) continue;
    const double cf = std::floor((wall.along(pt) - s_lo) / cell);  // tested in double before the cast
    if (!(cf >= 0 && cf < cols)) continue;
    (in_body ? body : head)[static_cast<int>(cf)].push_back(static_cast<float>(d));
  }
  // Medians over three columns: the body's and the head's offsets.
  std::vector<float> pool;
  auto median3 = [&](const std::vector<std::vector<float>>& v, int c, double& out) {
    pool.clear();
    for (int k = std::max(0, c - 1); k <= std::min(cols - 1, c + 1); ++k) pool.insert(pool.end(), v[k].begin(), v[k].end());
    if (pool.size() < 8) return false;
    std::nth_element(pool.begin(), pool.begin() + pool.size() / 2, pool.end());
    out = pool[pool.size() / 2];
    return true;
  };
  std::vector<int> state(cols, 0);  // 1 set back, -1 level with the wall above, 0 unknown
  std::vector<double> depth(cols, 0.0);
  for (int c = 0; c < cols; ++c) {
    double b = 0, h = 0;
    if (!median3(body, c, b) || !median3(head, c, h)) continue;
    const double delta = std::max(0.1, 2 * col_tol[c]);
    depth[c] = h - b;
    state[c] = depth[c] >= delta ? 1 : std::abs(depth[c]) < delta / 2 ? -1 : 0;
  }
  std::vector<SetBack> out;
  const int beside = std::max(1, static_cast<int>(0.2 / cell));
  for (int c = 0; c < cols;) {
    if (state[c] != 1) {
      ++c;
      continue;
    }
    int e = c;
    while (e + 1 < cols && (state[e + 1] == 1 || (e + 2 < cols && state[e + 1] == 0 && state[e + 2] == 1))) ++e;
    auto levelNear = [&](int from, int step) {
      for (int k = 1; k <= beside; ++k) {
        const int j = from + step * k;
        if (j < 0 || j >= cols) return false;
        if (state[j] == -1) return true;
      }
      return false;
    };
    const double s0 = s_lo + c * cell, s1 = s_lo + (e + 1) * cell;
    if (s1 - s0 >= p.door_min_width - 0.1 && s1 - s0 <= p.door_max_width + 0.1 && levelNear(c, -1) && levelNear(e, 1)) {
      std::vector<double> dd(depth.begin() + c, depth.begin() + e + 1);
      std::nth_element(dd.begin(), dd.begin() + dd.size() / 2, dd.end());
      out.push_back({s0, s1, dd[dd.size() / 2]});
    }
    c = e + 1;
  }
  return out;
}

// Points of a cloud from which findDoorways reads them in two halves at once.
constexpr std::size_t kSplitPoints = 20000;

}  // namespace

// Standard errors of the wall's noise by which the mean offset of a trim
// leg or head stands out (by chance in one sub-column of about 30000; a
// cloud's walls hold about a thousand, a drive a hundred clouds).
constexpr double kLegZ = 4.0;
// m either side of a column within which its wall's noise is taken where quietest.
constexpr double kQuietReach = 1.0;
// Rows (5 cm) above and below an empty cell between a LiDAR's rings looked at for the rings next to it.
constexpr int kRingRows = 6;
// Points a trim leg out of the plane needs where its neighbours are seen.
constexpr int kLegMinPoints = 10;
// Face points a head of trim needs across its doorway to be told by their
// mean offset (in a camera frame; half as many on each side beside it).
constexpr int kHeadMeanMinPoints = 60;
// Elevation margin (tan) inside a camera frame's view for an empty cell to count as looked at.
constexpr float kInViewMargin = 0.01f;
// A run wider than a door, this share of whose unseen cells lie in the
// shadow of something in front: maybe a leaf's shadow over its doorway.
constexpr double kShadowRun = 0.8;

std::vector<Doorway> findDoorways(const Points& points, const segmentation::WallPlane& wall, double floor_z,
                                  double top_z, const Eigen::Vector3f& viewpoint, const Parameters& p,
                                  bool no_return_is_free, const segmentation::ViewTop* view) {
  const double cell = p.grid_cell, row_h = 0.05;
  const double s_lo = wall.s_min - 0.3, s_hi = wall.s_max + 0.3;
  const int cols = std::max(1, static_cast<int>(std::ceil((s_hi - s_lo) / cell)));
  const double z_span = std::min(top_z - floor_z, 2.6);
  const int rows = std::max(1, static_cast<int>(std::ceil(z_span / row_h)));
  if (cols > 20000) return {};
  std::vector<Cell> grid(static_cast<std::size_t>(cols) * rows);
  std::vector<int> front_diff(static_cast<std::size_t>(cols + 1) * (rows + 1), 0);
  // Trim is sought on sub-columns of half a cell, summed over the body.
  const int sub = 2 * cols;
  std::vector<int> face_d_out(sub, 0), face_d_n(sub, 0);
  std::vector<double> face_d_sum(sub, 0.0);
  const double d_view = wall.signedDistance(viewpoint);
  if (d_view <= 0) return {};
  auto cellIndex = [&](double s, double z) -> std::ptrdiff_t {  // the cell at (s, z), as an index; -1 for none
    const int c = util::floorToInt((s - s_lo) / cell), r = util::floorToInt((z - floor_z) / row_h);
    if (c < 0 || c >= cols || r < 0 || r >= rows) return -1;
    return static_cast<std::ptrdiff_t>(r) * cols + c;
  };
  const double footprint = std::max(p.voxel_size, 0.01);
  const int body0 = static_cast<int>(0.25 / row_h), body1 = std::min(rows, static_cast<int>(1.75 / row_h));
  // The lower body, below a window's sill (0.8 m and up): a doorway seen
  // through is seen through here too, where the floor runs on beyond it.
  const int low1 = std::min(body1, static_cast<int>(0.8 / row_h));
  // Face and trim counts above the body in rows a fifth as high (a 5 cm row
  // slid in 1 cm steps over them): a head's trim only 7 cm high fills no
  // 5 cm row of the grid when it straddles two.
  constexpr int kFine = 5;
  const int fine0 = body1 * kFine, fine_n = (rows - body1) * kFine;
  std::vector<std::pair<int, int>> head_fine(static_cast<std::size_t>(std::max(0, fine_n)) * cols, {0, 0});  // face, out
  // The face points' offsets summed in the same fine rows, in a camera
  // frame only: a depth camera's trim stands out of the wall by less than
  // its noise point by point, but clearly in the mean (rule (5) below).
  std::vector<double> head_fine_d(view ? head_fine.size() : 0, 0.0);
  // The wall's own noise sets how thick its face is: laser scans are
  // millimetre-sharp, depth-camera returns spread with range. The tolerance
  // is local: 2.5 sigma of the wall's inliers within half a metre along it.
  std::vector<double> col_tol(cols, p.face_tolerance);
  // The noise itself (sigma, from the same median deviation): what a mean
  // offset of n face points must exceed to stand out of the wall (trim legs).
  std::vector<double> col_sigma(cols, p.face_tolerance / 2.5);
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
  auto tolAt = [&](double s) {
    const int c = util::floorToInt((s - s_lo) / cell);
    return col_tol[std::clamp(c, 0, cols - 1)];
  };
  // Points at the wall's body height within its face and 0.6 m behind it
  // (near the wall), where the jambs and the wall's thickness are read
  // below, in point order: those within the face (tolAt) as positions
  // along the wall; those behind it by tolAt to 0.6 m as (position, depth).
  const double max_tol = *std::max_element(col_tol.begin(), col_tol.end());
  std::vector<double> face_along;
  std::vector<std::pair<double, double>> behind_face;
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
  // Rays of an organized cloud cross every cell near enough: at most one
  // cell size apart there. Farther, a cell without a return may lie between
  // two of them (a 64-beam LiDAR's rings are 7 cm apart 6 m off, a 16-beam's
  // 20 cm): not looked at, nothing told of it (lidar64 drive 1008: a plain
  // wall 6 m off, its cells between rings taken as seen through, made a doorway).
  // Between rings, a cell next to a ring that met the wall's face (in the
  // rows within one ring spacing above and below, at most kRingRows) is that
  // face, unsampled: not seen through.
  auto sampled = [&](const Eigen::Vector3f& q, int c, int r) {
    if (!view || view->ray_spacing <= 0) return true;
    const double gap = (q - view->viewpoint).norm() * view->ray_spacing;
    if (gap <= std::min(row_h, cell)) return true;
    const int k = std::min(kRingRows, static_cast<int>(std::ceil(gap / row_h)));
    for (int rr = std::max(0, r - k); rr <= std::min(rows - 1, r + k); ++rr)
      if (grid[static_cast<std::size_t>(rr) * cols + c].face) return false;
    return true;
  };
  auto cellCentre = [&](int c, int r) {
    const Eigen::Vector2d xy = wall.point + (s_lo + (c + 0.5) * cell) * wall.direction;
    return Eigen::Vector3f(static_cast<float>(xy.x()), static_cast<float>(xy.y()),
                           static_cast<float>(floor_z + (r + 0.5) * row_h));
  };
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
  std::vector<double> face(cols), expl(cols), casing_share(sub, 0.0);
  // Shares among the observed cells of a column: a camera may see nothing
  // at all through the upper part of a doorway (the room beyond out of range).
  for (int c = 0; c < cols; ++c) {
    int f = 0, e = 0;
    for (int r = body0; r < body1; ++r) {
      const Cell& g = grid[static_cast<std::size_t>(r) * cols + c];
      if (g.face) ++f;
      else if (g.through || g.front || g.recess || g.empty_in_view) ++e;
    }
    const int observed = f + e;
    const bool enough = observed >= std::max(4.0, 0.15 * nbody);
    face[c] = enough ? static_cast<double>(f) / observed : (f > 0 ? 1.0 : 0.0);
    expl[c] = enough ? static_cast<double>(e) / observed : 0.0;
  }
  // A mean offset of n face points stands out of the wall's noise when it
  // lies kLegZ standard errors out: a rotating LiDAR's 1.5-2 cm range noise
  // puts the mean of the handful of points a ring leaves in a sub-column
  // 8 mm out of the plane by chance, somewhere along every wall (lidar64
  // drive 1011: two such sub-columns a door's width apart made a closed
  // door of a plain wall).
  // The noise is the wall's quietest metre within kQuietReach of the column:
  // over a doorway the face's deviations hold its leaf and trim (sigma of
  // 3 cm beside 1 cm, lidar64 3002), and the noise itself changes slowly with range.
  std::vector<double> quiet_sigma(cols);
  {
    const int reach = std::max(1, static_cast<int>(std::lround(kQuietReach / cell)));
    for (int c = 0; c < cols; ++c)
      quiet_sigma[c] = *std::min_element(col_sigma.begin() + std::max(0, c - reach),
                                         col_sigma.begin() + std::min(cols - 1, c + reach) + 1);
  }
  auto significant = [&](int c, double offset, int n) {
    return offset * std::sqrt(static_cast<double>(n)) >= kLegZ * quiet_sigma[std::min(cols - 1, c / 2)];
  };
  // Trim: most face points of the sub-column stand out of the wall (a corner
  // with another wall mixes points at all offsets and stays below).
  for (int c = 0; c < sub; ++c)
    casing_share[c] = face_d_n[c] >= 5 && face_d_sum[c] / face_d_n[c] > p.casing_min_offset &&
                              significant(c, face_d_sum[c] / face_d_n[c], face_d_n[c])
                          ? static_cast<double>(face_d_out[c]) / face_d_n[c]
                          : 0.0;
  auto colS = [&](int c) { return s_lo + c * cell; };

  std::vector<Doorway> out;
  auto addCandidate = [&](double s0, double s1, bool casing) {
    if (s1 - s0 < p.door_min_width - 0.1 || s1 - s0 > p.door_max_width + 0.1) return;
    for (Doorway& d : out)  // merge with an overlapping candidate, the edges of paired legs win
      if (s0 < d.s1 && d.s0 < s1) {
        if (casing && !d.paired) d.s0 = s0, d.s1 = s1, d.casing = d.paired = true;
        return;
      }
    Doorway d;
    d.s0 = s0;
    d.s1 = s1;
    d.casing = d.paired = casing;
    out.push_back(d);
  };

  // (1) Trim legs: runs of sub-columns whose face points stand out of the
  // wall, paired across a doorway under a head of trim (the edges of two
  // cupboards or of a leaf touching the wall make legs, never a head).
  const double half = cell / 2;
  auto subS = [&](int c) { return s_lo + c * half; };
  std::vector<std::pair<int, int>> legs;
  for (int c = 0; c < sub;) {
    if (casing_share[c] < 0.6) {
      ++c;
      continue;
    }
    int e = c;
    while (e + 1 < sub && casing_share[e + 1] >= 0.6) ++e;
    const double w = (e - c + 1) * half;
    // Trim is a hand wide; a leaf just ajar stands out as little over a wider run.
    if (w <= 0.13) legs.push_back({c, e});
    c = e + 1;
  }
  // Trim seen against its neighbours: a depth camera's noise spreads the
  // wall's face over centimetres, and a leaf filling much of a small view
  // tilts or shifts the fitted plane by about the trim's depth, so "out of
  // the plane" fails; the mean depth of a sub-column (a hundred points or
  // more) still stands out from both sides, 8-14 cm off, by the trim's depth.
  {
    std::vector<double> mean(sub, std::numeric_limits<double>::quiet_NaN());
    for (int c = 0; c < sub; ++c)
      if (face_d_n[c] >= 30) mean[c] = face_d_sum[c] / face_d_n[c];
    auto side = [&](int a, int b) {  // mean of the valid means in [a, b]
      double sum = 0;
      int n = 0;
      for (int k = std::max(0, a); k <= std::min(sub - 1, b); ++k)
        if (std::isfinite(mean[k])) sum += mean[k], ++n;
      return n >= 2 ? sum / n : std::numeric_limits<double>::quiet_NaN();
    };
    // A leg out of the plane needs kLegMinPoints points where a neighbour
    // 8-14 cm off is seen (a sub-column the voxel grid left with a handful
    // of points stands out by chance).
    legs.erase(std::remove_if(legs.begin(), legs.end(),
                              [&](const std::pair<int, int>& g) {
                                int n = 0;
                                for (int k = g.first; k <= g.second; ++k) n += face_d_n[k];
                                const bool sides_seen = std::isfinite(side(g.first - 7, g.first - 4)) ||
                                                        std::isfinite(side(g.second + 4, g.second + 7));
                                return sides_seen && n < kLegMinPoints;
                              }),
               legs.end());
    auto stands_out = [&](int c) {
      const double l = side(c - 7, c - 4), r = side(c + 4, c + 7);
      return std::isfinite(mean[c]) && std::isfinite(l) && std::isfinite(r) &&
             mean[c] - std::max(l, r) >= p.casing_min_offset && significant(c, mean[c] - std::max(l, r), face_d_n[c]);
    };
    for (int c = 0; c < sub;) {
      if (!stands_out(c)) {
        ++c;
        continue;
      }
      int e = c;
      while (e + 1 < sub && stands_out(e + 1)) ++e;
      const bool known = std::any_of(legs.begin(), legs.end(), [&](const std::pair<int, int>& g) {
        return g.first <= e && c <= g.second;
      });
      if (!known && e > c && (e - c + 1) * half <= 0.13) legs.push_back({c, e});
      c = e + 1;
    }
    std::sort(legs.begin(), legs.end());
  }
  // 1: trim runs across the doorway above the body; 0: the rows there show
  // wall without trim; -1: nothing is seen there (a camera's view ends lower).
  constexpr double kHeadSeenFrom = 2.25;  // m above the floor: above the highest door head with its trim
  // The fine head cells of columns c0..c1 summed over the row of kFine fine
  // rows from w0: face points, those standing out, columns holding face
  // points, and (camera frames) the face points' summed offsets.
  struct HeadRow {
    int face = 0, out = 0, columns = 0;
    double offset = 0;
  };
  auto headRow = [&](int c0, int c1, int w0) {
    HeadRow h;
    for (int c = c0; c <= c1; ++c) {
      int cf = 0;
      for (int j = w0; j < w0 + kFine; ++j) {
        const std::size_t k = static_cast<std::size_t>(j) * cols + c;
        cf += head_fine[k].first;
        h.out += head_fine[k].second;
        if (!head_fine_d.empty()) h.offset += head_fine_d[k];
      }
      h.face += cf;
      h.columns += cf > 0;
    }
    return h;
  };
  auto headState = [&](double a, double b) {
    const int c0 = std::max(0, static_cast<int>((a - s_lo) / cell)), c1 = std::min(cols - 1, static_cast<int>((b - s_lo) / cell));
    const int ncols = c1 - c0 + 1;
    std::vector<int> row_covered(rows, 0);  // columns of the doorway the face shows in, per row
    for (int r = body1; r < rows; ++r)
      for (int c = c0; c <= c1; ++c) row_covered[r] += grid[static_cast<std::size_t>(r) * cols + c].face > 0;
    std::vector<int> above;
    bool seen = false;
    for (int r = body1; r < rows; ++r) {
      const int covered = row_covered[r];
      // Rows below a door's head show its leaf or opening, not the head:
      // only rows from kHeadSeenFrom up tell that a head would have been seen.
      if (r * row_h >= kHeadSeenFrom) seen |= covered >= 0.3 * ncols;
      // Trim across most of the doorway, not a few trim points at its edge.
      // "Most" is judged against what the scan could show: a scanner's
      // vertical scan lines sparser than the columns (a sparse scan, a wall
      // far off or seen obliquely) leave the same columns empty in every
      // row. Where the wall above (from the second row up, the median of the
      // rows it shows in) shows in at most half the columns, the trim need
      // show in only half as many as elsewhere (seed 1014 at 100k rays).
      double share = 0.6;
      above.clear();
      for (int k = r + 2; k < rows; ++k)
        if (row_covered[k] > 0) above.push_back(row_covered[k]);
      if (above.size() >= 3) {
        std::nth_element(above.begin(), above.begin() + above.size() / 2, above.end());
        if (above[above.size() / 2] <= 0.5 * ncols) share = 0.3;
      }
      // The row and the row slid up by k fifths of its height: a trim 7 cm
      // high straddling two rows fills at most 70 % of either (seed 1018 at
      // 1M rays: 68 % and 63 %), but all of a row slid into it.
      for (int k = 0; k < kFine; ++k) {
        const int w0 = (r - body1) * kFine + k;  // first fine row of the (slid) row
        if (w0 + kFine > fine_n) break;
        const HeadRow h = headRow(c0, c1, w0);
        // (with the offsets known, their mean stands out of the noise as a leg's must)
        const bool stands_out = head_fine_d.empty() || significant(2 * ((c0 + c1) / 2), h.offset / h.face, h.face);
        if (h.face >= 5 && h.out >= 0.7 * h.face && h.columns >= share * ncols && stands_out) return 1;
      }
    }
    return seen ? 0 : -1;
  };
  auto hasHead = [&](double a, double b) { return headState(a, b) == 1; };
  for (std::size_t i = 0; i + 1 < legs.size(); ++i) {
    const double a = subS(legs[i].second + 1), b = subS(legs[i + 1].first);
    // Without a view of the head, both legs must be clearly trim: two sub-columns wide.
    const int head = headState(a, b);
    const bool strong_legs = legs[i].second > legs[i].first && legs[i + 1].second > legs[i + 1].first;
    if (b - a >= p.door_min_width - 0.1 && b - a <= p.door_max_width + 0.1 && (head == 1 || (head == -1 && strong_legs))) {
      addCandidate(a, b, true);
      ++i;
    }
  }

  // A cell without face: seen through it (a return behind the plane, far or
  // near), or only shadowed (something in front, nothing behind).
  auto seenThrough = [](const Cell& g) { return g.through != 0 || g.recess != 0; };
  auto shadowOnly = [](const Cell& g) { return g.front != 0 && g.through == 0 && g.recess == 0; };
  // Sub-runs of columns [lo, hi] seen through (through or recess cells at
  // least twice the shadowed ones over the body), bridging single columns
  // of neither and pairs of columns with no evidence at all, that lie
  // between one end of the run (where the wall's face resumes: a jamb; up
  // to two columns of neither beyond them) and a shadow (the reverse) at
  // least kMinShadowCols wide: as column ranges [first, last + 1).
  // shadow_side -1: only parts with the shadow towards lo (the jamb at hi),
  // +1: towards hi, 0: either.
  constexpr int kMinShadowCols = 3;
  auto throughBesideShadow = [&](int lo, int hi, int shadow_side) {
    auto kindOf = [&](int k) {  // 1 seen through, 2 shadow, 0 mixed, -1 nothing seen
      int tr = 0, sh = 0;
      for (int r = body0; r < body1; ++r) {
        const Cell& g = grid[static_cast<std::size_t>(r) * cols + k];
        if (g.face) continue;
        tr += seenThrough(g);
        sh += shadowOnly(g);
      }
      if (tr + sh == 0) return -1;
      return tr >= 2 * sh ? 1 : sh >= 2 * tr ? 2 : 0;
    };
    const int n = hi - lo + 1;
    std::vector<int> kind(n);
    for (int k = 0; k < n; ++k) kind[k] = kindOf(lo + k);
    // kMinShadowCols shadow columns from k on, in direction step; columns
    // with no evidence at all (-1: in a laser scan, the gaps between a
    // sparse scan's vertical scan lines, every second or third 4 cm column
    // at 33k rays 3 m off) are passed over, up to two at a time.
    auto shadowFrom = [&](int k, int step) {
      int found = 0, gap = 0;
      for (; k >= 0 && k < n && found < kMinShadowCols; k += step) {
        if (kind[k] == 2) found++, gap = 0;
        else if (kind[k] == -1 && ++gap <= 2) continue;
        else return false;
      }
      return found == kMinShadowCols;
    };
    std::vector<std::pair<int, int>> parts;
    for (int a = 0; a < n;) {
      if (kind[a] != 1) {
        ++a;
        continue;
      }
      int b = a;
      // (two columns no ray reached at all are bridged too: see shadowFrom)
      while (b + 1 < n && kind[b + 1] != 2 &&
             (kind[b + 1] == 1 || (b + 2 < n && kind[b + 2] == 1) ||
              (b + 3 < n && kind[b + 1] == -1 && kind[b + 2] == -1 && kind[b + 3] == 1)))
        ++b;
      // At an end of the run: at most two columns beyond, neither seen
      // through nor shadow (the jamb's edge, seen in part).
      auto endWithin = [&](int from, int to) {
        for (int k = from; k != to; k += from < to ? 1 : -1)
          if (kind[k] > 0) return false;
        return std::abs(to - from) <= 2;
      };
      if ((shadow_side >= 0 && endWithin(a - 1, -1) && shadowFrom(b + 1, 1)) ||
          (shadow_side <= 0 && endWithin(b + 1, n) && shadowFrom(a - 1, -1)))
        parts.push_back({lo + a, lo + b + 1});
      a = b + 1;
    }
    return parts;
  };
  // (2) Openings: body without face but with evidence of what lies beyond.
  auto open = [&](int c) { return face[c] < 0.3 && expl[c] >= 0.4; };
  for (int c = 0; c < cols;) {
    if (!open(c)) {
      ++c;
      continue;
    }
    // A camera sees nothing through parts of a doorway whose room beyond is
    // out of range: unobserved columns belong to the run when open columns
    // or a wall face bound them (within 0.6 m), never the unseen ends of the wall.
    auto unseen = [&](int k) { return face[k] == 0 && expl[k] == 0; };
    const int reach_cols = static_cast<int>(0.6 / cell);
    int e = c;
    for (;;) {
      int k = e + 1;
      while (k < cols && k - e <= reach_cols && unseen(k)) ++k;
      if (k < cols && k - e <= reach_cols + 1 && open(k)) {
        e = k;
        continue;
      }
      // Bridge one weak column (noise), never a column of wall face: a hinge
      // jamb between a doorway and the shadow of its leaf ends the run.
      if (e + 2 < cols && face[e + 1] < 0.5 && open(e + 2)) {
        e += 2;
        continue;
      }
      break;
    }
    int lo = c, hi = e;
    {
      int k = c - 1;
      while (k >= 0 && c - k <= reach_cols && unseen(k)) --k;
      if (k >= 0 && k < c - 1 && face[k] >= 0.3) lo = k + 1;
      k = e + 1;
      while (k < cols && k - e <= reach_cols && unseen(k)) ++k;
      if (k < cols && k > e + 1 && face[k] >= 0.3) hi = k - 1;
    }
    // Jambs where the face points end, refined from the points themselves.
    double s0 = colS(lo), s1 = colS(hi + 1);
    std::vector<double> left, right;
    for (const double a : face_along) {
      if (a > s0 - 0.12 && a < s0 + 0.06) left.push_back(a);
      if (a > s1 - 0.06 && a < s1 + 0.12) right.push_back(a);
    }
    if (left.size() >= 5) {
      std::sort(left.begin(), left.end());
      s0 = left[left.size() * 97 / 100];
    }
    if (right.size() >= 5) {
      std::sort(right.begin(), right.end());
      s1 = right[right.size() * 3 / 100];
    }
    // A run seen through over a door's width on one side and lying in the
    // shadow of something in front on the other: a leaf swung towards the
    // sensor, seen through its doorway, shadows the wall beyond its hinge,
    // and a sparse scan may show no face at the hinge jamb between the two
    // (the station beyond room 1001's door at 50k rays). The part seen
    // through, beside the shadow, is a doorway candidate; the leaf search
    // decides (and moves the hinge, as the shadow's edge is not the jamb).
    // At a grid end (shadow_side set), a part only within the wall's face
    // seen (a column of play): the shadow covers the wall's continuation
    // beyond its end; past that end, seen through, is the end of whatever
    // the plane met (beyond-400k 5027: a wardrobe's face, 3 columns of
    // shadow past it, gave a door there).
    auto addPartsSeenThrough = [&](int shadow_side) {
      for (const auto& [a, b] : throughBesideShadow(lo, hi, shadow_side)) {
        if (shadow_side < 0 && colS(a) < wall.s_min - cell) continue;
        if (shadow_side > 0 && colS(b) > wall.s_max + cell) continue;
        addCandidate(a == lo ? s0 : colS(a), b == hi + 1 ? s1 : colS(b), false);
      }
    };
    // A run a little wider than a door is itself a candidate, which would
    // take the place of a part overlapping it: the parts go first (1027 at
    // 33k rays: a doorway and its leaf's shadow 1.50 m wide, the leaf fitted
    // 28 deg off across both and the doorway refused as too wide).
    // So is a run no wider than that which reaches an end of the grid (0.3 m
    // past the wall's face seen): its edge there is no jamb when the wall
    // beyond lies in a leaf's shadow (4023 at 33k rays: a leaf open 121 deg
    // towards the station shadows the wall's last 0.3 m; the run ran 1.14 m
    // for 0.76); only parts with the shadow towards that end.
    const bool just_too_wide = s1 - s0 > p.door_max_width && s1 - s0 <= p.door_max_width + 0.1;
    const int grid_end = lo == 0 && hi < cols - 1 ? -1 : hi == cols - 1 && lo > 0 ? 1 : 0;
    if (d_view > 0.1 && just_too_wide) addPartsSeenThrough(0);
    else if (d_view > 0.1 && grid_end != 0 && s1 - s0 <= p.door_max_width + 0.1) addPartsSeenThrough(grid_end);
    addCandidate(s0, s1, false);
    // A run wider than any door, hidden from the sensor by something in
    // front: a leaf swung towards the sensor shadows its doorway and the wall
    // beyond it. Its hinge jamb is the run's end nearer the sensor; the
    // doorway from there, a widest door long, is left to the leaf search
    // (which takes it only if the leaf is what hides it).
    if (s1 - s0 > p.door_max_width + 0.1 && d_view > 0.1) {
      int fr = 0, ex = 0;
      for (int k = lo; k <= hi; ++k)
        for (int r = body0; r < body1; ++r) {
          const Cell& g = grid[static_cast<std::size_t>(r) * cols + k];
          if (g.face) continue;
          ex += seenThrough(g) || g.front;
          fr += shadowOnly(g);
        }
      const double vs = wall.along(viewpoint);
      if (ex > 0 && fr >= kShadowRun * ex && (vs < s0 || vs > s1)) {
        const std::size_t before = out.size();
        if (vs < s0) addCandidate(s0, s0 + p.door_max_width, false);
        else addCandidate(s1 - p.door_max_width, s1, false);
        if (out.size() > before) out.back().shadow_end = true;
      }
      addPartsSeenThrough(0);
    }
    c = e + 1;
  }

  // (3) Panels set back from a noisy face (see setBackPanels), first: a
  // run of (4) overlapping one of them merges into it. Only in camera frames
  // (no_return_is_free): a laser's face is millimetre-sharp, and the pass
  // over every point near the wall costs a laser room milliseconds per wall.
  const std::vector<SetBack> panels =
      no_return_is_free ? setBackPanels(points, wall, floor_z, top_z, d_view, s_lo, cell, col_tol, p) : std::vector<SetBack>{};
  for (const SetBack& sb : panels) {
    const std::size_t before = out.size();
    addCandidate(sb.s0, sb.s1, false);
    if (out.size() > before) out.back().set_back = sb.depth;
  }

  // (4) A leaf set back in its doorway, seen through depth noise that puts
  // it within the wall's face tolerance (a depth camera a few metres off):
  // runs of sub-columns whose face points lie, on average, kSetBack or more
  // behind the face (the mean of a hundred points is sharp where single
  // points are not).
  constexpr double kSetBack = 0.025;
  for (int c = 0; c < sub;) {
    auto behind = [&](int k) { return face_d_n[k] >= 10 && face_d_sum[k] / face_d_n[k] <= -kSetBack; };
    if (!behind(c)) {
      ++c;
      continue;
    }
    int e = c;
    while (e + 1 < sub && behind(e + 1)) ++e;
    addCandidate(subS(c), subS(e + 1), false);
    c = e + 1;
  }
  // (4b) The same in a camera frame, where a leaf filling much of the wall
  // seen pulls the fitted plane towards itself: a leaf 7 cm behind the face
  // 2.2 m off lies 2 cm behind the plane and the face 2 cm before it (rgbd
  // 5008). Runs kSetBack or more behind the median of the sub-columns'
  // means (the face, where the wall shows more than the leaf), each judged
  // against its own sides: the mean of the sub-columns 12-30 cm beyond each
  // edge stands kSetBack or more before the run's mean (a plane turned a
  // little about the vertical tilts the sides alike). Only where no other
  // candidate lies.
  if (view) {
    auto meanAt = [&](int k) { return face_d_sum[k] / face_d_n[k]; };
    std::vector<double> means;
    for (int k = 0; k < sub; ++k)
      if (face_d_n[k] >= 10) means.push_back(meanAt(k));
    if (means.size() >= 10) {
      std::nth_element(means.begin(), means.begin() + means.size() / 2, means.end());
      const double face_level = means[means.size() / 2];
      auto behind = [&](int k) { return face_d_n[k] >= 10 && meanAt(k) <= face_level - kSetBack; };
      // The mean over sub-columns [k0, k1] holding 10 points or more; NaN with fewer than 3 of them.
      auto meanOver = [&](int k0, int k1) {
        double sum = 0;
        int n = 0;
        for (int k = std::max(0, k0); k <= std::min(sub - 1, k1); ++k)
          if (face_d_n[k] >= 10) sum += meanAt(k), ++n;
        return n >= 3 ? sum / n : std::numeric_limits<double>::quiet_NaN();
      };
      const int near = static_cast<int>(std::lround(0.12 / half)), far = static_cast<int>(std::lround(0.30 / half));
      for (int c = 0; c < sub;) {
        if (!behind(c)) {
          ++c;
          continue;
        }
        int e = c;
        while (e + 1 < sub && behind(e + 1)) ++e;
        const double a = subS(c), b = subS(e + 1);
        const double run = meanOver(c, e), left = meanOver(c - far, c - near), right = meanOver(e + near, e + far);
        if (left - run >= kSetBack && right - run >= kSetBack &&
            std::none_of(out.begin(), out.end(), [&](const Doorway& d) { return a < d.s1 && d.s0 < b; }))
          addCandidate(a, b, false);
        c = e + 1;
      }
      // A candidate narrower than a door whose set-back run goes on beside
      // it (a leaf ajar in a recess: its hinge end within the face
      // tolerance, set back in the mean only, its latch end beyond the
      // tolerance, rgbd 3027) is widened over that run, when that makes it a door wide.
      for (Doorway& d : out) {
        if (d.paired || d.s1 - d.s0 >= p.door_min_width) continue;
        int a = static_cast<int>(std::floor((d.s0 - s_lo) / half)), b = static_cast<int>(std::ceil((d.s1 - s_lo) / half)) - 1;
        while (a - 1 >= 0 && behind(a - 1)) --a;
        while (b + 1 < sub && behind(b + 1)) ++b;
        const double s0 = std::min(d.s0, subS(a)), s1 = std::max(d.s1, subS(b + 1));
        if (s1 - s0 >= p.door_min_width && s1 - s0 <= p.door_max_width) d.s0 = s0, d.s1 = s1;
      }
    }
  }

  // (5) In a camera frame, trim legs paired under a head that stands out
  // only in the mean: depth noise of 1-3 cm (a closed door 3-3.6 m off)
  // hides trim 1.8 cm deep point by point, so (1) finds no head, while the
  // mean of a few hundred points stands out by 10-18 mm (rgbd 1020, 1022,
  // 4002, 5014). Per row 5 cm high (slid in 1 cm steps, with points in 60 %
  // of the doorway's columns): the mean offset of the face points
  // across the doorway less the mean of the two sides' means, the same rows
  // 12-30 cm beyond its edges (a plane turned a little about the vertical
  // tilts both sides alike, and the rows share any tilt about the
  // horizontal). A head: the best row stands out by casing_min_offset, and
  // by as much from the median row. Legs door_min_width to door_max_width
  // apart (without (1)'s 10 cm of margin). Only where no other candidate lies:
  // noisy legs put a doorway's edges a few centimetres off, worse than the
  // other rules' where they find it (rgbd 4009, 5011, 5024).
  if (view) {
    auto meanHead = [&](double a, double b) {
      const int c0 = std::max(0, static_cast<int>((a - s_lo) / cell)), c1 = std::min(cols - 1, static_cast<int>((b - s_lo) / cell));
      const int ncols = c1 - c0 + 1;
      std::vector<double> diffs;  // per slid row: the doorway's mean offset less its sides'
      double peak = -std::numeric_limits<double>::infinity();
      for (int w0 = 0; w0 + kFine <= fine_n; ++w0) {
        const HeadRow h = headRow(c0, c1, w0);
        if (h.face < kHeadMeanMinPoints || h.columns < 0.6 * ncols) continue;
        double ref = 0;
        int sides = 0;
        for (int side = 0; side < 2; ++side) {
          const double lo = side == 0 ? a - 0.30 : b + 0.12, hi = side == 0 ? a - 0.12 : b + 0.30;
          const int k0 = std::max(0, static_cast<int>(std::ceil((lo - s_lo) / cell)));
          const int k1 = std::min(cols - 1, static_cast<int>(std::floor((hi - s_lo) / cell)) - 1);
          const HeadRow sd = headRow(k0, k1, w0);
          if (sd.face >= kHeadMeanMinPoints / 2) ref += sd.offset / sd.face, ++sides;
        }
        if (sides < 2) continue;
        diffs.push_back(h.offset / h.face - ref / 2);
        peak = std::max(peak, diffs.back());
      }
      if (diffs.size() < 3) return false;
      std::nth_element(diffs.begin(), diffs.begin() + diffs.size() / 2, diffs.end());
      return peak >= p.casing_min_offset && peak - diffs[diffs.size() / 2] >= p.casing_min_offset;
    };
    for (std::size_t i = 0; i + 1 < legs.size(); ++i) {
      const double a = subS(legs[i].second + 1), b = subS(legs[i + 1].first);
      if (b - a < p.door_min_width || b - a > p.door_max_width) continue;
      if (std::any_of(out.begin(), out.end(), [&](const Doorway& d) { return a < d.s1 && d.s0 < b; })) continue;
      if (!meanHead(a, b)) continue;
      addCandidate(a, b, true);
      ++i;
    }
  }

  // Shares, head and thickness of every candidate.
  for (Doorway& d : out) {
    // An opening with a trim leg at one of its edges and a head above: the
    // other leg may hide behind a leaf swung towards the sensor, and a leaf
    // ajar hides its own doorway near the hinge; the head spans the doorway
    // from leg to leg, so the doorway is snapped to it.
    if (!d.casing && !d.shadow_end)
      for (const auto& leg : legs) {
        const double inner_right = subS(leg.second + 1), inner_left = subS(leg.first);
        if ((std::abs(inner_right - d.s0) < 0.12 || std::abs(inner_left - d.s1) < 0.12) && hasHead(d.s0, d.s1)) {
          d.casing = true;
          const double leg_w = std::max(half, (leg.second - leg.first + 1) * half);
          // The head row: the row above the body with the most trim cells.
          int best_r = -1, best_n = 0;
          const int cm = static_cast<int>(((d.s0 + d.s1) / 2 - s_lo) / cell);
          for (int r = body1; r < rows; ++r) {
            int n = 0;
            for (int c = std::max(0, cm - 40); c <= std::min(cols - 1, cm + 40); ++c) {
              const Cell& g = grid[static_cast<std::size_t>(r) * cols + c];
              n += g.face > 0 && g.out >= 0.6 * g.face;
            }
            if (n > best_n) best_n = n, best_r = r;
          }
          if (best_r >= 0) {
            auto trim = [&](int c) {
              const Cell& g = grid[static_cast<std::size_t>(best_r) * cols + c];
              return g.face > 0 && g.out >= 0.6 * g.face;
            };
            auto unseen = [&](int c) { return grid[static_cast<std::size_t>(best_r) * cols + c].face == 0; };
            int lo = std::clamp(cm, 0, cols - 1), hi = lo;
            while (lo > 0 && (trim(lo - 1) || (lo > 1 && unseen(lo - 1) && trim(lo - 2)))) --lo;
            while (hi + 1 < cols && (trim(hi + 1) || (hi + 2 < cols && unseen(hi + 1) && trim(hi + 2)))) ++hi;
            const double a = colS(lo) + leg_w, b = colS(hi + 1) - leg_w;
            if (b - a >= p.door_min_width - 0.1 && b - a <= p.door_max_width + 0.1 && a <= d.s0 + 0.1 && b >= d.s1 - 0.1) {
              d.s0 = a;
              d.s1 = b;
            }
          }
          break;
        }
      }
    const int c0 = std::max(0, static_cast<int>((d.s0 - s_lo) / cell) + 1);
    const int c1 = std::min(cols - 1, static_cast<int>((d.s1 - s_lo) / cell) - 1);
    int n = 0, f = 0, t = 0, fr = 0, re = 0, low_through = 0;
    for (int c = c0; c <= c1; ++c)
      for (int r = body0; r < body1; ++r) {
        const Cell& g = grid[static_cast<std::size_t>(r) * cols + c];
        ++n;
        const bool empty_seen = !g.face && !g.recess && !g.front && no_return_is_free && sampled(cellCentre(c, r), c, r);
        const bool through = g.through || empty_seen;
        if (g.face) ++f;
        else if (g.through) ++t;
        else if (g.recess) ++re;
        else if (g.front) ++fr;
        else if (empty_seen) ++t;  // a camera got nothing back in range: nothing is there
        low_through += through && r < low1;
      }
    d.low_through = low_through > 0;
    n = f + t + fr + re;  // observed cells
    if (n > 0) {
      d.face = static_cast<double>(f) / n;
      d.through = static_cast<double>(t) / n;
      d.front = static_cast<double>(fr) / n;
      d.recess = static_cast<double>(re) / n;
    }
    d.top = std::numeric_limits<double>::quiet_NaN();
    // The head: the first row above the body where the wall's face spans the
    // doorway, clearly more of it than the body's own face share (a leaf
    // closed a few centimetres behind the face shows in part within it).
    const double head_share = std::clamp(d.face + 0.3, 0.5, 0.9);
    for (int r = body1; r < rows && c1 >= c0; ++r) {
      int rf = 0;
      for (int c = c0; c <= c1; ++c) rf += grid[static_cast<std::size_t>(r) * cols + c].face > 0;
      if (rf >= head_share * (c1 - c0 + 1) && (d.face < 0.5 || r * row_h > 1.9)) {
        d.top = floor_z + r * row_h;
        break;
      }
    }
    std::vector<double> depth_l, depth_r;
    for (const auto& [a, dd] : behind_face) {
      if (std::abs(a - d.s0) < 0.03) depth_l.push_back(dd);
      if (std::abs(a - d.s1) < 0.03) depth_r.push_back(dd);
    }
    d.thickness = std::max(thicknessFrom(depth_l, tolAt(d.s0)), thicknessFrom(depth_r, tolAt(d.s1)));
  }
  return out;
}

}  // namespace recognition
}  // namespace dsr
