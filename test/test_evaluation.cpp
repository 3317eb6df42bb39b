#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "door_state_recognition/eval/evaluation.hpp"

using dsr::eval::evaluate;
using dsr::eval::EvalResult;
using nlohmann::json;

namespace {

json vec(double x, double y, double z) { return json::array({x, y, z}); }

json truthDoor(json center, json hinge, double angle, const std::string& state) {
  return {{"opening_center", center}, {"hinge", hinge}, {"width", 0.9}, {"height", 2.0},
          {"opening_angle_deg", angle}, {"state", state}, {"swing", "toward_viewer"}, {"extra", 1}};
}

json reportDoor(int id, json center, json hinge, double angle, const std::string& state) {
  return {{"id", id}, {"wall_id", nullptr}, {"state", state}, {"opening_angle_deg", angle},
          {"confidence", 0.8}, {"hinge", hinge}, {"opening_center", center}, {"width", 0.9},
          {"height", 2.0}, {"swing", "unknown"}};
}

json truthDoc(json doors, json up = vec(0, 0, 1)) {
  return {{"scene", "t"}, {"sensor", "tls"}, {"up", up}, {"floor", 0.0}, {"ceiling", 2.5},
          {"doors", doors}, {"decoys", json::array()}};
}

json reportDoc(json doors) {
  return {{"input", "x.pcd"}, {"points_in", 10}, {"points_used", 10}, {"up", vec(0, 0, 1)},
          {"floor", nullptr}, {"ceiling", nullptr}, {"walls", json::array()}, {"doors", doors},
          {"others", json::array()}, {"timing_ms", json::object()}};
}

// One truth door at the origin (hinge at -0.45 x), one reported door at `c`.
EvalResult single(json c, json up = vec(0, 0, 1)) {
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(-0.45, 0, 0), 30, "semi_open")}, up);
  json r = reportDoc({reportDoor(0, c, vec(-0.45, 0, 0), 30, "semi_open")});
  return evaluate(t, r);
}

}  // namespace

TEST(Evaluation, ExactMatch) {
  EvalResult r = single(vec(0, 0, 0));
  EXPECT_EQ(r.true_doors, 1);
  EXPECT_EQ(r.reported_doors, 1);
  EXPECT_EQ(r.matched, 1);
  EXPECT_EQ(r.state_correct, 1);
  ASSERT_EQ(r.matches.size(), 1u);
  EXPECT_EQ(r.matches[0].truth_index, 0);
  EXPECT_EQ(r.matches[0].report_index, 0);
  EXPECT_DOUBLE_EQ(r.matches[0].center_distance_m, 0.0);
  EXPECT_DOUBLE_EQ(r.precision(), 1.0);
  EXPECT_DOUBLE_EQ(r.recall(), 1.0);
  EXPECT_DOUBLE_EQ(r.stateAccuracy(), 1.0);
  EXPECT_DOUBLE_EQ(r.angleMaeDeg(), 0.0);
  EXPECT_DOUBLE_EQ(r.hingeErrorMeanM(), 0.0);
  EXPECT_DOUBLE_EQ(r.hingeErrorMedianM(), 0.0);
  EXPECT_TRUE(r.missed_truth.empty());
  EXPECT_TRUE(r.unmatched_report.empty());
}

TEST(Evaluation, VerticalOffsetIgnoredZUp) {
  EvalResult r = single(vec(0.49, 0, 2.0));
  ASSERT_EQ(r.matched, 1);
  EXPECT_NEAR(r.matches[0].center_distance_m, 0.49, 1e-12);
}

TEST(Evaluation, VerticalOffsetIgnoredCameraFrameYDown) {
  // Camera frame: up = -y, so a 2 m offset along y is vertical.
  EvalResult r = single(vec(0.49, 2.0, 0), vec(0, -1, 0));
  ASSERT_EQ(r.matched, 1);
  EXPECT_NEAR(r.matches[0].center_distance_m, 0.49, 1e-12);
  // Same offset with horizontal x/z split, and non-unit up gets normalised.
  r = single(vec(0.24, -2.0, 0.32), vec(0, -3, 0));
  ASSERT_EQ(r.matched, 1);
  EXPECT_NEAR(r.matches[0].center_distance_m, 0.4, 1e-12);
  // With the default z-up, the y offset is horizontal: no match.
  EXPECT_EQ(single(vec(0.49, 2.0, 0)).matched, 0);
}

