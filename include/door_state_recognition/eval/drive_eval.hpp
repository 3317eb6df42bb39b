// Door states fused over a simulated drive, scored (issue 20): a drive is
// planned for a seed and a sensor (sim::planDrive on sim::randomRoom(seed),
// the drive `door_scene_sim --drive --seed S --sensor X` writes), every
// every-th cloud is simulated and processed through dsr::DriveTracker (the
// nodelet's core: cloud in the sensor frame, pose in map, stamp = seconds
// after the start), and the tracks after the last processed cloud (the last
// `tracked_doors` message) are scored against the drive's truth in map.
//
// Per truth door (its state at the end of the drive):
//  - passed: the sensor came within pass_within_m (horizontally) of the
//    doorway's middle at some frame of the drive (driveTruthJson's
//    passed_within_3m for 3 m);
//  - in_view: some processed cloud saw the doorway (sim::sensorSeesDoor);
//  - leaf_seen: some processed cloud, after the door's last change, held
//    points on the leaf in at least leaf_seen_share of its 5 cm x 10 cm
//    cells over its body (0.25-1.75 m above the floor), as
//    scripts/leaf_visibility.py counts them;
//  - right: a track matches it (opening centres within match_distance_m
//    across z, nearest pairs first, one to one) and either its leaf was
//    measured with the true state and an angle within angle_tolerance_deg,
//    or the angle is a lower bound (NOT_CLOSED, or OPEN from a bound), the
//    leaf never came into sight, the door is not closed, the state is the
//    true one or NOT_CLOSED, and the bound is at most the true angle +
//    kBoundSlackDeg.
// Per drive: false doors = tracks matching no truth door; ids per door =
// the distinct track ids matched to it in any processed cloud (one id per
// door: 1); for each change of a door during the drive, the latency in
// processed clouds from the first processed cloud after the change that
// shows the doorway (1 = that cloud's tracked_doors already holds the new
// state: the true state, or NOT_CLOSED for a door opened from closed), and
// from the first processed cloud whose own doors show the new state (the
// fusion's own delay; the "within 2 processed clouds").
// ROS-free.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "door_state_recognition/pipeline/parameters.hpp"
#include "door_state_recognition/sim/drive.hpp"
#include "door_state_recognition/tracking/drive_tracker.hpp"

namespace dsr {
namespace eval {

struct DriveEvalOptions {
  std::string sensor = "lidar64";  // lidar16 | lidar32 | lidar64 | lidar128 | rgbd
  // Process every every-th cloud (the nodelet drops the others); 0: the one
  // that processes about 3.5 clouds/s (LiDAR 10 Hz: 3, RGB-D 15 Hz: 4).
  int every = 0;
  bool lidar_motion = false;               // sweeps not deskewed (sim::DriveOptions)
  std::vector<sim::DoorChange> changes;    // as door_scene_sim --toggle-door
  // One change per drive: the passed door seen in the most frames (not the
  // one driven through), closed -> 60 deg or else -> closed, at the middle
  // of its time in view; the next such door when that change leaves no
  // drive; none when no door is left.
  bool auto_toggle = false;
  double pass_within_m = 3.0, angle_tolerance_deg = 5.0, match_distance_m = 0.5;
  double leaf_seen_share = 0.10;
  Parameters params;                       // the pipeline's
  DriveTrackerOptions tracker;             // the nodelet's defaults
};

struct DoorOutcome {
  int door = 0;
  std::string truth_state;
  double truth_angle_deg = 0;
  double min_distance_m = 0;
  bool passed = false, in_view = false, leaf_seen = false;
  double leaf_share_max = 0;               // best leaf cell share of a processed cloud (after the last change)
  bool matched = false, right = false;
  std::uint32_t track_id = 0;
  std::uint32_t observations = 0;          // the matched track's
  std::string state;                       // the matched track's
  double angle_deg = 0;
  bool lower_bound = false;
  int ids = 0;                             // distinct track ids matched over the drive
  std::string why;                         // when not right: missed | state | angle | bound_with_leaf_seen | bound_above_truth | bound_on_closed
};

struct ChangeOutcome {
  sim::DoorChange change;
  std::string from_state, to_state;
  int first_showing = -1;                  // ordinal of the processed cloud (-1: none after the change)
  int latency = -1;                        // processed clouds, 1 = at once (-1: never shown)
  // From the first processed cloud after the change whose own doors (the
  // `doors` topic: that cloud alone) show the new state: the fusion's delay.
  int first_detecting = -1;
  int latency_from_detection = -1;
};

struct DriveEvalResult {
  std::uint64_t seed = 0;
  std::string sensor;
  std::size_t frames = 0, processed = 0;
  int every = 1;
  double seconds = 0;
  std::vector<DoorOutcome> doors;
  int false_doors = 0;
  std::vector<TrackedDoor> false_tracks;   // the last tracks matching no truth door
  std::vector<ChangeOutcome> changes;
  double pipeline_ms_median = 0;           // per processed cloud: DriveTracker::run (the pipeline)
  double fusion_ms_median = 0, fusion_ms_max = 0;  // DriveTracker::fuse with the withdrawal pass
  int relocalisations = 0;                 // resets for a sensor jump (none expected in a simulated drive)
  int disproved = 0;                       // tracks withdrawn, their doorway looked at and not found (DriveTracker)
  int unconfirmed = 0;                     // the last tracks not published (DriveTracker's confirmation)
  std::map<std::uint32_t, double> spread_m;  // by published track id: DriveTracker::spread
};

// Throws std::invalid_argument for absurd options (as sim::planDrive).
DriveEvalResult evaluateDrive(std::uint64_t seed, const DriveEvalOptions& options);

nlohmann::json toJson(const DriveEvalResult& r);
// The figures over several drives: passed doors right (and among
// those in view), false doors, drives without one, doors with several ids,
// changes shown within 2 processed clouds.
nlohmann::json summarize(const std::vector<DriveEvalResult>& drives);

}  // namespace eval
}  // namespace dsr
