// The plan SVG (dsr::io::planSvg, door_state_cli --svg) checked against the
// report it draws and the truth of simulated scenes: an element per wall and
// per door, every leaf at its hinge and angle in the plan's metre transform,
// coloured by state, a lower bound dashed, well-formed XML.
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "door_state_recognition/io/report.hpp"
#include "door_state_recognition/io/svg.hpp"
#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/sim/ground_truth.hpp"
#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/sim/sensors.hpp"
#include "run_command.hpp"

#include <unistd.h>

using namespace dsr;

namespace {

// An element: its tag name and attributes.
struct Element {
  std::string name;
  std::map<std::string, std::string> attr;
  std::string text;  // for <text>: its content
};

// Parses the document into elements, checking that every tag closes in
// order, attributes are quoted and '&' starts an entity. Fails the test
// (and returns what it has) on the first fault.
std::vector<Element> parseXml(const std::string& doc) {
  std::vector<Element> out;
  std::vector<std::string> open;
  std::size_t i = 0;
  EXPECT_EQ(doc.rfind("<?xml", 0), 0u) << "no XML declaration";
  static const std::regex entity("^&(amp|lt|gt|quot|apos|#[0-9]+|#x[0-9a-fA-F]+);");
  for (std::size_t k = 0; k < doc.size(); ++k)
    if (doc[k] == '&') {
      const std::string rest = doc.substr(k, 12);
      EXPECT_TRUE(std::regex_search(rest, entity)) << "bare & at " << k << ": " << rest;
    }
  while ((i = doc.find('<', i)) != std::string::npos) {
    const std::size_t end = doc.find('>', i);
    if (end == std::string::npos) {
      ADD_FAILURE() << "unterminated tag at " << i;
      break;
    }
    std::string tag = doc.substr(i + 1, end - i - 1);
    const std::size_t text_start = end + 1;
    i = end + 1;
    if (tag.empty()) {
      ADD_FAILURE() << "empty tag";
      continue;
    }
    if (tag[0] == '?' || tag[0] == '!') continue;
    if (tag[0] == '/') {
      if (open.empty() || open.back() != tag.substr(1)) {
        ADD_FAILURE() << "</" << tag.substr(1) << "> closes " << (open.empty() ? "nothing" : "<" + open.back() + ">");
        return out;
      }
      open.pop_back();
      continue;
    }
    const bool self_closing = tag.back() == '/';
    if (self_closing) tag.pop_back();
    Element e;
    std::istringstream is(tag);
    is >> e.name;
    // Attributes by hand (std::regex recurses per character and overflows the
    // stack on a long path): name="value", separated by white space.
    const std::string rest = tag.substr(e.name.size());
    std::size_t k = 0;
    while (k < rest.size()) {
      if (std::isspace(static_cast<unsigned char>(rest[k]))) {
        ++k;
        continue;
      }
      const std::size_t eq = rest.find('=', k);
      const bool quoted = eq != std::string::npos && eq + 1 < rest.size() && rest[eq + 1] == '"';
      const std::size_t close = quoted ? rest.find('"', eq + 2) : std::string::npos;
      const std::string name = eq == std::string::npos ? rest.substr(k) : rest.substr(k, eq - k);
      const bool name_ok = !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == ':' || c == '.';
      });
      if (!quoted || close == std::string::npos || !name_ok) {
        ADD_FAILURE() << "<" << e.name << "> has a malformed attribute at: " << rest.substr(k, 40);
        break;
      }
      const std::string value = rest.substr(eq + 2, close - eq - 2);
      EXPECT_EQ(value.find('<'), std::string::npos) << "'<' in attribute " << name;
      EXPECT_EQ(e.attr.count(name), 0u) << "attribute " << name << " twice";
      e.attr[name] = value;
      k = close + 1;
    }
    if (e.name == "text") e.text = doc.substr(text_start, doc.find('<', text_start) - text_start);
    out.push_back(e);
    if (!self_closing) open.push_back(e.name);
  }
  EXPECT_TRUE(open.empty()) << "unclosed <" << (open.empty() ? "" : open.back()) << ">";
  EXPECT_FALSE(out.empty());
  if (!out.empty()) {
    EXPECT_EQ(out.front().name, "svg");
  }
  return out;
}