TEST(Evaluation, MissingUpDefaultsToZ) {
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 0), 0, "closed")});
  t.erase("up");
  json r = reportDoc({reportDoor(0, vec(0.2, 0, 3.0), vec(0, 0, 0), 0, "closed")});
  EXPECT_EQ(evaluate(t, r).matched, 1);
}

TEST(Evaluation, TooFarDoesNotMatch) {
  EvalResult r = single(vec(0.51, 0, 0));
  EXPECT_EQ(r.matched, 0);
  EXPECT_EQ(r.missed_truth, std::vector<int>{0});
  EXPECT_EQ(r.unmatched_report, std::vector<int>{0});
  EXPECT_DOUBLE_EQ(r.precision(), 0.0);
  EXPECT_DOUBLE_EQ(r.recall(), 0.0);
  EXPECT_TRUE(std::isnan(r.stateAccuracy()));
  // A larger threshold lets it match.
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 0), 0, "closed")});
  json rep = reportDoc({reportDoor(0, vec(0.51, 0, 0), vec(0, 0, 0), 0, "closed")});
  EXPECT_EQ(evaluate(t, rep, 0.6).matched, 1);
  EXPECT_THROW(evaluate(t, rep, -0.1), std::invalid_argument);
}

TEST(Evaluation, CrossedOrderMatchesNearest) {
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 0), 0, "closed"),
                     truthDoor(vec(3, 0, 0), vec(3, 0, 0), 90, "open")});
  json r = reportDoc({reportDoor(0, vec(3.1, 0, 0), vec(3, 0, 0), 90, "open"),
                      reportDoor(1, vec(0.2, 0, 0), vec(0, 0, 0), 0, "closed")});
  EvalResult res = evaluate(t, r, 5.0);
  ASSERT_EQ(res.matched, 2);
  EXPECT_EQ(res.matches[0].truth_index, 0);
  EXPECT_EQ(res.matches[0].report_index, 1);
  EXPECT_EQ(res.matches[1].truth_index, 1);
  EXPECT_EQ(res.matches[1].report_index, 0);
  EXPECT_EQ(res.state_correct, 2);
}

TEST(Evaluation, GreedyTakesGloballyNearestPairFirst) {
  // Truth 0 at x=0, truth 1 at x=1; report 0 at x=0.7 is nearest to truth 1 (0.3),
  // so truth 1 takes it even though truth 0 comes first; truth 0 gets report 1.
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 0), 0, "closed"),
                     truthDoor(vec(1, 0, 0), vec(1, 0, 0), 0, "closed")});
  json r = reportDoc({reportDoor(0, vec(0.7, 0, 0), vec(0, 0, 0), 0, "closed"),
                      reportDoor(1, vec(1.5, 0, 0), vec(0, 0, 0), 0, "closed")});
  EvalResult res = evaluate(t, r, 2.0);
  ASSERT_EQ(res.matched, 2);
  EXPECT_EQ(res.matches[0].report_index, 1);
  EXPECT_NEAR(res.matches[0].center_distance_m, 1.5, 1e-12);
  EXPECT_EQ(res.matches[1].report_index, 0);
  EXPECT_NEAR(res.matches[1].center_distance_m, 0.3, 1e-12);
}

TEST(Evaluation, TiesBrokenByLowerIndex) {
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 0), 0, "closed")});
  json r = reportDoc({reportDoor(0, vec(0.2, 0, 0), vec(0, 0, 0), 0, "closed"),
                      reportDoor(1, vec(-0.2, 0, 0), vec(0, 0, 0), 0, "closed")});
  EvalResult res = evaluate(t, r);
  ASSERT_EQ(res.matched, 1);
  EXPECT_EQ(res.matches[0].report_index, 0);
  EXPECT_EQ(res.unmatched_report, std::vector<int>{1});
}

TEST(Evaluation, FalsePositiveHalvesPrecision) {
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 0), 0, "closed")});
  json r = reportDoc({reportDoor(0, vec(0, 0, 0), vec(0, 0, 0), 0, "closed"),
                      reportDoor(1, vec(5, 5, 0), vec(5, 5, 0), 0, "closed")});
  EvalResult res = evaluate(t, r);
  EXPECT_DOUBLE_EQ(res.precision(), 0.5);
  EXPECT_DOUBLE_EQ(res.recall(), 1.0);
  EXPECT_EQ(res.unmatched_report, std::vector<int>{1});
}

