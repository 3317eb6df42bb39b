// The executables' command-line contract: --help exits 0 with the usage on
// stdout, wrong arguments exit 2; the simulator writes what it promises and
// is deterministic across runs.
#include <gtest/gtest.h>

#include "run_command.hpp"
#include "door_state_recognition/util/keep_freed_memory.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <tuple>
#include <vector>

namespace fs = std::filesystem;

namespace {

using Result = CommandResult;

Result run(const std::string& args, bool stderr_only = false) {
  return runCommand(std::string(DSR_BIN_DIR) + "/" + args + (stderr_only ? " 2>&1 >/dev/null" : " 2>/dev/null"));
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
  for (const std::string exe : {"door_scene_sim", "door_state_eval", "door_state_cli"}) {
    SCOPED_TRACE(exe);
    const Result help = run(exe + " --help");
    EXPECT_EQ(help.code, 0);
    EXPECT_NE(help.out.find("usage"), std::string::npos);
    EXPECT_EQ(run(exe + " --no-such-flag").code, 2);
  }
  // An option given twice, or an empty axis, is a usage error (the last
  // silently won, an empty axis was +z).
  EXPECT_EQ(run("door_state_cli --json a.json --json b.json x.pcd").code, 2);
  EXPECT_EQ(run("door_state_cli --up '' x.pcd").code, 2);
  EXPECT_EQ(run("door_scene_sim").code, 2);                                   // no --out
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --points many").code, 2);        // not a number
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --sensor sonar").code, 2);       // unknown sensor
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --scene atlantis").code, 2);     // unknown scene
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --angle 270").code, 2);          // out of range
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --sensor rgbd --depth-model sonar").code, 2);  // unknown family
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --depth-model tof").code, 2);    // a camera's option for the scanner
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --sensor rgbd --pitch 90").code, 2);  // out of range
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --sensor rgbd --resolution 1x1").code, 2);
  EXPECT_EQ(run("door_state_eval only_one.json").code, 2);
  EXPECT_EQ(run("door_state_eval --leaf-in-view-only 1.5 a.json b.json").code, 2);  // a share above 1
  EXPECT_EQ(run("door_state_cli").code, 2);                                   // no INPUT
  EXPECT_EQ(run("door_state_cli a.pcd b.pcd").code, 2);                       // two stations, neither there
  EXPECT_EQ(run("door_state_cli --up sideways x.pcd").code, 2);               // bad axis
  EXPECT_EQ(run("door_state_eval /nonexistent/a.json /nonexistent/b.json").code, 2);
}

// util::shortOmpSpin: the tools run (again) with GOMP_SPINCOUNT 10000 unless
// GOMP_SPINCOUNT or OMP_WAIT_POLICY is set, as the bench's header says.
TEST(Tools, ToolsRunWithAShortOpenMpSpinUnlessTheEnvironmentSaysOtherwise) {
  const fs::path dir = tempDir("spin");
  auto header = [&](const std::string& env) {
    const std::string cmd = "env -u GOMP_SPINCOUNT -u OMP_WAIT_POLICY " + env + " " + DSR_BIN_DIR +
                            "/door_state_bench --no-rgbd --no-robot --sizes '' --runs 1 --accuracy-scenes 0 --json " +
                            (dir / "b.json").string() + " 2>/dev/null";
    FILE* p = popen(cmd.c_str(), "r");
    std::string out;
    char buf[4096];
    while (p && fgets(buf, sizeof buf, p)) out += buf;
    if (p) pclose(p);
    const std::size_t at = out.find("OpenMP threads wait: ");
    return at == std::string::npos ? std::string("none") : out.substr(at, out.find('\n', at) - at);
  };
  EXPECT_NE(header("").find("GOMP_SPINCOUNT=10000"), std::string::npos) << header("");
  EXPECT_NE(header("GOMP_SPINCOUNT=77").find("GOMP_SPINCOUNT=77"), std::string::npos);
  const std::string passive = header("OMP_WAIT_POLICY=passive");
  EXPECT_NE(passive.find("GOMP_SPINCOUNT=unset, OMP_WAIT_POLICY=passive"), std::string::npos) << passive;
  fs::remove_all(dir);
}

// util::keepFreedMemory: a 40 MB block freed and asked for again is the same
// memory, still holding what was written (by default glibc mmaps a block that
// large and gives it back to the kernel when it is freed: the next one comes
// zeroed from the kernel, faulted in again), unless the environment sets
// malloc's thresholds itself. Each case in a child process of its own (the
// setting is the process's); its exit code is 0 when the second block still
// held the first one's bytes. (Page faults cannot tell: with transparent huge
// pages a fresh 40 MB block takes only some 20.)
TEST(Tools, FreedMemoryIsKeptForTheNextCloudUnlessTheEnvironmentSaysOtherwise) {
  auto secondBlockIsTheFirstKept = [](bool keep, const char* env) {
    const pid_t pid = fork();
    if (pid == 0) {
      for (const char* v : dsr::util::kMallocEnvironment) unsetenv(v);
      if (env) setenv(env, "1", 1);  // read by keepFreedMemory only: glibc read its environment at start-up
      if (keep) dsr::util::keepFreedMemory();
      const std::size_t n = 40u << 20;
      char* volatile a = static_cast<char*>(std::malloc(n));
      if (!a) _exit(3);
      for (std::size_t i = 4096; i < n; i += 4096) a[i] = 1;
      std::free(a);
      char* volatile b = static_cast<char*>(std::malloc(n));
      if (!b) _exit(3);
      std::size_t kept = 0;
      for (std::size_t i = 4096; i < n; i += 4096) kept += b[i] == 1;
      std::free(b);
      _exit(kept == n / 4096 - 1 ? 0 : 1);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  EXPECT_EQ(secondBlockIsTheFirstKept(false, nullptr), 1) << "glibc's default kept the block: the test tells nothing";
  EXPECT_EQ(secondBlockIsTheFirstKept(true, nullptr), 0) << "keepFreedMemory: the freed block was given back";
  EXPECT_EQ(secondBlockIsTheFirstKept(true, "MALLOC_TRIM_THRESHOLD_"), 1) << "keepFreedMemory overrode the environment";
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
  // The bag reads back: the cloud on /points in the truth's frame, three
  // copies a second apart, and the latched static tf to the fixed frame.
  {
    rosbag::Bag bag((dir / "a.bag").string(), rosbag::bagmode::Read);
    int clouds = 0, tfs = 0;
    for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
      if (auto pc = m.instantiate<sensor_msgs::PointCloud2>()) {
        ++clouds;
        EXPECT_EQ(pc->header.frame_id, "tls_scanner");
        EXPECT_EQ(m.getTopic(), "/points");
        EXPECT_GT(pc->width * pc->height, 15000u);
      } else if (auto tf = m.instantiate<tf2_msgs::TFMessage>()) {
        ++tfs;
        EXPECT_EQ(m.getTopic(), "/tf_static");
        ASSERT_EQ(tf->transforms.size(), 1u);
        EXPECT_EQ(tf->transforms[0].header.frame_id, "map");
        EXPECT_EQ(tf->transforms[0].child_frame_id, "tls_scanner");
        EXPECT_EQ(m.getConnectionHeader()->at("latching"), "1");
      }
    }
    EXPECT_EQ(clouds, 3);
    EXPECT_EQ(tfs, 1);
  }
  const nlohmann::json truth = nlohmann::json::parse(slurp(dir / "a.json"));
  EXPECT_EQ(truth["sensor"], "tls");
  EXPECT_GE(truth["doors"].size(), 1u);
  fs::remove_all(dir);
}

// door_state_eval TRUTH REPORT scores; the arguments swapped, or the same
// document given for both, are refused (exit 2, one line saying so), not
// scored (it gave precision 0.5, or a perfect score for a report against itself).
TEST(Tools, EvalRefusesSwappedOrWrongDocuments) {
  const fs::path dir = tempDir("eval_swap");
  const std::string truth = (dir / "s.json").string(), report = (dir / "r.json").string();
  ASSERT_EQ(run("door_scene_sim --quiet --seed 5 --points 100000 --out " + (dir / "s").string()).code, 0);
  ASSERT_EQ(run("door_state_cli --quiet --json " + report + " " + (dir / "s.pcd").string()).code, 0);
  const Result ok = run("door_state_eval " + truth + " " + report);
  ASSERT_EQ(ok.code, 0);
  EXPECT_TRUE(nlohmann::json::parse(ok.out).contains("precision"));
  for (const auto& [a, b, needle] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {report, truth, "swapped"}, {report, report, "not simulator ground truth"}, {truth, truth, "not a report"}}) {
    SCOPED_TRACE(a + " " + b);
    const Result r = run("door_state_eval " + a + " " + b, true);
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.out.find(needle), std::string::npos) << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  }
  fs::remove_all(dir);
}

