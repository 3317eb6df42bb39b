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
// Disproof (options.disprove, off by default; process() only: it needs the
// points and the sensor): a door is
// a fixed structure, found again in most sweeps that measure it, while a
// door made of one sweep's artefacts (ring gaps, a shadow on a plain wall)
// is not found again where later sweeps measure plain wall. A track that
// this cloud does not show, whose opening centre lies within 4 m of the
// sensor (horizontally), gets a miss when the cloud measured its doorway as
// wall: of the rays that reached the doorway's rectangle on its wall's plane
// (its middle 80 %, 0.3-1.8 m above its floor), at least 30 ended on the
// plane (within 5 cm) and at least 70 % of them did (the rest passed
// through). A track with at least 3 misses and at least 3 times as many
// misses as observations is dropped (Step::disproved). An open or ajar
// doorway passes rays through it or stops them before its plane: never a
// miss; a closed door whose leaf is flush with its wall can get misses, but
// is found again in most of the sweeps that measure it.
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
  // Drop tracks whose doorway later sweeps measure as wall (above). Off by
  // default: it can drop a closed door whose leaf is flush with its wall
  // and that the pipeline finds in few sweeps, which then comes back with a
  // new id (door_state_drive_eval --disprove measures it; doc/results.md).
  bool disprove = false;
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
    std::size_t disproved = 0;    // tracks dropped: their doorway measured as wall (process() only)
  };
  struct Processed {
    PipelineResult result;        // in the fixed frame
    Step step;
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
  // DoorFusion::update.
  Step fuse(const PipelineResult& result, double stamp, const Parameters& params,
            const std::optional<Eigen::Vector3d>& sensor);

  // run() then fuse(), the sensor known exactly when sensor_to_fixed is.
  Processed process(const Pipeline& pipeline, pcl::PointCloud<pcl::PointXYZ>& cloud,
                    const std::optional<Eigen::Isometry3d>& sensor_to_fixed, double stamp,
                    bool with_reconstruction = true, bool without_viewpoint = false);

  const std::vector<TrackedDoor>& tracks() const { return fusion_.tracks(); }
  const DoorFusion& fusion() const { return fusion_; }
  // Drops every track and the sensor's last position.
  void reset();

 private:
  // Counts misses (doorway measured as wall) and drops the disproved tracks.
  std::size_t disprove(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& sensor);

  DriveTrackerOptions options_;
  DoorFusion fusion_;
  std::map<std::uint32_t, int> misses_;  // by track id
  std::optional<Eigen::Vector3d> last_sensor_;
  double last_sensor_stamp_ = 0;
};

}  // namespace dsr