TEST(Evaluation, MissedDoorLowersRecall) {
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 0), 0, "closed"),
                     truthDoor(vec(4, 0, 0), vec(4, 0, 0), 0, "closed"),
                     truthDoor(vec(8, 0, 0), vec(8, 0, 0), 0, "closed")});
  json r = reportDoc({reportDoor(0, vec(4, 0, 0), vec(4, 0, 0), 0, "closed")});
  EvalResult res = evaluate(t, r);
  EXPECT_DOUBLE_EQ(res.precision(), 1.0);
  EXPECT_NEAR(res.recall(), 1.0 / 3.0, 1e-12);
  EXPECT_EQ(res.missed_truth, (std::vector<int>{0, 2}));
}

TEST(Evaluation, WrongStateStillMatched) {
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 0), 10, "semi_open"),
                     truthDoor(vec(4, 0, 0), vec(4, 0, 0), 0, "closed")});
  json r = reportDoc({reportDoor(0, vec(0, 0, 0), vec(0, 0, 0), 10, "open"),
                      reportDoor(1, vec(4, 0, 0), vec(4, 0, 0), 0, "closed")});
  EvalResult res = evaluate(t, r);
  EXPECT_EQ(res.matched, 2);
  EXPECT_EQ(res.state_correct, 1);
  EXPECT_FALSE(res.matches[0].state_correct);
  EXPECT_TRUE(res.matches[1].state_correct);
  EXPECT_DOUBLE_EQ(res.stateAccuracy(), 0.5);
  EXPECT_DOUBLE_EQ(res.precision(), 1.0);
  EXPECT_DOUBLE_EQ(res.recall(), 1.0);
}

TEST(Evaluation, AngleAndHingeErrors) {
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 1), 30, "semi_open"),
                     truthDoor(vec(4, 0, 0), vec(4, 0, 1), 90, "open"),
                     truthDoor(vec(8, 0, 0), vec(8, 0, 1), 0, "closed")});
  json r = reportDoc({reportDoor(0, vec(0, 0, 0), vec(0.3, 0.4, 1), 40, "semi_open"),    // 10 deg, 0.5 m
                      reportDoor(1, vec(4, 0, 0), vec(4, 0, 1.1), 85, "open"),           // 5 deg, 0.1 m
                      reportDoor(2, vec(8, 0, 0), vec(8, 0.2, 1.2), 0, "closed")});      // 0 deg, sqrt(0.08)
  EvalResult res = evaluate(t, r);
  ASSERT_EQ(res.matched, 3);
  EXPECT_NEAR(res.matches[0].angle_error_deg, 10.0, 1e-9);
  EXPECT_NEAR(res.matches[1].angle_error_deg, 5.0, 1e-9);
  EXPECT_NEAR(res.matches[0].hinge_error_m, 0.5, 1e-12);
  EXPECT_NEAR(res.matches[1].hinge_error_m, 0.1, 1e-12);
  EXPECT_NEAR(res.matches[2].hinge_error_m, std::sqrt(0.08), 1e-12);
  EXPECT_NEAR(res.angleMaeDeg(), 5.0, 1e-9);
  EXPECT_NEAR(res.hingeErrorMeanM(), (0.5 + 0.1 + std::sqrt(0.08)) / 3.0, 1e-12);
  EXPECT_NEAR(res.hingeErrorMedianM(), std::sqrt(0.08), 1e-12);
  // Even count: median is the mean of the two middle values.
  EvalResult two = evaluate(truthDoc({t["doors"][0], t["doors"][1]}), reportDoc({r["doors"][0], r["doors"][1]}));
  EXPECT_NEAR(two.hingeErrorMedianM(), 0.3, 1e-12);
}

TEST(Evaluation, EmptyReport) {
  EvalResult res = evaluate(truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 0), 0, "closed")}),
                            reportDoc(json::array()));
  EXPECT_EQ(res.reported_doors, 0);
  EXPECT_DOUBLE_EQ(res.precision(), 1.0);
  EXPECT_DOUBLE_EQ(res.recall(), 0.0);
  EXPECT_TRUE(std::isnan(res.stateAccuracy()));
  EXPECT_TRUE(std::isnan(res.angleMaeDeg()));
  EXPECT_TRUE(std::isnan(res.hingeErrorMeanM()));
  EXPECT_TRUE(std::isnan(res.hingeErrorMedianM()));
  EXPECT_EQ(res.missed_truth, std::vector<int>{0});
}