TEST(Tools, CliRefusesMalformedFilesWithOneLineAndExitTwo) {
  const fs::path dir = tempDir("cli_bad");
  std::ofstream(dir / "text.pcd") << "this is not a point cloud\n";
  std::ofstream(dir / "empty.ply");
  std::ofstream(dir / "lying.pcd") << "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                                      "WIDTH 1000\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1000\nDATA binary\n"
                                   << std::string(100, '\0');
  std::ofstream(dir / "bad.yaml") << "voxel_size: -1\n";
  for (const std::string f : {"text.pcd", "empty.ply", "lying.pcd", "missing.pcd"}) {
    SCOPED_TRACE(f);
    const Result r = run("door_state_cli " + (dir / f).string(), true);
    EXPECT_EQ(r.code, 2);
    EXPECT_FALSE(r.out.empty());
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;  // one line on stderr
  }
  ASSERT_EQ(run("door_scene_sim --quiet --seed 3 --points 50000 --out " + (dir / "ok").string()).code, 0);
  const Result bad_config = run("door_state_cli --config " + (dir / "bad.yaml").string() + " " + (dir / "ok.pcd").string(), true);
  EXPECT_EQ(bad_config.code, 2);
  EXPECT_NE(bad_config.out.find("voxel_size"), std::string::npos) << bad_config.out;
  fs::remove_all(dir);
}

