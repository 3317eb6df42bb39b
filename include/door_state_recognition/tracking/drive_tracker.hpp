// One processed cloud of a drive, from the sensor to the fused doors: the
// cloud moved from its sensor frame into the fixed frame (REP 105: map,
// odom), the pipeline run with the sensor's origin as the viewpoint, a
// relocalisation check on the sensor's path, and DoorFusion. ROS-free: the
// nodelet (tf lookup, messages, throttled logging) and the offline drive
// evaluator (eval/drive_eval.hpp) are two shells around it; the outcomes
// are returned, never logged here.
//
// Relocalisation: the sensor's position in the fixed frame moving between
// two processed clouds by more than max_sensor_speed allows (plus
// jump_slack_m) means that the doors tracked before and those seen now are
// not in one frame any more: every track is dropped (DoorFusion::reset()).
// Not judged when the sensor is unknown (a cloud arriving in the fixed frame
// already) nor across stamps going backwards (DoorFusion resets then anyway).
//
// Withdrawal (options.disprove, on by default; process(), or fuse() given the
// cloud: it needs the points and the sensor): a door is a fixed structure, found again in a
// good share of the clouds that look at it (a 64-beam sweep in 9 of 10, a
// 320x240 camera in fewer), while a door made of one view's artefacts (trim
// legs from range noise, the gap between two cupboards, a shadow on a plain
// wall) is not found again when later clouds look at the same place. A
// cloud looked at a track's doorway when at least 30 of its rays reached the
// doorway's rectangle on its wall's plane (its middle 80 %, 0.3-1.8 m above
// its floor: ending on the plane within 5 cm, or passing through it) with
// the sensor within 4 m (horizontally) and off the wall's plane. Such a
// cloud that does not show the door is a miss. A track with at least 3
// misses and at least 6 times as many misses as observations is withdrawn
// (Step::disproved counts the tracks withdrawn by this cloud): kept, matched
// and counted as any track, its id held, but not published; once its
// observations catch up with its misses (fewer than 6 misses each) it is
// published again with the same id (one id per door per drive). On the
// tuning drives 1000-1019 it took lidar64's false doors 7 -> 3 and the
// camera's 10 -> 6, for one passed closed door that the camera and the
// 16-beam LiDAR find in 2-3 of the clouds looking at it; on the untouched
// drives 3000-3019, 33 -> 17 false doors over four sensors for 3 of 172
// passed doors (doc/results.md, "Drives: doors looked at and not found").
//
// Confirmation (options.confirm_clouds, options.confirm_spread_m): a door is
// a fixed structure that the sensor finds again in the next clouds, while
// most false doors of a single cloud rest on how that one cloud sampled a
// wall and its noise (a LiDAR's 1.5-2 cm of range noise over a few points
// makes trim legs a door's width apart on plain wall, whose face then reads
// as a closed leaf) and are not found again at the same place: on the
// drives of seeds 1000-1019, 30 of lidar64's 51 false doors were seen in one
// cloud only, every passed door in 6 or more. A track is published
// (published(), the nodelet's `tracked_doors` and tracked markers) once at
// least confirm_clouds processed clouds showed it, seen from sensor
// positions at least confirm_spread_m apart (horizontally, the farthest
// from the first position that saw it; not asked while the sensor is
// unknown); once confirmed it stays so. Fusion is not changed: an
// unconfirmed track is matched, joined and forgotten as any other and keeps
// its id when confirmed. The spread is 0 by default: the RGB-D camera shows
// some passed doors in 1-2 clouds from one spot (on those drives 0.2 m kept
// 24 of its 38 passed doors right against 27 without), and a robot standing
// still should still publish the door it waits at (doc/results.md, Drives).
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <optional>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/tracking/door_fusion.hpp"

