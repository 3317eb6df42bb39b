// The ROS shells' command line, checked without a master: door_state_node --help.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>

namespace {

struct Result {
  int code;
  std::string out;
};

// Runs `cmd` through the shell; stdout only.
Result shell(const std::string& cmd) {
  FILE* p = popen((cmd + " 2>/dev/null </dev/null").c_str(), "r");
  if (!p) return {-1, ""};
  std::string out;
  char buf[4096];
  while (std::size_t n = fread(buf, 1, sizeof buf, p)) out.append(buf, n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

// door_state_node with ROS_MASTER_URI at a port nobody listens on, killed after 20 s.
Result node(const std::string& args) {
  return shell("ROS_MASTER_URI=http://127.0.0.1:9 timeout 20 " + std::string(DSR_BIN_DIR) + "/door_state_node " + args);
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
