// Recognition: doorways whose leaf (or panel) is set back from the wall's
// face in findDoorways ((3), (4), (4b)), told through a noisy face.
#include "doorway_search.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace dsr {
namespace recognition {
namespace detail {

namespace {

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

}  // namespace

void DoorwaySearch::findSetBackLeaves() {
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
}

}  // namespace detail
}  // namespace recognition
}  // namespace dsr
