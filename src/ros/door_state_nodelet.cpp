// DoorStateNodelet: a thin ROS shell around dsr::Pipeline.
//
// Subscribes `points` (sensor_msgs/PointCloud2, queue 1) only while one of
// its outputs has a subscriber; with ~fixed_frame set, clouds wait in a
// tf2_ros::MessageFilter until their transform to the fixed frame is known.
// The subscriber callback only puts the cloud into a one-cloud slot; a worker
// thread of the nodelet's own processes the cloud in the slot. A cloud that
// arrives while another waits in the slot replaces it (the stale one is
// dropped and counted): under a stream faster than the pipeline, latency stays
// bounded by about two processing times and memory by two clouds, and the
// nodelet's callback queue (dynamic_reconfigure, diagnostics, connection
// callbacks) is never blocked by the pipeline.
// Publishes `doors` (DoorStateArray), `markers` (MarkerArray) and
// `reconstructed_walls` (PointCloud2). With ~fixed_frame set, also
// `tracked_doors` (DoorStateArray in the fixed frame, with every processed
// cloud): every door seen within ~forget_after_s (s, default 300), each with
// one id and its best estimate over the drive (dsr::DriveTracker around
// dsr::DoorFusion, whose headers give the rules; ~state_change_deg, default
// 20, is its state change); a
// door the cloud shows has last_seen equal to the header's stamp. Stamps
// going back by more than 1 s (a bag looped) reset the tracks, older clouds
// within 1 s are not fused; the sensor moving in the fixed frame faster than
// ~max_sensor_speed (m/s, default 3; 0: never) + 0.5 m between two
// processed clouds (a relocalisation jump) resets the tracks: each with a
// throttled warning. A track is published once ~confirm_clouds processed
// clouds (default 2) showed it, from sensor positions ~confirm_spread_m
// (default 0) apart (DriveTracker: a false door of one cloud is not), and
// withdrawn (~withdraw_not_found, default true) while later clouds look at
// its doorway and do not find it (6 times as often as they did). Bad input is logged (throttled) and
// answered with an empty DoorStateArray carrying the input's header; nothing
// here may throw into the nodelet manager. Bad ~ parameters at start (unknown
// name, wrong type, out of range) are refused before dynamic_reconfigure can
// clamp or ignore them: the nodelet then stays loaded but does nothing except
// log the problems and report them in its diagnostics.
#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <message_filters/subscriber.h>
#include <nodelet/nodelet.h>
#include <pcl_conversions/pcl_conversions.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>
#include <xmlrpcpp/XmlRpcException.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <boost/thread/recursive_mutex.hpp>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <optional>
#include <mutex>
#include <vector>
#include <thread>

#include "door_state_recognition/DoorStateArray.h"
#include "door_state_recognition/DoorStateConfig.h"
#include "door_state_recognition/pipeline/parameters.hpp"
#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/ros/cloud_conversion.hpp"
#include "door_state_recognition/ros/markers.hpp"
#include "door_state_recognition/ros/nodelet_parameters.hpp"
#include "door_state_recognition/tracking/door_fusion.hpp"
#include "door_state_recognition/tracking/door_tracker.hpp"
#include "door_state_recognition/tracking/drive_tracker.hpp"

namespace door_state_recognition {

namespace {

// The last kWindow values of a figure, without allocating per value.
class Window {
 public:
  static constexpr std::size_t kWindow = 256;
  void add(double v) {
    values_[next_] = v;
    next_ = (next_ + 1) % kWindow;
    size_ = std::min(size_ + 1, kWindow);
  }
  // Quantile q in [0, 1] of the values held (0 when none).
  double quantile(double q) const {
    if (size_ == 0) return 0.0;
    std::array<double, kWindow> v;
    std::copy(values_.begin(), values_.begin() + size_, v.begin());
    const std::size_t k = std::min(size_ - 1, static_cast<std::size_t>(std::lround(q * (size_ - 1))));
    std::nth_element(v.begin(), v.begin() + k, v.begin() + size_);
    return v[k];
  }
  std::size_t size() const { return size_; }

