// Segmentation: the floor and the ceiling from the height histogram of
// horizontal-surface points (findFloorCeiling).
#include "door_state_recognition/segmentation/segmentation.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <unordered_set>
#include <vector>

namespace dsr {
namespace segmentation {

// Vertical structure this far above a horizontal level (m), in more than
// 2% of the vertical points (and at least this many), says the level is
// not the ceiling.
constexpr double kAboveCeiling = 0.3;
constexpr std::size_t kAboveCeilingPoints = 50;
// A ceiling has free space below it. A rotating LiDAR's rings on the walls
// are lines whose points' normals may turn upright (a ring 2 deg from the
// next leaves a point's neighbourhood a line), and the top ring's points
// make a peak of "horizontal" points on the walls: every one with more
// wall a ring or more below it, in the same cell of kBelowCell (m) across,
// kBelowFrom to kBelowTo (m) lower. A level most of whose points have
// something below them so is no ceiling (16-beam drive 1004: a "ceiling"
// 1.35 m above the sensor in 108 of its 118 clouds, 0.55 m below the
// true one, which no ring reaches in the room; walls were held to reach it).
// A true ceiling's points over a wall's top or a cupboard are few of them.
constexpr double kBelowCell = 0.05, kBelowFrom = 0.08, kBelowTo = 0.6, kBelowShare = 0.5;
// Cells of the level's box marked in a grid at most (16 MB); more, in a hash.
constexpr std::int64_t kMaxBelowCells = std::int64_t{1} << 24;

namespace {

// Whether most points of the level at z = hi (those of `horizontal`, the
// points with a horizontal surface's normal, within `band`) have a point
// kBelowFrom to kBelowTo lower in their cell of kBelowCell across: marked
// in a grid over the level's cells (a hash of the cells where that grid
// would be too large).
bool wallBelowLevel(const Points& points, const std::vector<std::size_t>& horizontal, double hi, double band) {
  std::vector<std::size_t> level;
  float x0 = std::numeric_limits<float>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  for (const std::size_t i : horizontal)
    if (std::abs(points[i].z() - hi) <= band) {
      level.push_back(i);
      x0 = std::min(x0, points[i].x()), x1 = std::max(x1, points[i].x());
      y0 = std::min(y0, points[i].y()), y1 = std::max(y1, points[i].y());
    }
  if (level.empty()) return false;
  auto cellOf = [](float v) { return static_cast<std::int64_t>(std::floor(static_cast<double>(v) / kBelowCell)); };
  const std::int64_t cx0 = cellOf(x0), cy0 = cellOf(y0), nx = cellOf(x1) - cx0 + 1, ny = cellOf(y1) - cy0 + 1;
  auto isBelow = [&](const Eigen::Vector3f& q) { return q.z() < hi - kBelowFrom && q.z() > hi - kBelowTo; };
  std::size_t over = 0;
  if (nx * ny <= kMaxBelowCells) {
    std::vector<unsigned char> below(static_cast<std::size_t>(nx * ny), 0);
    for (const auto& q : points)
      if (isBelow(q)) {
        const std::int64_t cx = cellOf(q.x()) - cx0, cy = cellOf(q.y()) - cy0;
        if (cx >= 0 && cx < nx && cy >= 0 && cy < ny) below[static_cast<std::size_t>(cy * nx + cx)] = 1;
      }
    for (const std::size_t i : level)
      over += below[static_cast<std::size_t>((cellOf(points[i].y()) - cy0) * nx + cellOf(points[i].x()) - cx0)];
  } else {
    auto key = [&](const Eigen::Vector3f& q) {
      return static_cast<std::uint64_t>(cellOf(q.x())) * 0x9E3779B97F4A7C15ULL ^ static_cast<std::uint64_t>(cellOf(q.y()));
    };
    std::unordered_set<std::uint64_t> below;
    for (const auto& q : points)
      if (isBelow(q)) below.insert(key(q));
    for (const std::size_t i : level) over += below.count(key(points[i])) > 0;
  }
  return over > kBelowShare * level.size();
}

}  // namespace

FloorCeiling findFloorCeiling(const Points& points, const Normals& normals, const Parameters& p, double viewpoint_z) {
  FloorCeiling fc;
  std::vector<float> z;
  std::vector<std::size_t> horizontal;  // the points with a horizontal surface's normal, whose z these are
  for (std::size_t i = 0; i < points.size(); ++i)
    if (std::abs(normals.n[i].z()) > p.horizontal_normal_z) z.push_back(points[i].z()), horizontal.push_back(i);
  if (z.size() < 50) return fc;
  const auto [mn, mx] = std::minmax_element(z.begin(), z.end());
  const double z0 = *mn, bin = std::max(p.histogram_bin, (*mx - z0) / 100000.0);
  const std::size_t bins = static_cast<std::size_t>((*mx - z0) / bin) + 1;
  std::vector<int> hist(bins, 0);
  for (float v : z) ++hist[std::min(bins - 1, static_cast<std::size_t>((v - z0) / bin))];
  const int peak = *std::max_element(hist.begin(), hist.end());
  const int threshold = std::max(30, peak / 8);
  // Significant local maxima, low to high.
  std::vector<std::size_t> peaks;
  for (std::size_t b = 0; b < bins; ++b) {
    const int left = b > 0 ? hist[b - 1] : 0, right = b + 1 < bins ? hist[b + 1] : 0;
    if (hist[b] >= threshold && hist[b] >= left && hist[b] >= right) peaks.push_back(b);
  }
  if (peaks.empty()) return fc;
  auto refine = [&](std::size_t b) {  // mean z of the points in the peak's neighbourhood
    double s = 0;
    int n = 0;
    for (float v : z)
      if (std::abs(v - (z0 + (b + 0.5) * bin)) <= 1.5 * bin) s += v, ++n;
    return n ? s / n : z0 + (b + 0.5) * bin;
  };
  const double lo = refine(peaks.front()), hi = refine(peaks.back());
  // A ceiling closes the room: walls do not rise above it. A horizontal
  // level with much vertical structure above it is the top of a desk or a
  // cupboard, or the underside of a shelf, seen by a sensor that does not
  // see the ceiling (a camera frame rarely does).
  std::size_t vertical = 0, above = 0;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (std::abs(normals.n[i].z()) < p.vertical_normal_z) {
      ++vertical;
      above += points[i].z() > hi + kAboveCeiling;
    }
  bool closes = above < std::max<std::size_t>(kAboveCeilingPoints, vertical / 50);
  if (closes) closes = !wallBelowLevel(points, horizontal, hi, 1.5 * bin);
  if (hi - lo >= p.min_room_height && closes) {
    fc.floor = lo;
    fc.ceiling = hi;
  } else if (lo < viewpoint_z) {
    fc.floor = lo;  // one horizontal level below the sensor: the floor
  } else if (closes) {
    fc.ceiling = hi;
  }
  return fc;
}

}  // namespace segmentation
}  // namespace dsr
