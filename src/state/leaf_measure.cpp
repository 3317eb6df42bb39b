// State: the leaf fitLeaf's search found, measured: closed in its band, or
// its angle and hinge refined by a line through its points and judged by
// its coverage; then what it explains of what hides the doorway, its hinge,
// direction and top.
#include "leaf_internal.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

namespace dsr {
namespace state {
namespace detail {

Eigen::Vector2d LeafSearch::toXY(double s, double d) const { return wall.point + s * wall.direction + d * wall.normal; }

double LeafSearch::crowdBefore(double angle_deg, double len) const {
  const double th = angle_deg * M_PI / 180;
  const LeafAxes axes(th, e0, m);
  const Eigen::Vector2d &e = axes.e, &k = axes.k;
  // The sensor's side of the leaf's plane; "out" measures past the band on that side.
  const double side = (vsd - Eigen::Vector2d(s_h, d_h)).dot(k) >= 0 ? 1.0 : -1.0;
  int in_band = 0, before = 0;
  for (const Local& q : pts) {
    const Eigen::Vector2d r(q.s - s_h, q.d - d_h);
    const double a = r.dot(e), b = r.dot(k);
    if (a < kCrowdFromHinge || a > len - kCrowdToTip) continue;
    const double out = side > 0 ? b - (lt + tol) : -tol - b;
    if (b >= -tol && b <= lt + tol) ++in_band;
    else if (out > 0 && out <= kCrowdSlab) ++before;
  }
  return in_band > 0 ? static_cast<double>(before) / in_band : 0.0;
}

double LeafSearch::restSeenThrough(double angle_deg, double len, double span) const {
  const int first = static_cast<int>(std::ceil((len + kRestMargin) / abin - 1e-9));
  const int last = std::min(na_max, static_cast<int>(std::floor(std::min(span, Lmax) / abin + 1e-9)));  // exclusive
  // The doorway's span is the leaf's length only where trim frames it (a
  // doorway without trim may hold a leaf's shadow on its wall).
  if (!door.casing || len >= kRestFromShare * span || last - first < 2) return 0.0;
  HingeRun w;
  w.s_h = s_h, w.d_h = d_h, w.e0 = e0, w.m = m, w.start = angle_deg, w.step = 1, w.count = 1;
  scoreRays(w, nullptr);
  int crossed = 0;
  for (int ab = first; ab < last; ++ab) crossed += w.con[static_cast<std::size_t>(ab)];
  return static_cast<double>(crossed) / (static_cast<double>(last - first) * nz);
}

double LeafSearch::frontAtTip(double angle_deg, double len) const {
  const double th = angle_deg * M_PI / 180;
  const LeafAxes axes(th, e0, m);
  const Eigen::Vector2d &e = axes.e, &k = axes.k;
  // The strip: within kAlong of the tip's distance from the hinge along the
  // leaf, from kFrom to kTo past the leaf's opening face (+k), in kBin cells
  // across by the search's height bins.
  constexpr double kFrom = 0.05, kTo = 0.45, kBin = 0.05, kAlong = 0.06;
  const int nb = static_cast<int>(std::lround((kTo - kFrom) / kBin));
  std::vector<char> hit(static_cast<std::size_t>(nb) * nz, 0);
  int cells = 0;
  for (const Local& q : pts) {
    const Eigen::Vector2d r(q.s - s_h, q.d - d_h);
    const double a = r.dot(e), b = r.dot(k) - lt - tol;
    if (a < len - kAlong || a > len + kAlong || b < kFrom || b >= kTo) continue;
    char& f = hit[static_cast<std::size_t>(std::min(nb - 1, static_cast<int>((b - kFrom) / kBin))) * nz + q.zbin];
    if (!f) f = 1, ++cells;
  }
  return static_cast<double>(cells) / (static_cast<double>(nb) * nz);
}

void LeafSearch::measureLeaf() {
  fit.best_angle_deg = best_deg;
  fit.best_coverage = gen_cov;
  fit.best_contradiction = gen_contra;
  fit.candidate_points = static_cast<int>(pts.size());
  fit.candidate_rays = static_cast<int>(rays.size());
  fit.length = L;
  fit.hinge_at_s0 = best_h == 0;
  fit.toward_viewer = best_sw == 0;
  s_h = best_s;
  s_other = best_h == 0 ? door.s1 : door.s0, e0 = best_h == 0 ? 1.0 : -1.0;
  m = best_sw == 0 ? 1.0 : -1.0, d_h = best_sw == 0 ? -best_recess : -t + best_recess;
  // Support of one hypothesis (cells holding points), with its inliers.
  auto support = [&](double sh, double th_deg, double len, double band_lo, double band_hi, std::vector<int>* inl,
                     std::vector<Eigen::Vector2d>* xy) {
    const double th = th_deg * M_PI / 180;
    const LeafAxes axes(th, e0, m);
    const Eigen::Vector2d &e = axes.e, &k = axes.k;
    const int nl = std::max(1, static_cast<int>(std::ceil(len / abin)));
    std::vector<char> hit(static_cast<std::size_t>(nl) * nz, 0);
    int cells = 0;
    for (const Local& q : pts) {
      const Eigen::Vector2d r(q.s - sh, q.d - d_h);
      const double a = r.dot(e), b = r.dot(k);
      if (a < 0.02 || a > len || b < band_lo || b > band_hi) continue;
      char& f = hit[static_cast<std::size_t>(std::min(nl - 1, static_cast<int>(a / abin))) * nz + q.zbin];
      if (!f) f = 1, ++cells;
      if (inl) inl->push_back(q.index);
      if (xy) xy->emplace_back(q.s, q.d);
    }
    return static_cast<double>(cells) / (static_cast<double>(nl) * nz);
  };

  if (closed_band) {
    fit.found = true;
    fit.closed_in_band = true;
    fit.angle_deg = band_angle;
    // A closed leaf sits flush with (or set back from) the face of the wall
    // on its swing side: its visible face near the near face says "towards
    // the viewer", near the far face (less a leaf thickness) "away".
    fit.face_d = band_face;
    fit.toward_viewer = -fit.face_d < (t - lt) / 2;
    fit.coverage = band_cov;
    for (const Local& q : band) fit.inliers.push_back(q.index);
    s_h = best_h == 0 ? door.s0 : door.s1;  // a closed leaf fills its doorway from jamb to jamb
  } else if ((gen_cov >= 0.1 || (view && gen_cov >= 0.05)) && gen_contra < 0.1) {
    // Refine: a TLS line through the inliers gives the angle; where it meets
    // the wall face on the swing side is the hinge (the doorway's edge seen
    // from the wall can be off where the leaf shadows the wall).
    double angle = best_deg;
    const double len = best_bins * abin;
    for (int iter = 0; iter < 3; ++iter) {
      std::vector<Eigen::Vector2d> xy;
      support(s_h, angle, len + 0.1, -0.05, lt + 0.05, nullptr, &xy);
      if (xy.size() < 10) break;
      Line2 l = fitLine(xy);
      const double th = angle * M_PI / 180;
      const Eigen::Vector2d e = LeafAxes(th, e0, m).e;
      if (l.direction.dot(e) < 0) l.direction = -l.direction;
      const double refined = std::atan2(l.direction.y() * m, l.direction.x() * e0) * 180 / M_PI;
      if (std::abs(refined - angle) > 8) break;  // the fit wandered off: keep the search's answer
      angle = std::clamp(refined, 0.0, 180.0);
      if (angle > 25 && angle < 155) {
        // The visible face is the one towards the sensor; the hinge line is
        // the swing face: shift the fitted line by the thickness if needed.
        const Eigen::Vector2d kk(std::sin(angle * M_PI / 180) * e0, -std::cos(angle * M_PI / 180) * m);
        Eigen::Vector2d on = l.point;
        if ((vsd - l.point).dot(kk) > 0) on -= kk * lt;  // sensor sees the back face: move to the swing face
        const double lam = (d_h - on.y()) / l.direction.y();
        const double s_new = on.x() + lam * l.direction.x();
        if (std::abs(s_new - s_h) < 0.2) s_h = s_new;
      }
    }
    // Keep the refinement only if the leaf it describes is as well supported:
    // the refined hinge and angle, else the refined angle alone, else the search's.
    const double search_s_h = best_s;
    const double cov_search = support(search_s_h, best_deg, len, -tol, lt + tol, nullptr, nullptr);
    if (support(s_h, angle, len, -tol, lt + tol, nullptr, nullptr) < 0.9 * cov_search) {
      s_h = search_s_h;
      if (support(s_h, angle, len, -tol, lt + tol, nullptr, nullptr) < 0.9 * cov_search) angle = best_deg;
    }
    std::vector<int> inl;
    const double cov = support(s_h, angle, len, -tol, lt + tol, &inl, nullptr);
    // A doorway beyond doubt (trim, or the room beyond seen through it) takes
    // a leaf seen only edge-on or in part, as long as no ray contradicts it.
    const bool sure_doorway = door.sure();
    // A leaf cut by the edge of a camera's view: its share of cells inside
    // the view holding points (as above, relaxed in a doorway beyond doubt),
    // where at least a quarter of it is inside.
    double in_view = 1.0;
    if (view) {
      const double th = angle * M_PI / 180;
      const LeafAxes axes(th, e0, m);
      const Eigen::Vector2d &e = axes.e, &k = axes.k;
      const int nl = std::max(1, static_cast<int>(std::ceil(len / abin)));
      int inside = 0;
      for (int i = 0; i < nl; ++i) {
        const Eigen::Vector2d sd = Eigen::Vector2d(s_h, d_h) + e * ((i + 0.5) * abin) + k * (lt / 2);
        const Eigen::Vector2d xy = toXY(sd.x(), sd.y());
        for (int zb = 0; zb < nz; ++zb)
          inside += view->inView(Eigen::Vector3f(static_cast<float>(xy.x()), static_cast<float>(xy.y()),
                                                 static_cast<float>(z0 + (zb + 0.5) * zbin)));
      }
      in_view = static_cast<double>(inside) / (static_cast<double>(nl) * nz);
    }
    const bool cut_by_view = in_view >= 0.25 && in_view < 0.9 && gen_contra <= 0.05 &&
                             cov >= (sure_doorway ? 0.5 : 1.0) * p.min_leaf_coverage * in_view;
    const double min_cov = p.min_leaf_coverage * fit.sampling;
    // A plane through a volume is no leaf (crowdBefore).
    fit.crowd_before = crowdBefore(angle, len);
    const bool in_volume = angle >= kCrowdFromDeg && fit.crowd_before >= kCrowdShare;
    const bool covered = cov >= min_cov || (sure_doorway && cov >= 0.5 * min_cov && gen_contra <= 0.05) || cut_by_view;
    fit.rest_seen_through = restSeenThrough(angle, len, std::abs(s_other - s_h));
    fit.front_at_tip = frontAtTip(angle, len);
    const bool seen_past_tip = fit.rest_seen_through >= kRestSeenThrough;
    const bool fronted = angle >= kTipFrontFromDeg && angle <= kTipFrontToDeg && fit.front_at_tip >= kTipFront;
    if (covered && !in_volume && !seen_past_tip && !fronted) {
      fit.found = true;
      fit.coverage = cov;
      fit.angle_deg = angle;
      fit.length = len;
      fit.inliers = std::move(inl);
    }
  }
  fit.s_hinge = s_h;
  fit.s_latch = fit.closed_in_band ? s_other : s_h + e0 * (fit.length + 0.008);
  // An open leaf seen only in part (cut by the edge of a camera's view, or
  // hidden in part) is shorter than any door; a doorway seen through from
  // jamb to jamb gives the door's width instead.
  if (fit.found && !fit.closed_in_band && fit.length < p.door_min_width && door.sure()) {
    const double span = std::abs(s_other - s_h);
    if (span >= p.door_min_width && span <= p.door_max_width) fit.s_latch = s_other;
  }
}

void LeafSearch::placeLeaf() {
  if (!fit.found) return;
  if (!fit.closed_in_band && vsd.y() > 0.1) {
    // What hides the doorway from the sensor, near it: points in front of the
    // wall whose sight lines, carried on, meet the wall inside the doorway.
    // A leaf swung towards the sensor is all of it; a cupboard's side taken
    // for a leaf leaves its front unexplained.
    // On the leaf: within its thickness either side of the hinge line (the
    // face seen may be either, and a recess the search missed shifts it).
    const double th = fit.angle_deg * M_PI / 180;
    const LeafAxes axes(th, e0, m);
    const Eigen::Vector2d &e = axes.e, &k = axes.k;
    int occluders = 0, explained = 0;
    for (const Local& q : pts) {
      if (q.d <= p.face_tolerance + 0.02 || q.d >= vsd.y()) continue;
      const double lam = vsd.y() / (vsd.y() - q.d);
      const double s_wall = vsd.x() + lam * (q.s - vsd.x());
      if (s_wall <= door.s0 + 0.05 || s_wall >= door.s1 - 0.05) continue;
      ++occluders;
      const Eigen::Vector2d r(q.s - s_h, q.d - d_h);
      const double a = r.dot(e), b = r.dot(k);
      explained += a >= 0.02 && a <= fit.length && b >= -lt - tol && b <= lt + tol;
    }
    fit.occluders_explained = occluders > 0 ? static_cast<double>(explained) / occluders : 0.0;
  }
  const double th = fit.angle_deg * M_PI / 180;
  const Eigen::Vector2d dir_sd = LeafAxes(th, e0, m).e;
  const double hinge_d = !fit.closed_in_band ? d_h : fit.toward_viewer ? fit.face_d : fit.face_d - lt;
  const Eigen::Vector2d hinge_xy = toXY(s_h, hinge_d);
  fit.hinge = hinge_xy;
  fit.direction = (dir_sd.x() * wall.direction + dir_sd.y() * wall.normal).normalized();
  // The leaf's top: highest of its points over its whole height.
  double top = z1;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& q = points[i];
    if (q.z() < z1) continue;
    const double s = wall.along(q), d = wall.signedDistance(q);
    const Eigen::Vector2d r(s - s_h, d - (fit.closed_in_band ? -t / 2 : d_h));
    const double a = r.dot(dir_sd), b = std::abs(r.x() * dir_sd.y() - r.y() * dir_sd.x());
    if (a > 0.05 && a < fit.length && b < (fit.closed_in_band ? t / 2 + 0.03 : lt + tol)) top = std::max<double>(top, q.z());
  }
  fit.top_z = top;
}

}  // namespace detail
}  // namespace state
}  // namespace dsr