// An output naming an INPUT or another output, or a report or plan named
// as a cloud (--svg with its file name forgotten before a shell glob takes
// the first scan), is refused before anything is written: the scan is left
// as it was.
TEST(Tools, CliRefusesAnOutputThatIsAnInput) {
  const fs::path dir = tempDir("cli_overwrite");
  ASSERT_EQ(run("door_scene_sim --quiet --seed 3 --points 50000 --out " + (dir / "a").string()).code, 0);
  ASSERT_EQ(run("door_scene_sim --quiet --seed 4 --points 50000 --out " + (dir / "b").string()).code, 0);
  const std::string a = (dir / "a.pcd").string(), b = (dir / "b.pcd").string();
  const std::string before = slurp(a);
  for (const std::string& args : {"--svg " + a + " " + b, "--json " + a + " " + b, "--reconstruction " + b + " " + a + " " + b,
                                  "--json " + (dir / "o").string() + " --svg " + (dir / "o").string() + " " + a}) {
    SCOPED_TRACE(args);
    const Result r = run("door_state_cli " + args, true);
    EXPECT_EQ(r.code, 2);
    EXPECT_TRUE(r.out.find("is also an INPUT") != std::string::npos || r.out.find("name the same file") != std::string::npos ||
                r.out.find("names a point cloud") != std::string::npos)
        << r.out;
  }
  EXPECT_EQ(slurp(a), before);
  EXPECT_FALSE(fs::exists(dir / "o"));
  // One file twice is no survey; an unknown axis is a usage error (with the usage).
  const Result twice = run("door_state_cli " + a + " " + (dir / "." / "a.pcd").string(), true);
  EXPECT_EQ(twice.code, 2);
  EXPECT_NE(twice.out.find("is given twice"), std::string::npos) << twice.out;
  const Result axis = run("door_state_cli --up q " + a, true);
  EXPECT_EQ(axis.code, 2);
  EXPECT_NE(axis.out.find("--up needs an axis"), std::string::npos) << axis.out;
  EXPECT_NE(axis.out.find("usage:"), std::string::npos) << axis.out;
  fs::remove_all(dir);
}

// A georeferenced cloud (float64 eastings and northings of 5e5 and 5e6 m,
// where float32 keeps 6 cm) is read moved near its points and reported in
// its own frame: the same doors as the cloud at the origin, as near once
// moved back as the voxel grid's phase allows (a few cm), and a warning.
TEST(Tools, CliReadsAGeoreferencedCloudToTheMillimetre) {
  const fs::path dir = tempDir("cli_utm");
  ASSERT_EQ(run("door_scene_sim --quiet --seed 7 --points 150000 --out " + (dir / "s").string()).code, 0);
  pcl::PointCloud<pcl::PointXYZ> c;
  ASSERT_EQ(pcl::io::loadPCDFile((dir / "s.pcd").string(), c), 0);
  // Not round: a VIEWPOINT read in float32 lands up to 0.25 m off at 5e6 m.
  const double dx = 512345.67, dy = 5432109.87, dz = 120.0;
  {
    std::ofstream out(dir / "utm.pcd");
    out << "VERSION .7\nFIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " << c.size() << "\nHEIGHT 1\n";
    out << std::fixed << std::setprecision(4) << "VIEWPOINT " << c.sensor_origin_.x() + dx << " " << c.sensor_origin_.y() + dy
        << " " << c.sensor_origin_.z() + dz << " 1 0 0 0\nPOINTS " << c.size() << "\nDATA ascii\n";
    for (const auto& p : c.points) out << p.x + dx << " " << p.y + dy << " " << p.z + dz << "\n";
  }
  const Result a = run("door_state_cli --quiet " + (dir / "s.pcd").string());
  const Result b = run("door_state_cli --quiet " + (dir / "utm.pcd").string());
  ASSERT_EQ(a.code, 0);
  ASSERT_EQ(b.code, 0) << b.out;
  const nlohmann::json ja = nlohmann::json::parse(a.out), jb = nlohmann::json::parse(b.out);
  ASSERT_FALSE(ja["doors"].empty());
  ASSERT_EQ(ja["doors"].size(), jb["doors"].size());
  for (std::size_t i = 0; i < ja["doors"].size(); ++i) {
    const auto &x = ja["doors"][i], &y = jb["doors"][i];
    EXPECT_EQ(x["state"], y["state"]);
    EXPECT_NEAR(x["opening_angle_deg"].get<double>(), y["opening_angle_deg"].get<double>(), 2.0);
    EXPECT_NEAR(y["hinge"][0].get<double>() - dx, x["hinge"][0].get<double>(), 0.05);
    EXPECT_NEAR(y["hinge"][1].get<double>() - dy, x["hinge"][1].get<double>(), 0.05);
    EXPECT_NEAR(y["hinge"][2].get<double>() - dz, x["hinge"][2].get<double>(), 0.05);
  }
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(jb["viewpoint"][k].get<double>(), (k == 0 ? dx : k == 1 ? dy : dz) + c.sensor_origin_[k], 0.005) << k;
  EXPECT_NE(jb["warnings"].dump().find("far from their origin"), std::string::npos) << jb["warnings"];
  // The same points as text (no VIEWPOINT): --viewpoint header has none to
  // take, and says so (not "beyond max_abs_coordinate": the origin is).
  {
    std::ofstream out(dir / "utm.xyz");
    out << std::fixed << std::setprecision(4);
    for (const auto& p : c.points) out << p.x + dx << " " << p.y + dy << " " << p.z + dz << "\n";
  }
  const Result h = run("door_state_cli --quiet --viewpoint header " + (dir / "utm.xyz").string(), true);
  EXPECT_EQ(h.code, 2) << h.out;
  EXPECT_NE(h.out.find("has no VIEWPOINT"), std::string::npos) << h.out;
  fs::remove_all(dir);
}

