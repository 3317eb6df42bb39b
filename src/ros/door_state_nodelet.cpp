// DoorStateNodelet: a thin ROS shell around dsr::Pipeline.
//
// Subscribes `points` (sensor_msgs/PointCloud2, queue 1) only while one of
// its outputs has a subscriber; with ~fixed_frame set, clouds wait in a
// tf2_ros::MessageFilter until their transform to the fixed frame is known.
// Publishes `doors` (DoorStateArray), `markers` (MarkerArray) and
// `reconstructed_walls` (PointCloud2). Bad input is logged (throttled) and
// answered with an empty DoorStateArray carrying the input's header; nothing
// here may throw into the nodelet manager.
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
#include <visualization_msgs/MarkerArray.h>

#include <atomic>
#include <boost/thread/recursive_mutex.hpp>
#include <chrono>
#include <memory>
#include <mutex>
#include <sstream>

#include "door_state_recognition/DoorStateArray.h"
#include "door_state_recognition/DoorStateConfig.h"
#include "door_state_recognition/pipeline/parameters.hpp"
#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/ros/cloud_conversion.hpp"
#include "door_state_recognition/ros/markers.hpp"
#include "door_state_recognition/tracking/door_tracker.hpp"

namespace door_state_recognition {

namespace {

// A dynamic_reconfigure config as YAML `name: value`, for dsr::parseParameters.
std::string toYaml(const DoorStateConfig& config) {
  std::ostringstream os;
  os.precision(17);
  for (const auto& d : DoorStateConfig::__getParamDescriptions__()) {
    boost::any v;
    d->getValue(config, v);
    os << d->name << ": ";
    if (d->type == "double") os << boost::any_cast<double>(v);
    else if (d->type == "int") os << boost::any_cast<int>(v);
    else if (d->type == "bool") os << (boost::any_cast<bool>(v) ? "true" : "false");
    else os << '"' << boost::any_cast<std::string>(v) << '"';
    os << "\n";
  }
  return os.str();
}

}  // namespace

class DoorStateNodelet : public nodelet::Nodelet {
 public:
  ~DoorStateNodelet() override {
    // Stop callbacks before the members they use go away.
    std::lock_guard<std::mutex> lock(connect_mutex_);
    unsubscribe();
  }

 private:
  void onInit() override {
    nh_ = getNodeHandle();
    pnh_ = getPrivateNodeHandle();
    pnh_.param<std::string>("fixed_frame", fixed_frame_, "");
    pnh_.param("tf_queue_size", tf_queue_size_, 5);
    if (tf_queue_size_ < 1) tf_queue_size_ = 1;
    pipeline_ = std::make_unique<dsr::Pipeline>(params_);

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

    // The connect callbacks may fire as soon as the publishers exist: hold
    // the lock until every publisher is assigned.
    std::lock_guard<std::mutex> lock(connect_mutex_);
    ros::SubscriberStatusCallback cb = [this](const ros::SingleSubscriberPublisher&) { connectionChanged(); };
    pub_doors_ = nh_.advertise<DoorStateArray>("doors", 1, cb, cb);
    pub_markers_ = nh_.advertise<visualization_msgs::MarkerArray>("markers", 1, cb, cb);
    pub_walls_ = nh_.advertise<sensor_msgs::PointCloud2>("reconstructed_walls", 1, cb, cb);
    diagnostics_timer_ = nh_.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { diagnostics_->update(); });
    NODELET_INFO("door_state: waiting for subscribers before subscribing to %s (fixed_frame '%s')",
                 nh_.resolveName("points").c_str(), fixed_frame_.c_str());
  }

