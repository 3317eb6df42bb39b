// A survey of several scan positions (stations) in one frame: each station's
// scan runs through the pipeline alone, with its own viewpoint (a ray is only
// known between a point and the station that saw it), and the results are
// merged here: walls on one line joined, a door seen from several stations
// reported once, from the station whose scan measured its leaf best.
#include <algorithm>
#include <chrono>
#include <iterator>
#include <cmath>
#include <stdexcept>
#include <string>

#include "door_state_recognition/pipeline/input_checks.hpp"
#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/pipeline/report_groups.hpp"
#include "door_state_recognition/pipeline/sight.hpp"
#include "door_state_recognition/preprocess/preprocess.hpp"
#include "door_state_recognition/recognition/recognition.hpp"
#include "door_state_recognition/reconstruction/reconstruction.hpp"

namespace dsr {
namespace {

// Walls of two stations are one wall when their lines agree this well.
constexpr double kWallParallelCos = 0.9986;  // 3 deg
constexpr double kWallOffset = 0.08;         // m, between the lines
constexpr double kWallGap = 0.3;             // m, between their extents along the line
// Doors of two stations are one door when their doorways' centres are this close.
constexpr double kSameDoor = 0.45;  // m
// ... or when, on one wall, their doorways overlap by more than this (two
// doorways side by side at most touch; a leaf fitted from the wrong jamb,
// or a doorway taken in its leaf's shadow, overlaps the true one).
constexpr double kSameDoorOverlap = 0.1;  // m
// Two parallel walls this close are the two faces of one wall (for doors).
constexpr double kWallFaces = 0.4;  // m

struct Line2 {  // a wall in the levelled frame
  Eigen::Vector2d point, dir;
  double s0, s1;
};

Line2 levelledLine(const WallResult& w, const Eigen::Matrix3d& R) {
  const Eigen::Vector3d p = R * w.line_point, d = R * w.line_direction;
  Line2 l{p.head<2>(), Eigen::Vector2d(d.x(), d.y()).normalized(), 0, w.length};
  return l;
}

// Rebuilds `into`'s corner box to hold both walls' boxes, along its line.
void unionCorners(WallResult& into, const WallResult& other, const Eigen::Matrix3d& R) {
  const Eigen::Matrix3d Rt = R.transpose();
  const Eigen::Vector3d d3 = R * into.line_direction;
  const Eigen::Vector3d e1 = Eigen::Vector3d(d3.x(), d3.y(), 0).normalized(), e3 = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d e2 = e3.cross(e1);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  for (const WallResult* w : {static_cast<const WallResult*>(&into), &other})
    for (const Eigen::Vector3d& c : w->corners) {
      const Eigen::Vector3d p = R * c, q(p.dot(e1), p.dot(e2), p.dot(e3));
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
  into.corners = recognition::boxCorners(lo, hi, e1, e2, e3);
  for (Eigen::Vector3d& c : into.corners) c = Rt * c;
}

}  // namespace

PipelineResult Pipeline::runStations(const std::vector<Station>& stations, bool with_reconstruction) const {
  if (stations.empty()) throw std::invalid_argument("no station given");
  std::size_t total_points = 0;
  for (const Station& st : stations) {
    if (!st.cloud) throw std::invalid_argument("station without a cloud");
    if (!st.viewpoint.allFinite() || st.viewpoint.cwiseAbs().maxCoeff() > params_.max_abs_coordinate)
      throw std::invalid_argument("station viewpoint is not finite or lies beyond max_abs_coordinate");
    total_points += st.cloud->size();
  }
  if (total_points > static_cast<std::size_t>(params_.max_points))
    throw std::invalid_argument("stations of " + std::to_string(total_points) + " points in all exceed max_points (" +
                                std::to_string(params_.max_points) + ")");
  if (stations.size() == 1) return run(*stations[0].cloud, with_reconstruction, stations[0].viewpoint);

  const auto t0 = std::chrono::steady_clock::now();
  // Each station reports every door whose leaf it did not see but found
  // not closed, with its lower bound: the bounds of several stations are
  // merged (the largest holds), and only then held against
  // unseen_leaf_min_bound_deg.
  Parameters each = params_;
  each.unseen_leaf_min_bound_deg = std::min(each.unseen_leaf_min_bound_deg, each.closed_below_deg);
  const Pipeline per_station(each);
  std::vector<PipelineResult> runs(stations.size());
  for (std::size_t k = 0; k < stations.size(); ++k)
    if (!stations[k].refine_only) runs[k] = per_station.run(*stations[k].cloud, false, stations[k].viewpoint);
  // Refine-only stations refine only doors whose leaf no other station saw
  // (below): run only where some door is such.
  const bool refine = std::any_of(runs.begin(), runs.end(), [](const PipelineResult& r) {
    return std::any_of(r.doors.begin(), r.doors.end(), [](const DoorResult& d) { return d.angle_is_lower_bound; });
  });
  for (std::size_t k = 0; k < stations.size(); ++k)
    if (stations[k].refine_only && refine) runs[k] = per_station.run(*stations[k].cloud, false, stations[k].viewpoint);

  // The frame of the main station that kept the most points after thinning.
  std::size_t primary = 0;
  for (std::size_t k = 1; k < runs.size(); ++k)
    if (!stations[k].refine_only && runs[k].points_used > runs[primary].points_used) primary = k;
  PipelineResult res;
  res.up = runs[primary].up;
  res.floor = runs[primary].floor;
  res.ceiling = runs[primary].ceiling;
  const Eigen::Matrix3d R = preprocess::levellingRotation(res.up);
  for (std::size_t k = 0; k < runs.size(); ++k) {
    res.points_in += runs[k].points_in;
    res.points_used += runs[k].points_used;
    for (const auto& w : runs[k].warnings) res.warnings.push_back("station " + std::to_string(k) + ": " + w);
    for (const auto& t : runs[k].trace) res.trace.push_back("station " + std::to_string(k) + ": " + t);
    for (const auto& [stage, ms] : runs[k].timing_ms) {
      if (stage == "total") continue;
      auto it = std::find_if(res.timing_ms.begin(), res.timing_ms.end(), [&](const auto& kv) { return kv.first == stage; });
      if (it == res.timing_ms.end()) res.timing_ms.emplace_back(stage, ms);
      else it->second += ms;
    }
  }

  // Walls: the primary station's first, then each other station's joined to
  // a wall on the same line or added; then joined walls that a later piece
  // bridged (two pieces of one wall, a third between them) until none meet.
  std::vector<std::vector<int>> wall_map(runs.size());
  std::vector<Line2> lines;
  // Whether `l` lies on `L`'s line near its extent; [lo, hi]: l along L.
  auto onLine = [](const Line2& L, const Line2& l, double& lo, double& hi) {
    if (std::abs(L.dir.dot(l.dir)) < kWallParallelCos) return false;
    const Eigen::Vector2d n(-L.dir.y(), L.dir.x());
    const Eigen::Vector2d a = l.point + l.dir * l.s0, b = l.point + l.dir * l.s1;
    if (std::abs((0.5 * (a + b) - L.point).dot(n)) > kWallOffset) return false;
    const double sa = (a - L.point).dot(L.dir), sb = (b - L.point).dot(L.dir);
    lo = std::min(sa, sb);
    hi = std::max(sa, sb);
    return lo <= L.s1 + kWallGap && hi >= L.s0 - kWallGap;
  };
  auto joinInto = [&](std::size_t m, const WallResult& w, double lo, double hi) {
    Line2& M = lines[m];
    WallResult& into = res.walls[m];
    const double s0 = std::min(M.s0, lo), s1 = std::max(M.s1, hi);
    unionCorners(into, w, R);
    const Eigen::Vector3d p0 = R * into.line_point;
    const Eigen::Vector2d start = M.point + M.dir * s0;
    into.line_point = R.transpose() * Eigen::Vector3d(start.x(), start.y(), p0.z());
    M.point = start;
    M.s0 = 0;
    M.s1 = s1 - s0;
    into.length = M.s1;
    into.height = std::max(into.height, w.height);
    into.points += w.points;
  };
  auto addWalls = [&](std::size_t k) {
    wall_map[k].assign(runs[k].walls.size(), -1);
    for (std::size_t wi = 0; wi < runs[k].walls.size(); ++wi) {
      const WallResult& w = runs[k].walls[wi];
      const Line2 l = levelledLine(w, R);
      int joined = -1;
      double lo = 0, hi = 0;
      for (std::size_t m = 0; m < lines.size() && joined < 0; ++m)
        if (onLine(lines[m], l, lo, hi)) {
          joined = static_cast<int>(m);
          joinInto(m, w, lo, hi);
        }
      if (joined < 0) {
        joined = static_cast<int>(res.walls.size());
        res.walls.push_back(w);
        lines.push_back(l);
      }
      wall_map[k][wi] = joined;
    }
  };
  addWalls(primary);
  for (std::size_t k = 0; k < runs.size(); ++k)
    if (k != primary) addWalls(k);
  for (bool joined = true; joined;) {
    joined = false;
    for (std::size_t m = 0; m < lines.size() && !joined; ++m)
      for (std::size_t n = m + 1; n < lines.size() && !joined; ++n) {
        double lo = 0, hi = 0;
        if (!onLine(lines[m], lines[n], lo, hi)) continue;
        joinInto(m, res.walls[n], lo, hi);
        res.walls.erase(res.walls.begin() + static_cast<long>(n));
        lines.erase(lines.begin() + static_cast<long>(n));
        for (auto& map : wall_map)
          for (int& x : map) x = x == static_cast<int>(n) ? static_cast<int>(m) : x > static_cast<int>(n) ? x - 1 : x;
        joined = true;
      }
  }
  for (std::size_t m = 0; m < res.walls.size(); ++m) res.walls[m].id = static_cast<int>(m);

  // Doors: one per doorway, the best report of it.
  std::vector<DoorResult> reports;
  std::vector<int> report_station;
  for (std::size_t k = 0; k < runs.size(); ++k)
    for (DoorResult d : runs[k].doors) {
      if (d.wall_id) d.wall_id = wall_map[k][*d.wall_id];
      // Swing is told from the first station, as for a single scan.
      if (d.swing != Swing::Unknown)
        d.swing = (stations[0].viewpoint - d.opening_center).dot(d.wall_normal) > 0 ? Swing::TowardViewer
                                                                                    : Swing::AwayFromViewer;
      reports.push_back(d);
      report_station.push_back(static_cast<int>(k));
    }
  // One doorway: centres close, or the doorways overlapping along one wall,
  // or along the two faces of one wall (parallel, the doorways' centres, each
  // at mid-thickness, up to kWallFaces apart across it: a station beyond a
  // door sees the wall's other face). A leaf's shadow
  // beside its doorway, or a leaf fitted from the wrong jamb, taken from
  // another station for a doorway of its own, overlaps the true one (5023,
  // 1011 seen from beyond a door). Or one leaf claimed by doorways on either
  // side of its hinge (sameLeaf): the wall in the shadow of a leaf swung
  // towards a station, taken for a doorway that holds the same leaf, where
  // trim frames one of the two doorways only (surerReport keeps that one;
  // with no trim to tell them apart both stay: mesh40k-clutter 2022 lost the
  // true door to the surer shadow).
  auto same = [&](const DoorResult& o, const DoorResult& d) {
    if ((o.opening_center - d.opening_center).norm() < kSameDoor || (o.casing != d.casing && sameLeaf(o, d))) return true;
    if (!o.wall_id || !d.wall_id) return false;
    const Line2 &Lo = lines[*o.wall_id], &Ld = lines[*d.wall_id];
    if (std::abs(Lo.dir.dot(Ld.dir)) < kWallParallelCos) return false;
    const Eigen::Vector2d n(-Lo.dir.y(), Lo.dir.x());
    if (std::abs(((R * d.opening_center).head<2>() - (R * o.opening_center).head<2>()).dot(n)) > kWallFaces) return false;
    auto span = [&](const DoorResult& x) {
      const double c = ((R * x.opening_center).head<2>() - Lo.point).dot(Lo.dir);
      return std::make_pair(c - x.width / 2, c + x.width / 2);
    };
    const auto [a0, a1] = span(o);
    const auto [b0, b1] = span(d);
    return std::min(a1, b1) - std::max(a0, b0) > kSameDoorOverlap;
  };
  // A door's reports: the connected parts of `same`, never joining two
  // doors of one station; a report the same as two of them joins the one
  // whose doorway's centre is nearer (groupReports).
  const std::vector<std::vector<std::size_t>> groups = stations::groupReports(
      report_station, [&](std::size_t i, std::size_t j) { return same(reports[i], reports[j]); },
      [&](std::size_t i, std::size_t j) { return (reports[i].opening_center - reports[j].opening_center).norm(); });
  // Of each door's reports the best (surerReport). (A station's free-space
  // bound is not a hard limit for a leaf measured from another: it assumes
  // that station's jambs and hinge. Replacing a measured leaf more than 5 deg
  // below another station's bound by the bound lost four correct doors in
  // the beyond and stations3 sweeps for one it mended.)
  // A refine-only station's report of a door others report takes part only
  // where none of theirs saw the leaf (all lower bounds), and only with the
  // leaf measured: it sees little, and is trusted for what the others could
  // not see (its free space, from where no scanner may have stood, bounds
  // nothing).
  for (const std::vector<std::size_t>& g : groups) {
    const DoorResult* best = nullptr;
    for (std::size_t i : g)
      if (!stations[report_station[i]].refine_only && (!best || surerReport(reports[i], *best))) best = &reports[i];
    if (!best) continue;  // a door only refine-only stations report is none
    if (best->angle_is_lower_bound)
      for (std::size_t i : g)
        if (stations[report_station[i]].refine_only && !reports[i].angle_is_lower_bound && surerReport(reports[i], *best))
          best = &reports[i];
    res.doors.push_back(*best);
    // A leaf no main station saw: their bounds combine side by side where
    // their rays were observed (stations given, not inferred).
    std::vector<const DoorResult*> others;
    for (std::size_t i : g) {
      const Station& st = stations[report_station[i]];
      if (&reports[i] != best && !st.refine_only && !st.inferred) others.push_back(&reports[i]);
    }
    const std::size_t best_station = static_cast<std::size_t>(report_station[static_cast<std::size_t>(best - reports.data())]);
    if (!others.empty() && !stations[best_station].inferred) combineBounds(res.doors.back(), others, each);
  }
  res.doors.erase(std::remove_if(res.doors.begin(), res.doors.end(),
                                 [&](const DoorResult& d) {
                                   return d.angle_is_lower_bound &&
                                          d.opening_angle_deg < params_.unseen_leaf_min_bound_deg;
                                 }),
                  res.doors.end());
  for (std::size_t i = 0; i < res.doors.size(); ++i) res.doors[i].id = static_cast<int>(i);

  // Other segments: each once (a box seen from two stations alike).
  for (const PipelineResult& r : runs)
    for (const SegmentResult& s : r.others) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const auto& q : s.corners) c += q / 8;
      const bool seen = std::any_of(res.others.begin(), res.others.end(), [&](const SegmentResult& o) {
        Eigen::Vector3d oc = Eigen::Vector3d::Zero();
        for (const auto& q : o.corners) oc += q / 8;
        return (oc - c).norm() < 0.2 && std::abs(o.height - s.height) < 0.2;
      });
      if (!seen) {
        res.others.push_back(s);
        res.others.back().id = static_cast<int>(res.others.size() - 1);
      }
    }