namespace dsr {

struct DriveTrackerOptions {
  FusionOptions fusion;           // its pipeline thresholds are overwritten by each cloud's Parameters
  double max_sensor_speed = 3.0;  // m/s; 0: no relocalisation check
  double jump_slack_m = 0.5;      // m, allowed on top of max_sensor_speed x dt
  // Withdraw tracks that later clouds look at and do not find (above).
  bool disprove = true;
  // Confirmation (above): clouds that must show a track, and how far apart
  // (m) the sensor positions seeing it must lie, before it is published.
  // 1 and 0: every track at once (as before the confirmation).
  int confirm_clouds = 2;
  double confirm_spread_m = 0.0;
  // Throws std::invalid_argument naming the first option out of range.
  void validate() const;
};

class DriveTracker {
 public:
  struct Step {
    DoorFusion::Update fusion;    // outcome of DoorFusion::update
    double newest_before = 0;     // the newest stamp fused before this cloud (NaN: none)
    bool relocalised = false;     // the tracks were reset for a sensor jump
    double moved_m = 0, dt_s = 0; // that jump: distance and time between the two clouds
    std::size_t disproved = 0;    // tracks withdrawn by this cloud: looked at and not found (given the cloud)
  };
  struct Processed {
    PipelineResult result;        // in the fixed frame
    Step step;
    double run_ms = 0, fuse_ms = 0;  // wall-clock time of run() and of fuse()
  };

  // Throws std::invalid_argument for options out of range.
  explicit DriveTracker(const DriveTrackerOptions& options = DriveTrackerOptions());
  const DriveTrackerOptions& options() const { return options_; }

  // Moves `cloud` (in the sensor frame) into the fixed frame in place by
  // sensor_to_fixed (none: it is in the fixed frame already) and runs the
  // pipeline there, rays from the sensor's origin (or, with
  // without_viewpoint, from the stations inferred by runWithoutViewpoint).
  static PipelineResult run(const Pipeline& pipeline, pcl::PointCloud<pcl::PointXYZ>& cloud,
                            const std::optional<Eigen::Isometry3d>& sensor_to_fixed, bool with_reconstruction = true,
                            bool without_viewpoint = false);

  // The doors of one processed cloud, in the fixed frame, into the tracks:
  // the relocalisation check (sensor: its position in the fixed frame, none
  // when unknown), the pipeline's thresholds into the fusion options, then
  // DoorFusion::update; with the cloud (in the fixed frame) and the sensor
  // known, the withdrawal pass (options.disprove) over its points.
  Step fuse(const PipelineResult& result, double stamp, const Parameters& params,
            const std::optional<Eigen::Vector3d>& sensor, const pcl::PointCloud<pcl::PointXYZ>* cloud = nullptr);

  // run() then fuse(), the sensor known exactly when sensor_to_fixed is.
  Processed process(const Pipeline& pipeline, pcl::PointCloud<pcl::PointXYZ>& cloud,
                    const std::optional<Eigen::Isometry3d>& sensor_to_fixed, double stamp,
                    bool with_reconstruction = true, bool without_viewpoint = false);

  // Every track, confirmed or not (ordered by id).
  const std::vector<TrackedDoor>& tracks() const { return fusion_.tracks(); }
  // The confirmed tracks (ordered by id): what `tracked_doors` publishes.
  std::vector<TrackedDoor> published() const;
  bool confirmed(std::uint32_t id) const;
  // How far (m, horizontally) the sensor positions seeing track `id` lie
  // from the first that saw it (0: unknown).
  double spread(std::uint32_t id) const;
  const DoorFusion& fusion() const { return fusion_; }
  // Drops every track and the sensor's last position.
  void reset();

 private:
  // Counts misses (doorway looked at, door not shown) and withdraws the disproved tracks.
  std::size_t disprove(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& sensor);
  // Withdraws or restores every track by its misses and observations; returns how many it withdrew.
  std::size_t standing();

  DriveTrackerOptions options_;
  DoorFusion fusion_;
  // Confirmation: records the sensor positions seeing each track.
  void confirm(const Step& s, const std::optional<Eigen::Vector3d>& sensor);
  struct Sight {
    Eigen::Vector2d first = Eigen::Vector2d::Zero();  // the first sensor position seeing it
    bool known = false;                               // first holds a position
    double spread = 0;                                // m, farthest position from first
    bool confirmed = false;
    bool withdrawn = false;  // disproved: kept (matched, its id held) but not published
  };

  std::map<std::uint32_t, int> misses_;  // by track id
  std::map<std::uint32_t, Sight> sights_;  // by track id
  std::optional<Eigen::Vector3d> last_sensor_;
  double last_sensor_stamp_ = 0;
};

}  // namespace dsr