TEST(Evaluation, EmptyTruth) {
  EvalResult res = evaluate(truthDoc(json::array()), reportDoc({reportDoor(0, vec(0, 0, 0), vec(0, 0, 0), 0, "open")}));
  EXPECT_DOUBLE_EQ(res.precision(), 0.0);
  EXPECT_DOUBLE_EQ(res.recall(), 1.0);
  EXPECT_EQ(res.unmatched_report, std::vector<int>{0});
  EvalResult none = evaluate(truthDoc(json::array()), reportDoc(json::array()));
  EXPECT_DOUBLE_EQ(none.precision(), 1.0);
  EXPECT_DOUBLE_EQ(none.recall(), 1.0);
  EXPECT_TRUE(std::isnan(none.stateAccuracy()));
}

TEST(Evaluation, ToJsonNaNBecomesNull) {
  json j = dsr::eval::toJson(evaluate(truthDoc(json::array()), reportDoc(json::array())));
  EXPECT_EQ(j["true_doors"], 0);
  EXPECT_EQ(j["precision"], 1.0);
  EXPECT_EQ(j["recall"], 1.0);
  for (const char* k : {"state_accuracy", "angle_mae_deg", "hinge_error_mean_m", "hinge_error_median_m"})
    EXPECT_TRUE(j.at(k).is_null()) << k;
  EXPECT_TRUE(j["matches"].is_array() && j["matches"].empty());
  EXPECT_TRUE(j["missed_truth"].is_array());
  EXPECT_TRUE(j["unmatched_report"].is_array());

  json m = dsr::eval::toJson(single(vec(0.3, 0, 0)));
  EXPECT_EQ(m["matched"], 1);
  EXPECT_EQ(m["state_correct"], 1);
  EXPECT_DOUBLE_EQ(m["state_accuracy"].get<double>(), 1.0);
  ASSERT_EQ(m["matches"].size(), 1u);
  EXPECT_EQ(m["matches"][0]["truth_index"], 0);
  EXPECT_EQ(m["matches"][0]["report_index"], 0);
  EXPECT_NEAR(m["matches"][0]["center_distance_m"].get<double>(), 0.3, 1e-12);
  EXPECT_EQ(m["matches"][0]["state_correct"], true);
}

TEST(Evaluation, MergeAddsCounts) {
  EvalResult a = single(vec(0, 0, 0));      // 1 true, 1 reported, matched
  EvalResult b = single(vec(0.51, 0, 0));   // 1 true, 1 reported, not matched
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 0), 0, "closed")});
  EvalResult c = evaluate(t, reportDoc({reportDoor(0, vec(0, 0, 0), vec(0, 0.2, 0), 20, "open")}));
  EvalResult m = dsr::eval::merge({a, b, c});
  EXPECT_EQ(m.true_doors, 3);
  EXPECT_EQ(m.reported_doors, 3);
  EXPECT_EQ(m.matched, 2);
  EXPECT_EQ(m.state_correct, 1);
  EXPECT_EQ(m.matches.size(), 2u);
  EXPECT_EQ(m.missed_truth.size(), 1u);
  EXPECT_EQ(m.unmatched_report.size(), 1u);
  EXPECT_NEAR(m.precision(), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(m.stateAccuracy(), 0.5, 1e-12);
  EXPECT_NEAR(m.angleMaeDeg(), 10.0, 1e-12);
  EXPECT_NEAR(m.hingeErrorMeanM(), 0.1, 1e-12);
  EvalResult e = dsr::eval::merge({});
  EXPECT_EQ(e.true_doors, 0);
  EXPECT_DOUBLE_EQ(e.precision(), 1.0);
}

