// door_state_bench: our pipeline against the stock-PCL baseline on the same
// simulated points, per stage, with peak memory and accuracy. Every scene is
// generated here with a fixed seed. Each measured case runs in a child
// process of its own (fork), so its peak RSS is its own.
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <pcl/console/print.h>

#include "door_state_recognition/baseline/stock_pcl.hpp"
#include "door_state_recognition/eval/evaluation.hpp"
#include "door_state_recognition/io/report.hpp"
#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/sim/ground_truth.hpp"
#include "door_state_recognition/sim/lidar.hpp"
#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/sim/sensors.hpp"
#include "door_state_recognition/util/keep_freed_memory.hpp"
#include "door_state_recognition/util/omp_spin.hpp"

using json = nlohmann::json;
using namespace dsr;

namespace {

const char* kUsage = R"(usage: door_state_bench [options]

Times our pipeline and the stock-PCL baseline (pcl::VoxelGrid,
NormalEstimationOMP, iterative SACSegmentation, RegionGrowing,
MomentOfInertiaEstimation, BoundaryEstimation) on the same simulated points:
laser-scanner rooms of each --sizes (and the 400k room as two stations merged
into one cloud), one 64-beam LiDAR sweep and one 640x480 RGB-D frame, seed
--seed, and the first --rgbd-door-frames RGB-D frames from seed 1000 on with a
door in view (where the leaf search works), at 640x480 and again at 320x240.
Per stage: median of --runs runs (over
every run of every frame for the frames with a door); peak RSS of each implementation in a child
process of its own; door accuracy of both against the simulator's truth, on
the timed scenes and on --accuracy-scenes more rooms of --accuracy-points,
with a line for every one of those scenes where the two score differently.

options:
  --runs R                  repetitions per case (default 5; env BENCH_RUNS is read by make bench)
  --sizes LIST              laser rays per room, comma list (default 100000,400000,1000000,4000000)
  --seed N                  seed of every timed scene (default 7)
  --no-rgbd                 leave out the RGB-D frames
  --no-robot                leave out a robot's clouds: one 64-beam LiDAR sweep (seed --seed) and the
                            RGB-D frames with a door at 320x240 (issue 20's targets)
  --rgbd-door-frames K      RGB-D frames with a door in view timed together (default 5; 0: none)
  --skip-baseline-above N   no baseline on clouds of more than N points (default 4000000: none skipped)
  --baseline-runs R         repetitions of the baseline (default: --runs)
  --accuracy-scenes K       extra laser rooms (seeds 1000..) and RGB-D frames scored once each (default 30; 0: none)
  --accuracy-points N       rays of those rooms (default 400000)
  --only TEXT               time only the cases whose name contains TEXT (e.g. "320x240"; for profiling)
  --json PATH               where to write the results (default bench.json)
  --note TEXT               printed in the header and kept in the JSON (make bench: the git commit)
  -h, --help                this text
)";

struct Options {
  int runs = 5, baseline_runs = -1;
  std::vector<std::size_t> sizes = {100000, 400000, 1000000, 4000000};
  std::uint64_t seed = 7;
  bool rgbd = true;
  bool robot = true;  // a 64-beam sweep and the door frames at 320x240
  int rgbd_door_frames = 5;
  std::size_t skip_baseline_above = 4000000;
  int accuracy_scenes = 30;
  std::size_t accuracy_points = 400000;
  std::string json_path = "bench.json";
  std::string note;
  std::string only;  // keep the cases whose name contains this
};

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

long long toInt(const std::string& flag, const std::string& v) {
  try {
    std::size_t pos = 0;
    const long long x = std::stoll(v, &pos);
    if (pos != v.size()) throw std::invalid_argument(v);
    return x;
  } catch (const std::exception&) {
    throw UsageError(flag + " needs an integer, got '" + v + "'");
  }
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(a + " needs a value");
      return argv[++i];
    };
    if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      std::exit(0);
    } else if (a == "--runs") o.runs = static_cast<int>(toInt(a, value()));
    else if (a == "--baseline-runs") o.baseline_runs = static_cast<int>(toInt(a, value()));
    else if (a == "--seed") o.seed = static_cast<std::uint64_t>(toInt(a, value()));
    else if (a == "--no-rgbd") o.rgbd = false;
    else if (a == "--no-robot") o.robot = false;
    else if (a == "--rgbd-door-frames") o.rgbd_door_frames = static_cast<int>(toInt(a, value()));
    else if (a == "--skip-baseline-above") o.skip_baseline_above = static_cast<std::size_t>(toInt(a, value()));
    else if (a == "--accuracy-scenes") o.accuracy_scenes = static_cast<int>(toInt(a, value()));
    else if (a == "--accuracy-points") o.accuracy_points = static_cast<std::size_t>(toInt(a, value()));
    else if (a == "--json") o.json_path = value();
    else if (a == "--note") o.note = value();
    else if (a == "--only") o.only = value();
    else if (a == "--sizes") {
      o.sizes.clear();
      std::stringstream ss(value());
      std::string s;
      while (std::getline(ss, s, ',')) {
        const long long n = toInt(a, s);
        if (n < 1000 || n > 100000000) throw UsageError("--sizes: every size must lie in [1000, 1e8]");
        o.sizes.push_back(static_cast<std::size_t>(n));
      }
    } else throw UsageError("unknown argument '" + a + "'");
  }
  if (o.runs < 1 || o.runs > 1000) throw UsageError("--runs must lie in [1, 1000]");
  if (o.baseline_runs < 0) o.baseline_runs = o.runs;
  if (o.baseline_runs < 1 || o.baseline_runs > 1000) throw UsageError("--baseline-runs must lie in [1, 1000]");
  if (o.accuracy_scenes < 0 || o.accuracy_scenes > 1000) throw UsageError("--accuracy-scenes must lie in [0, 1000]");
  if (o.rgbd_door_frames < 0 || o.rgbd_door_frames > 100) throw UsageError("--rgbd-door-frames must lie in [0, 100]");
  return o;
}