// A registered room as S3DIS ships it (a text file of "x y z r g b" lines,
// no viewpoint), or as an OBJ's vertices, gives the doors the same points
// give as a PCD.
TEST(Tools, CliReadsARoomAsATextFileOrAnObjMesh) {
  const fs::path dir = tempDir("cli_text");
  ASSERT_EQ(run("door_scene_sim --quiet --seed 3001 --points 400000 --viewpoints 2 --merge --out " +
                (dir / "s").string()).code, 0);
  pcl::PointCloud<pcl::PointXYZ> c;
  ASSERT_EQ(pcl::io::loadPCDFile((dir / "s.pcd").string(), c), 0);
  {
    std::ofstream out(dir / "room.txt");
    out << std::setprecision(9);
    for (const auto& p : c.points) out << p.x << " " << p.y << " " << p.z << " 128 128 128\n";
    std::ofstream obj(dir / "room.obj");
    obj << std::setprecision(9) << "# exported\no room\n";
    for (const auto& p : c.points) obj << "v " << p.x << " " << p.y << " " << p.z << "\n";
    obj << "f 1 2 3\n";
  }
  const Result a = run("door_state_cli --quiet " + (dir / "s.pcd").string());
  ASSERT_EQ(a.code, 0);
  const nlohmann::json ja = nlohmann::json::parse(a.out);
  ASSERT_FALSE(ja["doors"].empty());
  for (const char* name : {"room.txt", "room.obj"}) {
    const Result b = run("door_state_cli --quiet " + (dir / name).string());
    ASSERT_EQ(b.code, 0) << name << ": " << b.out;
    const nlohmann::json jb = nlohmann::json::parse(b.out);
    EXPECT_EQ(ja["doors"], jb["doors"]) << name;
    EXPECT_EQ(ja["viewpoint"], jb["viewpoint"]) << name;
  }
  fs::remove_all(dir);
}

// A report that ends before levelling (nothing usable in the cloud) says the
// up axis it was given, not +z.
TEST(Tools, CliEmptyReportKeepsTheGivenUpAxis) {
  const fs::path dir = tempDir("cli_empty_up");
  std::ofstream(dir / "nan.pcd") << "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                                    "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\nnan nan nan\nnan nan nan\n";
  const Result r = run("door_state_cli --quiet --up -y " + (dir / "nan.pcd").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["doors"].empty());
  EXPECT_EQ(j["up"], nlohmann::json::array({0.0, -1.0, 0.0})) << j["up"];
  fs::remove_all(dir);
}

TEST(Tools, CliReportHasTheDocumentedShape) {
  const fs::path dir = tempDir("cli_ok");
  ASSERT_EQ(run("door_scene_sim --quiet --seed 8 --points 200000 --out " + (dir / "s").string()).code, 0);
  const Result r = run("door_state_cli --quiet --reconstruction " + (dir / "rec.ply").string() + " " + (dir / "s.pcd").string());
  ASSERT_EQ(r.code, 0);
  const nlohmann::json j = nlohmann::json::parse(r.out);
  for (const char* k : {"input", "points_in", "points_used", "up", "viewpoint", "stations", "floor", "ceiling", "walls",
                        "doors", "others", "timing_ms", "warnings"})
    EXPECT_TRUE(j.contains(k)) << k;
  EXPECT_EQ(j["points_in"].get<int>() > 0, true);
  ASSERT_FALSE(j["walls"].empty());
  EXPECT_EQ(j["walls"][0]["corners"].size(), 8u);
  for (const auto& d : j["doors"]) {
    EXPECT_EQ(d["leaf_corners"].size(), 4u);
    const std::string st = d["state"];
    EXPECT_TRUE(st == "closed" || st == "semi_open" || st == "open" || st == "not_closed");
    EXPECT_GE(d["clear_width"].get<double>(), 0.0);
    EXPECT_LE(d["clear_width"].get<double>(), d["width"].get<double>());
    if (st == "closed") EXPECT_EQ(d["clear_width"].get<double>(), 0.0);
    EXPECT_GE(d["confidence"].get<double>(), 0.0);
    EXPECT_LE(d["confidence"].get<double>(), 1.0);
  }
  EXPECT_TRUE(j["timing_ms"].contains("total"));
  EXPECT_GT(fs::file_size(dir / "rec.ply"), 1000u);
  fs::remove_all(dir);
}