TEST(Evaluation, MalformedInputThrows) {
  json good_t = truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 0), 0, "closed")});
  json good_r = reportDoc({reportDoor(0, vec(0, 0, 0), vec(0, 0, 0), 0, "closed")});
  ASSERT_NO_THROW(evaluate(good_t, good_r));

  auto expectThrow = [](const json& t, const json& r, const std::string& needle) {
    try {
      evaluate(t, r);
      ADD_FAILURE() << "no exception, expected one mentioning " << needle;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  json t = good_t;
  t["doors"] = json::object();
  expectThrow(t, good_r, "truth.doors");
  json r = good_r;
  r["doors"] = "none";
  expectThrow(good_t, r, "report.doors");
  r = good_r;
  r.erase("doors");
  expectThrow(good_t, r, "report.doors");
  t = good_t;
  t["doors"][0].erase("opening_center");
  expectThrow(t, good_r, "truth.doors[0].opening_center");
  r = good_r;
  r["doors"][0]["opening_center"] = json::array({1.0, 2.0});
  expectThrow(good_t, r, "report.doors[0].opening_center");
  r = good_r;
  r["doors"][0]["hinge"] = json::array({1.0, "a", 2.0});
  expectThrow(good_t, r, "report.doors[0].hinge[1]");
  r = good_r;
  r["doors"][0]["state"] = 3;
  expectThrow(good_t, r, "report.doors[0].state");
  r = good_r;
  r["doors"][0]["opening_angle_deg"] = "30";
  expectThrow(good_t, r, "report.doors[0].opening_angle_deg");
  r = good_r;
  r["doors"][0] = 5;
  expectThrow(good_t, r, "report.doors[0]");
  t = good_t;
  t["up"] = vec(0, 0, 0);
  expectThrow(t, good_r, "truth.up");
  expectThrow(json::array(), good_r, "truth");
  expectThrow(good_t, json(nullptr), "report");
}

TEST(Evaluation, AnglesGivenAsLowerBoundsCountInTheMaeButNotTheMeasuredMae) {
  // Two doors: one measured 2 deg off, one whose leaf was unseen, reported
  // at its free-space bound 95 deg against a true 110 (15 deg off).
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(-0.45, 0, 0), 30, "semi_open"),
                     truthDoor(vec(3, 0, 0), vec(2.55, 0, 0), 110, "open")});
  json bound = reportDoor(1, vec(3, 0, 0), vec(2.55, 0, 0), 95, "open");
  bound["angle_is_lower_bound"] = true;
  json r = reportDoc({reportDoor(0, vec(0, 0, 0), vec(-0.45, 0, 0), 32, "semi_open"), bound});
  const EvalResult res = evaluate(t, r);
  ASSERT_EQ(res.matched, 2);
  EXPECT_EQ(res.state_correct, 2);
  EXPECT_FALSE(res.matches[0].angle_is_lower_bound);
  EXPECT_TRUE(res.matches[1].angle_is_lower_bound);
  EXPECT_NEAR(res.angleMaeDeg(), 8.5, 1e-9);
  EXPECT_NEAR(res.angleMaeMeasuredDeg(), 2.0, 1e-9);
  const json j = dsr::eval::toJson(res);
  EXPECT_EQ(j["angle_lower_bounds"], 1);
  EXPECT_NEAR(j["angle_mae_measured_deg"].get<double>(), 2.0, 1e-9);
  // Without the field every angle counts as measured.
  EXPECT_NEAR(single(vec(0, 0, 0)).angleMaeMeasuredDeg(), 0.0, 1e-12);
}