Eigen::Vector3d vec3(const std::string& s) {
  std::istringstream is(s);
  Eigen::Vector3d v;
  is >> v.x() >> v.y() >> v.z();
  return v;
}

double num(const Element& e, const std::string& key) {
  const auto it = e.attr.find(key);
  if (it == e.attr.end()) {
    ADD_FAILURE() << "<" << e.name << "> has no " << key;
    return std::nan("");
  }
  return std::stod(it->second);
}

std::vector<const Element*> byClass(const std::vector<Element>& els, const std::string& cls, const std::string& key = "",
                                    const std::string& value = "") {
  std::vector<const Element*> out;
  for (const auto& e : els) {
    const auto c = e.attr.find("class");
    if (c == e.attr.end() || c->second != cls) continue;
    if (!key.empty() && (e.attr.count(key) == 0 || e.attr.at(key) != value)) continue;
    out.push_back(&e);
  }
  return out;
}

pcl::PointCloud<pcl::PointXYZ> xyz(const pcl::PointCloud<pcl::PointXYZL>& in) {
  pcl::PointCloud<pcl::PointXYZ> out;
  for (const auto& p : in.points) out.points.emplace_back(p.x, p.y, p.z);
  out.width = static_cast<std::uint32_t>(out.size());
  out.height = 1;
  return out;
}