TEST(Tools, CliTakesTheStationsOfASurveyEachFromItsViewpoint) {
  // door_scene_sim --viewpoints 2 writes each station's scan with its
  // VIEWPOINT; door_state_cli given both reports one survey. A station
  // missing, or a VIEWPOINT out of range, is exit 2 with one line.
  const fs::path dir = tempDir("stations");
  const std::string prefix = (dir / "s").string();
  ASSERT_EQ(run("door_scene_sim --quiet --seed 1016 --viewpoints 2 --points 400000 --out " + prefix).code, 0);
  const std::string s0 = prefix + ".station0.pcd", s1 = prefix + ".station1.pcd";
  ASSERT_TRUE(fs::exists(s0) && fs::exists(s1));
  EXPECT_EQ(slurp(s1).find("VIEWPOINT 0 0 0 1"), std::string::npos);  // station 1 stood elsewhere
  const Result r = run("door_state_cli --quiet " + s0 + " " + s1);
  ASSERT_EQ(r.code, 0);
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["input"].get<std::string>(), s0 + "," + s1);
  const Result a = run("door_state_cli --quiet " + s0), b = run("door_state_cli --quiet " + s1);
  ASSERT_EQ(a.code, 0);
  ASSERT_EQ(b.code, 0);
  EXPECT_EQ(j["points_in"].get<long>(), nlohmann::json::parse(a.out)["points_in"].get<long>() +
                                            nlohmann::json::parse(b.out)["points_in"].get<long>());
  EXPECT_FALSE(j["doors"].empty());
  const Result missing = run("door_state_cli " + s0 + " " + (dir / "nope.pcd").string(), true);
  EXPECT_EQ(missing.code, 2);
  EXPECT_EQ(std::count(missing.out.begin(), missing.out.end(), '\n'), 1) << missing.out;
  std::string far = slurp(s1);
  const std::size_t at = far.find("VIEWPOINT");
  ASSERT_NE(at, std::string::npos);
  far.replace(at, far.find('\n', at) - at, "VIEWPOINT 1e30 0 0 1 0 0 0");
  std::ofstream(dir / "far.pcd", std::ios::binary) << far;
  const Result bad = run("door_state_cli " + s0 + " " + (dir / "far.pcd").string(), true);
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.out.find("VIEWPOINT"), std::string::npos) << bad.out;
  fs::remove_all(dir);
}

// --viewpoint: auto takes a station's own VIEWPOINT and refuses the origin
// of three stations merged (room 1001: a tenth of its points lie behind
// other surfaces seen from the first station); header and X,Y,Z are taken
// as given, none infers the stations; malformed values are usage errors.
TEST(Tools, CliDecidesWhereItsRaysComeFrom) {
  const fs::path dir = tempDir("viewpoint");
  const std::string prefix = (dir / "s").string();
  ASSERT_EQ(run("door_scene_sim --quiet --seed 1001 --viewpoints 3 --points 600000 --out " + prefix).code, 0);
  const std::string merged = prefix + ".pcd", s1 = prefix + ".station1.pcd";
  auto report = [&](const std::string& args) {
    const Result r = run("door_state_cli --quiet " + args);
    EXPECT_EQ(r.code, 0) << args;
    return r.code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
  };
  auto hasWarning = [](const nlohmann::json& j, const std::string& text) {
    for (const auto& w : j["warnings"])
      if (w.get<std::string>().find(text) != std::string::npos) return true;
    return false;
  };
  const nlohmann::json a = report(merged);  // auto
  EXPECT_TRUE(a["viewpoint"].is_null());
  EXPECT_FALSE(a["stations"].empty());
  EXPECT_TRUE(hasWarning(a, "not credible")) << a["warnings"];
  EXPECT_FALSE(a["doors"].empty());
  const nlohmann::json h = report("--viewpoint header " + merged);
  ASSERT_TRUE(h["viewpoint"].is_array());
  EXPECT_EQ(h["viewpoint"][0].get<double>(), 0.0);
  const nlohmann::json one = report(s1);  // auto on one station's scan: its VIEWPOINT
  ASSERT_TRUE(one["viewpoint"].is_array());
  EXPECT_NE(one["viewpoint"][0].get<double>(), 0.0);
  EXPECT_FALSE(hasWarning(one, "not credible"));
  const nlohmann::json none = report("--viewpoint none " + s1);
  EXPECT_TRUE(none["viewpoint"].is_null());
  EXPECT_TRUE(hasWarning(none, "no viewpoint"));
  const nlohmann::json given = report("--viewpoint 0.5,-0.25,0.1 " + merged);
  ASSERT_TRUE(given["viewpoint"].is_array());
  EXPECT_DOUBLE_EQ(given["viewpoint"][1].get<double>(), -0.25);
  for (const std::string bad : {"1,2", "1,2,3,4", "abc", "nan,0,0", "1,,2", ""}) {
    SCOPED_TRACE(bad);
    EXPECT_EQ(run("door_state_cli --viewpoint '" + bad + "' " + merged).code, 2);
  }
  EXPECT_EQ(run("door_state_cli --viewpoint 1,2,3 " + s1 + " " + merged).code, 2);  // one position, two inputs
  const Result far = run("door_state_cli --viewpoint 1e30,0,0 " + merged, true);
  EXPECT_EQ(far.code, 2);
  EXPECT_NE(far.out.find("max_abs_coordinate"), std::string::npos) << far.out;
  fs::remove_all(dir);
}