  // Lazy subscription: subscribe to the input only while someone listens.
  void connectionChanged() {
    std::lock_guard<std::mutex> lock(connect_mutex_);
    const bool wanted = pub_doors_.getNumSubscribers() > 0 || pub_markers_.getNumSubscribers() > 0 ||
                        pub_walls_.getNumSubscribers() > 0;
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

  void reconfigure(DoorStateConfig& config, uint32_t) {
    // Holding the processing lock: a cloud is processed with one set of
    // parameters, never half of two.
    std::lock_guard<std::mutex> lock(process_mutex_);
    try {
      dsr::Parameters next = dsr::parseParameters(toYaml(config), dsr::Parameters(), "parameters");
      // A fixed frame is gravity-aligned (REP 105): there z is up, whatever ~up_axis says.
      if (!fixed_frame_.empty()) next.up_axis = "+z";
      pipeline_ = std::make_unique<dsr::Pipeline>(next);
      params_ = next;
    } catch (const std::exception& e) {
      NODELET_ERROR("door_state: parameters refused, the previous ones stay in force: %s", e.what());
      noteError(std::string("parameters refused: ") + e.what());
    }
  }

  void cloudCallback(const sensor_msgs::PointCloud2ConstPtr& msg) {
    const auto t0 = std::chrono::steady_clock::now();
    ++clouds_in_;
    std::size_t max_points;
    {
      std::lock_guard<std::mutex> lock(process_mutex_);
      max_points = static_cast<std::size_t>(params_.max_points);
    }
    const std::string problem = dsr::ros_io::validate(*msg, max_points);
    if (!problem.empty()) {
      NODELET_ERROR_THROTTLE(5.0, "door_state: malformed cloud in frame '%s': %s", msg->header.frame_id.c_str(),
                             problem.c_str());
      noteError("malformed cloud: " + problem);
      publishEmpty(msg->header);
      return;
    }
    try {
      pcl::PointCloud<pcl::PointXYZ> cloud;
      dsr::ros_io::toPcl(*msg, cloud);
      std_msgs::Header out_header = msg->header;
      Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();
      if (!fixed_frame_.empty() && msg->header.frame_id != fixed_frame_) {
        const Eigen::Isometry3d T =
            tf2::transformToEigen(tf_buffer_->lookupTransform(fixed_frame_, msg->header.frame_id, msg->header.stamp));
        const Eigen::Matrix3f R = T.linear().cast<float>();
        const Eigen::Vector3f t = T.translation().cast<float>();
        for (auto& p : cloud.points) p.getVector3fMap() = R * p.getVector3fMap() + t;
        viewpoint = T.translation();
        out_header.frame_id = fixed_frame_;
      }
      dsr::PipelineResult result;
      {
        std::lock_guard<std::mutex> lock(process_mutex_);
        result = pipeline_->run(cloud, wantWalls(), viewpoint);
      }
      publish(result, out_header);
      last_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      ++clouds_done_;
    } catch (const std::exception& e) {
      NODELET_ERROR_THROTTLE(5.0, "door_state: cloud in frame '%s' not processed: %s", msg->header.frame_id.c_str(), e.what());
      noteError(e.what());
      publishEmpty(msg->header);
    }
  }

  bool wantWalls() const { return pub_walls_.getNumSubscribers() > 0 || pub_markers_.getNumSubscribers() > 0; }

  void publish(const dsr::PipelineResult& r, const std_msgs::Header& header) {
    std::vector<Eigen::Vector3d> centres;
    for (const auto& d : r.doors) centres.push_back(d.opening_center);
    const std::vector<std::uint32_t> ids = tracker_.update(centres);

    DoorStateArrayPtr out = boost::make_shared<DoorStateArray>();
    out->header = header;
    for (std::size_t i = 0; i < r.doors.size(); ++i) {
      const dsr::DoorResult& d = r.doors[i];
      DoorState s;
      s.id = ids[i];
      s.wall_id = d.wall_id ? static_cast<std::uint32_t>(*d.wall_id) : 0;
      s.state = static_cast<std::uint8_t>(d.state);
      s.opening_angle = static_cast<float>(d.opening_angle_deg * M_PI / 180.0);
      s.confidence = static_cast<float>(d.confidence);
      s.hinge = tf2::toMsg(d.hinge);
      s.opening_center = tf2::toMsg(d.opening_center);
      s.wall_normal.x = d.wall_normal.x();
      s.wall_normal.y = d.wall_normal.y();
      s.wall_normal.z = d.wall_normal.z();
      s.width = static_cast<float>(d.width);
      s.height = static_cast<float>(d.height);
      for (int k = 0; k < 4; ++k) s.leaf_corners[k] = tf2::toMsg(d.leaf_corners[k]);
      out->doors.push_back(s);
    }
    pub_doors_.publish(out);
    if (pub_markers_.getNumSubscribers() > 0)
      pub_markers_.publish(boost::make_shared<visualization_msgs::MarkerArray>(dsr::ros_io::makeMarkers(r, ids, header)));
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

  void noteError(const std::string& what) {
    std::lock_guard<std::mutex> lock(diag_mutex_);
    last_error_ = what;
    last_error_time_ = ros::WallTime::now();
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    const ros::WallTime now = ros::WallTime::now();
    const double dt = last_diag_.isZero() ? 0.0 : (now - last_diag_).toSec();
    const unsigned long in = clouds_in_, done = clouds_done_;
    const double rate = dt > 0 ? (in - last_in_) / dt : 0.0;
    last_diag_ = now;
    last_in_ = in;
    std::lock_guard<std::mutex> lock(diag_mutex_);
    const bool recent_error = !last_error_.empty() && (now - last_error_time_).toSec() < 10.0;
    stat.summary(recent_error ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK,
                 recent_error ? last_error_ : (subscribed_ ? "processing" : "idle: nobody listens"));
    stat.add("input rate (Hz)", rate);
    stat.add("clouds received", in);
    stat.add("clouds processed", done);
    stat.add("last processing time (ms)", last_ms_.load());
    stat.add("last error", last_error_.empty() ? std::string("none") : last_error_);
    stat.add("subscribed", subscribed_ ? "yes" : "no");
    stat.add("fixed frame", fixed_frame_.empty() ? std::string("(cloud frame)") : fixed_frame_);
  }

  ros::NodeHandle nh_, pnh_;
  std::string fixed_frame_;
  int tf_queue_size_ = 5;
  ros::Publisher pub_doors_, pub_markers_, pub_walls_;
  ros::Subscriber sub_;
  message_filters::Subscriber<sensor_msgs::PointCloud2> mf_sub_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<tf2_ros::MessageFilter<sensor_msgs::PointCloud2>> tf_filter_;
  std::mutex connect_mutex_, process_mutex_, diag_mutex_;
  bool subscribed_ = false;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<DoorStateConfig>> reconfigure_;
  dsr::Parameters params_;
  std::unique_ptr<dsr::Pipeline> pipeline_;
  dsr::DoorTracker tracker_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::WallTimer diagnostics_timer_;
  std::atomic<unsigned long> clouds_in_{0}, clouds_done_{0};
  unsigned long last_in_ = 0;
  ros::WallTime last_diag_;
  std::atomic<double> last_ms_{0.0};
  std::string last_error_;
  ros::WallTime last_error_time_;
};

}  // namespace door_state_recognition

PLUGINLIB_EXPORT_CLASS(door_state_recognition::DoorStateNodelet, nodelet::Nodelet)
