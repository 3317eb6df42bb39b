#include "bag_writer.hpp"

#include <pcl_conversions/pcl_conversions.h>
#include <rosbag/bag.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>

#include <stdexcept>

namespace dsr {
namespace tools {

void writeBag(const std::string& path, const sim::SimulatedCloud& sim, const BagOptions& o) {
  if (o.count < 1 || !(o.rate_hz > 0)) throw std::runtime_error("bag: count must be >= 1 and rate > 0");
  try {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    const ros::Time t0(o.start_time);

    geometry_msgs::TransformStamped tf = tf2::eigenToTransform(sim.sensor_to_world);
    tf.header.stamp = t0;
    tf.header.frame_id = o.fixed_frame;
    tf.child_frame_id = sim.frame_id;
    tf2_msgs::TFMessage tfm;
    tfm.transforms.push_back(tf);
    auto latched = boost::make_shared<ros::M_string>();
    // A connection header given to rosbag replaces the one it would build:
    // it needs the message's type, md5sum and definition besides latching.
    (*latched)["type"] = ros::message_traits::datatype<tf2_msgs::TFMessage>();
    (*latched)["md5sum"] = ros::message_traits::md5sum<tf2_msgs::TFMessage>();
    (*latched)["message_definition"] = ros::message_traits::definition<tf2_msgs::TFMessage>();
    (*latched)["latching"] = "1";
    (*latched)["callerid"] = "/door_scene_sim";
    bag.write("/tf_static", t0, tfm, latched);

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

}  // namespace tools
}  // namespace dsr