// max_points from --config bounds what the reader accepts: a header asking
// more is refused unread, the message naming max_points (the reader kept its
// own 50M limit, and its message named no parameter). 5e8, the range's top
// as default.yaml writes it, is taken as an integer.
TEST(Tools, CliAppliesMaxPointsFromItsConfigToReading) {
  const fs::path dir = tempDir("cli_max_points");
  auto lying = [&](const std::string& name, long points) {
    std::ofstream(dir / name, std::ios::binary)
        << "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " << points
        << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << points << "\nDATA binary\n"
        << std::string(120, '\0');
  };
  lying("2000.pcd", 2000);
  lying("60M.pcd", 60000000);
  std::ofstream(dir / "small.yaml") << "max_points: 1000\n";
  std::ofstream(dir / "top.yaml") << "max_points: 5e8\n";
  const Result small = run("door_state_cli --config " + (dir / "small.yaml").string() + " " + (dir / "2000.pcd").string(), true);
  EXPECT_EQ(small.code, 2);
  EXPECT_NE(small.out.find("asks for 2000 points"), std::string::npos) << small.out;
  EXPECT_NE(small.out.find("1000 (parameter max_points)"), std::string::npos) << small.out;
  const Result dflt = run("door_state_cli " + (dir / "60M.pcd").string(), true);
  EXPECT_EQ(dflt.code, 2);
  EXPECT_NE(dflt.out.find("50000000 (parameter max_points)"), std::string::npos) << dflt.out;
  // Raised to 5e8 the header's 60M is not refused for its count: the file is
  // refused for holding less than it promises.
  const Result top = run("door_state_cli --config " + (dir / "top.yaml").string() + " " + (dir / "60M.pcd").string(), true);
  EXPECT_EQ(top.code, 2);
  EXPECT_EQ(top.out.find("(parameter max_points)"), std::string::npos) << top.out;
  EXPECT_NE(top.out.find("header promises 60000000 points"), std::string::npos) << top.out;
  EXPECT_EQ(std::count(top.out.begin(), top.out.end(), '\n'), 1) << top.out;
  fs::remove_all(dir);
}

// Outputs are checked before any input is read: an unwritable --json or
// --reconstruction is exit 2 naming the flag and the system's reason, with no
// report (it was exit 1 after the pipeline, with the report already on
// stdout for --reconstruction); an output file created for a run that fails
// is removed again; '-' as INPUT is refused as a bad argument.
TEST(Tools, CliOpensItsOutputsBeforeReadingAndRefusesStdin) {
  const fs::path dir = tempDir("cli_out");
  ASSERT_EQ(run("door_scene_sim --quiet --seed 3 --points 50000 --out " + (dir / "ok").string()).code, 0);
  const std::string ok = (dir / "ok.pcd").string();
  std::ofstream(dir / "text.pcd") << "this is not a point cloud\n";
  for (const std::string flag : {"--json", "--reconstruction"}) {
    SCOPED_TRACE(flag);
    const std::string cmd = "door_state_cli --quiet " + flag + " /nonexistent/dir/out ";
    const Result err = run(cmd + ok, true), out = run(cmd + ok);
    EXPECT_EQ(err.code, 2);
    EXPECT_NE(err.out.find(flag + " /nonexistent/dir/out: cannot write: No such file or directory"), std::string::npos)
        << err.out;
    EXPECT_EQ(std::count(err.out.begin(), err.out.end(), '\n'), 1) << err.out;
    EXPECT_TRUE(out.out.empty()) << "a report was written";
    // Before the input is read: a bad input is not what is reported.
    const Result first = run(cmd + (dir / "text.pcd").string(), true);
    EXPECT_EQ(first.code, 2);
    EXPECT_NE(first.out.find(flag), std::string::npos) << first.out;
  }
  const Result failed = run("door_state_cli --json " + (dir / "new.json").string() + " --reconstruction " +
                            (dir / "new.ply").string() + " " + (dir / "text.pcd").string());
  EXPECT_EQ(failed.code, 2);
  EXPECT_FALSE(fs::exists(dir / "new.json"));
  EXPECT_FALSE(fs::exists(dir / "new.ply"));
  const Result dash = run("door_state_cli -", true);
  EXPECT_EQ(dash.code, 2);
  EXPECT_NE(dash.out.find("stdin"), std::string::npos) << dash.out;
  fs::remove_all(dir);
}

// A cloud without walls still gets a report (exit 0) and --reconstruction a
// valid PLY of 0 points in place of whatever the path held before (the old
// file was left there).
TEST(Tools, CliWritesAnEmptyReconstructionWhenNoWallIsFound) {
  const fs::path dir = tempDir("cli_no_wall");
  {
    std::ofstream f(dir / "floor.pcd");
    f << "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2500\nHEIGHT 1\n"
         "VIEWPOINT 0 0 1.5 1 0 0 0\nPOINTS 2500\nDATA ascii\n";
    for (int i = 0; i < 50; ++i)
      for (int j = 0; j < 50; ++j) f << 0.04 * i - 1 << " " << 0.04 * j - 1 << " 0\n";
  }
  std::ofstream(dir / "rec.ply") << "an old reconstruction\n";
  const Result r = run("door_state_cli --quiet --json " + (dir / "r.json").string() + " --reconstruction " +
                       (dir / "rec.ply").string() + " " + (dir / "floor.pcd").string());
  ASSERT_EQ(r.code, 0);
  EXPECT_TRUE(nlohmann::json::parse(slurp(dir / "r.json"))["walls"].empty());
  const std::string ply = slurp(dir / "rec.ply");
  EXPECT_EQ(ply.rfind("ply\n", 0), 0u) << ply;
  EXPECT_NE(ply.find("element vertex 0\n"), std::string::npos) << ply;
  EXPECT_EQ(ply.find("old"), std::string::npos) << ply;
  pcl::PointCloud<pcl::PointXYZL> back;
  EXPECT_EQ(pcl::io::loadPLYFile((dir / "rec.ply").string(), back), 0);
  EXPECT_TRUE(back.empty());
  fs::remove_all(dir);
}

