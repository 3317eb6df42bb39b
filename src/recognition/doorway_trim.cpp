// Recognition: trim (door casing) in findDoorways: legs, runs of
// sub-columns whose face points stand out of the wall, paired across a
// doorway under a head of trim ((1), and (5) in camera frames by the mean).
#include "doorway_search.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

namespace dsr {
namespace recognition {
namespace detail {

// Standard errors of the wall's noise by which the mean offset of a trim
// leg or head stands out (by chance in one sub-column of about 30000; a
// cloud's walls hold about a thousand, a drive a hundred clouds).
constexpr double kLegZ = 4.0;
// m either side of a column within which its wall's noise is taken where quietest.
constexpr double kQuietReach = 1.0;
// Points a trim leg out of the plane needs where its neighbours are seen.
constexpr int kLegMinPoints = 10;
// Face points a head of trim needs across its doorway to be told by their
// mean offset (in a camera frame; half as many on each side beside it).
constexpr int kHeadMeanMinPoints = 60;
// A column of the grid is an opening's when this share of its seen body
// cells (kOpenMinCells at least) or more is seen through (rays past the
// wall's plane, a reveal behind it, or none back inside a camera's view),
// not its face; a leaf swung towards the sensor, hiding the wall beside its
// doorway, is no opening (rgbd-structured-robot 1026: a closed door beside
// it). Sought within kOpenBeyondColumns (4 cm each) beyond a trim leg.
constexpr double kOpenThrough = 0.6;
constexpr int kOpenMinCells = 4, kOpenBeyondColumns = 2;

void DoorwaySearch::findTrimLegs() {
  // The noise is the wall's quietest metre within kQuietReach of the column:
  // over a doorway the face's deviations hold its leaf and trim (sigma of
  // 3 cm beside 1 cm, lidar64 3002), and the noise itself changes slowly with range.
  quiet_sigma.assign(cols, 0.0);
  {
    const int reach = std::max(1, static_cast<int>(std::lround(kQuietReach / cell)));
    for (int c = 0; c < cols; ++c)
      quiet_sigma[c] = *std::min_element(col_sigma.begin() + std::max(0, c - reach),
                                         col_sigma.begin() + std::min(cols - 1, c + reach) + 1);
  }
  // Trim: most face points of the sub-column stand out of the wall (a corner
  // with another wall mixes points at all offsets and stays below).
  for (int c = 0; c < sub; ++c)
    casing_share[c] = face_d_n[c] >= 5 && face_d_sum[c] / face_d_n[c] > p.casing_min_offset &&
                              significant(c, face_d_sum[c] / face_d_n[c], face_d_n[c])
                          ? static_cast<double>(face_d_out[c]) / face_d_n[c]
                          : 0.0;

  // (1) Trim legs: runs of sub-columns whose face points stand out of the
  // wall, paired across a doorway under a head of trim (the edges of two
  // cupboards or of a leaf touching the wall make legs, never a head).
  half = cell / 2;
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
      // A leg found by (1) in part (noise leaves some of its sub-columns
      // short of the share) spans the run standing out of its neighbours.
      bool known = false;
      for (std::pair<int, int>& g : legs)
        if (g.first <= e && c <= g.second) {
          known = true;
          if (e > c && (std::max(e, g.second) - std::min(c, g.first) + 1) * half <= 0.13)
            g = {std::min(c, g.first), std::max(e, g.second)};
        }
      if (!known && e > c && (e - c + 1) * half <= 0.13) legs.push_back({c, e});
      c = e + 1;
    }
    std::sort(legs.begin(), legs.end());
    // Legs of (1) widened into one run are one leg.
    std::vector<std::pair<int, int>> merged;
    for (const std::pair<int, int>& g : legs) {
      if (!merged.empty() && g.first <= merged.back().second) merged.back().second = std::max(merged.back().second, g.second);
      else merged.push_back(g);
    }
    legs.swap(merged);
  }
  // A leg with an opening just beyond its outer edge (one of the two
  // columns there seen through) is that opening's casing and pairs with no
  // leg on its other side: paired across the wall between two neighbouring
  // doorways, the trims of both read as a closed door there (the head out
  // of a rotating LiDAR's view: lidar16 drive 1023 cloud 18, lidar64 drive 1023).
  auto seenThrough = [&](int c) {
    return col_seen[c] >= kOpenMinCells && col_through[c] >= kOpenThrough * col_seen[c];
  };
  // The opening runs to the next leg beyond (or a narrowest door's width):
  // a doorway's, unless the rows above it show plain wall (a door's head
  // has trim or lies out of view; one 64-beam sweep of room 2008: the wall
  // beside a closed door, seen at a grazing 9 deg, "seen through" below
  // plain wall above).
  auto openBeyond = [&](std::size_t i, bool right) {
    const std::pair<int, int>& g = legs[i];
    bool open = false;
    for (int k = 1; k <= kOpenBeyondColumns && !open; ++k) {
      const int c = right ? g.second / 2 + k : g.first / 2 - k;
      open = c >= 0 && c < cols && seenThrough(c);
    }
    if (!open) return false;
    const double edge = right ? subS(g.second + 1) : subS(g.first);
    double far = right ? edge + p.door_min_width : edge - p.door_min_width;
    if (right && i + 1 < legs.size() && subS(legs[i + 1].first) - edge <= p.door_max_width + 0.1)
      far = subS(legs[i + 1].first);
    if (!right && i > 0 && edge - subS(legs[i - 1].second + 1) <= p.door_max_width + 0.1)
      far = subS(legs[i - 1].second + 1);
    return headState(std::min(edge, far), std::max(edge, far)) != 0;
  };
  for (std::size_t i = 0; i + 1 < legs.size(); ++i) {
    const double a = subS(legs[i].second + 1), b = subS(legs[i + 1].first);
    if (openBeyond(i, false) || openBeyond(i + 1, true)) continue;
    // Without a view of the head, both legs must be clearly trim: two sub-columns wide.
    const int head = headState(a, b);
    const bool strong_legs = legs[i].second > legs[i].first && legs[i + 1].second > legs[i + 1].first;
    if (b - a >= p.door_min_width - 0.1 && b - a <= p.door_max_width + 0.1 && (head == 1 || (head == -1 && strong_legs))) {
      addCandidate(a, b, true);
      ++i;
    }
  }
}

// A mean offset of n face points stands out of the wall's noise when it
// lies kLegZ standard errors out: a rotating LiDAR's 1.5-2 cm range noise
// puts the mean of the handful of points a ring leaves in a sub-column
// 8 mm out of the plane by chance, somewhere along every wall (lidar64
// drive 1011: two such sub-columns a door's width apart made a closed
// door of a plain wall).
bool DoorwaySearch::significant(int c, double offset, int n) const {
  return offset * std::sqrt(static_cast<double>(n)) >= kLegZ * quiet_sigma[std::min(cols - 1, c / 2)];
}

namespace {
// 1: trim runs across the doorway above the body; 0: the rows there show
// wall without trim; -1: nothing is seen there (a camera's view ends lower).
constexpr double kHeadSeenFrom = 2.25;  // m above the floor: above the highest door head with its trim
}  // namespace

DoorwaySearch::HeadRow DoorwaySearch::headRow(int c0, int c1, int w0) const {
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
}

int DoorwaySearch::headState(double a, double b) const {
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
}

bool DoorwaySearch::hasHead(double a, double b) const { return headState(a, b) == 1; }

void DoorwaySearch::pairLegsUnderMeanHead() {
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
}

}  // namespace detail
}  // namespace recognition
}  // namespace dsr
