// Scores a door-state report (pipeline CLI output) against simulator ground
// truth. Both JSON documents use the cloud's own frame (metres, degrees).
#pragma once

#include <vector>

#include <nlohmann/json.hpp>

namespace dsr {
namespace eval {

// One truth door paired with one reported door.
struct DoorMatch {
  int truth_index;           // index into truth["doors"]
  int report_index;          // index into report["doors"]
  double center_distance_m;  // horizontal distance between opening centres
  bool state_correct;        // state strings equal
  double angle_error_deg;    // |reported - true| opening angle
  double hinge_error_m;      // 3D distance between hinges
  bool angle_is_lower_bound = false;  // the report gave the angle as a lower bound (leaf unseen)
  bool not_closed = false;            // the report's state was "not_closed" (never a right state)
  bool bound_error = false;           // a lower bound above the true angle by more than kBoundSlackDeg
};

// A lower bound may exceed the true angle by the step of its search (2 deg,
// state/leaf_free_space.cpp) without being wrong; beyond that it is a bound error.
constexpr double kBoundSlackDeg = 2.0;

struct EvalResult {
  int true_doors = 0, reported_doors = 0, matched = 0, state_correct = 0;
  // Reports (counted in reported_doors) whose state was "not_closed": found
  // when matched (recall), never a right state.
  int not_closed = 0;
  // Matches whose angle was a lower bound above the true angle (+ kBoundSlackDeg).
  int bound_errors = 0;
  std::vector<DoorMatch> matches;     // sorted by truth_index (per scene)
  std::vector<int> missed_truth;      // truth indices without a match
  std::vector<int> unmatched_report;  // report indices without a match (false positives)

  double precision() const;          // matched / reported; 1.0 when reported == 0
  double recall() const;             // matched / true; 1.0 when true == 0
  double stateAccuracy() const;      // state_correct / matched; NaN when matched == 0
  // The same over the matches whose leaf was measured (angle not a lower
  // bound); NaN when none.
  double stateAccuracyMeasured() const;
  double angleMaeDeg() const;        // mean angle error; NaN when no matches
  // Mean angle error over the matches whose angle was measured (not given
  // as a lower bound); NaN when none. angleMaeDeg() counts every match.
  double angleMaeMeasuredDeg() const;
  double hingeErrorMeanM() const;    // mean hinge error; NaN when no matches
  double hingeErrorMedianM() const;  // median hinge error; NaN when no matches
};

// Matches reported doors to truth doors one-to-one. Distance between opening
// centres is horizontal: the component along the truth's "up" (normalised,
// default [0,0,1]) is removed. Pairs with distance <= max_center_distance_m are
// eligible and assigned greedily by increasing distance (ties: lower truth
// index, then lower report index).
// Throws std::invalid_argument (message names the document and field, e.g.
// "report.doors[1].hinge: ...") when a needed field is missing or mistyped, or
// when max_center_distance_m is negative or not finite. The truth must hold
// "scene" (simulator ground truth) and the report "points_in" (a pipeline
// report): swapped or wrong documents are refused, not scored.
// With in_view_only, truth doors marked "in_view": false (outside a camera's
// view) are left out: neither missed, nor a false positive when reported.
// With min_leaf_in_view >= 0 (at most 1), so are truth doors whose
// "leaf_in_view" (the share of the leaf the sensor sees: truth of RGB-D
// frames and laser scans) is below it; a truth door without that field is an error then. Negative: unused.
EvalResult evaluate(const nlohmann::json& truth, const nlohmann::json& report,
                    double max_center_distance_m = 0.5, bool in_view_only = false,
                    double min_leaf_in_view = -1.0);

// Counts (with not_closed and bound_errors), the figures (NaN -> null;
// state_accuracy_measured too), matches, missed_truth, unmatched_report.
// A report whose state is "not_closed" counts as found when it matches a
// true door, and never as a right state.
nlohmann::json toJson(const EvalResult& result);

// Sums several results: counts add up; matches, missed_truth and
// unmatched_report are concatenated (their indices stay per scene).
EvalResult merge(const std::vector<EvalResult>& results);

}  // namespace eval
}  // namespace dsr