// door_scene_sim --drive: a bag rosbag reads back with the promised topics,
// frames and rates, and the truth of the same drive beside it.
TEST(Tools, SimulatorDriveWritesABagOfCloudsTfAndClock) {
  const fs::path dir = tempDir("drive");
  const std::string prefix = (dir / "d").string();
  const Result r = run("door_scene_sim --drive --sensor lidar16 --seed 1004 --drive-seconds 8 --rate 2 "
                       "--toggle-door 0:90@1.5 --mount-height 0.7 --quiet --out " + prefix);
  ASSERT_EQ(r.code, 0);
  ASSERT_TRUE(fs::exists(prefix + ".bag"));
  ASSERT_TRUE(fs::exists(prefix + ".json"));
  EXPECT_FALSE(fs::exists(prefix + ".pcd"));
  int clouds = 0, tfs = 0, statics = 0, clocks = 0;
  double last_cloud = 0, last_clock = 0;
  {
    rosbag::Bag bag(prefix + ".bag", rosbag::bagmode::Read);
    for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
      if (m.getTopic() == "/points") {
        auto pc = m.instantiate<sensor_msgs::PointCloud2>();
        ASSERT_TRUE(pc);
        EXPECT_EQ(pc->header.frame_id, "lidar");
        EXPECT_EQ(pc->height, 16u);
        EXPECT_EQ(pc->width, 1800u);
        EXPECT_NEAR(pc->header.stamp.toSec(), 1000.0 + clouds * 0.5, 1e-6);
        last_cloud = pc->header.stamp.toSec();
        ++clouds;
      } else if (m.getTopic() == "/tf") {
        auto tf = m.instantiate<tf2_msgs::TFMessage>();
        ASSERT_TRUE(tf);
        ASSERT_EQ(tf->transforms.size(), 1u);
        EXPECT_EQ(tf->transforms[0].header.frame_id, "map");
        EXPECT_EQ(tf->transforms[0].child_frame_id, "base_link");
        EXPECT_NEAR(tf->transforms[0].transform.translation.z, 0.0, 1e-9);
        ++tfs;
      } else if (m.getTopic() == "/tf_static") {
        auto tf = m.instantiate<tf2_msgs::TFMessage>();
        ASSERT_TRUE(tf);
        EXPECT_EQ(tf->transforms[0].header.frame_id, "base_link");
        EXPECT_EQ(tf->transforms[0].child_frame_id, "lidar");
        EXPECT_NEAR(tf->transforms[0].transform.translation.z, 0.7, 1e-9);
        EXPECT_EQ(m.getConnectionHeader()->at("latching"), "1");
        ++statics;
      } else if (m.getTopic() == "/clock") {
        auto c = m.instantiate<rosgraph_msgs::Clock>();
        ASSERT_TRUE(c);
        EXPECT_GE(c->clock.toSec(), last_clock);  // never backwards
        last_clock = c->clock.toSec();
        ++clocks;
      } else {
        ADD_FAILURE() << "unexpected topic " << m.getTopic();
      }
    }
  }
  EXPECT_EQ(clouds, 16);  // 8 s x 2 Hz
  EXPECT_EQ(tfs, 16);
  EXPECT_EQ(statics, 1);
  EXPECT_GE(clocks, 800);  // every 10 ms
  EXPECT_GE(last_clock, last_cloud);
  const nlohmann::json truth = nlohmann::json::parse(slurp(prefix + ".json"));
  EXPECT_EQ(truth["frame_id"], "map");
  EXPECT_EQ(truth["drive"]["frames"], 16);
  EXPECT_EQ(truth["drive"]["sensor_frame"], "lidar");
  ASSERT_EQ(truth["drive"]["changes"].size(), 1u);
  EXPECT_EQ(truth["drive"]["changes"][0]["first_frame_after"], 3);
  EXPECT_EQ(truth["doors"][0]["state"], "open");
  EXPECT_EQ(truth["drive"]["path"].size(), 16u);
  EXPECT_EQ(run("door_scene_sim --drive --sensor lidar16 --seed 1004 --drive-seconds 3 --out " + prefix).code, 2);  // too short for its turns
  // Deterministic for a seed: the same drive again, truth alone.
  ASSERT_EQ(run("door_scene_sim --drive --sensor lidar16 --seed 1004 --drive-seconds 8 --rate 2 "
                "--toggle-door 0:90@1.5 --mount-height 0.7 --quiet --formats json --out " + prefix + "2").code, 0);
  EXPECT_EQ(slurp(prefix + ".json"), slurp(prefix + "2.json"));
  // Bad drive arguments: exit 2.
  EXPECT_EQ(run("door_scene_sim --drive --sensor tls --out " + prefix).code, 2);
  EXPECT_EQ(run("door_scene_sim --drive --formats ply --out " + prefix).code, 2);
  EXPECT_EQ(run("door_scene_sim --drive --toggle-door 0:90 --out " + prefix).code, 2);
  EXPECT_EQ(run("door_scene_sim --drive --toggle-door 9:90@1 --seed 1004 --out " + prefix).code, 2);
  EXPECT_EQ(run("door_scene_sim --drive --rate 0 --out " + prefix).code, 2);
  EXPECT_EQ(run("door_scene_sim --sensor lidar24 --out " + prefix).code, 2);
  EXPECT_EQ(run("door_scene_sim --sensor lidar16 --toggle-door 0:90@1 --out " + prefix).code, 2);  // not a drive
  EXPECT_EQ(run("door_scene_sim --sensor tls --mount-height 0.8 --out " + prefix).code, 2);
  fs::remove_all(dir);
}