// Checks `doc` against `result`: one wall element per wall, one leaf, hinge,
// swing and label per door, in the plan's metre transform, at the report's
// hinge and latch and at its angle, coloured by its state.
void checkAgainstReport(const std::string& doc, const PipelineResult& result, const std::string& where) {
  SCOPED_TRACE(where);
  const std::vector<Element> els = parseXml(doc);
  ASSERT_FALSE(els.empty());
  const Element& root = els.front();
  const Eigen::Vector3d up = vec3(root.attr.at("data-plan-up")), u = vec3(root.attr.at("data-plan-u")),
                        v = vec3(root.attr.at("data-plan-v"));
  EXPECT_NEAR(up.dot(result.up.normalized()), 1.0, 1e-5);
  EXPECT_NEAR(u.dot(up), 0.0, 1e-5);
  EXPECT_NEAR(u.cross(v).dot(up), 1.0, 1e-5) << "u x v must be up: a view from above";
  // The group in metres: translate(ox,oy) scale(s,-s), s the root's pixels a metre.
  const Element* plan = nullptr;
  for (const auto& e : els)
    if (e.attr.count("id") && e.attr.at("id") == "plan") plan = &e;
  ASSERT_NE(plan, nullptr);
  const double s = num(root, "data-pixels-per-metre");
  std::smatch m;
  const std::string tr = plan->attr.at("transform");
  ASSERT_TRUE(std::regex_search(tr, m, std::regex("scale\\(([-0-9.]+),([-0-9.]+)\\)"))) << tr;
  EXPECT_NEAR(std::stod(m[1]), s, 1e-3);
  EXPECT_NEAR(std::stod(m[2]), -s, 1e-3);
  const auto bars = byClass(els, "scale-bar");
  ASSERT_EQ(bars.size(), 1u);
  EXPECT_NEAR(num(*bars[0], "data-px"), num(*bars[0], "data-metres") * s, 0.02);

  auto plan2 = [&](const Eigen::Vector3d& p) { return Eigen::Vector2d(p.dot(u), p.dot(v)); };
  std::set<std::string> wall_ids;
  for (const auto* w : byClass(els, "wall")) wall_ids.insert(w->attr.at("data-wall"));
  EXPECT_EQ(byClass(els, "wall").size(), result.walls.size());
  for (const WallResult& w : result.walls) EXPECT_EQ(wall_ids.count(std::to_string(w.id)), 1u) << "wall " << w.id;

  for (const DoorResult& d : result.doors) {
    const std::string id = std::to_string(d.id);
    SCOPED_TRACE("door " + id);
    const auto leaf = byClass(els, "leaf", "data-door", id), hinge = byClass(els, "hinge", "data-door", id),
               swing = byClass(els, "swing", "data-door", id), label = byClass(els, "label", "data-door", id);
    ASSERT_EQ(leaf.size(), 1u);
    ASSERT_EQ(hinge.size(), 1u);
    ASSERT_EQ(label.size(), 1u);
    ASSERT_EQ(byClass(els, "doorway", "data-door", id).size(), 1u);
    const Eigen::Vector2d h = plan2(d.hinge), h0 = plan2(d.leaf_corners[0]), latch = plan2(d.leaf_corners[1]);
    EXPECT_NEAR(num(*hinge[0], "cx"), h.x(), 2e-3);
    EXPECT_NEAR(num(*hinge[0], "cy"), h.y(), 2e-3);
    EXPECT_NEAR(num(*leaf[0], "x1"), h0.x(), 2e-3);
    EXPECT_NEAR(num(*leaf[0], "y1"), h0.y(), 2e-3);
    EXPECT_NEAR(num(*leaf[0], "x2"), latch.x(), 2e-3);
    EXPECT_NEAR(num(*leaf[0], "y2"), latch.y(), 2e-3);
    EXPECT_EQ(leaf[0]->attr.at("data-state"), toString(d.state));
    EXPECT_EQ(leaf[0]->attr.at("stroke"), io::stateColour(toString(d.state)));
    EXPECT_EQ(leaf[0]->attr.count("stroke-dasharray"), d.angle_is_lower_bound ? 1u : 0u);
    EXPECT_NEAR(num(*leaf[0], "data-angle-deg"), d.opening_angle_deg, 0.051);
    // The label names id, state and angle.
    EXPECT_NE(label[0]->text.find("door " + id + ": " + toString(d.state)), std::string::npos) << label[0]->text;
    char angle[32];
    std::snprintf(angle, sizeof angle, "%.1f&#176;", d.opening_angle_deg);
    EXPECT_NE(label[0]->text.find(angle), std::string::npos) << label[0]->text;
    // The swing arc runs from the leaf closed (along the wall) to the latch:
    // the angle between the two at the hinge is the door's angle.
    ASSERT_EQ(swing.size(), 1u);
    std::smatch a;
    const std::string path = swing[0]->attr.at("d");
    ASSERT_TRUE(std::regex_match(path, a, std::regex("M([-0-9.]+) ([-0-9.]+) A([-0-9.]+) ([-0-9.]+) 0 0 [01] ([-0-9.]+) ([-0-9.]+)")))
        << path;
    const Eigen::Vector2d closed(std::stod(a[1]), std::stod(a[2])), end(std::stod(a[5]), std::stod(a[6]));
    EXPECT_NEAR((end - latch).norm(), 0.0, 2e-3);
    EXPECT_NEAR((closed - h0).norm(), (latch - h0).norm(), 2e-3);
    const Eigen::Vector2d e0 = (closed - h0).normalized(), e1 = (latch - h0).normalized();
    const double drawn = std::acos(std::clamp(e0.dot(e1), -1.0, 1.0)) * 180 / M_PI;
    EXPECT_NEAR(drawn, d.opening_angle_deg, 2.0);
  }
  EXPECT_EQ(byClass(els, "leaf").size(), result.doors.size());
}

struct SimRun {
  nlohmann::json truth;
  PipelineResult result;
  pcl::PointCloud<pcl::PointXYZ> cloud;
};

SimRun simulate(const sim::RoomSpec& spec, std::uint64_t seed) {
  const sim::Scene scene = sim::buildScene(spec);
  sim::TlsOptions o;
  o.points = 400000;
  o.seed = seed;
  const sim::SimulatedCloud c = sim::scanTls(scene, o);
  SimRun r;
  r.truth = sim::groundTruthJson(scene, c);
  r.cloud = xyz(c.cloud);
  r.result = Pipeline(Parameters()).run(r.cloud, false);
  return r;
}

}  // namespace

