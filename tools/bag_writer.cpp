#include "bag_writer.hpp"

#include <pcl_conversions/pcl_conversions.h>
#include <rosbag/bag.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include <cmath>
#include <stdexcept>

namespace dsr {
namespace tools {
namespace {

// A connection header given to rosbag replaces the one it would build:
// it needs the message's type, md5sum and definition besides latching.
boost::shared_ptr<ros::M_string> latchedTf() {
  auto latched = boost::make_shared<ros::M_string>();
  (*latched)["type"] = ros::message_traits::datatype<tf2_msgs::TFMessage>();
  (*latched)["md5sum"] = ros::message_traits::md5sum<tf2_msgs::TFMessage>();
  (*latched)["message_definition"] = ros::message_traits::definition<tf2_msgs::TFMessage>();
  (*latched)["latching"] = "1";
  (*latched)["callerid"] = "/door_scene_sim";
  return latched;
}

tf2_msgs::TFMessage tfMessage(const Eigen::Isometry3d& child_to_parent, const ros::Time& stamp, const std::string& parent,
                              const std::string& child) {
  geometry_msgs::TransformStamped tf = tf2::eigenToTransform(child_to_parent);
  tf.header.stamp = stamp;
  tf.header.frame_id = parent;
  tf.child_frame_id = child;
  tf2_msgs::TFMessage tfm;
  tfm.transforms.push_back(tf);
  return tfm;
}

}  // namespace

void writeBag(const std::string& path, const sim::SimulatedCloud& sim, const BagOptions& o) {
  if (o.count < 1 || !(o.rate_hz > 0)) throw std::runtime_error("bag: count must be >= 1 and rate > 0");
  try {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    const ros::Time t0(o.start_time);
    bag.write("/tf_static", t0, tfMessage(sim.sensor_to_world, t0, o.fixed_frame, sim.frame_id), latchedTf());

    sensor_msgs::PointCloud2 msg;
    pcl::toROSMsg(sim.cloud, msg);
    msg.header.frame_id = sim.frame_id;
    for (int i = 0; i < o.count; ++i) {
      const ros::Time stamp = t0 + ros::Duration(0.05 + i / o.rate_hz);
      msg.header.stamp = stamp;
      msg.header.seq = i;
      bag.write("/points", stamp, msg);
    }
    bag.close();
  } catch (const std::exception& e) {
    throw std::runtime_error("bag: cannot write " + path + ": " + e.what());
  }
}

void writeDriveBag(const std::string& path, const sim::DrivePlan& plan, const BagOptions& o,
                   const std::function<void(const sim::DriveFrame&)>& each) {
  try {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    const ros::Time t0(o.start_time);
    bag.write("/tf_static", t0, tfMessage(plan.sensor_to_base, t0, plan.base_frame, plan.sensor_frame), latchedTf());
    const double clock_step = 0.01;
    long long next_clock = 0;  // index of the next 10 ms tick
    auto clockUpTo = [&](double t) {  // ticks before t
      for (; next_clock * clock_step < t - 1e-9; ++next_clock) {
        rosgraph_msgs::Clock c;
        c.clock = t0 + ros::Duration(next_clock * clock_step);
        bag.write("/clock", c.clock, c);
      }
    };
    sim::simulateDrive(plan, [&](const sim::DriveFrame& f) {
      const ros::Time stamp = t0 + ros::Duration(f.t);
      clockUpTo(f.t);
      rosgraph_msgs::Clock c;
      c.clock = stamp;
      bag.write("/clock", stamp, c);
      if (std::abs(next_clock * clock_step - f.t) < 1e-9) ++next_clock;  // that tick was this one
      bag.write("/tf", stamp, tfMessage(f.base_to_map, stamp, o.fixed_frame, plan.base_frame));
      sensor_msgs::PointCloud2 msg;
      pcl::toROSMsg(f.cloud.cloud, msg);
      msg.header.frame_id = plan.sensor_frame;
      msg.header.stamp = stamp;
      msg.header.seq = static_cast<std::uint32_t>(f.index);
      bag.write("/points", stamp + ros::Duration(0.001), msg);
      if (each) each(f);
    });
    clockUpTo(plan.options.seconds + 1e-6);
    bag.close();
  } catch (const std::exception& e) {
    throw std::runtime_error("bag: cannot write " + path + ": " + e.what());
  }
}

}  // namespace tools
}  // namespace dsr