 private:
  std::array<double, kWindow> values_{};
  std::size_t next_ = 0, size_ = 0;
};

}  // namespace

class DoorStateNodelet : public nodelet::Nodelet {
 public:
  ~DoorStateNodelet() override {
    // Stop callbacks before the members they use go away, then the worker
    // (it finishes the cloud under way: the pipeline cannot be interrupted).
    // Nothing here may throw.
    try {
      refusal_timer_.stop();
      diagnostics_timer_.stop();
      {
        std::lock_guard<std::mutex> lock(connect_mutex_);
        unsubscribe();
      }
      {
        std::lock_guard<std::mutex> lock(slot_mutex_);
        stop_ = true;
        pending_.reset();
      }
      slot_cv_.notify_all();
      if (worker_.joinable()) worker_.join();
    } catch (...) {
    }
  }

 private:
  void onInit() override {
    nh_ = getNodeHandle();
    pnh_ = getPrivateNodeHandle();
    // The ~ parameters are checked as they stand, before anything reads them
    // (see checkPrivateParameters). Any problem: the nodelet stays loaded but
    // does not start: no subscription, no dynamic_reconfigure server, nothing
    // published but its diagnostics (ERROR), and the problems logged as
    // errors now and again every 10 s. Nothing is thrown into the manager.
    std::vector<std::string> problems;
    try {
      problems = checkPrivateParameters(pnh_);
    } catch (const XmlRpc::XmlRpcException& e) {
      problems.push_back("cannot read the ~ parameters: " + e.getMessage());
    } catch (const std::exception& e) {
      problems.push_back(std::string("cannot read the ~ parameters: ") + e.what());
    }
    if (!problems.empty()) {
      refuseToStart(problems);
      return;
    }
    pnh_.param<std::string>("fixed_frame", fixed_frame_, "");
    // sensor: free space by rays from the cloud frame's origin (through tf
    // into the fixed frame); none: an accumulated map or registered cloud,
    // whose stations are inferred from its surfaces (checked above).
    std::string viewpoint;
    pnh_.param<std::string>("viewpoint", viewpoint, "sensor");
    without_viewpoint_ = viewpoint == "none";
    pnh_.param("tf_queue_size", tf_queue_size_, 5);
    if (tf_queue_size_ < 1) tf_queue_size_ = 1;
    {
      dsr::DriveTrackerOptions o;
      pnh_.param("forget_after_s", o.fusion.forget_after_s, o.fusion.forget_after_s);
      pnh_.param("state_change_deg", o.fusion.state_change_deg, o.fusion.state_change_deg);
      pnh_.param("max_sensor_speed", o.max_sensor_speed, o.max_sensor_speed);
      pnh_.param("confirm_clouds", o.confirm_clouds, o.confirm_clouds);
      pnh_.param("confirm_spread_m", o.confirm_spread_m, o.confirm_spread_m);
      pnh_.param("withdraw_not_found", o.disprove, o.disprove);
      drive_ = dsr::DriveTracker(o);  // checked above: cannot throw
    }
    pipeline_ = std::make_shared<const dsr::Pipeline>(params_);
    last_good_config_ = DoorStateConfig::__getDefault__();

    // Every pipeline parameter is a ~ parameter, read (and kept live) by the
    // dynamic_reconfigure server; its first callback sets them up.
    reconfigure_ = std::make_unique<dynamic_reconfigure::Server<DoorStateConfig>>(reconfigure_mutex_, pnh_);
    reconfigure_->setCallback([this](DoorStateConfig& c, uint32_t level) { reconfigure(c, level); });

    if (!fixed_frame_.empty()) {
      tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
      tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh_);
    }

    diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh_, pnh_, getName());
    diagnostics_->setHardwareID("none");
    diagnostics_->add("door_state", this, &DoorStateNodelet::diagnose);

    // The worker that runs the pipeline. Should no thread be had, clouds are
    // processed in the subscriber callback (and queue 1 drops stale ones).
    try {
      worker_ = std::thread([this] { work(); });
    } catch (const std::exception& e) {
      NODELET_ERROR("door_state: no worker thread (%s): clouds are processed in the subscriber callback", e.what());
    }