// ------------------------------------------------------------------ scenes

struct Case {
  // tls | rgbd | merged (two laser stations in one cloud, run without a
  // viewpoint) | lidar64 (one sweep of a 64-beam LiDAR, 64 x 1024)
  std::string sensor;
  std::size_t points;  // rays (tls) or pixels (rgbd, lidar64)
  std::uint64_t seed;
  std::vector<std::uint64_t> more_seeds;  // further frames timed with it (the frames with a door)
  bool door_frames = false;               // the RGB-D frames with a door in view
  int width = 640, height = 480;          // rgbd: the image (intrinsics scaled with it)
  std::string name() const {
    if (sensor == "tls") return "laser " + std::to_string(points / 1000) + "k";
    if (sensor == "merged") return "merged " + std::to_string(points / 1000) + "k";
    if (sensor == "lidar64") return "LiDAR 64-beam";
    const std::string size = std::to_string(width) + "x" + std::to_string(height);
    if (!door_frames) return "RGB-D " + size;
    return "RGB-D door x" + std::to_string(more_seeds.size() + 1) + (width == 640 && height == 480 ? "" : " " + size);
  }
  std::vector<std::uint64_t> seeds() const {
    std::vector<std::uint64_t> all{seed};
    all.insert(all.end(), more_seeds.begin(), more_seeds.end());
    return all;
  }
};

struct Scene {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  json truth;
  double sim_ms = 0;
};

Scene simulate(const Case& c) {
  const auto t0 = std::chrono::steady_clock::now();
  Scene s;
  const sim::Scene scene = sim::buildScene(sim::randomRoom(c.seed));
  sim::SimulatedCloud sc;
  if (c.sensor == "tls" || c.sensor == "merged") {
    sim::TlsOptions o;
    o.points = c.points;
    o.seed = c.seed;
    o.viewpoints = c.sensor == "merged" ? 2 : 1;
    sc = sim::scanTls(scene, o);
  } else if (c.sensor == "lidar64") {
    sim::LidarOptions o = sim::LidarOptions::preset(64);
    o.seed = c.seed;
    sc = sim::scanLidar(scene, o);
  } else {
    sim::RgbdOptions o;
    o.seed = c.seed;
    if (c.width != o.width || c.height != o.height) o.resize(c.width, c.height);
    sc = sim::captureRgbd(scene, o);
  }
  s.sim_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  s.truth = sim::groundTruthJson(scene, sc);
  s.cloud.width = sc.cloud.width;
  s.cloud.height = sc.cloud.height;
  s.cloud.is_dense = sc.cloud.is_dense;
  s.cloud.points.resize(sc.cloud.size());
  for (std::size_t i = 0; i < sc.cloud.size(); ++i) s.cloud.points[i] = pcl::PointXYZ(sc.cloud[i].x, sc.cloud[i].y, sc.cloud[i].z);
  return s;
}

