#include "door_state_recognition/eval/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>

#include <Eigen/Core>

namespace dsr {
namespace eval {
namespace {

using nlohmann::json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Door {
  Eigen::Vector3d center, hinge;
  double angle;
  std::string state;
  bool out_of_view = false;  // truth only: left out ("in_view": false, or too little "leaf_in_view")
  bool lower_bound = false;  // report only: "angle_is_lower_bound": true
};

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

const json& field(const json& obj, const char* key, const std::string& where) {
  if (!obj.is_object()) fail(where, "expected an object");
  auto it = obj.find(key);
  if (it == obj.end()) fail(where + "." + key, "missing field");
  return *it;
}

double number(const json& j, const std::string& where) {
  if (!j.is_number()) fail(where, "expected a number, got " + std::string(j.type_name()));
  double v = j.get<double>();
  if (!std::isfinite(v)) fail(where, "expected a finite number");
  return v;
}

Eigen::Vector3d vec3(const json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3)
    fail(where, "expected an array of 3 numbers, got " +
                    (j.is_array() ? std::to_string(j.size()) + " elements" : std::string(j.type_name())));
  return {number(j[0], where + "[0]"), number(j[1], where + "[1]"), number(j[2], where + "[2]")};
}

std::vector<Door> parseDoors(const json& doc, const std::string& name) {
  const json& arr = field(doc, "doors", name);
  if (!arr.is_array()) fail(name + ".doors", "expected an array, got " + std::string(arr.type_name()));
  std::vector<Door> doors;
  for (std::size_t i = 0; i < arr.size(); ++i) {
    const std::string w = name + ".doors[" + std::to_string(i) + "]";
    const json& d = arr[i];
    const json& state = field(d, "state", w);
    if (!state.is_string()) fail(w + ".state", "expected a string, got " + std::string(state.type_name()));
    doors.push_back({vec3(field(d, "opening_center", w), w + ".opening_center"),
                     vec3(field(d, "hinge", w), w + ".hinge"),
                     number(field(d, "opening_angle_deg", w), w + ".opening_angle_deg"),
                     state.get<std::string>()});
    const auto lb = d.find("angle_is_lower_bound");
    doors.back().lower_bound = lb != d.end() && lb->is_boolean() && lb->get<bool>();
  }
  return doors;
}

Eigen::Vector3d parseUp(const json& truth) {
  auto it = truth.find("up");
  if (it == truth.end() || it->is_null()) return Eigen::Vector3d::UnitZ();
  Eigen::Vector3d up = vec3(*it, "truth.up");
  if (up.norm() < 1e-9) fail("truth.up", "zero-length vector");
  return up.normalized();
}

double meanOf(const std::vector<double>& v) {
  if (v.empty()) return kNaN;
  double s = 0;
  for (double x : v) s += x;
  return s / v.size();
}

json numOrNull(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

}  // namespace

double EvalResult::precision() const { return reported_doors == 0 ? 1.0 : double(matched) / reported_doors; }
double EvalResult::recall() const { return true_doors == 0 ? 1.0 : double(matched) / true_doors; }
double EvalResult::stateAccuracy() const { return matched == 0 ? kNaN : double(state_correct) / matched; }

double EvalResult::stateAccuracyMeasured() const {
  int n = 0, ok = 0;
  for (const auto& m : matches)
    if (!m.angle_is_lower_bound) ++n, ok += m.state_correct;
  return n == 0 ? kNaN : double(ok) / n;
}

double EvalResult::angleMaeDeg() const {
  std::vector<double> v;
  for (const auto& m : matches) v.push_back(m.angle_error_deg);
  return meanOf(v);
}

double EvalResult::angleMaeMeasuredDeg() const {
  std::vector<double> v;
  for (const auto& m : matches)
    if (!m.angle_is_lower_bound) v.push_back(m.angle_error_deg);
  return meanOf(v);
}

double EvalResult::hingeErrorMeanM() const {
  std::vector<double> v;
  for (const auto& m : matches) v.push_back(m.hinge_error_m);
  return meanOf(v);
}

double EvalResult::hingeErrorMedianM() const {
  std::vector<double> v;
  for (const auto& m : matches) v.push_back(m.hinge_error_m);
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

EvalResult evaluate(const json& truth, const json& report, double max_center_distance_m, bool in_view_only,
                    double min_leaf_in_view) {
  if (!std::isfinite(max_center_distance_m) || max_center_distance_m < 0)
    throw std::invalid_argument("max_center_distance_m must be a finite number >= 0");
  if (std::isnan(min_leaf_in_view) || min_leaf_in_view > 1)
    throw std::invalid_argument("min_leaf_in_view must lie in [0, 1] (negative: every door)");
  if (!truth.is_object()) fail("truth", "expected a JSON object");
  if (!report.is_object()) fail("report", "expected a JSON object");
  // Each document must be what it claims: simulator truth has "scene" (a
  // report never does), a report "points_in" (truth never does). Without
  // this a report scored as truth, or truth as a report, gives a score.
  if (!truth.contains("scene"))
    fail("truth", truth.contains("points_in")
                      ? "has \"points_in\" and no \"scene\": a report, not simulator ground truth (arguments swapped?)"
                      : "missing field \"scene\": not simulator ground truth");
  if (!report.contains("points_in"))
    fail("report", report.contains("scene")
                       ? "has \"scene\" and no \"points_in\": simulator ground truth, not a report (arguments swapped?)"
                       : "missing field \"points_in\": not a door_state_cli report");
  const Eigen::Vector3d up = parseUp(truth);
  std::vector<Door> t = parseDoors(truth, "truth");
  const std::vector<Door> r = parseDoors(report, "report");
  if (in_view_only) {
    const json& arr = truth.at("doors");
    for (std::size_t i = 0; i < t.size(); ++i) {
      const auto it = arr[i].find("in_view");
      t[i].out_of_view = it != arr[i].end() && it->is_boolean() && !it->get<bool>();
    }
  }
  if (min_leaf_in_view >= 0) {
    const json& arr = truth.at("doors");
    for (std::size_t i = 0; i < t.size(); ++i) {
      const std::string w = "truth.doors[" + std::to_string(i) + "]";
      const auto it = arr[i].find("leaf_in_view");
      if (it == arr[i].end()) fail(w + ".leaf_in_view", "missing field (truth of RGB-D frames and laser scans only)");
      if (number(*it, w + ".leaf_in_view") < min_leaf_in_view) t[i].out_of_view = true;
    }
  }

  // All eligible pairs, sorted by (distance, truth index, report index).
  std::vector<std::tuple<double, int, int>> pairs;
  for (int i = 0; i < int(t.size()); ++i)
    for (int j = 0; j < int(r.size()); ++j) {
      Eigen::Vector3d d = r[j].center - t[i].center;
      const double dist = (d - d.dot(up) * up).norm();
      if (dist <= max_center_distance_m) pairs.emplace_back(dist, i, j);
    }
  std::sort(pairs.begin(), pairs.end());

  EvalResult res;
  res.true_doors = int(t.size());
  res.reported_doors = int(r.size());
  std::vector<bool> t_used(t.size(), false), r_used(r.size(), false), r_out_of_view(r.size(), false);
  for (const Door& d : t) res.true_doors -= d.out_of_view;
  for (const auto& [dist, i, j] : pairs) {
    if (t_used[i] || r_used[j]) continue;
    t_used[i] = r_used[j] = true;
    if (t[i].out_of_view) {  // a door outside the view counts neither way
      --res.reported_doors;
      r_out_of_view[j] = true;
      continue;
    }
    const bool not_closed = r[j].state == "not_closed";
    const bool ok = t[i].state == r[j].state && !not_closed;
    const bool bound_error = r[j].lower_bound && r[j].angle > t[i].angle + kBoundSlackDeg;
    res.matches.push_back({i, j, dist, ok, std::abs(r[j].angle - t[i].angle), (r[j].hinge - t[i].hinge).norm(),
                           r[j].lower_bound, not_closed, bound_error});
    res.state_correct += ok;
    res.bound_errors += bound_error;
  }
  // Every report still counted in reported_doors (not one matched to a door out of view).
  for (int j = 0; j < int(r.size()); ++j)
    if (r[j].state == "not_closed" && !r_out_of_view[j]) ++res.not_closed;
  res.matched = int(res.matches.size());
  std::sort(res.matches.begin(), res.matches.end(),
            [](const DoorMatch& a, const DoorMatch& b) { return a.truth_index < b.truth_index; });
  for (int i = 0; i < int(t.size()); ++i)
    if (!t_used[i] && !t[i].out_of_view) res.missed_truth.push_back(i);
  for (int j = 0; j < int(r.size()); ++j)
    if (!r_used[j]) res.unmatched_report.push_back(j);
  return res;
}

json toJson(const EvalResult& res) {
  json matches = json::array();
  for (const auto& m : res.matches)
    matches.push_back({{"truth_index", m.truth_index},
                       {"report_index", m.report_index},
                       {"center_distance_m", numOrNull(m.center_distance_m)},
                       {"state_correct", m.state_correct},
                       {"angle_error_deg", numOrNull(m.angle_error_deg)},
                       {"hinge_error_m", numOrNull(m.hinge_error_m)},
                       {"angle_is_lower_bound", m.angle_is_lower_bound},
                       {"not_closed", m.not_closed},
                       {"bound_error", m.bound_error}});
  return {{"true_doors", res.true_doors},
          {"reported_doors", res.reported_doors},
          {"matched", res.matched},
          {"state_correct", res.state_correct},
          {"precision", numOrNull(res.precision())},
          {"recall", numOrNull(res.recall())},
          {"not_closed", res.not_closed},
          {"bound_errors", res.bound_errors},
          {"state_accuracy", numOrNull(res.stateAccuracy())},
          {"state_accuracy_measured", numOrNull(res.stateAccuracyMeasured())},
          {"angle_mae_deg", numOrNull(res.angleMaeDeg())},
          {"angle_mae_measured_deg", numOrNull(res.angleMaeMeasuredDeg())},
          {"angle_lower_bounds", std::count_if(res.matches.begin(), res.matches.end(),
                                               [](const DoorMatch& m) { return m.angle_is_lower_bound; })},
          {"hinge_error_mean_m", numOrNull(res.hingeErrorMeanM())},
          {"hinge_error_median_m", numOrNull(res.hingeErrorMedianM())},
          {"matches", matches},
          {"missed_truth", res.missed_truth},
          {"unmatched_report", res.unmatched_report}};
}

EvalResult merge(const std::vector<EvalResult>& results) {
  EvalResult out;
  for (const auto& r : results) {
    out.true_doors += r.true_doors;
    out.reported_doors += r.reported_doors;
    out.matched += r.matched;
    out.state_correct += r.state_correct;
    out.not_closed += r.not_closed;
    out.bound_errors += r.bound_errors;
    out.matches.insert(out.matches.end(), r.matches.begin(), r.matches.end());
    out.missed_truth.insert(out.missed_truth.end(), r.missed_truth.begin(), r.missed_truth.end());
    out.unmatched_report.insert(out.unmatched_report.end(), r.unmatched_report.begin(), r.unmatched_report.end());
  }
  return out;
}

}  // namespace eval
}  // namespace dsr
