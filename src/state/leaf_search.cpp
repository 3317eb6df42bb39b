// State: fitLeaf's search of the leaf: hinge at either jamb (or moved off
// it), swing side, recess and angle, the global search every 2 deg, then
// the local search moving hinge and angle; the best hypothesis kept.
#include "leaf_internal.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace dsr {
namespace state {
namespace detail {

namespace {
// A leaf whose best hypothesis at the jambs holds points in fewer of its
// cells is sought with hinges outwards of them too.
constexpr double kRetryBelowCoverage = 0.5;
}  // namespace

void LeafSearch::searchHinges() {
  // Exhaustive search over hinge side, swing side and angle: cells of the
  // leaf holding points (support) against cells rays went through (contradiction).
  na = std::max(1, static_cast<int>(std::ceil(L / abin)));
  na_max = std::max(na, static_cast<int>(std::ceil(Lmax / abin)));
  // With both trim legs seen the leaf spans the doorway; otherwise its length is sought.
  na_min = door.paired ? std::max(1, na - 1)
                     : std::min(na, std::max(1, static_cast<int>(std::floor((p.door_min_width - 0.05) / abin))));
  band_hw = lt + tol;  // farthest a supporting point lies off the hinge line
  r_pts = std::hypot(Lmax, band_hw), r_rays = std::hypot(Lmax, lt / 2);
  cells = static_cast<std::size_t>(na_max) * nz;

  // A leaf swung towards the sensor hangs at its recess behind the face,
  // which jambs seen only in part can put deeper than the wall measured
  // there: its recesses go to the default wall thickness at least. Not in
  // a camera frame, whose depth noise a deeper hinge line fits as well.
  t_toward = view ? t : std::max(t, p.default_wall_thickness);
  for (double r = 0.0; r + lt <= t_toward + 1e-9 && recess_steps.size() < 4; r += 0.05) recess_steps.push_back(r);
  // A doorway sought from the end of a shadow wider than a door nearer the
  // sensor (Doorway::shadow_end) is there only as the leaf hinged at that
  // end and swung towards the sensor.
  shadow_h = std::abs(vsd.x() - door.s0) < std::abs(vsd.x() - door.s1) ? 0 : 1;
  best_h = 0, best_sw = 0;
  best_deg = 0, best_recess = 0, best_s = door.s0;
  // Global search: hinge at either jamb, either swing side, hinge on the
  // face or set back (recess), every 2 deg. The hinges are scored as tasks
  // (over the cores), the best taken in order. Support bounds a hypothesis's
  // score from above (contradiction only lowers it): rays are tested only at
  // the angles whose bound reaches the exact score of the best-bounded one,
  // the others cannot be the best.
  globalSearch(hingesAt(0.0), -std::numeric_limits<double>::infinity());
  // The doorway seen can end short of the hinge or run past it: a leaf
  // ajar hides the jamb at its hinge from a sensor on its swing side, and a
  // leaf swung past 90 deg towards the sensor shadows the wall beyond its
  // hinge, which then looks like doorway. Either way no angle at the jamb
  // fits the leaf. Where the best fits poorly and no trim pair fixes the
  // jambs, hinges up to 40 cm outwards and inwards of each jamb too (10 cm
  // apart, leaving at least the narrowest door between them). Not in a
  // camera frame: there a leaf is often seen only in part, and hinges moved
  // off the jambs fitted wrong leaves better (rgbd sweeps 2000 and 3000).
  if (!view && !door.paired && best.bins > 0 && best.cells < kRetryBelowCoverage * best.bins * nz) {
    std::vector<Hinge> more;
    for (int k = -4; k <= 4; ++k) {
      const double out = 0.1 * k;
      if (k == 0 || w + std::min(0.0, out) < p.door_min_width) continue;
      const std::vector<Hinge> at = hingesAt(out);
      more.insert(more.end(), at.begin(), at.end());
    }
    // Rays only where support could beat the best so far and reach the
    // least a leaf is taken with (half min_leaf_coverage, times sampling, of the shortest
    // leaf's cells, in a doorway beyond doubt): where no leaf is seen (a
    // doorway seen through, its leaf out of sight) that leaves few or none.
    globalSearch(more, std::max(best.score, 0.5 * p.min_leaf_coverage * fit.sampling * na_min * nz));
  }
  // Local search: the jamb seen from the wall can be off where a leaf hides
  // or shadows its own doorway; move the hinge along the wall and the angle.
  // It moves the angle by 2.5 deg at most: with the wall band full enough for
  // a closed leaf (band_cov >= 0.55, below) and the best angle below
  // closed_below_deg + 0.5, the leaf is taken closed in the band whatever it
  // finds, and nothing it finds is used (but best_*, which then tell the
  // global search's best): skipped.
  const bool closed_in_band_for_sure = band_cov >= 0.55 && best_deg + 2.5 < p.closed_below_deg + 3;
  if (!closed_in_band_for_sure) {
    const double e0 = best_h == 0 ? 1.0 : -1.0, m = best_sw == 0 ? 1.0 : -1.0;
    const double d_h = best_sw == 0 ? -best_recess : -t + best_recess;
    const double s_center = best_s, deg_center = best_deg;
    const int reach_steps = door.paired ? 3 : 15;  // 2 cm steps
    const double start = deg_center - 2.5, step = 0.5;
    std::vector<HingeRun> shifts(2 * reach_steps + 1);
    for (std::size_t i = 0; i < shifts.size(); ++i) {
      HingeRun& w = shifts[i];
      w.s_h = s_center + (static_cast<int>(i) - reach_steps) * 0.02;
      w.d_h = d_h, w.e0 = e0, w.m = m, w.start = start, w.step = step, w.count = 11;
    }
    // Support first. A hypothesis replaces the best only when it scores
    // more, and it scores no more than its support (bound): rays are tested
    // only where the bound beats the global search's best, and at angles
    // within [0, 170] deg (the others are never taken).
    // Few hinges (a paired doorway): each on its own costs less.
    if (reach_steps > 3) {
      scoreShifts(shifts, reach_steps, s_center, nullptr);
    } else {
      forEachTask(shifts.size(), [&](std::size_t i) { scorePoints(shifts[i]); });
    }
    std::vector<std::vector<char>> need(shifts.size(), std::vector<char>(11, 0));
    for (std::size_t i = 0; i < shifts.size(); ++i)
      for (int ai = 0; ai < 11; ++ai) {
        const double deg = start + ai * step;
        need[i][ai] = deg >= 0 && deg <= 170 && bound(shifts[i], ai) > best.score;
      }
    if (reach_steps > 3) {
      scoreShifts(shifts, reach_steps, s_center, &need);
    } else {
      forEachTask(shifts.size(), [&](std::size_t i) {
        if (std::find(need[i].begin(), need[i].end(), 1) != need[i].end()) {
          scoreRays(shifts[i], &need[i]);
        } else {
          shifts[i].con.assign(static_cast<std::size_t>(shifts[i].count) * na_max, 0);
        }
      });
    }
    for (std::size_t i = 0; i < shifts.size(); ++i) finishScores(shifts[i], &need[i]);
    for (int ds = -reach_steps; ds <= reach_steps; ++ds) {
      const double s_h = s_center + ds * 0.02;
      for (int ai = 0; ai < 11; ++ai) {
        const double deg = start + ai * step;
        if (deg < 0 || deg > 170) continue;
        const Score& sc = shifts[ds + reach_steps].scores[ai];
        if (sc.score > best.score) best = sc, best_deg = deg, best_s = s_h;
      }
    }
  }
  best_support = best.cells, best_contra = best.contra, best_bins = best.bins;
}

std::vector<LeafSearch::Hinge> LeafSearch::hingesAt(double out) const {
  std::vector<Hinge> hs;
  for (int h = 0; h < 2; ++h)
    for (int sw = 0; sw < 2; ++sw)
      for (double rec : recess_steps) {
        if (rec > 0 && rec + lt > (sw == 0 ? t_toward : t)) continue;
        if (door.shadow_end && (h != shadow_h || sw != 0)) continue;
        hs.push_back({h, sw, rec, out});
      }
  return hs;
}

// The hinges given, every 2 deg; the best replaced by a hypothesis that
// scores more. `lower`: the exact score of a hypothesis already scored
// (rays are tested only where support could beat it).
void LeafSearch::globalSearch(const std::vector<Hinge>& hinges, double lower) {
  std::vector<HingeRun> global(hinges.size());
  for (std::size_t i = 0; i < hinges.size(); ++i) {
    const Hinge& g = hinges[i];
    HingeRun& w = global[i];
    w.s_h = g.h == 0 ? door.s0 - g.out : door.s1 + g.out, w.e0 = g.h == 0 ? 1.0 : -1.0;
    w.m = g.sw == 0 ? 1.0 : -1.0, w.d_h = g.sw == 0 ? -g.rec : -t + g.rec;
    // Beyond 170 deg a leaf lies flat on its wall and cannot be told from it.
    w.start = 0.0, w.step = 2.0, w.count = 86;  // every 2 deg, refined below
  }
  forEachTask(global.size(), [&](std::size_t i) { scorePoints(global[i]); });
  if (!global.empty() && !std::isfinite(lower)) {
    std::size_t bi = 0;
    int ba = 0, bb = -1;
    for (std::size_t i = 0; i < global.size(); ++i)
      for (int ai = 0; ai < global[i].count; ++ai)
        if (bound(global[i], ai) > bb) bb = bound(global[i], ai), bi = i, ba = ai;
    HingeRun probe = global[bi];
    std::vector<char> only(probe.count, 0);
    only[ba] = 1;
    // Its rays in two halves at once, the cells they block joined.
    std::vector<char> blocked(probe.count * cells, 0), blocked2(probe.count * cells, 0);
    const std::size_t mid = rays.size() / 2;
    forEachTask(2, [&](std::size_t h) {
      markRays(probe, &only, h == 0 ? 0 : mid, h == 0 ? mid : rays.size(), h == 0 ? blocked : blocked2);
    });
    for (std::size_t k = 0; k < blocked.size(); ++k) blocked[k] |= blocked2[k];
    tallyRays(probe, &only, blocked);
    finishScores(probe, &only);
    lower = probe.scores[ba].score;
  }
  forEachTask(global.size(), [&](std::size_t i) {
    HingeRun& w = global[i];
    std::vector<char> need(w.count, 0);
    bool any = false;
    for (int ai = 0; ai < w.count; ++ai) any |= (need[ai] = bound(w, ai) >= lower) != 0;
    // A hinge none of whose angles can be the best needs no rays at all
    // (most hinges: the bound leaves a few dozen of a thousand hypotheses).
    if (any) {
      scoreRays(w, &need);
    } else {
      w.con.assign(static_cast<std::size_t>(w.count) * na_max, 0);
    }
    finishScores(w, &need);
  });
  for (std::size_t i = 0; i < hinges.size(); ++i) {
    const Hinge& g = hinges[i];
    for (int ai = 0; ai < 86; ++ai) {
      const Score& sc = global[i].scores[ai];
      if (sc.score > best.score)
        best = sc, best_h = g.h, best_sw = g.sw, best_deg = 2.0 * ai, best_recess = g.rec, best_s = global[i].s_h;
    }
  }
}

}  // namespace detail
}  // namespace state
}  // namespace dsr