    // The connect callbacks may fire as soon as the publishers exist: hold
    // the lock until every publisher is assigned.
    std::lock_guard<std::mutex> lock(connect_mutex_);
    ros::SubscriberStatusCallback cb = [this](const ros::SingleSubscriberPublisher&) { connectionChanged(); };
    pub_doors_ = nh_.advertise<DoorStateArray>("doors", 1, cb, cb);
    pub_markers_ = nh_.advertise<visualization_msgs::MarkerArray>("markers", 1, cb, cb);
    pub_walls_ = nh_.advertise<sensor_msgs::PointCloud2>("reconstructed_walls", 1, cb, cb);
    if (!fixed_frame_.empty()) pub_tracked_ = nh_.advertise<DoorStateArray>("tracked_doors", 1, cb, cb);
    diagnostics_timer_ = nh_.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { diagnostics_->update(); });
    NODELET_INFO("door_state: waiting for subscribers before subscribing to %s (fixed_frame '%s')",
                 nh_.resolveName("points").c_str(), fixed_frame_.c_str());
  }

  // Bad ~ parameters: log them, report them in the diagnostics, do nothing else.
  void refuseToStart(const std::vector<std::string>& problems) {
    std::string all;
    for (const auto& p : problems) all += (all.empty() ? "" : "; ") + p;
    refused_ = "parameters refused, not processing clouds: " + all;
    auto log = [this, problems] {
      for (const auto& p : problems) NODELET_ERROR("door_state: parameter refused: %s", p.c_str());
      NODELET_ERROR("door_state: %zu bad ~ parameter(s): this nodelet does not subscribe to %s nor publish doors; "
                    "fix them and restart it",
                    problems.size(), nh_.resolveName("points").c_str());
    };
    log();
    refusal_timer_ = nh_.createWallTimer(ros::WallDuration(10.0), [log](const ros::WallTimerEvent&) { log(); });
    try {
      diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh_, pnh_, getName());
      diagnostics_->setHardwareID("none");
      diagnostics_->add("door_state", this, &DoorStateNodelet::diagnose);
      diagnostics_timer_ = nh_.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { diagnostics_->update(); });
    } catch (const std::exception& e) {
      NODELET_ERROR("door_state: no diagnostics: %s", e.what());
    }
  }

  // Lazy subscription: subscribe to the input only while someone listens.
  void connectionChanged() {
    std::lock_guard<std::mutex> lock(connect_mutex_);
    const bool wanted = pub_doors_.getNumSubscribers() > 0 || pub_markers_.getNumSubscribers() > 0 ||
                        pub_walls_.getNumSubscribers() > 0 || pub_tracked_.getNumSubscribers() > 0;
    if (wanted && !subscribed_) subscribe();
    if (!wanted && subscribed_) unsubscribe();
  }

  void subscribe() {
    if (fixed_frame_.empty()) {
      sub_ = nh_.subscribe<sensor_msgs::PointCloud2>("points", 1, &DoorStateNodelet::cloudCallback, this);
    } else {
      mf_sub_.subscribe(nh_, "points", 1);
      tf_filter_ = std::make_unique<tf2_ros::MessageFilter<sensor_msgs::PointCloud2>>(mf_sub_, *tf_buffer_, fixed_frame_,
                                                                                    tf_queue_size_, nh_);
      tf_filter_->registerCallback(&DoorStateNodelet::cloudCallback, this);
      tf_filter_->registerFailureCallback(
          [this](const sensor_msgs::PointCloud2ConstPtr& msg, tf2_ros::filter_failure_reasons::FilterFailureReason) {
            NODELET_WARN_THROTTLE(5.0, "door_state: no transform from '%s' to '%s' at %.3f: cloud dropped",
                                  msg->header.frame_id.c_str(), fixed_frame_.c_str(), msg->header.stamp.toSec());
            ++clouds_no_tf_;
            noteError("no transform from '" + msg->header.frame_id + "' to '" + fixed_frame_ + "'");
          });
    }
    subscribed_ = true;
  }

  void unsubscribe() {
    sub_.shutdown();
    if (tf_filter_) tf_filter_.reset();
    mf_sub_.unsubscribe();
    subscribed_ = false;
  }

  // dynamic_reconfigure: a configuration the pipeline refuses (out of range,
  // NaN, inconsistent with another parameter, unknown up axis) is logged,
  // the previous one stays in force, and `config` is set back to it: the
  // server stores what the callback leaves in `config` on the parameter
  // server, publishes it on parameter_updates and returns it to the caller.
  void reconfigure(DoorStateConfig& config, uint32_t) {
    // The first call carries the ~ parameters, checked in onInit; later ones
    // are requests, clamped by the server to the .cfg range before they get
    // here: say so when a value lands on an end of its range.
    if (configured_) {
      const std::string ends = atRangeEnd(config, last_good_config_);
      if (!ends.empty())
        NODELET_WARN("door_state: dynamic_reconfigure request: %s; the server clamps a value asked beyond the range "
                     "to its end without telling, so the value asked may have been outside it and was clamped",
                     ends.c_str());
    }
    configured_ = true;
    try {
      const std::string non_finite = nonFinite(config);
      if (!non_finite.empty()) throw std::invalid_argument(non_finite);
      dsr::Parameters next = dsr::parseParameters(toYaml(config), dsr::Parameters(), "dynamic_reconfigure");
      // A fixed frame is gravity-aligned (REP 105): there z is up, whatever ~up_axis says.
      if (!fixed_frame_.empty()) next.up_axis = "+z";
      auto pipeline = std::make_shared<const dsr::Pipeline>(next);
      {
        // A cloud is processed with one set of parameters, never half of two:
        // the worker takes the pipeline under this lock and keeps its copy.
        std::lock_guard<std::mutex> lock(process_mutex_);
        pipeline_ = std::move(pipeline);
        params_ = next;
      }
      last_good_config_ = config;
    } catch (const std::exception& e) {
      // Each distinct refusal is logged; the same one repeated at most every 10 s.
      const std::string what = e.what();
      const ros::WallTime now = ros::WallTime::now();
      if (what != last_refusal_ || (now - last_refusal_time_).toSec() > 10.0) {
        NODELET_ERROR("door_state: parameters refused, the previous ones stay in force: %s", what.c_str());
        last_refusal_ = what;
        last_refusal_time_ = now;
      }
      noteError("parameters refused: " + what);
      config = last_good_config_;
    }
  }

  // Subscriber (or tf filter) callback: hand the cloud to the worker through
  // the one-cloud slot. A cloud still waiting there is stale: dropped. So is
  // a cloud older than the one waiting or under way: the tf filter releases
  // the clouds it held for a late transform all at once, in no particular
  // order. (Once the worker is idle any stamp is taken: a bag played again,
  // a restarted driver.)
  void cloudCallback(const sensor_msgs::PointCloud2ConstPtr& msg) {
    ++clouds_in_;
    const ros::WallTime received = ros::WallTime::now();
    if (!worker_.joinable()) {
      process(msg, received);
      return;
    }
    bool dropped = false;
    {
      std::lock_guard<std::mutex> lock(slot_mutex_);
      if (stop_) return;
      const ros::Time newest = pending_ ? pending_->header.stamp : busy_stamp_;
      if ((pending_ || busy_) && msg->header.stamp < newest) {
        ++clouds_dropped_;
        NODELET_DEBUG_THROTTLE(5.0, "door_state: cloud at %.3f older than one at %.3f already taken: dropped",
                               msg->header.stamp.toSec(), newest.toSec());
        return;
      }
      dropped = static_cast<bool>(pending_);
      pending_ = msg;
      pending_received_ = received;
    }
    slot_cv_.notify_one();
    if (dropped) {
      ++clouds_dropped_;
      NODELET_DEBUG_THROTTLE(5.0, "door_state: clouds arrive faster than they are processed: stale cloud dropped");
    }
  }

  void work() {
    for (;;) {
      sensor_msgs::PointCloud2ConstPtr msg;
      ros::WallTime received;
      {
        std::unique_lock<std::mutex> lock(slot_mutex_);
        busy_ = false;
        slot_cv_.wait(lock, [this] { return stop_ || pending_; });
        if (stop_) return;
        msg.swap(pending_);
        received = pending_received_;
        busy_ = true;
        busy_stamp_ = msg->header.stamp;
      }
      process(msg, received);
    }
  }

  // Runs the pipeline on one cloud and publishes. Never throws.
  void process(const sensor_msgs::PointCloud2ConstPtr& msg, const ros::WallTime& received) {
    try {
      processOrThrow(msg, received);
    } catch (const std::exception& e) {
      NODELET_ERROR_THROTTLE(5.0, "door_state: cloud in frame '%s' not processed: %s", msg->header.frame_id.c_str(), e.what());
      noteError(e.what());
      publishEmptyNoThrow(msg->header);
    } catch (...) {
      NODELET_ERROR_THROTTLE(5.0, "door_state: cloud in frame '%s' not processed: unknown exception", msg->header.frame_id.c_str());
      noteError("unknown exception");
      publishEmptyNoThrow(msg->header);
    }
  }

  void processOrThrow(const sensor_msgs::PointCloud2ConstPtr& msg, const ros::WallTime& received) {
    const auto t0 = std::chrono::steady_clock::now();
    std::shared_ptr<const dsr::Pipeline> pipeline;
    {
      std::lock_guard<std::mutex> lock(process_mutex_);
      pipeline = pipeline_;
    }
    const std::string problem =
        dsr::ros_io::validate(*msg, static_cast<std::size_t>(pipeline->parameters().max_points));
    if (!problem.empty()) {
      NODELET_ERROR_THROTTLE(5.0, "door_state: malformed cloud in frame '%s': %s", msg->header.frame_id.c_str(),
                             problem.c_str());
      ++clouds_refused_;
      noteError("malformed cloud: " + problem);
      publishEmpty(msg->header);
      return;
    }
    // One conversion PointCloud2 -> PCL into a buffer kept between clouds
    // (its capacity is reused: no per-cloud allocation of the point array
    // once the largest cloud has been seen); the move into the fixed frame
    // is done in place.
    dsr::ros_io::toPcl(*msg, cloud_);
    std_msgs::Header out_header = msg->header;
    std::optional<Eigen::Isometry3d> to_fixed;  // none: the cloud is in the fixed frame (or none is set)
    if (!fixed_frame_.empty() && msg->header.frame_id != fixed_frame_) {
      to_fixed = tf2::transformToEigen(tf_buffer_->lookupTransform(fixed_frame_, msg->header.frame_id, msg->header.stamp));
      out_header.frame_id = fixed_frame_;
    }
    // With a fixed frame, dsr::DriveTracker moves the cloud, runs the
    // pipeline and fuses its doors; without, the cloud's doors only.
    std::optional<dsr::DriveTracker::Step> step;
    dsr::PipelineResult result;
    if (fixed_frame_.empty()) {
      result = dsr::DriveTracker::run(*pipeline, cloud_, std::nullopt, wantWalls(), without_viewpoint_);
    } else {
      dsr::DriveTracker::Processed p =
          drive_.process(*pipeline, cloud_, to_fixed, msg->header.stamp.toSec(), wantWalls(), without_viewpoint_);
      result = std::move(p.result);
      step = p.step;
      last_fuse_ms_ = p.fuse_ms;
    }
    if (!result.warnings.empty()) {
      std::string all;
      for (const auto& w : result.warnings) all += (all.empty() ? "" : "; ") + w;
      // Nothing found at all: the input is degenerate (empty, all NaN, a
      // line, a plane, a wrong up axis): worth a warning. Otherwise (e.g.
      // "no ceiling in view" for a camera) only a debug message.
      if (result.walls.empty()) {
        NODELET_WARN_THROTTLE(5.0, "door_state: cloud in frame '%s' (%zu points): no walls: %s",
                              msg->header.frame_id.c_str(), result.points_in, all.c_str());
        ++clouds_degenerate_;
        noteError("no walls: " + all);
      } else {
        NODELET_DEBUG_THROTTLE(5.0, "door_state: %s", all.c_str());
      }
    }
    publish(result, out_header, step);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const double in_node_ms = (ros::WallTime::now() - received).toSec() * 1e3;
    const double age_ms = (ros::Time::now() - msg->header.stamp).toSec() * 1e3;
    {
      std::lock_guard<std::mutex> lock(diag_mutex_);
      processing_ms_.add(ms);
      in_node_ms_.add(in_node_ms);
      age_ms_.add(age_ms);
    }
    last_ms_ = ms;
    ++clouds_done_;
  }

  bool wantWalls() const { return pub_walls_.getNumSubscribers() > 0 || pub_markers_.getNumSubscribers() > 0; }

  static DoorState toMsg(const dsr::DoorResult& d, std::uint32_t id, const ros::Time& last_seen,
                         std::uint32_t observations) {
    DoorState s;
    s.id = id;
    s.wall_id = d.wall_id ? static_cast<std::uint32_t>(*d.wall_id) : 0;
    s.state = static_cast<std::uint8_t>(d.state);
    s.opening_angle = static_cast<float>(d.opening_angle_deg * M_PI / 180.0);
    s.confidence = static_cast<float>(d.confidence);
    s.angle_is_lower_bound = d.angle_is_lower_bound;
    s.hinge = tf2::toMsg(d.hinge);
    s.opening_center = tf2::toMsg(d.opening_center);
    s.wall_normal.x = d.wall_normal.x();
    s.wall_normal.y = d.wall_normal.y();
    s.wall_normal.z = d.wall_normal.z();
    s.width = static_cast<float>(d.width);
    s.height = static_cast<float>(d.height);
    s.clear_width = static_cast<float>(d.clear_width);
    for (int k = 0; k < 4; ++k) s.leaf_corners[k] = tf2::toMsg(d.leaf_corners[k]);
    s.last_seen = last_seen;
    s.observations = observations;
    return s;
  }

  // tracked_doors after the cloud's doors went into the fused tracks (fixed
  // frame only); a warning (throttled) for a relocalisation jump (tracks
  // reset), stamps going backwards (reset) or out of order (not fused).
  void publishTracked(const dsr::DriveTracker::Step& step, const std_msgs::Header& header) {
    const double stamp = header.stamp.toSec(), newest = step.newest_before;
    if (step.relocalised) {
      ++relocalisations_;
      NODELET_WARN_THROTTLE(5.0, "door_state: the sensor moved %.2f m in the fixed frame '%s' in %.3f s (more than "
                                 "~max_sensor_speed %.2f m/s allows): relocalisation; tracked_doors reset",
                            step.moved_m, fixed_frame_.c_str(), step.dt_s, drive_.options().max_sensor_speed);
      noteError("relocalisation jump: tracked doors reset");
    }
    if (step.disproved > 0)
      NODELET_DEBUG_THROTTLE(5.0, "door_state: %zu tracked door(s) withdrawn: their doorway looked at and not found",
                             step.disproved);
    disproved_ += step.disproved;
    if (step.fusion.outcome == dsr::DoorFusion::Outcome::Reset) {
      ++fusion_resets_;
      NODELET_WARN_THROTTLE(5.0, "door_state: cloud stamped %.3f is %.3f s older than the newest fused (%.3f): "
                                 "time went backwards (bag looped?); tracked_doors reset",
                            stamp, newest - stamp, newest);
      noteError("time went backwards: tracked doors reset");
    } else if (step.fusion.outcome == dsr::DoorFusion::Outcome::IgnoredOutOfOrder) {
      ++fusion_ignored_;
      NODELET_WARN_THROTTLE(5.0, "door_state: cloud stamped %.3f is older than the newest fused (%.3f): "
                                 "published in doors, not fused into tracked_doors",
                            stamp, newest);
    }
    DoorStateArrayPtr tracked = boost::make_shared<DoorStateArray>();
    tracked->header = header;
    for (const dsr::TrackedDoor& t : drive_.published()) {
      ros::Time seen = header.stamp;  // exactly the header's for a door this cloud shows
      if (!t.seen_now) seen.fromSec(std::max(0.0, t.last_seen));
      tracked->doors.push_back(toMsg(t.door, t.id, seen, t.observations));
    }
    tracked_count_ = tracked->doors.size();
    pub_tracked_.publish(tracked);
  }

  // `step`: the fusion of this cloud (fixed frame only).
  void publish(const dsr::PipelineResult& r, const std_msgs::Header& header,
               const std::optional<dsr::DriveTracker::Step>& step = std::nullopt) {
    std::vector<Eigen::Vector3d> centres;
    for (const auto& d : r.doors) centres.push_back(d.opening_center);
    // Matched across the pipeline's up vector (-y in a camera optical frame).
    const std::vector<std::uint32_t> ids = tracker_.update(centres, r.up);

    DoorStateArrayPtr out = boost::make_shared<DoorStateArray>();
    out->header = header;
    for (std::size_t i = 0; i < r.doors.size(); ++i) out->doors.push_back(toMsg(r.doors[i], ids[i], header.stamp, 1));
    pub_doors_.publish(out);
    if (step) publishTracked(*step, header);
    if (pub_markers_.getNumSubscribers() > 0) {
      auto markers = boost::make_shared<visualization_msgs::MarkerArray>(dsr::ros_io::makeMarkers(r, ids, header));
      if (!fixed_frame_.empty()) dsr::ros_io::addTrackedMarkers(drive_.published(), header, *markers);
      pub_markers_.publish(markers);
    }
    if (pub_walls_.getNumSubscribers() > 0) {
      sensor_msgs::PointCloud2Ptr walls = boost::make_shared<sensor_msgs::PointCloud2>();
      pcl::toROSMsg(r.reconstruction, *walls);
      walls->header = header;
      pub_walls_.publish(walls);
    }
  }

  void publishEmpty(const std_msgs::Header& header) {
    DoorStateArrayPtr out = boost::make_shared<DoorStateArray>();
    out->header = header;
    pub_doors_.publish(out);
  }

  void publishEmptyNoThrow(const std_msgs::Header& header) {
    try {
      publishEmpty(header);
    } catch (...) {
    }
  }

  void noteError(const std::string& what) {
    std::lock_guard<std::mutex> lock(diag_mutex_);
    last_error_ = what;
    last_error_time_ = ros::WallTime::now();
  }

  // Counters since start; processing time and latencies over the last
  // Window::kWindow processed clouds. "latency from stamp" is the age of the
  // cloud (ROS time now minus its header stamp) when its doors are published:
  // it includes what happened before the nodelet (driver, transport).
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    const ros::WallTime now = ros::WallTime::now();
    const double dt = last_diag_.isZero() ? 0.0 : (now - last_diag_).toSec();
    const unsigned long in = clouds_in_, done = clouds_done_;
    const double rate = dt > 0 ? (in - last_in_) / dt : 0.0;
    last_diag_ = now;
    last_in_ = in;
    std::lock_guard<std::mutex> lock(diag_mutex_);
    if (!refused_.empty()) {
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, refused_);
      stat.add("last error", refused_);
      stat.add("subscribed", "no");
      return;
    }
    const bool recent_error = !last_error_.empty() && (now - last_error_time_).toSec() < 10.0;
    stat.summary(recent_error ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK,
                 recent_error ? last_error_ : (subscribed_ ? "processing" : "idle: nobody listens"));
    stat.add("input rate (Hz)", rate);
    stat.add("clouds received", in);
    stat.add("clouds processed", done);
    stat.add("clouds dropped (stale)", clouds_dropped_.load());
    stat.add("clouds dropped (no tf)", clouds_no_tf_.load());
    stat.add("clouds refused (malformed)", clouds_refused_.load());
    stat.add("clouds without walls", clouds_degenerate_.load());
    stat.add("last processing time (ms)", last_ms_.load());
    stat.add("processing time p50 (ms)", processing_ms_.quantile(0.5));
    stat.add("processing time max (ms)", processing_ms_.quantile(1.0));
    stat.add("latency in node p50 (ms)", in_node_ms_.quantile(0.5));
    stat.add("latency in node max (ms)", in_node_ms_.quantile(1.0));
    stat.add("latency from stamp p50 (ms)", age_ms_.quantile(0.5));
    stat.add("latency from stamp max (ms)", age_ms_.quantile(1.0));
    stat.add("last error", last_error_.empty() ? std::string("none") : last_error_);
    stat.add("subscribed", subscribed_ ? "yes" : "no");
    stat.add("worker thread", worker_.joinable() ? "yes" : "no (processing in the callback)");
    stat.add("fixed frame", fixed_frame_.empty() ? std::string("(cloud frame)") : fixed_frame_);
    if (!fixed_frame_.empty()) {
      stat.add("tracked doors", tracked_count_.load());
      stat.add("last fusion time (ms)", last_fuse_ms_.load());
      stat.add("tracked doors reset (time went backwards)", fusion_resets_.load());
      stat.add("clouds not fused (out of order)", fusion_ignored_.load());
      stat.add("tracked doors reset (relocalisation)", relocalisations_.load());
      stat.add("tracked doors withdrawn (doorway looked at, not found)", disproved_.load());
    }
  }

  ros::NodeHandle nh_, pnh_;
  std::string fixed_frame_;
  bool without_viewpoint_ = false;  // ~viewpoint none
  int tf_queue_size_ = 5;
  ros::Publisher pub_doors_, pub_markers_, pub_walls_, pub_tracked_;
  ros::Subscriber sub_;
  message_filters::Subscriber<sensor_msgs::PointCloud2> mf_sub_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<tf2_ros::MessageFilter<sensor_msgs::PointCloud2>> tf_filter_;
  std::mutex connect_mutex_, process_mutex_, diag_mutex_;
  std::atomic<bool> subscribed_{false};
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<DoorStateConfig>> reconfigure_;
  dsr::Parameters params_;
  std::shared_ptr<const dsr::Pipeline> pipeline_;  // swapped under process_mutex_
  DoorStateConfig last_good_config_;                // the configuration in force
  bool configured_ = false;                         // reconfigure() has run once (under the server's mutex)
  std::string last_refusal_;
  ros::WallTime last_refusal_time_;
  dsr::DoorTracker tracker_;                        // worker only
  dsr::DriveTracker drive_;                         // worker only (fixed frame): ~forget_after_s, ~state_change_deg, ~max_sensor_speed, ~confirm_*
  std::atomic<unsigned long> fusion_resets_{0}, fusion_ignored_{0}, relocalisations_{0}, disproved_{0};
  std::atomic<std::size_t> tracked_count_{0};
  pcl::PointCloud<pcl::PointXYZ> cloud_;            // worker only, reused between clouds
  // The one-cloud slot between the subscriber callback and the worker.
  std::mutex slot_mutex_;
  std::condition_variable slot_cv_;
  sensor_msgs::PointCloud2ConstPtr pending_;
  ros::WallTime pending_received_;
  bool busy_ = false;  // the worker is processing a cloud stamped busy_stamp_
  ros::Time busy_stamp_;
  bool stop_ = false;
  std::thread worker_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diagnostics_timer_;
  std::atomic<unsigned long> clouds_in_{0}, clouds_done_{0}, clouds_dropped_{0}, clouds_no_tf_{0}, clouds_refused_{0},
      clouds_degenerate_{0};
  Window processing_ms_, in_node_ms_, age_ms_;  // under diag_mutex_
  unsigned long last_in_ = 0;
  ros::WallTime last_diag_;
  std::atomic<double> last_ms_{0.0}, last_fuse_ms_{0.0};  // fuse: DriveTracker::fuse, a part of last_ms_
  std::string last_error_;
  ros::WallTime last_error_time_;
  std::string refused_;          // set once in onInit: bad ~ parameters, not started
  ros::WallTimer refusal_timer_;
};

}  // namespace door_state_recognition

PLUGINLIB_EXPORT_CLASS(door_state_recognition::DoorStateNodelet, nodelet::Nodelet)
