// door_state_drive_eval: door states fused over simulated drives, scored
// (issue 20; eval/drive_eval.hpp gives the rules).
#include <cstdlib>
#include <exception>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "door_state_recognition/eval/drive_eval.hpp"
#include "door_state_recognition/util/omp_spin.hpp"
#include "cli_args.hpp"

namespace {

const char* kUsage =
    "usage: door_state_drive_eval [--sensor S] [--seeds A-B] [--every K] [--toggle auto]\n"
    "                             [--toggle-door K:ANGLE@T ...] [--lidar-motion]\n"
    "                             [--keep-not-found] [--confirm-clouds N] [--confirm-spread M]\n"
    "                             [--config YAML] [--verbose]\n"
    "\n"
    "For each seed, plans the drive of `door_scene_sim --drive --seed S --sensor X`,\n"
    "simulates every K-th cloud, runs it through the nodelet's core (DriveTracker:\n"
    "the pipeline with the sensor's origin as viewpoint, then DoorFusion) and scores\n"
    "the last tracked doors against the drive's truth in map. Prints the figures\n"
    "as JSON on stdout (with --verbose also each drive's, under \"per_drive\") and one\n"
    "line per drive, with its seed, on stderr.\n"
    "\n"
    "  --sensor S            lidar16 | lidar32 | lidar64 | lidar128 | rgbd (default lidar64)\n"
    "  --seeds A-B           the drives' seeds, inclusive (default 1000-1019); or one seed A\n"
    "  --every K             process every K-th cloud (default: ~3.5 clouds/s, LiDAR\n"
    "                        at 10 Hz: 3, RGB-D at 15 Hz: 4)\n"
    "  --toggle auto         in each drive, the passed door seen in the most frames\n"
    "                        changes state (closed -> 60 deg, else -> closed) in the\n"
    "                        middle of its time in view; the latency is scored\n"
    "  --toggle-door K:ANGLE@T  door K is at ANGLE deg from T s on (repeatable)\n"
    "  --lidar-motion        LiDAR sweeps not deskewed (the robot moves during one)\n"
    "  --confirm-clouds N    publish a track once N processed clouds showed it (default 2;\n"
    "                        1 with --confirm-spread 0: every track at once)\n"
    "  --confirm-spread M    ... from sensor positions M metres apart (default 0)\n"
    "  --keep-not-found      never withdraw a track that later clouds look at and do\n"
    "                        not find (the nodelet's ~withdraw_not_found false)\n"
    "  --config YAML         pipeline parameters (as door_state_cli --config)\n"
    "  --verbose             each drive's doors and changes in the JSON\n"
    "  -h, --help            show this help\n"
    "\n"
    "Exit status: 0 on success, 2 on bad arguments.\n";

using dsr::tools::toDouble;
using dsr::tools::toInt;
using dsr::tools::UsageError;

}  // namespace

int main(int argc, char** argv) {
  dsr::util::shortOmpSpin(argv);  // before anything else: the program may be run again
  dsr::eval::DriveEvalOptions o;
  long first = 1000, last = 1019;
  bool verbose = false;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&]() { return dsr::tools::nextValue(argc, argv, i); };
      if (a == "-h" || a == "--help") {
        std::cout << kUsage;
        return 0;
      } else if (a == "--sensor") {
        o.sensor = value();
        if (o.sensor != "lidar16" && o.sensor != "lidar32" && o.sensor != "lidar64" && o.sensor != "lidar128" &&
            o.sensor != "rgbd")
          throw UsageError("--sensor must be lidar16, lidar32, lidar64, lidar128 or rgbd");
      } else if (a == "--seeds") {
        const std::string v = value();
        const std::size_t dash = v.find('-', 1);
        first = static_cast<long>(toInt(a, v.substr(0, dash)));
        last = dash == std::string::npos ? first : static_cast<long>(toInt(a, v.substr(dash + 1)));
        if (first < 0 || last < first) throw UsageError("--seeds needs A-B with 0 <= A <= B");
      } else if (a == "--every") {
        const long long k = toInt(a, value());
        if (k < 1 || k > 1000) throw UsageError("--every must be an integer in [1, 1000]");
        o.every = static_cast<int>(k);
      } else if (a == "--toggle") {
        if (value() != "auto") throw UsageError("--toggle takes auto");
        o.auto_toggle = true;
      } else if (a == "--toggle-door") {
        const dsr::tools::Toggle c = dsr::tools::toToggle(a, value());
        o.changes.push_back({c.door, c.angle_deg, c.t});
      } else if (a == "--lidar-motion") {
        o.lidar_motion = true;
      } else if (a == "--config") {
        o.params = dsr::loadParameters(value());
      } else if (a == "--keep-not-found") {
        o.tracker.disprove = false;
      } else if (a == "--confirm-clouds") {
        const long long k = toInt(a, value());
        if (k < 1 || k > 1000) throw UsageError("--confirm-clouds must be an integer in [1, 1000]");
        o.tracker.confirm_clouds = static_cast<int>(k);
      } else if (a == "--confirm-spread") {
        o.tracker.confirm_spread_m = toDouble(a, value());
        if (!(o.tracker.confirm_spread_m >= 0) || o.tracker.confirm_spread_m > 100)
          throw UsageError("--confirm-spread must be a number of metres in [0, 100]");
      } else if (a == "--verbose") {
        verbose = true;
      } else {
        throw UsageError("unknown argument '" + a + "'");
      }
    }
    if (o.lidar_motion && o.sensor == "rgbd") throw UsageError("--lidar-motion is for a LiDAR");
    std::vector<dsr::eval::DriveEvalResult> drives;
    nlohmann::json per = nlohmann::json::array();
    for (long seed = first; seed <= last; ++seed) {
      drives.push_back(dsr::eval::evaluateDrive(static_cast<std::uint64_t>(seed), o));
      const dsr::eval::DriveEvalResult& r = drives.back();
      int passed = 0, right = 0, several = 0;
      std::string wrong, latency;
      for (const auto& d : r.doors) {
        several += d.ids > 1;
        if (!d.passed) continue;
        ++passed;
        right += d.right;
        if (!d.right) wrong += " " + std::to_string(d.door) + ":" + d.why;
      }
      auto clouds = [](int n) { return n < 0 ? std::string("none") : std::to_string(n); };
      for (const auto& c : r.changes)
        latency += " " + clouds(c.latency) + " (from detection " + clouds(c.latency_from_detection) + ")";
      std::cerr << "seed " << seed << " " << o.sensor << ": " << r.processed << "/" << r.frames << " clouds, passed "
                << passed << ", right " << right << ", false " << r.false_doors << " (" << r.disproved << " withdrawn), doors with several ids "
                << several << (latency.empty() ? "" : ", change latency" + latency)
                << (wrong.empty() ? "" : ", wrong" + wrong) << ", " << r.pipeline_ms_median << " ms/cloud (fusion " << r.fusion_ms_median << ", max " << r.fusion_ms_max << ")\n";
      if (verbose) per.push_back(dsr::eval::toJson(r));
    }
    nlohmann::json out = dsr::eval::summarize(drives);
    out["sensor"] = o.sensor;
    out["seeds"] = std::to_string(first) + "-" + std::to_string(last);
    out["every"] = drives.empty() ? 0 : drives.front().every;
    if (verbose) out["per_drive"] = per;
    std::cout << out.dump(1) << "\n";
    return 0;
  } catch (const UsageError& e) {
    std::cerr << "door_state_drive_eval: " << e.what() << "\n" << kUsage;
    return 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << "door_state_drive_eval: " << e.what() << "\n";
    return 2;
  }
}
