#include "door_state_recognition/state/doors.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>

#include "door_state_recognition/recognition/recognition.hpp"
#include "door_state_recognition/state/door_state.hpp"
#include "door_state_recognition/util/first_error.hpp"

namespace dsr {
namespace state {

namespace {

// A closed leaf is a door's only evidence when it covers more than this
// share of its doorway (no trim, see-through or recess).
constexpr double kClosedBandEvidence = 0.7;
// A doorway this close to an end of its wall's face reaches that end.
constexpr double kWallEndSlack = 0.05;  // m
// A doorway this much hidden by what stands in front of it (share of its
// body cells) is searched for a leaf swung towards the sensor, which makes it
// a door when it explains at least kOwnLeafExplained of what hides it.
constexpr double kOwnLeafFront = 0.5;
constexpr double kOwnLeafExplained = 0.6;
constexpr double kOwnLeafCoverage = 0.6;
constexpr double kBoxSideDeg = 5.0;
// The look before the search (mayBeOwnLeaf): the plane's rms (m) and how
// near a jamb it meets the wall's face (m).
constexpr double kOwnLeafRms = 0.05;
constexpr double kOwnLeafJamb = 0.15, kOwnLeafJambMax = 0.3;
// A door whose leaf was not seen (its angle a lower bound from free space).
constexpr double kUnseenLeafConfidence = 0.3;
// m: no wall holding a door is this thick (interior walls 0.1-0.3 m, heavy
// outer walls up to about 0.4); cupboards and wardrobes are 0.5-0.7 m deep.
constexpr double kMaxWallThickness = 0.45;
// m: a leaf swung out of sight needs the space behind its doorway this much less deep than it reaches.
constexpr double kRoomSlack = 0.1;
// depthBeyond: what lies this far behind a wall's face (m) is seen through
// it, up to kBeyondMax; at least kBeyondMinPoints such points tell the depth.
constexpr double kBeyondMin = 0.05, kBeyondMax = 20.0;
constexpr std::size_t kBeyondMinPoints = 30;
// A recess's back wall seen through a doorway (depthBeyond, seen_through
// below): kRecessBackShare of the points seen through (the jambs' reveals,
// within kRevealBand of the doorway's edges, left out) lie within
// kRecessBackBand (m) of one depth at most kRecessBackMax (m) beyond
// kMaxWallThickness behind the face, fewer than kRecessBackPast beyond it.
constexpr double kRecessBackMax = 0.3, kRecessBackBand = 0.02, kRecessBackShare = 0.4, kRecessBackPast = 0.1;
constexpr double kRevealBand = 0.04;
// A wall whose inliers are more than this share another door's leaf is that leaf.
constexpr double kLeafWallShare = 0.3;
// Of a doorway's observed body cells below 0.8 m, the share seen past its
// plane without which a leaf out of sight is not bounded (see open_unseen).
constexpr double kUnseenLowPast = 0.15;
// m: a doorway is an opening in its wall, the wall's face on both sides or
// at least as far as its jambs; one reaching this far past the wall's last
// point is not in that wall (past the corner of a cupboard's side, the
// side taken for a wall, its front for a leaf at 90 deg: lidar64 1033).
constexpr double kPastWallEnd = 0.15;
// Where past such a doorway (m beyond it, m above the floor) its wall's
// plane must have been seen for that.
constexpr double kPastWallLook = 0.1, kPastWallLookZ = 1.0;
// Bearing bins either side where that look point counts as in view
// (ViewTop::inViewNear), as many as the rays' spacing spans, at most
// kPastWallLookBins: a 64-beam LiDAR's columns, 0.35 deg apart and thinned
// by the voxel grid, leave some 0.25 deg bins without upper rings; a
// camera's pixels fill every bin (its view's edges stay where they are).
constexpr int kPastWallLookBins = 2;
// Something stands between `from` and `x` (m): a point within kRayReach of
// the segment, more than kRayShort short of x (not the wall's own face).
constexpr float kRayReach = 0.05f, kRayShort = 0.15f;
bool hiddenFrom(const segmentation::Points& pts, const Eigen::Vector3f& from, const Eigen::Vector3f& x) {
  const Eigen::Vector3f d = x - from;
  const float len = d.norm();
  if (!(len > kRayShort)) return false;
  const Eigen::Vector3f u = d / len;
  for (const Eigen::Vector3f& q : pts) {
    const float t = (q - from).dot(u);
    if (t <= 0.05f || t >= len - kRayShort) continue;
    if ((q - from - t * u).squaredNorm() < kRayReach * kRayReach) return true;
  }
  return false;
}

// f(0) ... f(n - 1) over the cores (OpenMP), each at most once; the first
// exception thrown is rethrown here (none may escape an OpenMP region).
template <class F>
void parallelFor(std::size_t n, F f) {
  util::FirstError error;
#pragma omp parallel for schedule(dynamic, 1)
  for (long long i = 0; i < static_cast<long long>(n); ++i) error.run([&] { f(static_cast<std::size_t>(i)); });
  error.rethrow();
}

// The foot of a closed leaf, over its width in 5 cm columns: `seen` the
// share where points at the leaf's depth lie within kFootHeight of the
// floor; `blocked` the share where, with the leaf unseen there, something
// stands on the floor right in front of the wall (within kClearance). A
// door stands on the floor and is kept clear; a cupboard front stands on a
// plinth, and boxes are put in front of it.
constexpr double kFootHeight = 0.3, kClearance = 0.4, kObjectHeight = 0.5;
struct Foot {
  double seen = 0, blocked = 0;
};
Foot footOf(const segmentation::Points& pts, const segmentation::WallPlane& wall, const LeafFit& leaf, double floor_z,
            double lt, double face_tol) {
  Foot f;
  const double a = std::min(leaf.s_hinge, leaf.s_latch) + 0.03, b = std::max(leaf.s_hinge, leaf.s_latch) - 0.03;
  if (b <= a) return f;
  const int cols = std::max(1, static_cast<int>((b - a) / 0.05));
  std::vector<char> seen(cols, 0), front(cols, 0);
  // The leaf's depth: its visible face inside the wall band, else at its hinge.
  const double face = leaf.closed_in_band ? leaf.face_d : wall.signedDistance(Eigen::Vector3f(leaf.hinge.x(), leaf.hinge.y(), 0));
  const double d_lo = face - lt - 0.05, d_hi = face + lt + 0.05;
  for (const auto& q : pts) {
    if (q.z() >= floor_z + kObjectHeight || q.z() < floor_z + 0.03) continue;
    const double s = wall.along(q);
    if (s <= a || s >= b) continue;
    const int c = std::min(cols - 1, static_cast<int>((s - a) / 0.05));
    const double d = wall.signedDistance(q);
    if (d >= d_lo && d <= d_hi && q.z() < floor_z + kFootHeight) seen[c] = 1;
    // Standing on the floor: above the floor's own noise.
    if (d > std::max(face_tol, d_hi) && d <= kClearance && q.z() >= floor_z + 0.1) front[c] = 1;
  }
  int n_seen = 0, n_blocked = 0;
  for (int c = 0; c < cols; ++c) n_seen += seen[c], n_blocked += !seen[c] && front[c];
  f.seen = static_cast<double>(n_seen) / cols;
  f.blocked = static_cast<double>(n_blocked) / cols;
  return f;
}

// What stands before a doorway, its own leaf aside. A doorway is kept clear
// to pass through, and a door's leaf closes it flush with the wall or
// recessed in it, never 20-40 cm before it; a door's trim is 1-3 cm proud and
// its handle some 7 cm. Furniture against a wall (a bookcase, a cupboard)
// shows just that before its back or the wall: its side panels, shelves,
// books or front stand kBeforeMin-kBeforeMax out of the wall across its whole
// width at body height, while its back panel (a few cm off the wall) and its
// side panels' edges look like a closed leaf with trim. The share of the
// leaf's width, in 5 cm columns between its jambs, in which at least
// kBeforeRows rows 10 cm high of the body (0.3-1.75 m) hold points
// kBeforeMin-kBeforeMax before the wall's face and farther than kOffLeaf
// from the leaf (a leaf swung towards the room stands there itself).
constexpr double kBeforeMin = 0.12, kBeforeMax = 0.7, kOffLeaf = 0.08;
constexpr int kBeforeRows = 2;
// A doorway this share of whose width something stands before is furniture.
constexpr double kFurnishedShare = 0.5;
double furnishedShare(const segmentation::Points& pts, const segmentation::WallPlane& wall, const LeafFit& leaf,
                      double floor_z) {
  const double a = std::min(leaf.s_hinge, leaf.s_latch) + 0.05, b = std::max(leaf.s_hinge, leaf.s_latch) - 0.05;
  if (b <= a) return 0;
  constexpr double kBody0 = 0.3, kBody1 = 1.75, kCol = 0.05, kRow = 0.1;
  const int cols = std::max(1, static_cast<int>((b - a) / kCol));
  const int rows = static_cast<int>(std::lround((kBody1 - kBody0) / kRow));
  std::vector<char> cell(static_cast<std::size_t>(cols) * rows, 0);
  const Eigen::Vector2d h = leaf.hinge, dir = leaf.direction;
  for (const auto& q : pts) {
    const double z = q.z() - floor_z;
    if (z < kBody0 || z >= kBody1) continue;
    const double d = wall.signedDistance(q);
    if (d < kBeforeMin || d > kBeforeMax) continue;
    const double s = wall.along(q);
    if (s <= a || s >= b) continue;
    const Eigen::Vector2d xy(q.x(), q.y());
    const double t = std::clamp((xy - h).dot(dir), 0.0, leaf.length);
    if ((xy - (h + t * dir)).norm() < kOffLeaf) continue;
    const int c = std::min(cols - 1, static_cast<int>((s - a) / kCol));
    const int r = std::min(rows - 1, static_cast<int>((z - kBody0) / kRow));
    cell[static_cast<std::size_t>(r) * cols + c] = 1;
  }
  int furnished = 0;
  for (int c = 0; c < cols; ++c) {
    int n = 0;
    for (int r = 0; r < rows; ++r) n += cell[static_cast<std::size_t>(r) * cols + c];
    furnished += n >= kBeforeRows;
  }
  return static_cast<double>(furnished) / cols;
}

// Could what hides a doorway be its own leaf, swung towards the sensor? A
// cheap look before the leaf search: the points in front of the wall whose
// sight lines meet the wall inside the doorway (body height) must lie on one
// vertical plane (rms within kOwnLeafRms) that meets the wall's face near a
// jamb and is not square to the wall (a cupboard's side).
bool mayBeOwnLeaf(const segmentation::Points& pts, const segmentation::WallPlane& wall, const recognition::Doorway& d,
                  double floor_z, const Eigen::Vector3f& viewpoint, const Parameters& p) {
  const double vs = wall.along(viewpoint), vd = wall.signedDistance(viewpoint);
  if (vd <= 0.1) return false;
  std::vector<Eigen::Vector2d> sd;
  for (const auto& q : pts) {
    if (q.z() < floor_z + 0.25 || q.z() > floor_z + 1.75) continue;
    const double dd = wall.signedDistance(q);
    if (dd <= p.face_tolerance + 0.02 || dd >= std::min(vd, p.door_max_width + 0.1)) continue;
    const double ss = wall.along(q);
    const double s_wall = vs + vd / (vd - dd) * (ss - vs);
    if (s_wall <= d.s0 + 0.05 || s_wall >= d.s1 - 0.05) continue;
    sd.emplace_back(ss, dd);
  }
  if (sd.size() < 30) return false;
  const Line2 l = fitLine(sd);
  double rms = 0;
  const Eigen::Vector2d nrm(-l.direction.y(), l.direction.x());
  for (const auto& q : sd) rms += std::pow((q - l.point).dot(nrm), 2);
  rms = std::sqrt(rms / sd.size());
  const double angle = std::acos(std::min(1.0, std::abs(l.direction.x()))) * 180 / M_PI;  // to the wall, 0-90
  if (rms > kOwnLeafRms || std::abs(l.direction.y()) < 1e-6 || 90 - angle < kBoxSideDeg) return false;
  const double s_face = l.point.x() - l.point.y() / l.direction.y() * l.direction.x();  // where it meets d = 0
  // Near its hinge a leaf ajar lies within the wall's face band (the face
  // tolerance and its thickness) for that over sin(angle) along the wall,
  // and the doorway seen ends there, a grid cell on; no farther than the
  // leaf search moves a hinge (kOwnLeafJambMax).
  const double band = p.face_tolerance + p.leaf_thickness;
  const double reach = std::clamp(band / std::sin(angle * M_PI / 180) + p.grid_cell, kOwnLeafJamb, kOwnLeafJambMax);
  return std::min(std::abs(s_face - d.s0), std::abs(s_face - d.s1)) <= reach;
}

// How deep the space seen through a doorway is: the median distance behind
// the wall's face (up to kBeyondMax) of the points whose sight lines from
// the viewpoint cross the wall inside the doorway at body height; NaN when
// fewer than kBeyondMinPoints do. With `back`, also whether those points
// end on a surface parallel to the wall: kRecessBackShare of them or more
// within kRecessBackBand of one depth between kMaxWallThickness -
// kRoomSlack and kMaxWallThickness + kRecessBackMax, fewer than
// kRecessBackPast of them beyond it.
double depthBeyond(const segmentation::Points& pts, const segmentation::WallPlane& wall, const recognition::Doorway& d,
                   double floor_z, const Eigen::Vector3f& viewpoint, bool* back = nullptr) {
  const double vs = wall.along(viewpoint), vd = wall.signedDistance(viewpoint), vz = viewpoint.z();
  if (back) *back = false;
  if (vd <= 0.1) return std::numeric_limits<double>::quiet_NaN();
  std::vector<double> depth, inside;
  for (const auto& q : pts) {
    const double dd = wall.signedDistance(q);
    if (dd > -kBeyondMin || dd < -kBeyondMax) continue;
    const double t = vd / (vd - dd);  // where the sight line crosses the wall's plane
    const double s_wall = vs + t * (wall.along(q) - vs), z_wall = vz + t * (q.z() - vz) - floor_z;
    if (s_wall <= d.s0 + 0.05 || s_wall >= d.s1 - 0.05 || z_wall < 0.3 || z_wall > 1.75) continue;
    depth.push_back(-dd);
    // (the jambs' reveals, square to the wall at the doorway's edges, are no
    // back; nor is what lies beyond a jamb's line, behind the wall beside the
    // doorway: a recess's back spans the gap between its sides, while a leaf
    // swung away past its hinge jamb shows only a strip there)
    const double s_own = wall.along(q);
    if (back && s_own >= d.s0 + kRevealBand && s_own <= d.s1 - kRevealBand) inside.push_back(-dd);
  }
  if (depth.size() < kBeyondMinPoints) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(depth.begin(), depth.begin() + depth.size() / 2, depth.end());
  if (back && inside.size() >= kBeyondMinPoints) {
    std::sort(inside.begin(), inside.end());
    // The densest band kRecessBackBand either side of a depth: a sliding window over the sorted depths.
    std::size_t best = 0, best_hi = 0;
    for (std::size_t lo = 0, hi = 0; lo < inside.size(); ++lo) {
      while (hi < inside.size() && inside[hi] - inside[lo] <= 2 * kRecessBackBand) ++hi;
      const double mid = inside[lo] + kRecessBackBand;
      if (hi - lo > best && mid > kMaxWallThickness - kRoomSlack && mid < kMaxWallThickness + kRecessBackMax)
        best = hi - lo, best_hi = hi;
    }
    *back = best >= kRecessBackShare * inside.size() && inside.size() - best_hi < kRecessBackPast * inside.size();
  }
  return depth[depth.size() / 2];
}

}  // namespace

DoorStage findDoors(const segmentation::Points& pts, const std::vector<segmentation::WallPlane>& walls, double floor_z,
                    double top_z, bool ceiling_known, const Eigen::Vector3f& viewpoint, const Eigen::Matrix3d& to_input,
                    bool organized, const Parameters& p, const segmentation::ViewTop* view_in,
                    const std::vector<std::vector<recognition::Doorway>>* given) {
  DoorStage out;
  auto toInput = [&](const Eigen::Vector3d& v) -> Eigen::Vector3d { return to_input * v; };
  auto onFloor = [&](const Eigen::Vector2d& xy) { return Eigen::Vector3d(xy.x(), xy.y(), floor_z); };
  out.is_leaf.assign(pts.size(), 0);
  // The doorways of each wall, then the leaf in each doorway: independent
  // searches, run over both cores; decisions follow in wall and doorway order.
  std::vector<std::vector<recognition::Doorway>> doorways(walls.size());
  // A camera frame's view ends on every side: what a doorway and a leaf
  // show is judged against the part of them inside the view
  // (the caller's, when it has one already).
  const segmentation::ViewTop own =
      organized && !view_in ? segmentation::viewTop(pts, viewpoint) : segmentation::ViewTop{};
  const segmentation::ViewTop* view = !organized ? nullptr : view_in ? view_in : &own;
  if (given && given->size() == walls.size()) {
    doorways = *given;
  } else {
    parallelFor(walls.size(), [&](std::size_t wi) {
      doorways[wi] = recognition::findDoorways(pts, walls[wi], floor_z, top_z, viewpoint, p, organized, view);
    });
  }
  struct Candidate {
    std::size_t wall;
    recognition::Doorway doorway;
    LeafFit leaf;
  };
  std::vector<Candidate> candidates;
  for (std::size_t wi = 0; wi < walls.size(); ++wi)
    for (const recognition::Doorway& d : doorways[wi]) candidates.push_back({wi, d, {}});
  // A closed leaf lies within its wall's thickness; no wall is thicker than
  // kMaxWallThickness (beside a gap between cupboards, their sides are).
  auto thicknessOf = [&](const recognition::Doorway& d) {
    return d.thickness > 0.04 ? std::min(d.thickness, kMaxWallThickness) : p.default_wall_thickness;
  };
  parallelFor(candidates.size(), [&](std::size_t i) {
    Candidate& c = candidates[i];
    // Without trim, see-through or a deep recess only a closed leaf filling
    // the doorway makes it a door (the evidence rule below): skip the search
    // when the wall band holds too little for one.
    const recognition::Doorway& d = c.doorway;
    // A doorway hidden by what stands in front of it may be hidden by its own
    // leaf swung towards the sensor: searched too (see the evidence rule).
    const bool other_evidence = d.casing || d.through >= 0.08 || d.recess > 0.3 || d.set_back > 0 ||
                                (d.front >= kOwnLeafFront && mayBeOwnLeaf(pts, walls[c.wall], d, floor_z, viewpoint, p));
    c.leaf = fitLeaf(pts, walls[c.wall], d, floor_z, thicknessOf(d), viewpoint, p,
                            other_evidence ? 0.0 : kClosedBandEvidence, view);
    // Trim legs pin the leaf's hinge and length to the doorway between them
    // (a few centimetres of play). A leg may be off: a leaf swung past 90 deg
    // towards the sensor hides the trim at its hinge and stands out of the
    // face there like trim. Where the leaf is seen (the best hypothesis
    // covers enough cells) but no pinned hypothesis fits, the doorway is
    // searched as if unpaired: hinge and length free (seed 1009, door 0).
    if (!c.leaf.found && d.paired && c.leaf.best_coverage >= p.min_leaf_coverage * c.leaf.sampling) {
      recognition::Doorway loose = d;
      loose.paired = false;
      LeafFit again = fitLeaf(pts, walls[c.wall], loose, floor_z, thicknessOf(d), viewpoint, p,
                              other_evidence ? 0.0 : kClosedBandEvidence, view);
      if (again.found) c.leaf = again;
    }
  });
  for (const Candidate& cand : candidates) {
    {
      const std::size_t wi = cand.wall;
      const segmentation::WallPlane& wall = walls[wi];
      const recognition::Doorway& d = cand.doorway;
      const double t = thicknessOf(d);
      LeafFit leaf = cand.leaf;
      // A leaf not seen, in a doorway seen through, that free space puts at
      // unseen_leaf_min_bound_deg or more (never below closed_below_deg: the
      // door is not closed): reported at the bound, NOT_CLOSED below
      // open_from_deg and OPEN from it (stateOfBound; issue 20). With no
      // leaf, what is seen through is the only evidence: a doorway has a jamb
      // of its wall on either side, so without trim the run seen through
      // must lie within the wall's face seen (a run past the face's end is
      // the room beyond the end of a wall or of a cupboard's front taken
      // for one: Stations.APartSeenThroughPastTheEndOfAWallSeenIsNoDoorway,
      // a false NOT_CLOSED door 0.3 m past such an end).
      const bool jambs = d.casing || (d.s0 >= wall.s_min - kWallEndSlack && d.s1 <= wall.s_max + kWallEndSlack);
      // A leaf swung away out of sight stands beyond the bound, reaching
      // width x sin(angle) behind the wall: the space seen through the
      // doorway must be that deep (less kRoomSlack) at the bound or at
      // 90 deg, whichever is less. A recess between two cupboards, with the
      // room's wall 0.3-0.7 m behind their fronts, leaves no room for a leaf.
      const bool bounded = !leaf.found && std::isfinite(leaf.free_from_deg) &&
                           leaf.free_from_deg >= std::max(p.unseen_leaf_min_bound_deg, p.closed_below_deg) &&
                           leaf.free_from_deg <= 170 && jambs;
      bool room_for_leaf = true;
      if (bounded) {
        const double beyond = depthBeyond(pts, wall, d, floor_z, viewpoint);
        const double reach = (d.s1 - d.s0) * std::sin(std::min(leaf.free_from_deg, 90.0) * M_PI / 180);
        room_for_leaf = !(beyond < reach - kRoomSlack);
      }
      // And a doorway reaches the floor: where its leaf is out of sight, the
      // rays must pass its plane low down too (of its observed cells below
      // 0.8 m, kUnseenLowPast seen through or just behind). A window seen
      // through above a sill, or above furniture before the wall, does not.
      const bool reaches_floor = d.low_past_share >= kUnseenLowPast;
      const bool open_unseen = bounded && room_for_leaf && reaches_floor;
      if (!leaf.found) {
        char buf[512];
        std::snprintf(buf, sizeof buf,
                      "wall %zu: doorway s=[%.2f, %.2f] casing=%d through=%.2f front=%.2f recess=%.2f top=%.2f "
                      "thick=%.2f | no leaf (%s: %.0f deg, coverage %.2f, contradicted %.2f, crowded before %.2f, rest seen through %.2f, front at tip %.2f; "
                      "%d points, %d rays; free from %.0f deg, by side %.0f/%.0f/%.0f/%.0f)%s",
                      wi, d.s0, d.s1, d.casing, d.through, d.front, d.recess, d.top - floor_z, d.thickness,
                      leaf.searched ? "best" : "not searched, no evidence and wall band",
                      leaf.best_angle_deg, leaf.best_coverage, leaf.best_contradiction, leaf.crowd_before, leaf.rest_seen_through, leaf.front_at_tip,
                      leaf.candidate_points, leaf.candidate_rays, leaf.free_from_deg, leaf.free_from_each[0],
                      leaf.free_from_each[1], leaf.free_from_each[2], leaf.free_from_each[3], open_unseen     ? " | leaf unseen, reported at the bound"
                      : !room_for_leaf ? " | no room behind it for a leaf out of sight"
                      : bounded        ? " | seen past only above its lower body: no doorway to the floor"
                                       : "");
        out.trace.push_back(buf);
        if (!open_unseen) continue;
        // The leaf where the bound puts it, the doorway's width long.
        const double e0 = leaf.hinge_at_s0 ? 1.0 : -1.0, m = leaf.toward_viewer ? 1.0 : -1.0;
        leaf.found = true;
        leaf.angle_deg = leaf.free_from_deg;
        leaf.coverage = 0;
        leaf.s_hinge = leaf.hinge_at_s0 ? d.s0 : d.s1;
        leaf.s_latch = leaf.hinge_at_s0 ? d.s1 : d.s0;
        leaf.length = std::max(0.1, d.width() - 0.008);
        const double th = leaf.angle_deg * M_PI / 180;
        const Eigen::Vector2d dir_sd(std::cos(th) * e0, std::sin(th) * m);
        leaf.hinge = wall.point + leaf.s_hinge * wall.direction + (leaf.toward_viewer ? 0.0 : -t) * wall.normal;
        leaf.direction = (dir_sd.x() * wall.direction + dir_sd.y() * wall.normal).normalized();
        leaf.top_z = std::isfinite(d.top) ? d.top : floor_z + 2.0;
      }
      // What tells a door from a cupboard or a gap: a closed leaf inside the
      // wall, or trim around the doorway, or the room beyond seen through it.
      // Or a leaf swung towards the sensor that is itself what hides the
      // doorway: a cupboard's side taken for a leaf leaves its front unexplained.
      // A leaf within kBoxSideDeg of square to the wall is not taken on this
      // evidence: the side of a cupboard against the wall looks just like it.
      const bool own_leaf_hides = !leaf.closed_in_band && leaf.toward_viewer && d.front >= kOwnLeafFront &&
                                  leaf.coverage >= kOwnLeafCoverage * leaf.sampling && leaf.occluders_explained >= kOwnLeafExplained &&
                                  std::abs(leaf.angle_deg - 90) >= kBoxSideDeg;
      // A panel set back from the wall around it must lie off the wall's
      // plane over a good part of its body too.
      const bool set_back = d.set_back > 0 && d.recess + d.through >= 0.3;
      // A closed leaf: found in the wall band, or swung by less than
      // closed_below_deg (a band seen too sparsely, far off, to be taken as
      // one whole).
      const bool closed = leaf.closed_in_band || leaf.angle_deg < p.closed_below_deg;
      // In a camera frame a run to where the wall's face ends (no wall seen
      // beyond one jamb) holding a "closed leaf" and nothing else is the
      // wall's own end off a plane tilted by depth noise (rgbd 1001, 2007,
      // 2015: false closed doors beside real doorways): the band's coverage
      // alone is no evidence there.
      const bool at_wall_end = d.s0 <= wall.s_min + kWallEndSlack || d.s1 >= wall.s_max - kWallEndSlack;
      const bool band_evidence = leaf.coverage > kClosedBandEvidence && !(organized && at_wall_end);
      // Or a leaf swung away by a little, that fills its own doorway just
      // behind the wall's plane: ajar by less than about 25 deg, it lets no
      // ray through (the gap at its latch narrower than the rays' spacing
      // there) and, without trim on the sensor's side, nothing else speaks
      // for the door; yet a door-wide, door-tall panel hinged at one jamb
      // and slanting into the reveal is what a leaf ajar is (a niche's back
      // or a recess between cupboards stands parallel to the wall). As for a
      // closed leaf's band, not at the end of a camera's wall (its own end
      // off a plane tilted by depth noise).
      const bool own_leaf_fills = !leaf.closed_in_band && !leaf.toward_viewer && d.recess >= kOwnLeafFront &&
                                  leaf.coverage >= kOwnLeafCoverage * leaf.sampling && !(organized && at_wall_end);
      // Seen through only above 0.8 m (what is below hidden or solid) is a
      // window over a sill, or a gap over furniture: a doorway's opening runs
      // down to the floor, and the rays through it do too.
      // What is seen through a doorway is the room beyond, not one flat
      // surface parallel to the wall just behind its face: that is the back
      // of a recess (the wall behind a gap between cupboards, whose sides
      // are the "jambs": lidar64 drive 1049), deeper than any wall holding
      // a door, too shallow for a room. Judged only where nothing else
      // (trim, a closed leaf) speaks for a door.
      bool seen_through = d.through >= 0.08 && d.low_through;
      if (seen_through && !d.casing && !closed) {
        bool back = false;
        depthBeyond(pts, wall, d, floor_z, viewpoint, &back);
        seen_through = !back;
      }
      const bool evidence = d.shadow_end ? own_leaf_hides
                            : closed ? (d.casing || d.recess > 0.3 || set_back || band_evidence)
                                     : (d.casing || seen_through || own_leaf_hides || own_leaf_fills);
      // A closed leaf whose foot is hidden by something standing right in
      // front of it is a blocked front, not a door.
      const Foot foot = closed ? footOf(pts, wall, leaf, floor_z, p.leaf_thickness, p.face_tolerance) : Foot{1, 0};
      const bool free_foot = foot.seen >= 0.3 || foot.blocked < 0.5;
      // Something standing before the doorway across its width: furniture
      // against the wall, not a door (see furnishedShare). A pass over the
      // points: only where nothing else has turned the doorway down yet
      // (-1 in the trace: not looked at).
      const double furnished = open_unseen || !evidence || !free_foot ? -1.0 : furnishedShare(pts, wall, leaf, floor_z);
      const bool clear_way = furnished < kFurnishedShare;
      const double height = (std::isfinite(d.top) ? d.top : leaf.top_z) - floor_z;
      const double wall_h = top_z - floor_z;
      // The paper's ratio to the room's height needs the ceiling: without it
      // the top of what was seen is where the view ends, not the room.
      const bool tall = height >= p.door_min_height &&
                        (!ceiling_known || height >= p.door_height_ratio * wall_h - p.door_height_phi);
      const double width = std::abs(leaf.s_latch - leaf.s_hinge);
      const bool wide = width >= p.door_min_width && width <= p.door_max_width;
      // A "wall" that is mostly the leaf of a door taken before (an open leaf
      // as tall as the view) holds no doorway of its own.
      std::size_t on_leaf = 0;
      for (int i : wall.inliers) on_leaf += out.is_leaf[i];
      const bool own_wall = on_leaf <= kLeafWallShare * wall.inliers.size();
      // A doorway reaching kPastWallEnd past its wall's end is not in it,
      // unless the wall's plane just past the doorway was not seen (out of
      // a camera's view, or hidden, as by a leaf swung towards the sensor):
      // the wall may go on there.
      auto pastEnd = [&](double past, double s_out) {
        if (past <= kPastWallEnd) return false;
        const Eigen::Vector2d xy = wall.point + s_out * wall.direction;
        const Eigen::Vector3f x(static_cast<float>(xy.x()), static_cast<float>(xy.y()), static_cast<float>(floor_z + kPastWallLookZ));
        return (!view || view->inViewNear(x, std::min(kPastWallLookBins, view->binsWithin(view->ray_spacing)))) &&
               !hiddenFrom(pts, viewpoint, x);
      };
      const bool other_rules = evidence && free_foot && clear_way && tall && wide && own_wall;
      // (Only for a doorway no other rule turned down: a pass over the points.)
      // Without trim (which marks the jambs) the wall's ends are where its
      // face is seen kPastWallLookZ above the floor or higher: a jamb is
      // wall, not the side of a table, a box or a chair that lines up with a
      // cupboard's side taken for a wall (lidar64 drive 1077: a table's side
      // 1.1 m off the end of a wardrobe's side).
      bool in_wall = true;
      if (other_rules) {
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        if (!d.casing)
          for (int i : wall.inliers)
            if (pts[i].z() >= floor_z + kPastWallLookZ) {
              const double a = wall.along(pts[i]);
              lo = std::min(lo, a), hi = std::max(hi, a);
            }
        if (!(hi >= lo)) lo = wall.s_min, hi = wall.s_max;
        in_wall = !pastEnd(d.s1 - hi, d.s1 + kPastWallLook) && !pastEnd(lo - d.s0, d.s0 - kPastWallLook);
      }
      {
        char buf[512];
        std::snprintf(buf, sizeof buf,
                      "wall %zu: doorway s=[%.2f, %.2f] casing=%d face=%.2f through=%.2f front=%.2f recess=%.2f "
                      "setback=%.2f top=%.2f thick=%.2f lowpast=%.2f | leaf found=%d band=%d angle=%.1f cov=%.2f rest=%.2f tipfront=%.2f explains=%.2f "
                      "foot=%.2f/%.2f furnished=%.2f hinge_s0=%d toward=%d handle=%d | %s",
                      wi, d.s0, d.s1, d.casing, d.face, d.through, d.front, d.recess, d.set_back, d.top - floor_z,
                      d.thickness, d.low_past_share, leaf.found, leaf.closed_in_band, leaf.angle_deg, leaf.coverage, leaf.rest_seen_through, leaf.front_at_tip, leaf.occluders_explained,
                      foot.seen, foot.blocked, furnished, leaf.hinge_at_s0, leaf.toward_viewer, leaf.handle_points,
                      !evidence ? "rejected: no casing, recess, see-through or own leaf hiding it"
                      : !free_foot ? "rejected: foot hidden by something right in front"
                      : !clear_way ? "rejected: something stands before it across its width (furniture)"
                      : !tall ? "rejected: too low" : !wide ? "rejected: width"
                      : !own_wall ? "rejected: its wall is another door's leaf"
                      : !in_wall ? "rejected: past its wall's end" : "door");
        out.trace.push_back(buf);
      }
      if (!other_rules || !in_wall) continue;

      DoorResult door;
      door.wall_id = static_cast<int>(wi);
      door.opening_angle_deg = leaf.angle_deg;
      door.angle_is_lower_bound = open_unseen;
      door.state = open_unseen ? stateOfBound(leaf.angle_deg, p) : classify(leaf.angle_deg, p);
      // Confidence: how much of the leaf was seen, and how sure the doorway is.
      door.confidence = open_unseen ? kUnseenLeafConfidence
                                    : std::min(1.0, leaf.coverage) * (d.sure() ? 1.0 : 0.7);
      door.swing = open_unseen ? Swing::Unknown : leaf.toward_viewer ? Swing::TowardViewer : Swing::AwayFromViewer;
      const Eigen::Vector2d n2 = leaf.toward_viewer ? wall.normal : Eigen::Vector2d(-wall.normal);
      door.wall_normal = toInput(Eigen::Vector3d(n2.x(), n2.y(), 0));
      door.hinge = toInput(onFloor(leaf.hinge));
      const Eigen::Vector2d center = wall.point + ((leaf.s_hinge + leaf.s_latch) / 2) * wall.direction - (t / 2) * wall.normal;
      door.opening_center = toInput(onFloor(center));
      door.width = std::abs(leaf.s_latch - leaf.s_hinge);
      door.height = height;
      door.clear_width = door.state == DoorStateKind::Closed
                             ? 0.0
                             : clearWidth(door.width, leaf.angle_deg, p.leaf_thickness, p.closed_below_deg);
      const double bottom = floor_z + 0.01, top = std::max(leaf.top_z, floor_z + 0.5);
      const Eigen::Vector2d latch = leaf.hinge + leaf.length * leaf.direction;
      door.leaf_corners = {toInput(Eigen::Vector3d(leaf.hinge.x(), leaf.hinge.y(), bottom)),
                           toInput(Eigen::Vector3d(latch.x(), latch.y(), bottom)),
                           toInput(Eigen::Vector3d(latch.x(), latch.y(), top)),
                           toInput(Eigen::Vector3d(leaf.hinge.x(), leaf.hinge.y(), top))};
      door.wall_line_point = toInput(onFloor(wall.point));
      door.wall_line_direction = toInput(Eigen::Vector3d(wall.direction.x(), wall.direction.y(), 0));
      door.leaf_line_point = door.hinge;
      door.leaf_line_direction = toInput(Eigen::Vector3d(leaf.direction.x(), leaf.direction.y(), 0));
      door.casing = d.casing;
      door.head_seen = std::isfinite(d.top);
      if (open_unseen)
        for (int h = 0; h < 2; ++h)
          for (int sw = 0; sw < 2; ++sw) {
            const Eigen::Vector2d hinge2 =
                wall.point + (h == 0 ? d.s0 : d.s1) * wall.direction + (sw == 0 ? 0.0 : -t) * wall.normal;
            const Eigen::Vector2d along2 = (h == 0 ? 1.0 : -1.0) * wall.direction, swing2 = (sw == 0 ? 1.0 : -1.0) * wall.normal;
            door.side_bounds.push_back({toInput(onFloor(hinge2)), toInput(Eigen::Vector3d(along2.x(), along2.y(), 0)),
                                        toInput(Eigen::Vector3d(swing2.x(), swing2.y(), 0)), leaf.free_from_each[h * 2 + sw]});
          }
      // The same doorway found from two overlapping wall hypotheses, or the
      // same leaf claimed by two doorways (a leaf's shadow beside its own
      // doorway looks like one): keep the surer one (surerReport, as
      // runStations ranks them). Or one leaf claimed by doorways on two
      // walls, hinged at its two ends (leavesOverlap): the doorway whose head
      // was seen is in a wall, the other a gap onto a surface beyond.
      bool duplicate = false;
      for (DoorResult& other : out.doors) {
        const bool same = (other.opening_center - door.opening_center).norm() < 0.4 || sameLeaf(other, door);
        if (!same && !leavesOverlap(other, door)) continue;
        duplicate = true;
        const bool take = !same && other.head_seen != door.head_seen ? door.head_seen : surerReport(door, other);
        if (take) other = door;
      }
      if (duplicate) continue;
      for (int i : leaf.inliers) out.is_leaf[i] = 1;
      out.doors.push_back(door);
      out.openings.push_back({static_cast<int>(wi), std::min(leaf.s_hinge, leaf.s_latch), std::max(leaf.s_hinge, leaf.s_latch), floor_z + height, leaf.hinge, leaf.direction, leaf.length,
                          bottom, top});
    }
  }
  for (std::size_t i = 0; i < out.doors.size(); ++i) out.doors[i].id = static_cast<int>(i);
  return out;
}

}  // namespace state
}  // namespace dsr
