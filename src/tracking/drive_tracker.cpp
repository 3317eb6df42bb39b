#include "door_state_recognition/tracking/drive_tracker.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace dsr {

void DriveTrackerOptions::validate() const {
  fusion.validate();
  if (!(max_sensor_speed >= 0) || !std::isfinite(max_sensor_speed))
    throw std::invalid_argument("max_sensor_speed must be a finite number of m/s >= 0 (0: no relocalisation check)");
  if (!(jump_slack_m >= 0) || !std::isfinite(jump_slack_m))
    throw std::invalid_argument("jump_slack_m must be a finite number of metres >= 0");
}

DriveTracker::DriveTracker(const DriveTrackerOptions& options) : options_(options), fusion_(options.fusion) {
  options_.validate();
}

PipelineResult DriveTracker::run(const Pipeline& pipeline, pcl::PointCloud<pcl::PointXYZ>& cloud,
                                 const std::optional<Eigen::Isometry3d>& sensor_to_fixed, bool with_reconstruction,
                                 bool without_viewpoint) {
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();
  if (sensor_to_fixed) {
    const Eigen::Matrix3f R = sensor_to_fixed->linear().cast<float>();
    const Eigen::Vector3f t = sensor_to_fixed->translation().cast<float>();
    for (auto& p : cloud.points) p.getVector3fMap() = R * p.getVector3fMap() + t;
    viewpoint = sensor_to_fixed->translation();
  }
  return without_viewpoint ? pipeline.runWithoutViewpoint(cloud, with_reconstruction)
                           : pipeline.run(cloud, with_reconstruction, viewpoint);
}

DriveTracker::Step DriveTracker::fuse(const PipelineResult& result, double stamp, const Parameters& params,
                                      const std::optional<Eigen::Vector3d>& sensor) {
  Step s;
  if (sensor && last_sensor_ && options_.max_sensor_speed > 0 && stamp >= last_sensor_stamp_) {
    s.moved_m = (*sensor - *last_sensor_).norm();
    s.dt_s = stamp - last_sensor_stamp_;
    if (s.moved_m > options_.jump_slack_m + options_.max_sensor_speed * s.dt_s) {
      s.relocalised = true;
      fusion_.reset();
    }
  }
  if (sensor && std::isfinite(stamp)) {
    last_sensor_ = sensor;
    last_sensor_stamp_ = stamp;
  }
  FusionOptions fo = fusion_.options();
  fo.closed_below_deg = params.closed_below_deg;
  fo.open_from_deg = params.open_from_deg;
  fo.leaf_thickness = params.leaf_thickness;
  fusion_.setOptions(fo);  // the pipeline's thresholds, validated with it
  s.newest_before = fusion_.newestStamp();
  s.fusion = fusion_.update(result.doors, stamp, result.up);
  return s;
}

DriveTracker::Processed DriveTracker::process(const Pipeline& pipeline, pcl::PointCloud<pcl::PointXYZ>& cloud,
                                              const std::optional<Eigen::Isometry3d>& sensor_to_fixed, double stamp,
                                              bool with_reconstruction, bool without_viewpoint) {
  Processed p;
  p.result = run(pipeline, cloud, sensor_to_fixed, with_reconstruction, without_viewpoint);
  std::optional<Eigen::Vector3d> sensor;
  if (sensor_to_fixed) sensor = sensor_to_fixed->translation();
  p.step = fuse(p.result, stamp, pipeline.parameters(), sensor);
  return p;
}

void DriveTracker::reset() {
  fusion_.reset();
  last_sensor_.reset();
}

}  // namespace dsr
