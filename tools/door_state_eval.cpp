// door_state_eval: scores door-state reports against simulator ground truth.
#include <cmath>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "door_state_recognition/eval/evaluation.hpp"
#include "door_state_recognition/util/omp_spin.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const char* kUsage =
    "usage: door_state_eval [--max-distance M] [--in-view-only] [--leaf-in-view-only [SHARE]]\n"
    "                       GROUND_TRUTH.json REPORT.json\n"
    "       door_state_eval [--max-distance M] [--in-view-only] [--leaf-in-view-only [SHARE]]\n"
    "                       --pairs LIST.txt\n"
    "\n"
    "Scores a door-state report against simulator ground truth and prints the\n"
    "result as JSON on stdout. A report in state \"not_closed\" (leaf unseen)\n"
    "counts as found, never as a right state (\"not_closed\": how many were\n"
    "reported); a lower bound more than 2 deg above the true angle counts in\n"
    "\"bound_errors\"; \"state_accuracy_measured\" is over measured leaves.\n"
    "\n"
    "  --max-distance M  max horizontal distance between opening centres for a\n"
    "                    match, metres (default 0.5, must be >= 0)\n"
    "  --in-view-only    leave out true doors marked \"in_view\": false (outside a\n"
    "                    camera's view): neither missed nor false positives\n"
    "  --leaf-in-view-only [SHARE]\n"
    "                    score only true doors whose \"leaf_in_view\" (the share of\n"
    "                    the leaf a camera, or any station of a laser scan, sees\n"
    "                    unoccluded, 0..1) is >= SHARE\n"
    "                    (a number in [0, 1] right after the option; default 0.5):\n"
    "                    the others are neither missed nor false positives\n"
    "  --pairs LIST.txt  evaluate many scenes: each line holds \"GT.json REPORT.json\"\n"
    "                    (relative paths are taken relative to LIST.txt's folder;\n"
    "                    blank lines and lines starting with '#' are skipped);\n"
    "                    prints the merged result plus \"scenes\"\n"
    "  -h, --help        show this help\n"
    "\n"
    "Exit status: 0 on success, 2 on bad arguments or unreadable/invalid input.\n";

// Error with a one-line message; exits 2 in main(). Missing files also show usage.
struct InputError : std::runtime_error {
  explicit InputError(const std::string& msg, bool usage = false) : std::runtime_error(msg), show_usage(usage) {}
  bool show_usage;
};

std::string oneLine(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

std::ifstream openFile(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": no such file", true);
  if (!fs::is_regular_file(path, ec)) throw InputError(path + ": not a regular file");
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open for reading");
  return in;
}

json readJson(const std::string& path) {
  std::ifstream in = openFile(path);
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw InputError(path + ": malformed JSON: " + oneLine(e.what()));
  }
}

dsr::eval::EvalResult evalPair(const std::string& gt, const std::string& rep, double max_dist, bool in_view_only,
                               double min_leaf) {
  const json truth = readJson(gt), report = readJson(rep);
  try {
    return dsr::eval::evaluate(truth, report, max_dist, in_view_only, min_leaf);
  } catch (const std::invalid_argument& e) {
    // Messages start with "truth" or "report": name the matching file.
    const std::string msg = e.what();
    throw InputError((msg.rfind("report", 0) == 0 ? rep : gt) + ": " + oneLine(msg));
  }
}

std::vector<std::pair<std::string, std::string>> readPairs(const std::string& list) {
  std::ifstream in = openFile(list);
  const fs::path base = fs::path(list).parent_path();
  auto resolve = [&](const std::string& p) { return fs::path(p).is_absolute() ? p : (base / p).string(); };
  std::vector<std::pair<std::string, std::string>> pairs;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    std::istringstream ss(line);
    std::string a, b, extra;
    if (!(ss >> a) || a[0] == '#') continue;
    if (!(ss >> b) || (ss >> extra))
      throw InputError(list + ":" + std::to_string(n) + ": expected \"GT.json REPORT.json\"");
    pairs.emplace_back(resolve(a), resolve(b));
  }
  if (pairs.empty()) throw InputError(list + ": no pairs listed");
  return pairs;
}

int usageError(const std::string& msg) {
  std::cerr << "door_state_eval: " << msg << "\n" << kUsage;
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  dsr::util::shortOmpSpin(argv);  // before anything else: the program may be run again
  double max_dist = 0.5;
  bool in_view_only = false;
  double min_leaf = -1.0;  // --leaf-in-view-only: unused when negative
  std::string pairs_file;
  std::vector<std::string> files;
  bool options_done = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (options_done || a.empty() || a[0] != '-' || a == "-") {
      files.push_back(a);
    } else if (a == "--") {
      options_done = true;
    } else if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      return 0;
    } else if (a == "--max-distance") {
      if (++i >= argc) return usageError("--max-distance needs a value");
      const std::string v = argv[i];
      char* end = nullptr;
      max_dist = std::strtod(v.c_str(), &end);
      if (v.empty() || *end != '\0' || !std::isfinite(max_dist))
        return usageError("--max-distance: not a number: '" + v + "'");
      if (max_dist < 0) return usageError("--max-distance must be >= 0, got " + v);
    } else if (a == "--in-view-only") {
      in_view_only = true;
    } else if (a == "--leaf-in-view-only") {
      min_leaf = 0.5;
      if (i + 1 < argc) {  // an optional SHARE: the next argument when it is a number
        const std::string v = argv[i + 1];
        char* end = nullptr;
        const double share = std::strtod(v.c_str(), &end);
        if (!v.empty() && *end == '\0') {
          if (!(share >= 0 && share <= 1)) return usageError("--leaf-in-view-only: SHARE must lie in [0, 1], got " + v);
          min_leaf = share;
          ++i;
        }
      }
    } else if (a == "--pairs") {
      if (++i >= argc) return usageError("--pairs needs a file");
      if (!pairs_file.empty()) return usageError("--pairs given twice");
      pairs_file = argv[i];
    } else {
      return usageError("unknown option '" + a + "'");
    }
  }
  if (!pairs_file.empty() && !files.empty()) return usageError("--pairs takes no further file arguments");
  if (pairs_file.empty() && files.size() != 2) return usageError("expected GROUND_TRUTH.json and REPORT.json");

  try {
    json out;
    if (pairs_file.empty()) {
      out = dsr::eval::toJson(evalPair(files[0], files[1], max_dist, in_view_only, min_leaf));
    } else {
      std::vector<dsr::eval::EvalResult> results;
      for (const auto& [gt, rep] : readPairs(pairs_file)) results.push_back(evalPair(gt, rep, max_dist, in_view_only, min_leaf));
      out = dsr::eval::toJson(dsr::eval::merge(results));
      out["scenes"] = results.size();
    }
    std::cout << out.dump(2) << "\n";
    return 0;
  } catch (const InputError& e) {
    std::cerr << "door_state_eval: " << e.what() << "\n" << (e.show_usage ? kUsage : "");
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "door_state_eval: internal error: " << oneLine(e.what()) << "\n";
    return 1;
  }
}
