#include "door_state_recognition/eval/drive_eval.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <tuple>
#include <unordered_set>

#include "door_state_recognition/eval/evaluation.hpp"
#include "door_state_recognition/sim/scene.hpp"

namespace dsr {
namespace eval {
namespace {

double horizontal(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return std::hypot(a.x() - b.x(), a.y() - b.y()); }

// The drive with one door changed: the passed doors (not the one driven
// through, which must stay open for the path) by frames in view, the first
// whose change still leaves a drive (the leaf's new swing can move the path).
sim::DrivePlan withAutoToggle(const sim::RoomSpec& spec, sim::DriveOptions d) {
  const sim::DrivePlan plain = sim::planDrive(spec, d);
  const nlohmann::json truth = sim::driveTruthJson(plain);
  std::vector<std::pair<int, int>> order;  // (-frames in view, door)
  for (std::size_t k = 0; k < truth["doors"].size(); ++k) {
    const nlohmann::json& t = truth["doors"][k];
    const int frames = t["frames_in_view"].get<int>();
    if (t["passed_within_3m"].get<bool>() && frames > 0 && static_cast<int>(k) != plain.through_door)
      order.emplace_back(-frames, static_cast<int>(k));
  }
  std::sort(order.begin(), order.end());
  for (const auto& [minus_frames, k] : order) {
    const nlohmann::json& t = truth["doors"][k];
    sim::DoorChange c;
    c.door = k;
    c.angle_deg = plain.scenes.front().doors[k].angle_deg < 5.0 ? 60.0 : 0.0;
    c.t = 0.5 * (t["first_in_view_t"].get<double>() + t["last_in_view_t"].get<double>());
    sim::DriveOptions changed = d;
    changed.changes.push_back(c);
    try {
      return sim::planDrive(spec, changed);
    } catch (const std::invalid_argument&) {
      // this door's change leaves no drive: the next one
    }
  }
  return plain;  // no door to change: the drive as it is (no change scored)
}

sim::DrivePlan plan(std::uint64_t seed, const DriveEvalOptions& o) {
  const sim::RoomSpec spec = sim::randomRoom(seed);
  sim::DriveOptions d;
  d.sensor = o.sensor;
  d.seed = seed;
  d.lidar_motion = o.lidar_motion;
  d.changes = o.changes;
  return o.auto_toggle ? withAutoToggle(spec, d) : sim::planDrive(spec, d);
}

// Share of door k's leaf cells (5 cm along x 10 cm up, 0.25-1.75 m above the
// floor) that hold a point of `c` labelled leaf within 6 cm of its plane.
double leafShare(const sim::Scene& scene, int k, const sim::SimulatedCloud& c) {
  const sim::DoorTruth& d = scene.doors[k];
  Eigen::Vector3d h = d.leaf_corners[0], l = d.leaf_corners[1];
  h.z() = l.z() = 0;
  const double length = (l - h).norm();
  if (!(length > 0.1)) return 0;
  const Eigen::Vector3d e = (l - h) / length, n = Eigen::Vector3d::UnitZ().cross(e);
  std::unordered_set<int> cells;
  for (const auto& q : c.cloud.points) {
    if (q.label != static_cast<std::uint32_t>(sim::Surface::Leaf) || !std::isfinite(q.x)) continue;
    const Eigen::Vector3d w = c.sensor_to_world * Eigen::Vector3d(q.x, q.y, q.z);
    const double height = w.z() - scene.floor_z;
    const Eigen::Vector3d r(w.x() - h.x(), w.y() - h.y(), 0);
    const double along = r.dot(e), off = r.dot(n);
    if (std::abs(off) < 0.06 && along > 0 && along < length && height > 0.25 && height < 1.75)
      cells.insert(static_cast<int>(along / 0.05) * 16 + static_cast<int>((height - 0.25) / 0.1));
  }
  return static_cast<double>(cells.size()) / (std::ceil(length / 0.05) * 15);
}

// Tracks to truth doors, nearest pairs first, one to one: per truth door the
// index of its track (-1: none).
std::vector<int> matchTracks(const std::vector<TrackedDoor>& tracks, const sim::Scene& scene, double max_d) {
  std::vector<std::tuple<double, int, int>> pairs;
  for (std::size_t k = 0; k < scene.doors.size(); ++k)
    for (std::size_t t = 0; t < tracks.size(); ++t) {
      const double dist = horizontal(tracks[t].door.opening_center, scene.doors[k].opening_center);
      if (dist <= max_d) pairs.emplace_back(dist, static_cast<int>(k), static_cast<int>(t));
    }
  std::sort(pairs.begin(), pairs.end());
  std::vector<int> of_door(scene.doors.size(), -1);
  std::vector<char> used(tracks.size(), 0);
  for (const auto& [dist, k, t] : pairs)
    if (of_door[k] < 0 && !used[t]) of_door[k] = t, used[t] = 1;
  return of_door;
}

bool showsState(const std::string& track_state, const std::string& from, const std::string& to) {
  return track_state == to || (from == "closed" && to != "closed" && track_state == "not_closed");
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

DriveEvalResult evaluateDrive(std::uint64_t seed, const DriveEvalOptions& o) {
  const sim::DrivePlan p = plan(seed, o);
  DriveEvalResult r;
  r.seed = seed;
  r.sensor = o.sensor;
  r.frames = p.frame_count;
  r.seconds = p.options.seconds;
  r.every = o.every > 0 ? o.every : std::max(1, static_cast<int>(std::lround(p.options.rate_hz / 3.5)));
  const sim::Scene& final_scene = p.scenes.back();
  const int n = static_cast<int>(final_scene.doors.size());
  r.doors.resize(n);
  for (int k = 0; k < n; ++k) {
    r.doors[k].door = k;
    r.doors[k].truth_state = final_scene.doors[k].state(o.params.closed_below_deg, o.params.open_from_deg);
    r.doors[k].truth_angle_deg = final_scene.doors[k].angle_deg;
    r.doors[k].min_distance_m = std::numeric_limits<double>::infinity();
  }
  for (std::size_t i = 0; i < p.frame_count; ++i) {
    const Eigen::Vector3d s = (p.baseToMap(p.frameTime(i)) * p.sensor_to_base).translation();
    for (int k = 0; k < n; ++k)
      r.doors[k].min_distance_m = std::min(r.doors[k].min_distance_m, horizontal(s, final_scene.doors[k].opening_center));
  }
  for (auto& d : r.doors) d.passed = d.min_distance_m <= o.pass_within_m;

  const Pipeline pipeline(o.params);
  DriveTracker tracker(o.tracker);
  std::vector<std::set<std::uint32_t>> ids(n);
  std::vector<std::vector<std::string>> shown(n);  // per door, per processed cloud: its matched track's state
  std::vector<std::vector<std::string>> detected(n);  // the same for the cloud's own doors
  std::vector<std::vector<char>> in_view(n);
  std::vector<double> times, fusion_times;
  pcl::PointCloud<pcl::PointXYZ> xyz;
  for (std::size_t i = 0; i < p.frame_count; i += static_cast<std::size_t>(r.every)) {
    const sim::DriveFrame f = sim::simulateFrame(p, i);
    const sim::Scene& scene = p.scenes[f.scene_index];
    xyz.clear();
    xyz.width = f.cloud.cloud.width;
    xyz.height = f.cloud.cloud.height;
    xyz.is_dense = false;
    xyz.points.reserve(f.cloud.cloud.size());
    for (const auto& q : f.cloud.cloud.points) xyz.points.emplace_back(q.x, q.y, q.z);
    const DriveTracker::Processed step = tracker.process(pipeline, xyz, f.cloud.sensor_to_world, f.t, false);
    times.push_back(step.run_ms);
    fusion_times.push_back(step.fuse_ms);
    if (step.step.relocalised) ++r.relocalisations;
    r.disproved += static_cast<int>(step.step.disproved);
    ++r.processed;
    const std::vector<TrackedDoor> tracks = tracker.published();
    for (const TrackedDoor& t : tracks) {  // every track near a door is one of its ids
      int nearest = -1;
      double best = o.match_distance_m;
      for (int k = 0; k < n; ++k) {
        const double dist = horizontal(t.door.opening_center, scene.doors[k].opening_center);
        if (dist <= best) best = dist, nearest = k;
      }
      if (nearest >= 0) ids[nearest].insert(t.id);
    }
    const std::vector<int> match = matchTracks(tracks, scene, o.match_distance_m);
    std::vector<TrackedDoor> own(step.result.doors.size());  // this cloud's doors, matched alike
    for (std::size_t j = 0; j < own.size(); ++j) own[j].door = step.result.doors[j];
    const std::vector<int> match_own = matchTracks(own, scene, o.match_distance_m);
    for (int k = 0; k < n; ++k) {
      shown[k].push_back(match[k] < 0 ? std::string() : toString(tracks[match[k]].door.state));
      detected[k].push_back(match_own[k] < 0 ? std::string() : toString(own[match_own[k]].door.state));
      in_view[k].push_back(sim::sensorSeesDoor(scene, f.cloud, k));
      if (in_view[k].back()) r.doors[k].in_view = true;
      if (scene.doors[k].angle_deg != final_scene.doors[k].angle_deg) continue;  // before the door's last change
      const double share = leafShare(scene, k, f.cloud);
      r.doors[k].leaf_share_max = std::max(r.doors[k].leaf_share_max, share);
    }
  }
  r.pipeline_ms_median = median(times);
  r.fusion_ms_median = median(fusion_times);
  for (double t : fusion_times) r.fusion_ms_max = std::max(r.fusion_ms_max, t);

  // The last tracked_doors (the confirmed tracks) against the final truth.
  const std::vector<TrackedDoor> tracks = tracker.published();
  for (const TrackedDoor& t : tracks) r.spread_m[t.id] = tracker.spread(t.id);
  r.unconfirmed = static_cast<int>(tracker.tracks().size() - tracks.size());
  const std::vector<int> match = matchTracks(tracks, final_scene, o.match_distance_m);
  std::vector<char> used(tracks.size(), 0);
  for (int k = 0; k < n; ++k) {
    DoorOutcome& d = r.doors[k];
    d.leaf_seen = d.leaf_share_max >= o.leaf_seen_share;
    d.ids = static_cast<int>(ids[k].size());
    if (match[k] < 0) {
      d.why = "missed";
      continue;
    }
    used[match[k]] = 1;
    const TrackedDoor& t = tracks[match[k]];
    d.matched = true;
    d.track_id = t.id;
    d.observations = t.observations;
    d.state = toString(t.door.state);
    d.angle_deg = t.door.opening_angle_deg;
    d.lower_bound = t.door.angle_is_lower_bound;
    if (!d.lower_bound) {
      d.right = d.state == d.truth_state && std::abs(d.angle_deg - d.truth_angle_deg) <= o.angle_tolerance_deg;
      d.why = d.right ? "" : d.state != d.truth_state ? "state" : "angle";
    } else if (d.truth_state == "closed") {
      d.why = "bound_on_closed";
    } else if (d.leaf_seen) {
      d.why = "bound_with_leaf_seen";
    } else if (d.angle_deg > d.truth_angle_deg + kBoundSlackDeg) {
      d.why = "bound_above_truth";
    } else {
      d.right = d.state == d.truth_state || d.state == "not_closed";
      d.why = d.right ? "" : "state";
    }
  }
  for (std::size_t t = 0; t < tracks.size(); ++t)
    if (!used[t]) r.false_tracks.push_back(tracks[t]);
  r.false_doors = static_cast<int>(r.false_tracks.size());

  for (const sim::DoorChange& c : p.changes) {
    ChangeOutcome co;
    co.change = c;
    const int si = p.sceneIndexAt(c.t);
    co.from_state = p.scenes[std::max(0, si - 1)].doors[c.door].state(o.params.closed_below_deg, o.params.open_from_deg);
    co.to_state = p.scenes[si].doors[c.door].state(o.params.closed_below_deg, o.params.open_from_deg);
    double next = std::numeric_limits<double>::infinity();  // the door's next change
    for (const sim::DoorChange& c2 : p.changes)
      if (c2.door == c.door && c2.t > c.t) next = std::min(next, c2.t);
    for (std::size_t j = 0; j < r.processed; ++j) {
      const double t = p.frameTime(j * r.every);
      if (t < c.t || t >= next) continue;
      if (co.first_showing < 0 && in_view[c.door][j]) co.first_showing = static_cast<int>(j);
      if (co.first_detecting < 0 && showsState(detected[c.door][j], co.from_state, co.to_state))
        co.first_detecting = static_cast<int>(j);
      const bool tracked = showsState(shown[c.door][j], co.from_state, co.to_state);
      if (co.first_showing >= 0 && co.latency < 0 && tracked) co.latency = static_cast<int>(j) - co.first_showing + 1;
      if (co.first_detecting >= 0 && tracked) {
        co.latency_from_detection = static_cast<int>(j) - co.first_detecting + 1;
        break;
      }
    }
    r.changes.push_back(co);
  }
  return r;
}

nlohmann::json toJson(const DriveEvalResult& r) {
  nlohmann::json doors = nlohmann::json::array(), changes = nlohmann::json::array();
  for (const DoorOutcome& d : r.doors)
    doors.push_back({{"door", d.door}, {"truth_state", d.truth_state}, {"truth_angle_deg", d.truth_angle_deg},
                     {"min_distance_m", d.min_distance_m}, {"passed", d.passed}, {"in_view", d.in_view},
                     {"leaf_seen", d.leaf_seen}, {"leaf_share_max", d.leaf_share_max}, {"matched", d.matched},
                     {"track_id", d.track_id}, {"observations", d.observations},
                     {"spread_m", r.spread_m.count(d.track_id) ? r.spread_m.at(d.track_id) : 0.0}, {"state", d.state}, {"angle_deg", d.angle_deg},
                     {"angle_is_lower_bound", d.lower_bound}, {"ids", d.ids}, {"right", d.right}, {"why", d.why}});
  for (const ChangeOutcome& c : r.changes)
    changes.push_back({{"door", c.change.door}, {"t", c.change.t}, {"to_deg", c.change.angle_deg},
                       {"from_state", c.from_state}, {"to_state", c.to_state},
                       {"first_showing_cloud", c.first_showing < 0 ? nlohmann::json(nullptr) : nlohmann::json(c.first_showing)},
                       {"latency_clouds", c.latency < 0 ? nlohmann::json(nullptr) : nlohmann::json(c.latency)},
                       {"first_detecting_cloud", c.first_detecting < 0 ? nlohmann::json(nullptr) : nlohmann::json(c.first_detecting)},
                       {"latency_from_detection_clouds", c.latency_from_detection < 0 ? nlohmann::json(nullptr) : nlohmann::json(c.latency_from_detection)}});
  nlohmann::json false_tracks = nlohmann::json::array();
  for (const TrackedDoor& t : r.false_tracks) {
    const Eigen::Vector3d& c = t.door.opening_center;
    false_tracks.push_back({{"id", t.id}, {"opening_center", {c.x(), c.y(), c.z()}}, {"state", toString(t.door.state)},
                            {"angle_deg", t.door.opening_angle_deg}, {"width", t.door.width},
                            {"observations", t.observations},
                            {"spread_m", r.spread_m.count(t.id) ? r.spread_m.at(t.id) : 0.0}, {"first_seen", t.first_seen}, {"last_seen", t.last_seen}});
  }
  return {{"seed", r.seed}, {"sensor", r.sensor}, {"seconds", r.seconds}, {"frames", r.frames},
          {"every", r.every}, {"processed", r.processed}, {"false_doors", r.false_doors},
          {"unconfirmed_tracks", r.unconfirmed},
          {"relocalisations", r.relocalisations}, {"disproved", r.disproved}, {"process_ms_median", r.pipeline_ms_median},
          {"fusion_ms_median", r.fusion_ms_median}, {"fusion_ms_max", r.fusion_ms_max},
          {"doors", doors}, {"changes", changes}, {"false_tracks", false_tracks}};
}

nlohmann::json summarize(const std::vector<DriveEvalResult>& drives) {
  int passed = 0, right = 0, passed_in_view = 0, right_in_view = 0, not_closed_right = 0, false_doors = 0,
      clean_drives = 0, several_ids = 0, changes = 0, shown_within_2 = 0, never_shown = 0, detected = 0,
      detected_within_2 = 0;
  std::map<std::string, int> why;
  nlohmann::json latencies = nlohmann::json::array(), from_detection = nlohmann::json::array();
  std::vector<double> fusion_medians;
  double fusion_max = 0;
  for (const DriveEvalResult& r : drives) {
    fusion_medians.push_back(r.fusion_ms_median);
    fusion_max = std::max(fusion_max, r.fusion_ms_max);
    false_doors += r.false_doors;
    clean_drives += r.false_doors == 0;
    for (const DoorOutcome& d : r.doors) {
      if (d.ids > 1) ++several_ids;
      if (!d.passed) continue;
      ++passed;
      right += d.right;
      not_closed_right += d.right && d.state == "not_closed";
      if (d.in_view) ++passed_in_view, right_in_view += d.right;
      if (!d.right) ++why[d.why];
    }
    for (const ChangeOutcome& c : r.changes) {
      if (c.first_showing < 0) continue;  // never in view after the change: nothing to show
      ++changes;
      latencies.push_back(c.latency < 0 ? nlohmann::json(nullptr) : nlohmann::json(c.latency));
      shown_within_2 += c.latency >= 1 && c.latency <= 2;
      never_shown += c.latency < 0;
      if (c.first_detecting < 0) continue;  // no cloud alone showed the new state
      ++detected;
      from_detection.push_back(c.latency_from_detection < 0 ? nlohmann::json(nullptr) : nlohmann::json(c.latency_from_detection));
      detected_within_2 += c.latency_from_detection >= 1 && c.latency_from_detection <= 2;
    }
  }
  auto share = [](int a, int b) { return b ? nlohmann::json(static_cast<double>(a) / b) : nlohmann::json(nullptr); };
  const int n = static_cast<int>(drives.size());
  return {{"drives", n},
          {"passed_doors", passed},
          {"passed_right", right},
          {"passed_right_share", share(right, passed)},
          {"passed_in_view", passed_in_view},
          {"passed_in_view_right_share", share(right_in_view, passed_in_view)},
          {"right_as_not_closed", not_closed_right},
          {"wrong_by_cause", why},
          {"false_doors", false_doors},
          {"drives_without_false_door", clean_drives},
          {"drives_without_false_door_share", share(clean_drives, n)},
          {"doors_with_several_ids", several_ids},
          {"fusion_ms_median", median(fusion_medians)},  // the median drive's median cloud
          {"fusion_ms_max", fusion_max},
          {"changes_shown", changes},
          {"changes_within_2_clouds", shown_within_2},
          {"changes_never_shown", never_shown},
          {"change_latencies_clouds", latencies},
          {"changes_detected", detected},
          {"changes_detected_within_2_clouds", detected_within_2},
          {"change_latencies_from_detection_clouds", from_detection}};
}

}  // namespace eval
}  // namespace dsr