TEST(PlanSvg, EveryWallAndDoorIsDrawnWhereTheReportPutsItOnScenesWithKnownTruth) {
  // The paper's scenes: a closed door, an open one (110 deg), two semi-open.
  for (const std::string name : {"paper_livingroom", "paper_house", "paper_multidoor"}) {
    const std::uint64_t seed = 11;
    SCOPED_TRACE(name + " seed " + std::to_string(seed));
    const SimRun r = simulate(sim::paperRoom(name), seed);
    ASSERT_EQ(r.result.doors.size(), r.truth["doors"].size());
    io::PlanOptions opt;
    opt.title = name;
    opt.viewpoints = {Eigen::Vector3d::Zero()};
    const std::string doc = io::planSvg(r.result, {&r.cloud}, opt);
    checkAgainstReport(doc, r.result, name);
    // Each true door has a leaf drawn in its state: matched as door_state_eval
    // matches, by opening centres within 0.5 m.
    const std::vector<Element> els = parseXml(doc);
    const Eigen::Vector3d u = vec3(els.front().attr.at("data-plan-u")), v = vec3(els.front().attr.at("data-plan-v"));
    for (const auto& t : r.truth["doors"]) {
      const Eigen::Vector3d tc(t["opening_center"][0], t["opening_center"][1], t["opening_center"][2]);
      const Element* nearest = nullptr;
      double best = 1e9;
      for (const auto* c : byClass(els, "opening-center")) {
        const double dist = std::hypot(num(*c, "cx") - tc.dot(u), num(*c, "cy") - tc.dot(v));
        if (dist < best) best = dist, nearest = c;
      }
      ASSERT_NE(nearest, nullptr);
      EXPECT_LT(best, 0.5) << "no door drawn at the true " << t["state"] << " door";
      const auto leaf = byClass(els, "leaf", "data-door", nearest->attr.at("data-door"));
      ASSERT_EQ(leaf.size(), 1u);
      EXPECT_EQ(leaf[0]->attr.at("data-state"), t["state"].get<std::string>());
    }
    // The points are drawn as density, and the sensor.
    EXPECT_FALSE(byClass(els, "density").empty());
    EXPECT_EQ(byClass(els, "viewpoint").size(), 1u);
  }
}

TEST(PlanSvg, ALowerBoundIsDashedAndAnyStateNameGetsAColour) {
  const std::uint64_t seed = 11;
  SimRun r = simulate(sim::paperRoom("paper_house"), seed);
  ASSERT_FALSE(r.result.doors.empty()) << "seed " << seed;
  r.result.doors[0].angle_is_lower_bound = true;
  checkAgainstReport(io::planSvg(r.result, {&r.cloud}), r.result, "paper_house as a bound");
  std::set<std::string> colours;
  for (const char* name : {"closed", "semi_open", "open", "not_closed", "ajar", "unknown"}) {
    const std::string c = io::stateColour(name);
    EXPECT_TRUE(std::regex_match(c, std::regex("#[0-9a-f]{6}"))) << name << " " << c;
    colours.insert(c);
  }
  EXPECT_EQ(colours.size(), 6u) << "every state name a colour of its own";
  EXPECT_EQ(io::stateColour("ajar"), io::stateColour("ajar"));
}

TEST(PlanSvg, AnEmptyResultAndAHostileTitleStillGiveAWellFormedPlan) {
  PipelineResult empty;
  io::PlanOptions opt;
  opt.title = "a <b> & \"c\" \x01";
  const std::string doc = io::planSvg(empty, {}, opt);
  const auto els = parseXml(doc);
  EXPECT_TRUE(byClass(els, "wall").empty());
  EXPECT_TRUE(byClass(els, "leaf").empty());
  EXPECT_NE(doc.find("a &lt;b&gt; &amp; &quot;c&quot;"), std::string::npos);
  // A cloud of NaN and far strays only: still a plan of a sensible size.
  pcl::PointCloud<pcl::PointXYZ> odd;
  odd.points.emplace_back(std::nanf(""), 0.f, 0.f);
  for (int i = 0; i < 1000; ++i) odd.points.emplace_back(0.01f * i, 0.f, 1.f);
  odd.points.emplace_back(1e6f, 1e6f, 1.f);
  io::PlanOptions tiny;
  tiny.cell = 1e-9;  // a cell far too fine for the extent is widened, not allocated
  EXPECT_FALSE(byClass(parseXml(io::planSvg(empty, {&odd}, tiny)), "density").empty());
  const auto els2 = parseXml(io::planSvg(empty, {&odd}));
  EXPECT_LE(num(els2.front(), "width"), 1000);
  EXPECT_GT(num(els2.front(), "data-pixels-per-metre"), 50) << "one stray point 1000 km off must not shrink the plan";
}