// Truth must be simulator ground truth ("scene") and the report a pipeline
// report ("points_in"): swapped or twice the same document is refused rather
// than scored (a report scored as truth gave a score, e.g. precision 0.5).
TEST(Evaluation, SwappedOrWrongDocumentsAreRefused) {
  const json t = truthDoc({truthDoor(vec(0, 0, 0), vec(0, 0, 0), 0, "closed")});
  const json r = reportDoc({reportDoor(0, vec(0, 0, 0), vec(0, 0, 0), 0, "closed")});
  ASSERT_NO_THROW(evaluate(t, r));
  auto message = [](const json& a, const json& b) -> std::string {
    try {
      evaluate(a, b);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no exception";
  };
  EXPECT_EQ(message(r, t).rfind("truth: ", 0), 0u) << message(r, t);
  EXPECT_NE(message(r, t).find("arguments swapped?"), std::string::npos) << message(r, t);
  EXPECT_NE(message(r, r).find("a report, not simulator ground truth"), std::string::npos) << message(r, r);
  EXPECT_NE(message(t, t).find("report: has \"scene\""), std::string::npos) << message(t, t);
  json bare_t = t, bare_r = r;
  bare_t.erase("scene");
  bare_r.erase("points_in");
  EXPECT_NE(message(bare_t, r).find("truth: missing field \"scene\""), std::string::npos) << message(bare_t, r);
  EXPECT_NE(message(t, bare_r).find("report: missing field \"points_in\""), std::string::npos) << message(t, bare_r);
}

// Issue 20: a door reported NOT_CLOSED (leaf unseen, bound under
// open_from_deg) is found but never in a right state; the count of such
// reports is kept, including one that matches no door (a false door).
TEST(Evaluation, NotClosedCountsAsFoundButNeverAsARightState) {
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(-0.45, 0, 0), 40, "semi_open"),
                     truthDoor(vec(3, 0, 0), vec(2.55, 0, 0), 110, "open"),
                     truthDoor(vec(6, 0, 0), vec(5.55, 0, 0), 0, "closed")});
  json nc0 = reportDoor(0, vec(0, 0, 0), vec(-0.45, 0, 0), 30, "not_closed");
  nc0["angle_is_lower_bound"] = true;
  json nc1 = reportDoor(1, vec(3, 0, 0), vec(2.55, 0, 0), 60, "not_closed");
  nc1["angle_is_lower_bound"] = true;
  json stray = reportDoor(2, vec(9, 0, 0), vec(8.55, 0, 0), 20, "not_closed");
  stray["angle_is_lower_bound"] = true;
  json r = reportDoc({nc0, nc1, reportDoor(3, vec(6, 0, 0), vec(5.55, 0, 0), 1, "closed"), stray});
  const EvalResult res = evaluate(t, r);
  EXPECT_EQ(res.true_doors, 3);
  EXPECT_EQ(res.reported_doors, 4);
  EXPECT_EQ(res.matched, 3);
  EXPECT_DOUBLE_EQ(res.recall(), 1.0);
  EXPECT_EQ(res.state_correct, 1);  // only the closed door
  EXPECT_EQ(res.not_closed, 3);     // every report in that state, the stray one too
  EXPECT_EQ(res.bound_errors, 0);
  ASSERT_EQ(res.matches.size(), 3u);
  EXPECT_TRUE(res.matches[0].not_closed);
  EXPECT_FALSE(res.matches[0].state_correct);
  EXPECT_FALSE(res.matches[2].not_closed);
  EXPECT_NEAR(res.stateAccuracy(), 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(res.stateAccuracyMeasured(), 1.0, 1e-12);  // the one measured leaf
  const json j = dsr::eval::toJson(res);
  EXPECT_EQ(j["not_closed"], 3);
  EXPECT_EQ(j["bound_errors"], 0);
  EXPECT_NEAR(j["state_accuracy_measured"].get<double>(), 1.0, 1e-12);
  EXPECT_EQ(j["matches"][0]["not_closed"], true);
  // A truth document that says "not_closed" is no excuse: still not a right state.
  json t2 = truthDoc({truthDoor(vec(0, 0, 0), vec(-0.45, 0, 0), 40, "not_closed")});
  EXPECT_EQ(evaluate(t2, reportDoc({nc0})).state_correct, 0);
  // merge adds the counts.
  const EvalResult m = dsr::eval::merge({res, res});
  EXPECT_EQ(m.not_closed, 6);
  EXPECT_EQ(m.matched, 6);
}

TEST(Evaluation, ALowerBoundAboveTheTrueAngleIsABoundError) {
  // Bounds of 44 (true 43: within the bound's 2 deg step, no error), 50
  // (true 40: an error), 95 given as a measured angle (true 60: not a bound,
  // so an angle error only), 91 as a bound of a door at 100 (no error).
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(-0.45, 0, 0), 43, "semi_open"),
                     truthDoor(vec(3, 0, 0), vec(2.55, 0, 0), 40, "semi_open"),
                     truthDoor(vec(6, 0, 0), vec(5.55, 0, 0), 60, "semi_open"),
                     truthDoor(vec(9, 0, 0), vec(8.55, 0, 0), 100, "open")});
  auto bound = [](json d) {
    d["angle_is_lower_bound"] = true;
    return d;
  };
  json r = reportDoc({bound(reportDoor(0, vec(0, 0, 0), vec(-0.45, 0, 0), 44, "not_closed")),
                      bound(reportDoor(1, vec(3, 0, 0), vec(2.55, 0, 0), 50, "not_closed")),
                      reportDoor(2, vec(6, 0, 0), vec(5.55, 0, 0), 95, "open"),
                      bound(reportDoor(3, vec(9, 0, 0), vec(8.55, 0, 0), 91, "open"))});
  const EvalResult res = evaluate(t, r);
  ASSERT_EQ(res.matched, 4);
  EXPECT_EQ(res.bound_errors, 1);
  EXPECT_FALSE(res.matches[0].bound_error);
  EXPECT_TRUE(res.matches[1].bound_error);
  EXPECT_FALSE(res.matches[2].bound_error);
  EXPECT_FALSE(res.matches[3].bound_error);
  EXPECT_EQ(res.state_correct, 1);  // the open bound; the measured 95 is "open" for a semi-open door
  EXPECT_NEAR(res.stateAccuracyMeasured(), 0.0, 1e-12);
  EXPECT_EQ(dsr::eval::toJson(res)["bound_errors"], 1);
  EXPECT_EQ(dsr::eval::toJson(res)["matches"][1]["bound_error"], true);
}