// door_scene_sim --sensor lidarN: one organized sweep, rows = beams, NaN where no return.
TEST(Tools, SimulatorWritesAnOrganizedLidarSweep) {
  const fs::path dir = tempDir("lidar");
  const std::string prefix = (dir / "l").string();
  ASSERT_EQ(run("door_scene_sim --sensor lidar64 --seed 3 --quiet --formats pcd,json,bag --out " + prefix).code, 0);
  const std::string pcd = slurp(prefix + ".pcd");
  EXPECT_NE(pcd.find("WIDTH 1024\nHEIGHT 64\n"), std::string::npos);
  const nlohmann::json truth = nlohmann::json::parse(slurp(prefix + ".json"));
  EXPECT_EQ(truth["sensor"], "lidar64");
  EXPECT_EQ(truth["frame_id"], "lidar");
  rosbag::Bag bag(prefix + ".bag", rosbag::bagmode::Read);
  int clouds = 0;
  for (const rosbag::MessageInstance& m : rosbag::View(bag))
    if (auto pc = m.instantiate<sensor_msgs::PointCloud2>()) {
      EXPECT_EQ(pc->height, 64u);
      EXPECT_EQ(pc->width, 1024u);
      EXPECT_FALSE(pc->is_dense);
      ++clouds;
    }
  EXPECT_EQ(clouds, 3);
  fs::remove_all(dir);
}

TEST(Tools, SimulatorMovesTheSameScanByAFrameOffset) {
  // --frame-offset: the same frame, every point, the VIEWPOINT and the
  // truth moved by the offset (NaN pixels stay NaN); malformed offsets and
  // a bag (whose tf puts the sensor at the frame's origin) refused.
  const fs::path dir = tempDir("offset");
  const std::string a = (dir / "a").string(), b = (dir / "b").string();
  ASSERT_EQ(run("door_scene_sim --sensor rgbd --seed 4 --quiet --out " + a).code, 0);
  ASSERT_EQ(run("door_scene_sim --sensor rgbd --seed 4 --quiet --frame-offset 1.5,-2,0.25 --out " + b).code, 0);
  pcl::PointCloud<pcl::PointXYZ> ca, cb;
  ASSERT_EQ(pcl::io::loadPCDFile(a + ".pcd", ca), 0);
  ASSERT_EQ(pcl::io::loadPCDFile(b + ".pcd", cb), 0);
  ASSERT_EQ(ca.size(), cb.size());
  EXPECT_EQ(cb.height, ca.height);
  const Eigen::Vector3f o(1.5f, -2.0f, 0.25f);
  std::size_t finite = 0;
  for (std::size_t i = 0; i < ca.size(); ++i) {
    EXPECT_EQ(std::isfinite(ca[i].x), std::isfinite(cb[i].x)) << i;
    if (!std::isfinite(ca[i].x)) continue;
    ++finite;
    EXPECT_LT((cb[i].getVector3fMap() - ca[i].getVector3fMap() - o).norm(), 1e-5f) << i;
  }
  EXPECT_GT(finite, ca.size() / 2);
  EXPECT_LT((cb.sensor_origin_.head<3>() - o).norm(), 1e-6f);
  const nlohmann::json ta = nlohmann::json::parse(slurp(a + ".json")), tb = nlohmann::json::parse(slurp(b + ".json"));
  ASSERT_EQ(ta["doors"].size(), tb["doors"].size());
  for (std::size_t k = 0; k < ta["doors"].size(); ++k)
    for (int j = 0; j < 3; ++j)
      EXPECT_NEAR(tb["doors"][k]["hinge"][j].get<double>() - ta["doors"][k]["hinge"][j].get<double>(), o[j], 1e-6);
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --frame-offset 1,2").code, 2);
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --frame-offset 1,2,nan").code, 2);
  EXPECT_EQ(run("door_scene_sim --out /tmp/x --frame-offset 1,2,3 --formats bag").code, 2);
  fs::remove_all(dir);
}