TEST(PlanSvg, CliWritesThePlanOfItsReportAndRefusesAnUnwritablePathFirst) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("dsr_plan_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string bin = DSR_BIN_DIR, prefix = (dir / "s").string();
  ASSERT_EQ(runCommand(bin + "/door_scene_sim --quiet --scene paper_multidoor --seed 11 --out " + prefix).code, 0);
  // An --svg path that cannot be written: exit 2 at once, naming it, no report.
  const auto bad = runCommand(bin + "/door_state_cli --quiet --json " + (dir / "r0.json").string() +
                              " --svg /nonexistent/dir/p.svg " + prefix + ".pcd 2>&1");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.out.find("--svg /nonexistent/dir/p.svg: cannot write"), std::string::npos) << bad.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "r0.json"));
  // A good run: the plan holds the report's doors where the report puts them.
  const std::string svg = (dir / "p.svg").string(), json = (dir / "r.json").string();
  ASSERT_EQ(runCommand(bin + "/door_state_cli --quiet --json " + json + " --svg " + svg + " " + prefix + ".pcd").code, 0);
  std::ifstream js(json), ss(svg);
  const nlohmann::json report = nlohmann::json::parse(js);
  const std::string doc((std::istreambuf_iterator<char>(ss)), std::istreambuf_iterator<char>());
  const auto els = parseXml(doc);
  ASSERT_FALSE(els.empty());
  const Eigen::Vector3d u = vec3(els.front().attr.at("data-plan-u")), v = vec3(els.front().attr.at("data-plan-v"));
  ASSERT_EQ(report["doors"].size(), 2u) << "paper_multidoor seed 11 has two semi-open doors";
  EXPECT_EQ(byClass(els, "leaf").size(), report["doors"].size());
  EXPECT_EQ(byClass(els, "wall").size(), report["walls"].size());
  for (const auto& d : report["doors"]) {
    const std::string id = std::to_string(d["id"].get<int>());
    const auto hinge = byClass(els, "hinge", "data-door", id);
    ASSERT_EQ(hinge.size(), 1u) << "door " << id;
    const Eigen::Vector3d h(d["hinge"][0], d["hinge"][1], d["hinge"][2]);
    EXPECT_NEAR(num(*hinge[0], "cx"), h.dot(u), 2e-3);
    EXPECT_NEAR(num(*hinge[0], "cy"), h.dot(v), 2e-3);
    EXPECT_EQ(byClass(els, "leaf", "data-door", id)[0]->attr.at("data-state"), d["state"].get<std::string>());
  }
  std::filesystem::remove_all(dir);
}

TEST(PlanSvg, TheXmlCheckOfTheseTestsCatchesBrokenDocuments) {
  // The checker the tests above rely on fails on what it must catch.
  EXPECT_NONFATAL_FAILURE(parseXml("<?xml version=\"1.0\"?>\n<svg><g></svg>\n"), "closes");
  EXPECT_NONFATAL_FAILURE(parseXml("<?xml version=\"1.0\"?>\n<svg><g>\n"), "unclosed");
  EXPECT_NONFATAL_FAILURE(parseXml("<?xml version=\"1.0\"?>\n<svg a=b></svg>\n"), "malformed attribute");
  EXPECT_NONFATAL_FAILURE(parseXml("<?xml version=\"1.0\"?>\n<svg><text>a & b</text></svg>\n"), "bare &");
  EXPECT_NONFATAL_FAILURE(parseXml("<svg></svg>\n"), "declaration");
}
