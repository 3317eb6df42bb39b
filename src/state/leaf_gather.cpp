// State: fitLeaf's first step, the doorway's frame (leaf length, heights,
// bins) and what lies near it: the points near its jambs, those in the
// wall band inside it, the wall's face beside it, and the rays passing it.
#include "leaf_internal.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace dsr {
namespace state {
namespace detail {

void LeafSearch::gather() {
  w = door.width(), L = std::max(0.1, w - 0.008), lt = p.leaf_thickness, tol = p.leaf_tolerance;
  z0 = floor_z + 0.25;
  z1 = floor_z + std::min(1.75, (std::isfinite(door.top) ? door.top - floor_z : 2.0) - 0.1);
  zbin = 0.1, abin = 0.05;
  nz = std::max(1, static_cast<int>((z1 - z0) / zbin));
  s_mid = (door.s0 + door.s1) / 2, reach = w + 0.25;
  // A leaf may be longer than the doorway seen (a leaf ajar hides its own
  // doorway): hypotheses reach up to the widest door from either jamb.
  Lmax = door.paired ? L + 0.05 : std::max(L, p.door_max_width), reach_h = Lmax + 0.15;
  reach_h2 = reach_h * reach_h;

  // The points near the doorway (and those in the wall band inside it), and
  // the rays passing near it: two passes over every point, independent, so
  // run at once when both are needed (one is not when the band's points
  // alone can end the search, below).
  // The wall's face beside the doorway, 0.15-0.6 m beyond each jamb: its
  // cells holding points (see LeafFit::sampling). Not in a camera frame.
  side_cols = static_cast<int>(std::lround((kSideTo - kSideFrom) / abin));
  side_cells.assign(view ? 0 : static_cast<std::size_t>(2 * side_cols * nz), 0);

  vsd = Eigen::Vector2d(wall.along(viewpoint), wall.signedDistance(viewpoint));
  vsz = viewpoint.z();
  dc = Eigen::Vector2d(s_mid, -t / 2);
  // The rays in kRayParts parts of the points (tasks), joined in order.
  ray_parts.resize(kRayParts);
  rays_needed = closed_band_only_above <= 0;
  if (rays_needed) {
    forEachTask(1 + kRayParts, [&](std::size_t i) { i == 0 ? gatherPoints() : gatherRayPart(static_cast<int>(i) - 1); });
    joinRays();
  } else {
    gatherPoints();
  }
}

// std::hypot(x, y) <= reach_h, calling hypot only where the squares are too close to tell.
bool LeafSearch::withinReach(double x, double y) const {
  if (std::abs(x) > reach_h) return false;  // hypot(x, y) >= |x|
  const double r2 = x * x + y * y;
  if (r2 < reach_h2 * (1 - 1e-9)) return true;
  if (r2 > reach_h2 * (1 + 1e-9)) return false;
  return std::hypot(x, y) <= reach_h;
}

bool LeafSearch::nearJamb(double s, double d) const {
  if (std::abs(d + t / 2) > reach_h) return false;
  return withinReach(s - door.s0, d + t / 2) || withinReach(s - door.s1, d + t / 2);
}

void LeafSearch::gatherPoints() {
  // Lists of this task's own, moved out when done (see gatherRayPart).
  std::vector<Local> near, in_band;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& q = points[i];
    if (q.z() < z0 || q.z() >= z1) continue;
    const double s = wall.along(q), d = wall.signedDistance(q);
    if (!side_cells.empty() && std::abs(d) <= p.face_tolerance) {
      const double out0 = door.s0 - s, out1 = s - door.s1;  // beyond each jamb
      const int side = out0 >= kSideFrom && out0 < kSideTo ? 0 : out1 >= kSideFrom && out1 < kSideTo ? 1 : -1;
      if (side >= 0) {
        const int col = std::min(side_cols - 1, static_cast<int>(((side == 0 ? out0 : out1) - kSideFrom) / abin));
        const int zb = std::min(nz - 1, static_cast<int>((q.z() - z0) / zbin));
        side_cells[(static_cast<std::size_t>(side) * side_cols + col) * nz + zb] = 1;
      }
    }
    if (!nearJamb(s, d)) continue;
    const int zb = std::min(nz - 1, static_cast<int>((q.z() - z0) / zbin));
    const bool inside = s > door.s0 + 0.03 && s < door.s1 - 0.03;
    const bool in_wall_band = d > -t - 0.03 && d < p.face_tolerance + 0.01;
    // A closed leaf may sit deeper than the estimated thickness (jambs unseen).
    if (inside && d > -std::max(t, 0.3) - 0.03 && d < p.face_tolerance + 0.01) in_band.push_back({s, d, zb, static_cast<int>(i)});
    if (in_wall_band && !inside) continue;  // wall, trim and jambs beside the doorway
    near.push_back({s, d, zb, static_cast<int>(i)});
  }
  pts.swap(near);
  band.swap(in_band);
}

// A return whose ray from the sensor passes near the doorway: its (s, d)
// and the ray's squared length in the wall's plan.
bool LeafSearch::nearDoorway(const Eigen::Vector3f& q, Eigen::Vector2d& qsd, double& len2) const {
  qsd = Eigen::Vector2d(wall.along(q), wall.signedDistance(q));
  const Eigen::Vector2d r = qsd - vsd;
  len2 = r.squaredNorm();
  if (len2 < 1e-6) return false;
  const double lam = std::clamp((dc - vsd).dot(r) / len2, 0.0, 1.0);
  return !((vsd + lam * r - dc).norm() > reach + Lmax);
}

// Each part (and the points' pass) fills lists of its own task, moved out
// when done: the ends of lists side by side, written at every ray, would
// share cache lines between the cores (false sharing).
void LeafSearch::gatherRayPart(int k) {
  const std::size_t i0 = points.size() * k / kRayParts, i1 = points.size() * (k + 1) / kRayParts;
  std::vector<Ray> part;
  part.reserve(i1 - i0);  // only what is used is touched
  for (std::size_t i = i0; i < i1; ++i) {
    const auto& q = points[i];
    Eigen::Vector2d qsd;
    double len2;
    if (nearDoorway(q, qsd, len2)) part.push_back({qsd, q.z(), std::sqrt(len2)});
  }
  ray_parts[k].swap(part);
}

// Joined, every stride-th kept: enough rays to see free space at 5 cm x
// 10 cm cells; more only cost time.
void LeafSearch::joinRays() {
  std::size_t total = 0;
  for (const auto& part : ray_parts) total += part.size();
  const std::size_t stride = total > 15000 ? (total + 14999) / 15000 : 1;
  rays.reserve((total + stride - 1) / stride);
  std::size_t at = 0;  // index in the joined list of the part's first ray
  for (auto& part : ray_parts) {
    for (std::size_t i = (stride - at % stride) % stride; i < part.size(); i += stride) rays.push_back(part[i]);
    at += part.size();
    std::vector<Ray>().swap(part);
  }
}

}  // namespace detail
}  // namespace state
}  // namespace dsr
