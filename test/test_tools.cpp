// The executables' command-line contract: --help exits 0 with the usage on
// stdout, wrong arguments exit 2; the simulator writes what it promises and
// is deterministic across runs.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace {

struct Result {
  int code;
  std::string out;
};

Result run(const std::string& args) {
  const std::string cmd = std::string(DSR_BIN_DIR) + "/" + args + " 2>/dev/null";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return {-1, ""};
  std::string out;
  char buf[4096];
  while (std::size_t n = fread(buf, 1, sizeof buf, p)) out.append(buf, n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

fs::path tempDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("dsr_test_tools_" + name + "_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

}  // namespace

TEST(Tools, HelpExitsZeroAndWrongArgumentsExitTwo) {
  for (const std::string exe : {"door_scene_sim", "door_state_eval"}) {
    SCOPED_TRACE(exe);
    const Result help = run(exe + " --help");
    EXPECT_EQ(help.code, 0);
    EXPECT_NE(help.out.find("usage"), std::string::npos);
    EXPECT_EQ(run(exe + " --no-such-flag").code, 2);
  }
  EXPECT_EQ(run("door_scene_sim").code, 2);                                   // no --out
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --points many").code, 2);        // not a number
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --sensor sonar").code, 2);       // unknown sensor
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --scene atlantis").code, 2);     // unknown scene
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --angle 270").code, 2);          // out of range
  EXPECT_EQ(run("door_state_eval only_one.json").code, 2);
  EXPECT_EQ(run("door_state_eval /nonexistent/a.json /nonexistent/b.json").code, 2);
}

TEST(Tools, SimulatorWritesCloudTruthAndBagDeterministically) {
  const fs::path dir = tempDir("sim");
  const std::string common = " --seed 5 --points 20000 --formats pcd,ply,json,bag --quiet";
  ASSERT_EQ(run("door_scene_sim --out " + (dir / "a").string() + common).code, 0);
  ASSERT_EQ(run("door_scene_sim --out " + (dir / "b").string() + common).code, 0);
  for (const std::string ext : {".pcd", ".ply", ".json", ".bag"}) {
    ASSERT_TRUE(fs::exists(dir / ("a" + ext))) << ext;
    EXPECT_GT(fs::file_size(dir / ("a" + ext)), 100u) << ext;
  }
  EXPECT_EQ(slurp(dir / "a.pcd"), slurp(dir / "b.pcd"));
  EXPECT_EQ(slurp(dir / "a.json"), slurp(dir / "b.json"));
  const nlohmann::json truth = nlohmann::json::parse(slurp(dir / "a.json"));
  EXPECT_EQ(truth["sensor"], "tls");
  EXPECT_GE(truth["doors"].size(), 1u);
  // The truth scored against itself as a report is perfect.
  const Result eval = run("door_state_eval " + (dir / "a.json").string() + " " + (dir / "a.json").string());
  ASSERT_EQ(eval.code, 0);
  const nlohmann::json score = nlohmann::json::parse(eval.out);
  EXPECT_DOUBLE_EQ(score["precision"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(score["recall"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(score["state_accuracy"].get<double>(), 1.0);
  fs::remove_all(dir);
}