  if (with_reconstruction) {
    // Every wall from the floor to the ceiling, as a single scan rebuilds
    // them; without a ceiling, to the top of the highest wall.
    std::vector<reconstruction::WallPatch> patches;
    double highest = 0;
    for (const WallResult& w : res.walls) highest = std::max(highest, w.height);
    for (std::size_t m = 0; m < res.walls.size(); ++m) {
      const double z = (R * res.walls[m].line_point).z();
      const double top = res.ceiling && res.floor ? z + (*res.ceiling - *res.floor) : z + highest;
      patches.push_back({lines[m].point, lines[m].dir, lines[m].s0, lines[m].s1, z, top});
    }
    std::vector<reconstruction::Opening> openings;
    for (const DoorResult& d : res.doors) {
      if (!d.wall_id) continue;
      const Line2& L = lines[*d.wall_id];
      const Eigen::Vector3d c = R * d.opening_center, h = R * d.leaf_corners[0], l = R * d.leaf_corners[1],
                            top = R * d.leaf_corners[2];
      const double s = (c.head<2>() - L.point).dot(L.dir);
      const Eigen::Vector2d leaf = (l - h).head<2>();
      const double len = leaf.norm();
      if (len <= 0) continue;
      openings.push_back({static_cast<int>(*d.wall_id), s - d.width / 2, s + d.width / 2, c.z() + d.height,
                          h.head<2>(), leaf / len, len, h.z(), top.z()});
    }
    res.reconstruction = reconstruction::reconstruct(patches, openings, params_.reconstruction_spacing,
                                                     R.transpose().cast<float>());
  }
  for (const Station& st : stations) res.stations.push_back(st.viewpoint);
  res.timing_ms.emplace_back("total",
                             std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  return res;
}

PipelineResult Pipeline::runWithoutViewpoint(const pcl::PointCloud<pcl::PointXYZ>& cloud, bool with_reconstruction) const {
  if (cloud.size() > static_cast<std::size_t>(params_.max_points))
    throw std::invalid_argument("cloud of " + std::to_string(cloud.size()) + " points exceeds max_points (" +
                                std::to_string(params_.max_points) + ")");
  if (const std::optional<std::string> why = implausibleExtent(cloud)) {
    PipelineResult res;
    res.points_in = cloud.size();
    res.viewpoint.reset();
    res.warnings.push_back(*why);
    return res;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const sight::InferredStations inferred = sight::inferStations(cloud, params_);
  const double sight_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  PipelineResult res;
  if (inferred.viewpoints.empty()) {
    res.points_in = cloud.size();
    res.up = inferred.up;
    res.warnings.push_back("no viewpoint, and no position inside the scanned space sees enough of the cloud "
                           "(no enclosed free space, or too few points): no doors");
  } else {
    std::vector<Station> stations;
    for (std::size_t k = 0; k < inferred.viewpoints.size(); ++k)
      stations.push_back({&inferred.clouds[k], inferred.viewpoints[k], k >= inferred.main, true});
    res = runStations(stations, with_reconstruction);
    res.viewpoint.reset();
    res.stations = inferred.viewpoints;
    res.points_in = cloud.size();  // the stations' scans overlap
    res.warnings.insert(res.warnings.begin(),
                        "no viewpoint: free space told by rays from " + std::to_string(stations.size()) +
                            " station(s) inferred from the cloud's surfaces");
    if (inferred.unseen > cloud.size() / 20)
      res.warnings.push_back(std::to_string(inferred.unseen) + " points seen from no inferred station were left out");
  }
  res.timing_ms.insert(res.timing_ms.begin(), inferred.timing_ms.begin(), inferred.timing_ms.end());
  auto total = std::find_if(res.timing_ms.begin(), res.timing_ms.end(), [](const auto& kv) { return kv.first == "total"; });
  if (total != res.timing_ms.end()) total->second += sight_ms;
  else res.timing_ms.emplace_back("total", sight_ms);
  return res;
}


namespace stations {

std::vector<std::vector<std::size_t>> groupReports(const std::vector<int>& station_of,
                                                   const std::function<bool(std::size_t, std::size_t)>& same,
                                                   const std::function<double(std::size_t, std::size_t)>& distance) {
  const std::size_t n = station_of.size();
  std::vector<std::size_t> part(n);
  std::vector<std::vector<int>> held(n);  // the stations of a part's reports, at its root, sorted
  for (std::size_t i = 0; i < n; ++i) part[i] = i, held[i] = {station_of[i]};
  auto root = [&](std::size_t i) {
    while (part[i] != i) i = part[i] = part[part[i]];
    return i;
  };
  auto join = [&](std::size_t a, std::size_t b) {
    const std::size_t to = std::min(a, b), from = std::max(a, b);
    part[from] = to;
    std::vector<int> merged;
    std::set_union(held[a].begin(), held[a].end(), held[b].begin(), held[b].end(), std::back_inserter(merged));
    held[to].swap(merged);
    held[from].clear();
  };
  std::vector<std::pair<std::size_t, std::size_t>> across;  // same door, different stations
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      if (!same(i, j)) continue;
      if (station_of[i] != station_of[j]) {
        across.push_back({i, j});
        continue;
      }
      const std::size_t a = root(i), b = root(j);
      if (a != b) join(a, b);
    }
  std::vector<double> dist(across.size());
  for (std::size_t k = 0; k < across.size(); ++k) dist[k] = distance(across[k].first, across[k].second);
  std::vector<std::size_t> order(across.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return dist[x] < dist[y]; });
  for (std::size_t k : order) {
    const std::size_t a = root(across[k].first), b = root(across[k].second);
    if (a == b) continue;
    std::vector<int> both;
    std::set_intersection(held[a].begin(), held[a].end(), held[b].begin(), held[b].end(), std::back_inserter(both));
    if (both.empty()) join(a, b);
  }
  std::vector<std::vector<std::size_t>> groups;
  std::vector<int> group_of(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    int& g = group_of[root(i)];
    if (g < 0) g = static_cast<int>(groups.size()), groups.emplace_back();
    groups[static_cast<std::size_t>(g)].push_back(i);
  }
  return groups;
}

}  // namespace stations

}  // namespace dsr
