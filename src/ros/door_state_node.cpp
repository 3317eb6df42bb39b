// door_state_node: loads DoorStateNodelet in its own process, so that the
// node and the nodelet share one code path.
#include <nodelet/loader.h>
#include <ros/ros.h>

#include "door_state_recognition/util/omp_spin.hpp"

int main(int argc, char** argv) {
  dsr::util::shortOmpSpin(argv);  // before anything else: the program may be run again
  ros::init(argc, argv, "door_state_node");
  nodelet::Loader loader;
  const nodelet::M_string remappings(ros::names::getRemappings());
  const nodelet::V_string args(argv + 1, argv + argc);
  if (!loader.load(ros::this_node::getName(), "door_state_recognition/DoorStateNodelet", remappings, args)) {
    ROS_FATAL("door_state_node: could not load door_state_recognition/DoorStateNodelet");
    return 1;
  }
  ros::spin();
  return 0;
}
