// door_state_node: loads DoorStateNodelet in its own process, so that the
// node and the nodelet share one code path.
#include <nodelet/loader.h>
#include <ros/ros.h>

#include <cstdio>
#include <string>

#include "door_state_recognition/util/keep_freed_memory.hpp"
#include "door_state_recognition/util/omp_spin.hpp"

namespace {

const char* const kUsage =
    "usage: door_state_node [ROS remappings and __name:=...]\n"
    "       door_state_node --help | -h\n"
    "\n"
    "Runs the door-state nodelet (door_state_recognition/DoorStateNodelet) in its own\n"
    "process; needs a ROS master.\n"
    "\n"
    "  subscribes  points               sensor_msgs/PointCloud2 (only while an output has a subscriber)\n"
    "  publishes   doors                door_state_recognition/DoorStateArray\n"
    "              markers              visualization_msgs/MarkerArray\n"
    "              reconstructed_walls  sensor_msgs/PointCloud2\n"
    "              /diagnostics\n"
    "  parameters  ~fixed_frame, ~tf_queue_size and every pipeline parameter of\n"
    "              config/default.yaml as ~name (live through dynamic_reconfigure);\n"
    "              unknown names, wrong types and out-of-range values are refused:\n"
    "              the node then processes nothing. See README.md, section\n"
    "              \"ROS: nodelet, topics, parameters, frames\".\n"
    "\n"
    "example: door_state_node points:=/camera/depth/points _up_axis:=-y\n";

}  // namespace

int main(int argc, char** argv) {
  // --help before ros::init, which would wait for a master. Anything but a
  // ROS argument (name:=value) is a mistake: usage, exit 2.
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    }
  }
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]).find(":=") == std::string::npos) {
      std::fprintf(stderr, "door_state_node: unknown argument '%s'\n%s", argv[i], kUsage);
      return 2;
    }
  dsr::util::shortOmpSpin(argv);  // before anything else: the program may be run again
  dsr::util::keepFreedMemory();   // a cloud after another: no pages given back and faulted in again
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