Parameters paramsFor(const std::string& sensor) {
  Parameters p;
  p.up_axis = sensor == "rgbd" ? "-y" : "+z";
  return p;
}

// A merged cloud has no viewpoint: ours infers its stations (stock has no
// such path and casts its rays from the origin, the first station).
PipelineResult runImpl(const std::string& impl, const Case& c, const pcl::PointCloud<pcl::PointXYZ>& cloud,
                       const Parameters& p) {
  if (impl == "ours") return c.sensor == "merged" ? Pipeline(p).runWithoutViewpoint(cloud, false) : Pipeline(p).run(cloud, false);
  return baseline::runStockPcl(cloud, p);
}

// ------------------------------------------------------------ measurement

long statusKb(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const std::size_t len = std::strlen(key);
  while (std::getline(f, line))
    if (line.compare(0, len, key) == 0) return std::atol(line.c_str() + len + 1);
  return -1;
}

// Runs fn in a child process and returns the JSON it produced (the child
// writes it to a pipe). A child that fails gives {"error": ...}.
json inChild(const std::function<json()>& fn) {
  std::fflush(stdout);
  std::fflush(stderr);
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("pipe failed");
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    close(fds[0]);
    std::string out;
    int code = 0;
    try {
      out = fn().dump();
    } catch (const std::exception& e) {
      out = json{{"error", e.what()}}.dump();
      code = 1;
    }
    std::size_t off = 0;
    while (off < out.size()) {
      const ssize_t w = write(fds[1], out.data() + off, out.size() - off);
      if (w <= 0) break;
      off += static_cast<std::size_t>(w);
    }
    close(fds[1]);
    _exit(code);
  }
  close(fds[1]);
  std::string buf;
  char chunk[65536];
  ssize_t r;
  while ((r = read(fds[0], chunk, sizeof chunk)) > 0) buf.append(chunk, static_cast<std::size_t>(r));
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (buf.empty()) return json{{"error", "child died (status " + std::to_string(status) + ")"}};
  return json::parse(buf);
}

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

json scoreJson(const eval::EvalResult& e) {
  auto num = [](double x) { return std::isfinite(x) ? json(x) : json(nullptr); };
  return {{"true_doors", e.true_doors},     {"reported", e.reported_doors},       {"matched", e.matched},
          {"state_correct", e.state_correct}, {"precision", num(e.precision())}, {"recall", num(e.recall())},
          {"state_accuracy", num(e.stateAccuracy())}, {"angle_mae_deg", num(e.angleMaeDeg())},
          {"hinge_error_median_m", num(e.hingeErrorMedianM())}};
}

// One implementation on one case, R runs (of each of its frames), in the calling (child) process.
json measure(const Case& c, const std::string& impl, int runs) {
  std::vector<Scene> scenes;
  for (std::uint64_t seed : c.seeds()) {
    Case one = c;
    one.seed = seed;
    one.more_seeds.clear();
    scenes.push_back(simulate(one));
  }
  const Parameters p = paramsFor(c.sensor);
  malloc_trim(0);
  { std::ofstream("/proc/self/clear_refs") << "5"; }  // VmHWM := VmRSS
  const long rss_before = statusKb("VmRSS:");
  std::map<std::string, std::vector<double>> stages;
  std::vector<std::string> order;
  std::vector<eval::EvalResult> scores;
  json doors = json::array(), truth_doors = json::array(), walls = json::array();
  double sim_ms = 0;
  std::size_t points_in = 0, points_used = 0;
  for (const Scene& s : scenes) {
    PipelineResult last;
    for (int r = 0; r < runs; ++r) {
      last = runImpl(impl, c, s.cloud, p);
      for (const auto& kv : last.timing_ms) {
        if (!stages.count(kv.first)) order.push_back(kv.first);
        stages[kv.first].push_back(kv.second);
      }
    }
    scores.push_back(eval::evaluate(s.truth, io::reportJson(last, c.name()), 0.5, true));
    for (const auto& d : last.doors) doors.push_back({{"state", toString(d.state)}, {"angle_deg", d.opening_angle_deg}});
    for (const auto& d : s.truth["doors"])
      if (d.value("in_view", true)) truth_doors.push_back({{"state", d["state"]}, {"angle_deg", d["opening_angle_deg"]}});
    walls.push_back(last.walls.size());
    sim_ms += s.sim_ms;
    points_in = std::max(points_in, last.points_in);
    points_used = std::max(points_used, last.points_used);
  }
  const long hwm = statusKb("VmHWM:");
  json st = json::object(), all = json::object();
  for (const auto& k : order) {
    st[k] = median(stages[k]);
    all[k] = stages[k];
  }
  return {{"impl", impl},
          {"runs", runs},
          {"seeds", c.seeds()},
          {"points_in", points_in},
          {"points_used", points_used},
          {"sim_ms", sim_ms},
          {"stage_median_ms", st},
          {"stage_runs_ms", all},
          {"rss_before_kb", rss_before},
          {"peak_rss_kb", hwm},
          {"peak_extra_kb", hwm - rss_before},
          {"accuracy", scoreJson(eval::merge(scores))},
          {"doors", doors},
          {"truth_doors", truth_doors},
          {"walls", scenes.size() == 1 ? walls[0] : walls}};
}

