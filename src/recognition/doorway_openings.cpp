// Recognition: openings in findDoorways ((2)): runs of columns without
// face over a door's body but with evidence of what lies beyond, and the
// parts of a run seen through beside a leaf's shadow.
#include "doorway_search.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

namespace dsr {
namespace recognition {
namespace detail {

// A run wider than a door, this share of whose unseen cells lie in the
// shadow of something in front: maybe a leaf's shadow over its doorway.
constexpr double kShadowRun = 0.8;

void DoorwaySearch::findOpenings() {
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
}

}  // namespace detail
}  // namespace recognition
}  // namespace dsr