TEST(Evaluation, ANotClosedReportOfADoorOutOfViewCountsNeitherWay) {
  json t = truthDoc({truthDoor(vec(0, 0, 0), vec(-0.45, 0, 0), 40, "semi_open")});
  t["doors"][0]["in_view"] = false;
  json nc = reportDoor(0, vec(0, 0, 0), vec(-0.45, 0, 0), 30, "not_closed");
  nc["angle_is_lower_bound"] = true;
  const EvalResult res = evaluate(t, reportDoc({nc}), 0.5, true);
  EXPECT_EQ(res.reported_doors, 0);
  EXPECT_EQ(res.not_closed, 0);
  EXPECT_TRUE(std::isnan(res.stateAccuracyMeasured()));
}

// Issue 21: with min_leaf_in_view, only truth doors whose leaf a camera sees
// (leaf_in_view >= the share) are scored; a door whose leaf is hidden is
// neither missed nor, when reported, a false positive.
TEST(Evaluation, LeafInViewOnlyScoresTheDoorsWhoseLeafIsSeen) {
  json seen = truthDoor(vec(0, 0, 0), vec(-0.45, 0, 0), 30, "semi_open");
  json hidden = truthDoor(vec(3, 0, 0), vec(2.55, 0, 0), 60, "semi_open");
  json missed_hidden = truthDoor(vec(6, 0, 0), vec(5.55, 0, 0), 0, "closed");
  seen["leaf_in_view"] = 0.8;
  hidden["leaf_in_view"] = 0.1;
  missed_hidden["leaf_in_view"] = 0.0;
  const json t = truthDoc({seen, hidden, missed_hidden});
  const json r = reportDoc({reportDoor(0, vec(0, 0, 0), vec(-0.45, 0, 0), 32, "semi_open"),
                            reportDoor(1, vec(3, 0, 0), vec(2.55, 0, 0), 20, "semi_open")});
  const EvalResult all = evaluate(t, r);
  EXPECT_EQ(all.true_doors, 3);
  EXPECT_EQ(all.matched, 2);
  const EvalResult leaf = evaluate(t, r, 0.5, false, 0.5);
  EXPECT_EQ(leaf.true_doors, 1);
  EXPECT_EQ(leaf.reported_doors, 1);
  EXPECT_EQ(leaf.matched, 1);
  EXPECT_DOUBLE_EQ(leaf.precision(), 1.0);
  EXPECT_DOUBLE_EQ(leaf.recall(), 1.0);
  EXPECT_DOUBLE_EQ(leaf.angleMaeDeg(), 2.0);
  EXPECT_TRUE(leaf.missed_truth.empty());
  EXPECT_TRUE(leaf.unmatched_report.empty());
  // A share of 0.05 keeps the door seen a little; 0 keeps every door.
  EXPECT_EQ(evaluate(t, r, 0.5, false, 0.05).true_doors, 2);
  EXPECT_EQ(evaluate(t, r, 0.5, false, 0.0).true_doors, 3);
  // Both filters: a door out of view is left out whatever its leaf.
  json t2 = t;
  t2["doors"][0]["in_view"] = false;
  EXPECT_EQ(evaluate(t2, r, 0.5, true, 0.5).true_doors, 0);
  EXPECT_EQ(evaluate(t2, r, 0.5, true, 0.5).reported_doors, 0);
  // Truth without the field (a laser scan's) or an absurd share is refused.
  json t3 = t;
  t3["doors"][1].erase("leaf_in_view");
  EXPECT_THROW(evaluate(t3, r, 0.5, false, 0.5), std::invalid_argument);
  EXPECT_NO_THROW(evaluate(t3, r, 0.5, false, -1.0));
  EXPECT_THROW(evaluate(t, r, 0.5, false, 1.5), std::invalid_argument);
}