// Accuracy only: both implementations on K extra scenes, one run each.
json accuracySweep(const std::string& sensor, int scenes, std::size_t points) {
  std::vector<eval::EvalResult> ours, stock;
  json differ = json::array();  // the scenes where the two score differently
  double ours_ms = 0, stock_ms = 0;
  for (int k = 0; k < scenes; ++k) {
    const Case c{sensor, points, static_cast<std::uint64_t>(1000 + k), {}, false};
    const Scene s = simulate(c);
    const Parameters p = paramsFor(sensor);
    const PipelineResult a = runImpl("ours", c, s.cloud, p);
    const PipelineResult b = runImpl("stock", c, s.cloud, p);
    ours_ms += a.timing_ms.back().second;
    stock_ms += b.timing_ms.back().second;
    ours.push_back(eval::evaluate(s.truth, io::reportJson(a, "sweep"), 0.5, true));
    stock.push_back(eval::evaluate(s.truth, io::reportJson(b, "sweep"), 0.5, true));
    const eval::EvalResult &o = ours.back(), &t = stock.back();
    if (o.matched != t.matched || o.reported_doors != t.reported_doors || o.state_correct != t.state_correct)
      differ.push_back({{"seed", c.seed},
                        {"true_doors", o.true_doors},
                        {"ours", {{"matched", o.matched}, {"reported", o.reported_doors}, {"state_correct", o.state_correct},
                                  {"missed_truth", o.missed_truth}}},
                        {"stock", {{"matched", t.matched}, {"reported", t.reported_doors}, {"state_correct", t.state_correct},
                                   {"missed_truth", t.missed_truth}}}});
  }
  return {{"sensor", sensor},
          {"scenes", scenes},
          {"seeds", std::to_string(1000) + "-" + std::to_string(1000 + scenes - 1)},
          {"points", sensor == "tls" ? json(points) : json(640 * 480)},
          {"ours", scoreJson(eval::merge(ours))},
          {"stock", scoreJson(eval::merge(stock))},
          {"differ", differ},
          {"ours_mean_total_ms", ours_ms / std::max(1, scenes)},
          {"stock_mean_total_ms", stock_ms / std::max(1, scenes)}};
}

// ----------------------------------------------------------------- output

std::string fmt(const char* f, double x) {
  if (!std::isfinite(x)) return "-";
  char b[64];
  std::snprintf(b, sizeof b, f, x);
  return b;
}

std::string fmtAcc(const json& a) {
  auto g = [&](const char* k, const char* f, double scale = 1) {
    return a[k].is_null() ? std::string("-") : fmt(f, a[k].get<double>() * scale);
  };
  std::ostringstream os;
  os << "P " << g("precision", "%.2f") << "  R " << g("recall", "%.2f") << "  state " << g("state_accuracy", "%.2f")
     << "  angle MAE " << g("angle_mae_deg", "%.1f") << " deg  hinge " << g("hinge_error_median_m", "%.1f", 100) << " cm  ("
     << a["matched"].get<int>() << "/" << a["true_doors"].get<int>() << " found, " << a["reported"].get<int>() << " reported)";
  return os.str();
}

std::string shell(const char* cmd) {
  std::string out;
  if (FILE* f = popen(cmd, "r")) {
    char b[512];
    while (std::fgets(b, sizeof b, f)) out += b;
    pclose(f);
  }
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  return out;
}

