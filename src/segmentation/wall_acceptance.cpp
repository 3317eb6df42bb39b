// Segmentation: the wall rules of findWalls for one plane's inliers
// (addWallSegments): split at gaps, then each segment kept or refused
// (tall, reaching the top, long enough, not shadowed, not edge-on, not sparse).
#include "door_state_recognition/segmentation/segmentation.hpp"

#include "door_state_recognition/util/both_halves.hpp"
#include "door_state_recognition/util/radix_sort.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

namespace dsr {
namespace segmentation {

// A gap in a wall's inliers with more than this share unseen splits it.
constexpr double kGapUnknown = 0.1;

// cos 15 deg: planes closer to parallel than this may shadow one another.
constexpr double kNearParallel = 0.966;

// sin 5 deg: a plane passing closer than this share of the range of its
// nearest point to the viewpoint is seen at more than 85 deg incidence
// everywhere. Range sensors return almost nothing from a surface that
// grazing: such a "wall" is a sheet of mixed (flying) pixels strung along
// the rays past a depth edge, not a surface.
constexpr double kEdgeOnShare = 0.087;

// Of a wall's surface not hidden from the viewpoint (by what stands in
// front of it), at least this share holds points: each point within
// kFillBand of its plane taken for the patch of surface a sensor's ray (or
// the voxel grid, where coarser) gives one point on. A wall is one
// continuous surface: on the tuning camera frames the walls holding a true
// door covered 0.78 or more of what they show; a "wall" joined from
// scattered pieces (the edges of furniture and of the room beyond seen
// through a doorway, flying pixels between them) covers down to a sixth.
constexpr double kMinWallFill = 0.5;
// Points this close to the plane count for it (depth noise of a few
// centimetres at a few metres spreads a wall's points that far).
constexpr double kFillBand = 0.1;
// The lowest this high above the floor are left out (the floor's own points).
constexpr double kFillAboveFloor = 0.15;

namespace {
// A wall's top within this of the view's top (tan of elevation) was cut by the view.
constexpr float kViewTopSlack = 0.02f;

// tanElevation(q) lies below hi for sure, told without hypot: the quotient
// in double by sqrt in double is within a few parts in 1e7 of it (both
// roundings to float included), far inside the margin of 1e-5 of it; near
// the viewpoint's vertical, or near hi, false (then the caller works
// tanElevation out). Nothing lies below -infinity (an empty bin).
inline bool surelyBelow(const ViewTop& v, const Eigen::Vector3f& q, float hi) {
  const float dx = q.x() - v.viewpoint.x(), dy = q.y() - v.viewpoint.y();
  const double h2 = static_cast<double>(dx) * dx + static_cast<double>(dy) * dy;
  if (!(h2 > 4e-6)) return false;  // h within 2 mm: tanElevation's cut-off at 1 mm is near
  const double t = static_cast<double>(q.z() - v.viewpoint.z()) / std::sqrt(h2);
  return t + 1e-5 * std::abs(t) + 1e-30 < hi;
}

// Lists of at least this many points are read in two halves at once by addWallSegments.
constexpr std::size_t kSplitSegment = 10000;
}  // namespace

void addWallSegments(const Points& points, const std::vector<int>& inliers, const Eigen::Vector2d& point,
                     const Eigen::Vector2d& direction, const Eigen::Vector2d& normal, double floor_z, double height_top,
                     bool ceiling_known, const Parameters& p, std::vector<WallPlane>& walls,
                     const ViewTop* view, const Eigen::Vector2d* viewpoint) {
  const double room_h = height_top - floor_z;
  // What the sensor saw across a gap (a, b) in the inliers, in 5 cm bins at
  // a door's body height: each hidden by something in front, seen through
  // (returns behind the plane, or rays of a camera's pixels without a
  // return), showing points near the plane, or nothing at all (unknown).
  auto gapSeen = [&](double a, double b, double& through, double& unknown) {
    through = 0;
    unknown = 1;
    if (!viewpoint) return;
    const double vs = (*viewpoint - point).dot(direction), vd = (*viewpoint - point).dot(normal);
    if (vd <= 0.1) return;
    const int bins = std::max(1, static_cast<int>(std::ceil((b - a) / 0.05)));
    std::vector<char> sh(bins, 0), th(bins, 0), any(bins, 0);
    auto binOf = [&](double s) { return s > a && s < b ? std::min(bins - 1, static_cast<int>((s - a) / 0.05)) : -1; };
    for (const auto& q : points) {
      if (q.z() < floor_z + 0.25 || q.z() > floor_z + 1.75) continue;
      const Eigen::Vector2d r(q.x() - point.x(), q.y() - point.y());
      const double d = r.dot(normal);
      if (d >= vd) continue;
      const int k = binOf(vs + vd / (vd - d) * (r.dot(direction) - vs));
      if (k < 0) continue;
      any[k] = 1;
      if (std::abs(d) > p.wall_distance) (d > 0 ? sh : th)[k] = 1;
    }
    if (view) {
      const Eigen::Vector3f v3(static_cast<float>(viewpoint->x()), static_cast<float>(viewpoint->y()), view->viewpoint.z());
      for (const Eigen::Vector3f& u : view->no_return) {
        const double un = u.x() * normal.x() + u.y() * normal.y();
        if (un >= -1e-6) continue;
        const Eigen::Vector3f x = v3 + static_cast<float>(vd / -un) * u;
        if (x.z() < floor_z + 0.25 || x.z() > floor_z + 1.75) continue;
        const int k = binOf((Eigen::Vector2d(x.x(), x.y()) - point).dot(direction));
        if (k >= 0) th[k] = 1;
      }
    }
    int nt = 0, nu = 0;
    for (int k = 0; k < bins; ++k) {
      nt += !sh[k] && th[k];
      nu += !sh[k] && !th[k] && !any[k];
    }
    through = nt * 0.05;
    unknown = static_cast<double>(nu) / bins;
  };
  // Seen edge-on from the viewpoint along all its length (kEdgeOnShare).
  auto edgeOn = [&](const WallPlane& w) {
    if (!viewpoint) return false;
    const double vd = std::abs((*viewpoint - point).dot(normal));
    double nearest = std::numeric_limits<double>::infinity();
    for (const int i : w.inliers)
      nearest = std::min(nearest, (Eigen::Vector2d(points[i].x(), points[i].y()) - *viewpoint).squaredNorm());
    return vd < kEdgeOnShare * std::sqrt(nearest);
  };
  // Too few points on the surface it shows (kMinWallFill), where the
  // sensor's ray spacing is known (an organized cloud: one return per ray,
  // on the plane, in front of it or beyond).
  auto sparse = [&](const WallPlane& w) {
    if (!view || view->ray_spacing <= 0) return false;
    const double z0 = floor_z + kFillAboveFloor, area = (w.s_max - w.s_min) * (w.z_max - z0);
    if (area <= 0) return false;
    const double voxel2 = p.voxel_size * p.voxel_size, spacing = view->ray_spacing;
    const Eigen::Vector3d v = view->viewpoint.cast<double>();
    const double vd = (Eigen::Vector2d(v.x(), v.y()) - point).dot(normal);
    // The patch a ray meets the plane in, at x (t: x's range over the range
    // of the point that stands for it, whose voxel it spreads by t).
    auto patch = [&](const Eigen::Vector3d& x, double t) {
      const Eigen::Vector3d r = x - v;
      const double range = r.norm();
      const double cos_inc = std::max(0.1, std::abs(r.x() * normal.x() + r.y() * normal.y()) / std::max(range, 1e-6));
      return std::max(voxel2 * t * t, range * spacing * range * spacing / cos_inc);
    };
    auto inBox = [&](const Eigen::Vector3d& x) {
      const double sv = (Eigen::Vector2d(x.x(), x.y()) - point).dot(direction);
      return sv >= w.s_min && sv <= w.s_max && x.z() >= z0 && x.z() <= w.z_max;
    };
    // Its inliers alone often suffice (they lie within the band, none hidden).
    double covered = 0;
    for (const int i : w.inliers) {
      const Eigen::Vector3d x = points[i].cast<double>();
      if (inBox(x)) covered += patch(x, 1.0);
    }
    if (covered >= kMinWallFill * area) return false;
    covered = 0;
    double hidden = 0;
    for (const auto& q : points) {
      const double d = (Eigen::Vector2d(q.x(), q.y()) - point).dot(normal);
      if (std::abs(d) <= kFillBand) {
        const Eigen::Vector3d x = q.cast<double>();
        if (inBox(x)) covered += patch(x, 1.0);
      } else if (d > kFillBand && d < vd) {  // in front: hides where its ray meets the plane
        const double t = vd / (vd - d);
        const Eigen::Vector3d x = v + t * (q.cast<double>() - v);
        if (inBox(x)) hidden += patch(x, t);
      }
    }
    return covered < kMinWallFill * std::max(area - hidden, 0.0);
  };
  // Split along the wall at gaps wider than wall_gap.
  // (Many inliers: in two halves at once.)
  std::vector<std::pair<double, int>> along(inliers.size());
  {
    const std::size_t n = inliers.size(), mid = n >= kSplitSegment ? n / 2 : n;
    util::bothHalves(mid < n, [&](int h) {
      for (std::size_t k = h ? mid : 0, end = h ? n : mid; k < end; ++k) {
        const int i = inliers[k];
        along[k] = {(Eigen::Vector2d(points[i].x(), points[i].y()) - point).dot(direction), i};
      }
    });
  }
  util::sortPairs(along);  // std::sort's order, in linear time
  std::size_t start = 0;
  for (std::size_t k = 1; k <= along.size(); ++k) {
    if (k < along.size() && along[k].first - along[k - 1].first <= p.wall_gap) continue;
    // A gap the sensor could not see the wall across (hidden by what stands
    // in front, and seen through no wider than a doorway) does not split it.
    if (k < along.size()) {
      double through, unknown;
      gapSeen(along[k - 1].first, along[k].first, through, unknown);
      if (unknown <= kGapUnknown && through <= p.door_max_width + 0.1) continue;
    }
    WallPlane w;
    w.point = point;
    w.direction = direction;
    w.normal = normal;
    w.s_min = along[start].first;
    w.s_max = along[k - 1].first;
    w.z_min = 1e9;
    w.z_max = -1e9;
    w.inliers.reserve(k - start);
    for (std::size_t j = start; j < k; ++j) {
      w.inliers.push_back(along[j].second);
      w.z_min = std::min<double>(w.z_min, points[along[j].second].z());
      w.z_max = std::max<double>(w.z_max, points[along[j].second].z());
    }
    start = k;
    const double h = w.z_max - floor_z;

    // Or the view's top: the highest points of the wall are the highest seen
    // on most of its bearings (a camera frame cuts a near wall below the ceiling).
    auto cutByView = [&]() {
      if (!view || view->max_tan.empty()) return false;
      // Each bearing's highest (a greatest value, whatever the order it is
      // taken in): many inliers in two halves at once, each into bins of its own.
      std::vector<float> top(view->max_tan.size(), -std::numeric_limits<float>::infinity()), top_second;
      const std::size_t n = w.inliers.size(), mid = n >= kSplitSegment ? n / 2 : n;
      util::bothHalves(mid < n, [&](int h) {
        std::vector<float>& t = h ? top_second : top;
        if (h) t.assign(top.size(), -std::numeric_limits<float>::infinity());
        for (std::size_t k = h ? mid : 0, end = h ? n : mid; k < end; ++k) {
          const auto& q = points[w.inliers[k]];
          const int b = view->bin(q);
          // A camera's rows come top down: a bearing's first point is mostly its highest.
          if (b >= 0 && !surelyBelow(*view, q, t[b])) t[b] = std::max(t[b], view->tanElevation(q));
        }
      });
      for (std::size_t b = 0; b < top_second.size(); ++b) top[b] = std::max(top[b], top_second[b]);
      int bins = 0, cut = 0;
      for (std::size_t b = 0; b < top.size(); ++b)
        if (std::isfinite(top[b])) ++bins, cut += top[b] >= view->max_tan[b] - kViewTopSlack;
      return bins > 0 && cut >= 0.5 * bins;
    };
    const bool cut = cutByView();
    const bool reaches_top = !ceiling_known || w.z_max > height_top - 0.25 || cut;
    // The view's bottom: the lowest points of the wall are the lowest seen
    // on most of its bearings (a camera pitched up, or close to a wall,
    // sees no floor before it); where the floor or anything standing before
    // the wall is seen below it, it is not cut there.
    auto cutBelowByView = [&]() {
      if (!view || view->min_tan.empty()) return false;
      std::vector<float> low(view->min_tan.size(), std::numeric_limits<float>::infinity());
      for (int i : w.inliers) {
        const auto& q = points[i];
        const int b = view->bin(q);
        if (b >= 0) low[b] = std::min(low[b], view->tanElevation(q));
      }
      int bins = 0, cut_low = 0;
      for (std::size_t b = 0; b < low.size(); ++b)
        if (std::isfinite(low[b])) ++bins, cut_low += low[b] <= view->min_tan[b] + kViewTopSlack;
      return bins > 0 && cut_low >= 0.5 * bins;
    };
    // Tall: from near the floor (or from the view's bottom) up to the share
    // of the room a wall spans, or (cut by the view) as high as a door at least.
    const bool from_floor = w.z_min < floor_z + 0.5 || cutBelowByView();
    const bool tall = (h >= p.wall_height_ratio * room_h || (cut && h >= p.door_min_height)) && from_floor;
    // A plane parallel to a stronger wall and close behind or before it
    // (a recessed leaf, trim, a cupboard front) is not another wall; nor is
    // one a few degrees off a stronger wall and close to it all along (a
    // second hypothesis of a noisy face): walls do not meet at such angles.
    bool shadowed = false;
    for (const WallPlane& o : walls) {
      const double c = std::abs(o.normal.dot(w.normal));
      if (c < kNearParallel) continue;
      const Eigen::Vector2d a = w.point + w.s_min * w.direction, b = w.point + w.s_max * w.direction;
      const double off = std::abs((0.5 * (a + b) - o.point).dot(o.normal));
      const double off_ends = std::max(std::abs((a - o.point).dot(o.normal)), std::abs((b - o.point).dot(o.normal)));
      const double s0 = std::min((a - o.point).dot(o.direction), (b - o.point).dot(o.direction));
      const double s1 = std::max((a - o.point).dot(o.direction), (b - o.point).dot(o.direction));
      // Off parallel, only along the stronger wall: not a wall meeting it at a shallow corner.
      const bool along = c >= 0.995 ? s0 < o.s_max && s1 > o.s_min : off_ends < 0.5 && s0 > o.s_min - 0.3 && s1 < o.s_max + 0.3;
      shadowed |= off < 0.3 && along;
    }
    // Without a ceiling to reach, a door leaf is as tall as a wall: then a
    // wall must also be longer than any door.
    const double min_length = ceiling_known ? p.min_wall_length : std::max(p.min_wall_length, p.door_max_width + 0.1);
    if (static_cast<int>(w.inliers.size()) >= p.min_wall_points && w.s_max - w.s_min >= min_length && tall &&
        reaches_top && !shadowed && !edgeOn(w) && !sparse(w))
      walls.push_back(std::move(w));
  }
}

// Depths of furniture against a wall (furnitureFronts): its front's middle
// this far in front of the wall (closer, the shadow rule of addWallSegments
// already takes it for trim or a recessed leaf), its ends no farther than
// kFurnitureEnd (two cupboards of different depths joined into one line).
constexpr double kFurnitureNear = 0.25, kFurnitureFar = 0.8, kFurnitureEnd = 0.95;
// At least this share of its length along the wall's visible part.
constexpr double kFurnitureOverlap = 0.5;

std::vector<char> furnitureFronts(const std::vector<WallPlane>& walls, const Eigen::Vector2d& viewpoint) {
  std::vector<char> front(walls.size(), 0);
  for (std::size_t i = 0; i < walls.size(); ++i) {
    const WallPlane& w = walls[i];
    const Eigen::Vector2d a = w.point + w.s_min * w.direction, b = w.point + w.s_max * w.direction;
    for (std::size_t j = 0; j < walls.size() && !front[i]; ++j) {
      const WallPlane& o = walls[j];
      if (j == i || std::abs(o.normal.dot(w.normal)) < kNearParallel) continue;
      if (o.s_max - o.s_min <= w.s_max - w.s_min) continue;  // only in front of a longer wall
      const double da = (a - o.point).dot(o.normal), db = (b - o.point).dot(o.normal);
      const double mid = 0.5 * (da + db), seen = (viewpoint - o.point).dot(o.normal);
      if (mid < kFurnitureNear || mid > kFurnitureFar || std::min(da, db) <= 0 ||
          std::max(da, db) > kFurnitureEnd || seen <= std::max(da, db))
        continue;
      const double sa = (a - o.point).dot(o.direction), sb = (b - o.point).dot(o.direction);
      // Most of it along the wall (which the furniture itself hides where it ends a wall's visible part).
      const double overlap = std::min(std::max(sa, sb), o.s_max) - std::max(std::min(sa, sb), o.s_min);
      front[i] = overlap >= kFurnitureOverlap * std::abs(sb - sa);
    }
  }
  return front;
}

}  // namespace segmentation
}  // namespace dsr
