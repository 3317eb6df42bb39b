// The stock-PCL baseline of the benchmark is a real baseline, not a
// strawman: on the paper's scenes (rebuilt in the simulator, seed fixed) it
// finds every door with its state, scored by the same evaluation as ours.
#include <gtest/gtest.h>

#include "door_state_recognition/baseline/stock_pcl.hpp"
#include "door_state_recognition/eval/evaluation.hpp"
#include "door_state_recognition/io/report.hpp"
#include "door_state_recognition/sim/ground_truth.hpp"
#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/sim/sensors.hpp"

using namespace dsr;

namespace {

struct BaselineRun {
  PipelineResult result;
  nlohmann::json truth;
  eval::EvalResult eval;
};

BaselineRun runPaperScene(const std::string& name, std::uint64_t seed) {
  const sim::Scene scene = sim::buildScene(sim::paperRoom(name));
  sim::TlsOptions o;
  o.points = 300000;
  o.seed = seed;
  const sim::SimulatedCloud sc = sim::scanTls(scene, o);
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (const auto& q : sc.cloud) cloud.push_back(pcl::PointXYZ(q.x, q.y, q.z));
  BaselineRun r;
  r.truth = sim::groundTruthJson(scene, sc);
  r.result = baseline::runStockPcl(cloud, Parameters());
  r.eval = eval::evaluate(r.truth, io::reportJson(r.result, name), 0.5, true);
  return r;
}

std::string describe(const BaselineRun& r) {
  std::string s = "truth:";
  for (const auto& d : r.truth["doors"])
    s += " " + d["state"].get<std::string>() + "@" + std::to_string(d["opening_angle_deg"].get<double>());
  s += " | stock-PCL baseline:";
  for (const auto& d : r.result.doors) s += std::string(" ") + toString(d.state) + "@" + std::to_string(d.opening_angle_deg);
  return s;
}

}  // namespace

TEST(StockPclBaseline, FindsTheDoorsOfThePaperScenesWithTheirStates) {
  const std::uint64_t seed = 11;
  for (const std::string name : {"paper_livingroom", "paper_house", "paper_multidoor"}) {
    SCOPED_TRACE(name + " seed=" + std::to_string(seed));
    const BaselineRun r = runPaperScene(name, seed);
    SCOPED_TRACE(describe(r));
    ASSERT_GT(r.eval.true_doors, 0);
    EXPECT_GE(r.result.walls.size(), 3u);
    EXPECT_EQ(r.eval.matched, r.eval.true_doors);          // every door found
    EXPECT_EQ(r.eval.reported_doors, r.eval.matched);      // and nothing else
    EXPECT_EQ(r.eval.state_correct, r.eval.matched);       // with its state
    EXPECT_LT(r.eval.angleMaeDeg(), 6.0);
  }
}

TEST(StockPclBaseline, ReportsTheSameStagesAsOurs) {
  const BaselineRun r = runPaperScene("paper_livingroom", 11);
  std::vector<std::string> names;
  for (const auto& kv : r.result.timing_ms) names.push_back(kv.first);
  const std::vector<std::string> expected = {"preprocess", "normals", "floor_ceiling", "walls", "doors", "segments",
                                             "boundary", "total"};
  EXPECT_EQ(names, expected);
  EXPECT_NEAR(r.result.up.z(), 1.0, 1e-3);
  ASSERT_TRUE(r.result.floor.has_value());
  ASSERT_TRUE(r.result.ceiling.has_value());
  EXPECT_NEAR(*r.result.ceiling - *r.result.floor, 2.33, 0.05);
}

TEST(StockPclBaseline, RefusesAutoUpAxis) {
  Parameters p;
  p.up_axis = "auto";
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back(pcl::PointXYZ(0, 0, 0));
  EXPECT_THROW(baseline::runStockPcl(cloud, p), std::invalid_argument);
}