// How the OpenMP threads wait, as the environment (libgomp reads it at
// start, after util/omp_spin.hpp's default) says.
std::string ompWait() {
  const char* spin = std::getenv("GOMP_SPINCOUNT");
  const char* policy = std::getenv("OMP_WAIT_POLICY");
  std::string s = std::string("GOMP_SPINCOUNT=") + (spin ? spin : policy ? "unset" : "unset (libgomp default 300000)");
  if (policy) s += std::string(", OMP_WAIT_POLICY=") + policy;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  dsr::util::shortOmpSpin(argv);  // before anything else: the program may be run again
  const std::string freed_memory = dsr::util::keepFreedMemory();
  Options opt;
  try {
    opt = parse(argc, argv);
  } catch (const UsageError& e) {
    std::cerr << "door_state_bench: " << e.what() << "\n\n" << kUsage;
    return 2;
  }
  const auto t_start = std::chrono::steady_clock::now();
  // SACSegmentation prints an error whenever a frame holds no more plane; the
  // baseline treats that as "no more walls".
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  std::vector<Case> cases;
  for (std::size_t n : opt.sizes) cases.push_back({"tls", n, opt.seed, {}, false});
  // The 400k room again as two stations merged into one cloud (issue 19: within 1.5x of the single scan).
  if (std::find(opt.sizes.begin(), opt.sizes.end(), 400000u) != opt.sizes.end())
    cases.push_back({"merged", 400000, opt.seed, {}, false});
  // A robot's LiDAR: one 64-beam sweep of the same room (issue 20: <= 30 ms).
  if (opt.robot) cases.push_back({"lidar64", 64 * 1024, opt.seed, {}, false});
  if (opt.rgbd) cases.push_back({"rgbd", 640 * 480, opt.seed, {}, false});
  if (opt.rgbd && opt.rgbd_door_frames > 0) {
    // The first frames from seed 1000 on (the accuracy sweep's) with a door
    // in view, found in a child (the simulator runs OpenMP, which a process
    // must not have started before it forks the children that measure).
    const json found = inChild([&] {
      json seeds = json::array();
      for (std::uint64_t seed = 1000; seed < 1200 && static_cast<int>(seeds.size()) < opt.rgbd_door_frames; ++seed) {
        const Scene s = simulate({"rgbd", 640 * 480, seed, {}, false});
        for (const auto& d : s.truth["doors"])
          if (d.value("in_view", true)) {
            seeds.push_back(seed);
            break;
          }
      }
      return json{{"seeds", seeds}};
    });
    std::vector<std::uint64_t> seeds;
    if (found.contains("seeds"))
      for (const auto& v : found["seeds"]) seeds.push_back(v.get<std::uint64_t>());
    if (!seeds.empty()) cases.push_back({"rgbd", 640 * 480, seeds.front(), {seeds.begin() + 1, seeds.end()}, true});
    // The same frames at 320x240, as a robot's camera streams them (issue 20: <= 10 ms; issue 21: <= 8 ms).
    if (!seeds.empty() && opt.robot)
      cases.push_back({"rgbd", 320 * 240, seeds.front(), {seeds.begin() + 1, seeds.end()}, true, 320, 240});
  }
  if (!opt.only.empty())
    cases.erase(std::remove_if(cases.begin(), cases.end(),
                               [&](const Case& c) { return c.name().find(opt.only) == std::string::npos; }),
                cases.end());

  json machine = {{"cpus", sysconf(_SC_NPROCESSORS_ONLN)},
                  {"cpu", shell("lscpu | sed -n 's/^Model name: *//p' | head -n1")},
                  {"mem_gb", std::round(sysconf(_SC_PHYS_PAGES) * double(sysconf(_SC_PAGESIZE)) / (1 << 30))},
                  {"kernel", shell("uname -r")},
                  {"loadavg_at_start", shell("cut -d' ' -f1-3 /proc/loadavg")},
                  {"omp_wait", ompWait()},
                  {"freed_memory", freed_memory}};
  char date[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  std::printf("door_state_bench: %s; %ld cores (%s), load %s; median of %d runs (baseline %d); seed %llu\n", date,
              static_cast<long>(machine["cpus"].get<long>()), machine["cpu"].get<std::string>().c_str(),
              machine["loadavg_at_start"].get<std::string>().c_str(), opt.runs, opt.baseline_runs,
              static_cast<unsigned long long>(opt.seed));
  if (!opt.note.empty()) std::printf("%s\n", opt.note.c_str());
  std::printf("OpenMP threads wait: %s (util/omp_spin.hpp)\n", machine["omp_wait"].get<std::string>().c_str());
  std::printf("freed memory: %s (util/keep_freed_memory.hpp)\n", freed_memory.c_str());
  std::printf("ours: dsr::Pipeline without reconstruction; stock: pcl::VoxelGrid, NormalEstimationOMP (all cores), "
              "iterative SACSegmentation (SACMODEL_PARALLEL_PLANE), RegionGrowing, MomentOfInertiaEstimation, "
              "BoundaryEstimation; doors on both by our findDoorways + fitLeaf\n");
  for (const Case& c : cases)
    if (c.points > opt.skip_baseline_above) {
      std::printf("baseline skipped on clouds above %zu points (--skip-baseline-above)\n", opt.skip_baseline_above);
      break;
    }

  const std::vector<std::string> stage_order = {"preprocess", "normals", "floor_ceiling", "walls", "doors", "segments", "boundary", "total"};
  json results = json::array();
  for (const Case& c : cases) {
    if (!c.door_frames) {
      std::printf("\n== %s, seed %llu ==\n", c.name().c_str(), static_cast<unsigned long long>(c.seed));
    } else {
      std::string list;
      for (std::uint64_t seed : c.seeds()) list += (list.empty() ? "" : ",") + std::to_string(seed);
      std::printf("\n== %s: RGB-D frames with a door in view, seeds %s; medians over every run of every frame ==\n",
                  c.name().c_str(), list.c_str());
    }
    json ours = inChild([&] { return measure(c, "ours", opt.runs); });
    json stock;
    const bool skip = c.points > opt.skip_baseline_above;
    if (!skip) stock = inChild([&] { return measure(c, "stock", opt.baseline_runs); });
    if (ours.contains("error")) {
      std::printf("ours failed: %s\n", ours["error"].get<std::string>().c_str());
      results.push_back({{"case", c.name()}, {"ours", ours}});
      continue;
    }
    const bool have_stock = !skip && !stock.contains("error");
    if (!skip && !have_stock) std::printf("baseline failed: %s\n", stock["error"].get<std::string>().c_str());
    const double in_mb = ours["points_in"].get<double>() * sizeof(pcl::PointXYZ) / 1048576.0;
    std::printf("input %zu points (%.1f MB as PointXYZ), simulated in %.0f ms; after the voxel grid: ours %zu, stock %s\n",
                ours["points_in"].get<std::size_t>(), in_mb, ours["sim_ms"].get<double>(),
                ours["points_used"].get<std::size_t>(),
                have_stock ? std::to_string(stock["points_used"].get<std::size_t>()).c_str() : "-");
    std::printf("%-15s %10s %10s %11s %9s\n", "stage (ms)", "ours", "stock", "ours/stock", "speed-up");
    for (const auto& k : stage_order) {
      const double a = ours["stage_median_ms"].value(k, std::nan(""));
      const double b = have_stock ? stock["stage_median_ms"].value(k, std::nan("")) : std::nan("");
      std::printf("%-15s %10s %10s %11s %9s\n", k.c_str(), fmt("%.1f", a).c_str(), fmt("%.1f", b).c_str(),
                  fmt("%.3f", a / b).c_str(), fmt("%.1fx", b / a).c_str());
    }
    {
      const double a = ours["stage_median_ms"].value("total", 0.0) - ours["stage_median_ms"].value("doors", 0.0);
      const double b = have_stock ? stock["stage_median_ms"].value("total", 0.0) - stock["stage_median_ms"].value("doors", 0.0)
                                  : std::nan("");
      std::printf("%-15s %10s %10s %11s %9s   (doors: the same code in both)\n", "total w/o doors", fmt("%.1f", a).c_str(),
                  fmt("%.1f", b).c_str(), fmt("%.3f", a / b).c_str(), fmt("%.1fx", b / a).c_str());
    }
    if (c.door_frames) {  // the frames apart: medians of their runs
      std::printf("%-15s %10s %10s   total ms per frame\n", "seed", "ours", "stock");
      const auto seeds = c.seeds();
      for (std::size_t k = 0; k < seeds.size(); ++k) {
        auto frame = [&](const json& j) {
          const int n = j["runs"].get<int>();
          const std::vector<double> all = j["stage_runs_ms"]["total"].get<std::vector<double>>();
          if (all.size() < (k + 1) * n) return std::nan("");
          return median(std::vector<double>(all.begin() + k * n, all.begin() + (k + 1) * n));
        };
        std::printf("%-15llu %10s %10s\n", static_cast<unsigned long long>(seeds[k]), fmt("%.1f", frame(ours)).c_str(),
                    have_stock ? fmt("%.1f", frame(stock)).c_str() : "-");
      }
    }
    auto mem = [&](const json& j) {
      const double extra = j["peak_extra_kb"].get<double>() / 1024.0;
      return fmt("%.0f", j["peak_rss_kb"].get<double>() / 1024.0) + " MB peak RSS, " + fmt("%.0f", extra) +
             " MB above the input held = " + fmt("%.2f", extra / in_mb) + "x input";
    };
    std::printf("memory ours:  %s\n", mem(ours).c_str());
    if (have_stock) std::printf("memory stock: %s\n", mem(stock).c_str());
    std::printf("accuracy ours:  %s\n", fmtAcc(ours["accuracy"]).c_str());
    if (have_stock) std::printf("accuracy stock: %s\n", fmtAcc(stock["accuracy"]).c_str());
    json r = {{"case", c.name()}, {"sensor", c.sensor}, {"rays", c.points}, {"seed", c.seed}, {"seeds", c.seeds()},
              {"input_bytes", ours["points_in"].get<double>() * sizeof(pcl::PointXYZ)}, {"ours", ours}};
    if (have_stock) {
      r["stock"] = stock;
      r["ratio_ours_over_stock"] = json::object();
      for (const auto& k : stage_order) {
        const double a = ours["stage_median_ms"].value(k, std::nan("")), b = stock["stage_median_ms"].value(k, std::nan(""));
        r["ratio_ours_over_stock"][k] = std::isfinite(a / b) ? json(a / b) : json(nullptr);
      }
    } else {
      r["stock"] = skip ? json{{"skipped", "more than --skip-baseline-above points"}} : stock;
    }
    results.push_back(r);
  }

  // Summary and the n log n curve over the laser sizes.
  std::printf("\n== summary (total ms, median) ==\n");
  std::printf("%-22s %10s %10s %11s %9s %16s %14s %14s\n", "case", "ours", "stock", "ours/stock", "speed-up",
              "w/o doors: s-up", "ours mem/in", "stock mem/in");
  json curve = json::array();
  double ref_ours = 0, ref_stock = 0;
  for (const auto& r : results) {
    if (!r.contains("input_bytes")) continue;
    const double a = r["ours"]["stage_median_ms"]["total"].get<double>();
    const bool hs = r["stock"].contains("stage_median_ms");
    const double b = hs ? r["stock"]["stage_median_ms"]["total"].get<double>() : std::nan("");
    const double in_kb = r["input_bytes"].get<double>() / 1024.0;
    const double ma = r["ours"]["peak_extra_kb"].get<double>() / in_kb;
    const double mb = hs ? r["stock"]["peak_extra_kb"].get<double>() / in_kb : std::nan("");
    const double ad = a - r["ours"]["stage_median_ms"].value("doors", 0.0);
    const double bd = hs ? b - r["stock"]["stage_median_ms"].value("doors", 0.0) : std::nan("");
    std::printf("%-22s %10.1f %10s %11s %9s %16s %14s %14s\n", r["case"].get<std::string>().c_str(), a, fmt("%.1f", b).c_str(),
                fmt("%.3f", a / b).c_str(), fmt("%.1fx", b / a).c_str(), fmt("%.1fx", bd / ad).c_str(),
                fmt("%.2fx", ma).c_str(), fmt("%.2fx", mb).c_str());
    if (r["sensor"] == "tls") {
      const double n = r["ours"]["points_in"].get<double>();
      const double nlogn = n * std::log2(n);
      if (curve.empty()) ref_ours = a / nlogn, ref_stock = b / nlogn;
      curve.push_back({{"points", n}, {"points_used", r["ours"]["points_used"]}, {"ours_ms", a}, {"stock_ms", hs ? json(b) : json(nullptr)},
                       {"ours_per_nlogn_rel", a / nlogn / ref_ours},
                       {"stock_per_nlogn_rel", hs && std::isfinite(ref_stock) ? json(b / nlogn / ref_stock) : json(nullptr)}});
    }
  }
  // Peak memory above the input held, fitted as fixed + slope * input bytes
  // over the laser sizes (least squares).
  json memfit = json::object();
  for (const std::string impl : {"ours", "stock"}) {
    std::vector<std::pair<double, double>> xy;  // input MB, extra MB
    for (const auto& r : results)
      if (r.value("sensor", "") == "tls" && r[impl].contains("peak_extra_kb"))
        xy.push_back({r["input_bytes"].get<double>() / 1048576.0, r[impl]["peak_extra_kb"].get<double>() / 1024.0});
    if (xy.size() < 2) continue;
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (const auto& q : xy) sx += q.first, sy += q.second, sxx += q.first * q.first, sxy += q.first * q.second;
    const double m = static_cast<double>(xy.size());
    const double slope = (m * sxy - sx * sy) / (m * sxx - sx * sx), fixed = (sy - slope * sx) / m;
    memfit[impl] = {{"fixed_mb", fixed}, {"slope_x_input", slope}};
    std::printf("memory %-5s: peak above the input held ~ %.0f MB + %.2f x input (least squares over the laser sizes)\n",
                impl.c_str(), fixed, slope);
  }

  std::printf("\n== cost against n log n (laser rooms; time / (n log2 n), relative to the smallest size; <= 1 is no worse than n log n) ==\n");
  std::printf("%12s %14s %10s %10s %10s %10s\n", "points", "after voxels", "ours ms", "ours rel", "stock ms", "stock rel");
  for (const auto& c : curve)
    std::printf("%12.0f %14.0f %10.1f %10.2f %10s %10s\n", c["points"].get<double>(), c["points_used"].get<double>(),
                c["ours_ms"].get<double>(),
                c["ours_per_nlogn_rel"].get<double>(),
                c["stock_ms"].is_null() ? "-" : fmt("%.1f", c["stock_ms"].get<double>()).c_str(),
                c["stock_per_nlogn_rel"].is_null() ? "-" : fmt("%.2f", c["stock_per_nlogn_rel"].get<double>()).c_str());

  json sweeps = json::array();
  if (opt.accuracy_scenes > 0) {
    std::printf("\n== accuracy on more scenes (one run each, truth doors in view) ==\n");
    for (const std::string sensor : {"tls", "rgbd"}) {
      if (sensor == "rgbd" && !opt.rgbd) continue;
      json sw = inChild([&] { return accuracySweep(sensor, opt.accuracy_scenes, opt.accuracy_points); });
      if (sw.contains("error")) {
        std::printf("%s sweep failed: %s\n", sensor.c_str(), sw["error"].get<std::string>().c_str());
        continue;
      }
      std::printf("%s, %d scenes (seeds %s)%s:\n", sensor == "tls" ? "laser" : "RGB-D", opt.accuracy_scenes,
                  sw["seeds"].get<std::string>().c_str(),
                  sensor == "tls" ? (", " + std::to_string(opt.accuracy_points) + " rays").c_str() : "");
      std::printf("  ours  (mean %6.0f ms): %s\n", sw["ours_mean_total_ms"].get<double>(), fmtAcc(sw["ours"]).c_str());
      std::printf("  stock (mean %6.0f ms): %s\n", sw["stock_mean_total_ms"].get<double>(), fmtAcc(sw["stock"]).c_str());
      for (const json& d : sw["differ"]) {
        auto side = [](const json& x) {
          std::string m;
          for (const json& i : x["missed_truth"]) m += (m.empty() ? "" : ",") + std::to_string(i.get<int>());
          return std::to_string(x["matched"].get<int>()) + " found, " + std::to_string(x["reported"].get<int>()) +
                 " reported, " + std::to_string(x["state_correct"].get<int>()) + " states right" +
                 (m.empty() ? "" : ", missed truth door " + m);
        };
        std::printf("    seed %d (%d doors): ours %s; stock %s\n", d["seed"].get<int>(), d["true_doors"].get<int>(),
                    side(d["ours"]).c_str(), side(d["stock"]).c_str());
      }
      sweeps.push_back(sw);
    }
  }

  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  json out = {{"date", date},
              {"note", opt.note},
              {"machine", machine},
              {"runs", opt.runs},
              {"baseline_runs", opt.baseline_runs},
              {"seed", opt.seed},
              {"skip_baseline_above", opt.skip_baseline_above},
              {"cases", results},
              {"nlogn_curve", curve},
              {"memory_fit", memfit},
              {"accuracy_sweeps", sweeps},
              {"bench_seconds", wall_s}};
  std::ofstream f(opt.json_path);
  f << out.dump(1) << "\n";
  if (!f) {
    std::cerr << "door_state_bench: cannot write " << opt.json_path << "\n";
    return 1;
  }
  std::printf("\nwrote %s (%.0f s)\n", opt.json_path.c_str(), wall_s);
  return 0;
}
