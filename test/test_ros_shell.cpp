// The ROS shells' command line and launch files, checked without a master:
// door_state_node --help, and the parameters launch/door_state.launch sets
// (roslaunch --dump-params needs no master).
#include <gtest/gtest.h>

#include "run_command.hpp"
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;

namespace {

using Result = CommandResult;

// Runs `cmd` through the shell; stdout only.
Result shell(const std::string& cmd) { return runCommand(cmd + " 2>/dev/null </dev/null"); }

// door_state_node with ROS_MASTER_URI at a port nobody listens on, killed after 20 s.
Result node(const std::string& args) {
  return shell("ROS_MASTER_URI=http://127.0.0.1:9 timeout 20 " + std::string(DSR_BIN_DIR) + "/door_state_node " + args);
}

// The value of `/door_state/<name>:` in roslaunch --dump-params output ("" if absent).
std::string dumped(const std::string& dump, const std::string& name) {
  const std::string key = "/door_state/" + name + ": ";
  const std::size_t at = dump.find(key);
  if (at == std::string::npos) return "";
  const std::size_t from = at + key.size();
  return dump.substr(from, dump.find('\n', from) - from);
}

std::string dumpParams(const std::string& args) {
  // Debian's ROS: /usr/bin first (a pyenv python3 lacks the ROS modules).
  const Result r = shell("PATH=/usr/bin:$PATH ROS_PACKAGE_PATH=" + std::string(DSR_SOURCE_DIR) +
                         " roslaunch --dump-params " + DSR_SOURCE_DIR + "/launch/door_state.launch " + args);
  EXPECT_EQ(r.code, 0) << "roslaunch --dump-params failed: " << args;
  return r.out;
}

}  // namespace

// --help and -h print the usage (exit 0) before ros::init: no master is
// contacted (without the early exit the node retries the master until the
// timeout kills it: exit 124). Anything but a ROS argument: exit 2.
TEST(RosShell, NodeHelpNeedsNoMaster) {
  for (const std::string flag : {"--help", "-h"}) {
    SCOPED_TRACE(flag);
    const Result help = node(flag);
    EXPECT_EQ(help.code, 0) << "124: still waiting for a master after 20 s";
    EXPECT_NE(help.out.find("usage"), std::string::npos);
    EXPECT_NE(help.out.find("doors"), std::string::npos) << "the usage names the topics";
  }
  EXPECT_EQ(node("--no-such-flag").code, 2);
}

// A params file's up_axis and fixed_frame stay in force unless the launch
// arguments are given; given, they override the file.
TEST(RosShell, LaunchKeepsTheParamsFilesUpAxisAndFixedFrameUnlessTheArgsAreGiven) {
  const fs::path yaml = fs::temp_directory_path() / ("dsr_test_ros_shell_" + std::to_string(::getpid()) + ".yaml");
  {
    std::ofstream out(yaml);
    out << "up_axis: \"-y\"\nfixed_frame: odom\nvoxel_size: 0.03\n";
  }
  const std::string file = dumpParams("params:=" + yaml.string());
  EXPECT_EQ(dumped(file, "up_axis"), "-y") << file;
  EXPECT_EQ(dumped(file, "fixed_frame"), "odom") << file;
  EXPECT_EQ(dumped(file, "voxel_size"), "0.03") << file;
  const std::string args = dumpParams("params:=" + yaml.string() + " up_axis:=+x fixed_frame:=map");
  EXPECT_EQ(dumped(args, "up_axis"), "+x") << args;
  EXPECT_EQ(dumped(args, "fixed_frame"), "map") << args;
  // config/default.yaml (the default params) holds up_axis +z and no fixed_frame.
  const std::string dflt = dumpParams("");
  EXPECT_EQ(dumped(dflt, "up_axis"), "+z") << dflt;
  EXPECT_EQ(dumped(dflt, "fixed_frame"), "") << dflt;
  fs::remove(yaml);
}
