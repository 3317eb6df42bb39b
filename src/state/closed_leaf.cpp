// State: the evidence of a leaf closed in its doorway, anywhere inside the
// wall's thickness (flush or recessed): the share of its cells holding
// points in the wall band, how densely the wall beside is sampled, and
// (after the search) whether the leaf is taken closed there, its visible
// face and the side its handle tells.
#include "leaf_internal.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

namespace dsr {
namespace state {
namespace detail {

namespace {
// A wall's face seen this densely (share of its 5 x 10 cm cells holding
// points) or more is sampled densely enough for the coverage thresholds as
// they stand (LeafFit::sampling).
constexpr double kDenseWallCover = 0.9;
}  // namespace

bool LeafSearch::bandEvidence() {
  // A closed leaf anywhere inside the wall's thickness (flush or recessed).
  // Its cells holding points: (leaf bin, z bin) pairs, counted once each.
  const double expected = static_cast<double>(std::max(1, static_cast<int>(std::ceil(L / abin)))) * nz;
  std::vector<std::pair<int, int>> band_cells;
  for (const Local& q : band) {
    band_cells.push_back({static_cast<int>((q.s - door.s0) / abin), q.zbin});
    band_xy.emplace_back(q.s, q.d);
  }
  // How many distinct cells: marked on a map over the cells' range (or,
  // were it large, by sorting).
  std::size_t band_distinct = 0;
  if (!band_cells.empty()) {
    int a_lo = band_cells.front().first, a_hi = a_lo, z_lo = band_cells.front().second, z_hi = z_lo;
    for (const auto& c : band_cells) {
      a_lo = std::min(a_lo, c.first), a_hi = std::max(a_hi, c.first);
      z_lo = std::min(z_lo, c.second), z_hi = std::max(z_hi, c.second);
    }
    const double span = (static_cast<double>(a_hi) - a_lo + 1) * (static_cast<double>(z_hi) - z_lo + 1);
    if (span <= 4.0 * static_cast<double>(band_cells.size()) + 4096) {
      const std::size_t zn = static_cast<std::size_t>(z_hi - z_lo + 1);
      std::vector<char> mark(static_cast<std::size_t>(span), 0);
      for (const auto& c : band_cells) {
        char& m = mark[static_cast<std::size_t>(c.first - a_lo) * zn + static_cast<std::size_t>(c.second - z_lo)];
        band_distinct += !m;
        m = 1;
      }
    } else {
      std::sort(band_cells.begin(), band_cells.end());
      band_distinct = static_cast<std::size_t>(std::unique(band_cells.begin(), band_cells.end()) - band_cells.begin());
    }
  }
  band_cov = std::min(1.0, band_distinct / expected);
  if (!side_cells.empty()) {
    double best_side = -1;
    for (int side = 0; side < 2; ++side) {
      int cols_on_wall = 0, held = 0;
      for (int col = 0; col < side_cols; ++col) {
        const double out = kSideFrom + (col + 0.5) * abin, sc = side == 0 ? door.s0 - out : door.s1 + out;
        if (sc < wall.s_min || sc > wall.s_max) continue;
        ++cols_on_wall;
        for (int zb = 0; zb < nz; ++zb) held += side_cells[(static_cast<std::size_t>(side) * side_cols + col) * nz + zb];
      }
      // A side without a single point on its face was hidden (furniture in
      // front, a leaf's shadow), not sampled: it tells nothing.
      if (cols_on_wall >= side_cols / 2 && held > 0)
        best_side = std::max(best_side, static_cast<double>(held) / (cols_on_wall * nz));
    }
    if (best_side >= 0) fit.sampling = std::clamp(best_side / kDenseWallCover, 0.5, 1.0);
  }
  fit.candidate_points = static_cast<int>(pts.size());
  if (closed_band_only_above > 0 && band_cov <= closed_band_only_above) {
    fit.searched = false;
    fit.best_coverage = band_cov;
    return false;
  }
  if (!rays_needed) {
    forEachTask(kRayParts, [&](std::size_t k) { gatherRayPart(static_cast<int>(k)); });
    joinRays();
  }
  return true;
}

void LeafSearch::closedInBand() {
  band_angle = 0;
  if (band_xy.size() >= 10) {
    // Only the points at the leaf's own depth: not jambs, trim or what lies beyond.
    std::vector<double> dv;
    for (const auto& q : band_xy) dv.push_back(q.y());
    std::nth_element(dv.begin(), dv.begin() + dv.size() / 2, dv.end());
    const double dmed = dv[dv.size() / 2];
    std::vector<Eigen::Vector2d> leaf_xy;
    for (const auto& q : band_xy)
      if (std::abs(q.y() - dmed) < std::max(0.03, lt)) leaf_xy.push_back(q);
    const Line2 l = fitLine(leaf_xy.size() >= 10 ? leaf_xy : band_xy);
    band_angle = std::acos(std::min(1.0, std::abs(l.direction.x()))) * 180 / M_PI;
  }

  const double best_expected = static_cast<double>(best_bins) * nz;
  gen_cov = best_support / best_expected;
  gen_contra = best_contra / best_expected;
  // A leaf closed in the wall band fills its doorway either way round: its
  // hinge side is told by its handle, at the latch edge, standing 3-10 cm
  // off the visible face about 0.9-1.1 m above the floor. Points there
  // within 30 cm of one jamb, at least three and three times those at the
  // other, put the latch at that jamb (else the search's side stands: a
  // closed leaf's hinge side is a guess without a handle).
  closed_band = band_cov >= 0.55 && (best_deg < p.closed_below_deg + 3 || gen_cov < band_cov);
  // Its visible face: the median depth of the band's points.
  band_face = 0;
  if (closed_band) {
    std::vector<double> dv;
    for (const Local& q : band) dv.push_back(q.d);
    std::nth_element(dv.begin(), dv.begin() + dv.size() / 2, dv.end());
    band_face = dv[dv.size() / 2];
  }
  if (closed_band && band.size() >= 10) {
    // A leaf ajar in its band slants across the doorway, and its points near
    // the hinge stand 3-10 cm before the median depth as a handle would
    // (rgbd 3027: 13 deg, recessed). Where the band's least-squares line
    // slants by 2 cm or more over the doorway, the face is that line.
    double face = band_face, slope = 0;
    const double s_mid = 0.5 * (door.s0 + door.s1);
    {
      double ms = 0, md = 0;
      for (const Local& q : band) ms += q.s, md += q.d;
      ms /= band.size(), md /= band.size();
      double ss = 0, sd = 0;
      for (const Local& q : band) ss += (q.s - ms) * (q.s - ms), sd += (q.s - ms) * (q.d - md);
      const double b = ss > 0 ? sd / ss : 0;
      if (std::abs(b) * (door.s1 - door.s0) >= 0.02) slope = b, face = md + b * (s_mid - ms);
    }
    int near0 = 0, near1 = 0;
    for (const Local& q : pts) {
      const double z = points[q.index].z() - floor_z, off = q.d - (face + slope * (q.s - s_mid));
      if (z < 0.9 || z > 1.1 || off < 0.03 || off > 0.1) continue;
      if (q.s > door.s0 + 0.02 && q.s < door.s0 + 0.3) ++near0;
      if (q.s < door.s1 - 0.02 && q.s > door.s1 - 0.3) ++near1;
    }
    fit.handle_points = std::max(near0, near1);
    if (near0 >= 3 && near0 >= 3 * near1) best_h = 1;       // latch at s0
    else if (near1 >= 3 && near1 >= 3 * near0) best_h = 0;  // latch at s1
    best_s = best_h == 0 ? door.s0 : door.s1;
  }
}

}  // namespace detail
}  // namespace state
}  // namespace dsr
