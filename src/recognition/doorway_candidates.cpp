// Recognition: findDoorways, its steps in turn (doorway_search.hpp), and
// its candidates: added and merged, then each one's shares, head and
// thickness measured.
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

namespace {

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

}  // namespace

double DoorwaySearch::colS(int c) const { return s_lo + c * cell; }
double DoorwaySearch::subS(int c) const { return s_lo + c * half; }

void DoorwaySearch::addCandidate(double s0, double s1, bool casing) {
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
}

void DoorwaySearch::measureCandidates() {
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
    int n = 0, f = 0, t = 0, fr = 0, re = 0, low_through = 0, low_seen = 0, low_past = 0;
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
        low_seen += r < low1 && (g.face || g.through || g.recess || g.front || empty_seen);
        low_past += r < low1 && !g.face && (through || g.recess);
      }
    d.low_through = low_through > 0;
    d.low_past_share = low_seen > 0 ? static_cast<double>(low_past) / low_seen : 0.0;
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
}

}  // namespace detail

std::vector<Doorway> findDoorways(const Points& points, const segmentation::WallPlane& wall, double floor_z,
                                  double top_z, const Eigen::Vector3f& viewpoint, const Parameters& p,
                                  bool no_return_is_free, const segmentation::ViewTop* view) {
  detail::DoorwaySearch search(points, wall, floor_z, top_z, viewpoint, p, no_return_is_free, view);
  if (!search.buildGrid()) return {};
  search.findTrimLegs();
  search.findOpenings();
  search.findSetBackLeaves();
  search.pairLegsUnderMeanHead();
  search.measureCandidates();
  return std::move(search.out);
}

}  // namespace recognition
}  // namespace dsr
