// rostest driving DoorStateNodelet from the outside, as a user's node would.
// ~mode selects the suite:
//   direct  the nodelet works in the cloud's frame (~fixed_frame empty)
//   tf      the nodelet works in the fixed frame `map`
//   bag     a simulated bag is played by rosbag; ~truth is its ground truth
//   drive   a simulated drive played through door_state.launch; ~truth its truth
//   bad_params  /door_state was given bad ~ parameters, /door_state_good good ones
//   map     the nodelet has ~viewpoint none and ~fixed_frame map: a registered cloud in `map`
#include <gtest/gtest.h>
#include <pcl_conversions/pcl_conversions.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <rosgraph_msgs/Log.h>

#include <cmath>
#include <fstream>
#include <map>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <cstring>
#include <functional>

#include "door_state_recognition/DoorStateArray.h"
#include "door_state_recognition/DoorStateConfig.h"
#include "door_state_recognition/pipeline/parameters.hpp"
#include <dynamic_reconfigure/Reconfigure.h>
#include "door_state_recognition/sim/ground_truth.hpp"
#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/sim/sensors.hpp"
#include "door_state_recognition/tracking/door_tracker.hpp"

using door_state_recognition::DoorStateArray;
namespace sim = dsr::sim;

namespace {

std::string g_mode;

struct Received {
  std::mutex m;
  std::vector<DoorStateArray> doors;
  std::vector<visualization_msgs::MarkerArray> markers;
  void clear() {
    std::lock_guard<std::mutex> l(m);
    doors.clear();
    markers.clear();
  }
  std::size_t count() {
    std::lock_guard<std::mutex> l(m);
    return doors.size();
  }
};

bool waitFor(const std::function<bool()>& cond, double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (cond()) return true;
    ros::WallDuration(0.02).sleep();
  }
  return cond();
}

// A simulated laser scan of the paper's House scene (one door open at 110.6 deg).
struct SimScan {
  sim::SimulatedCloud cloud;
  nlohmann::json truth;
  sim::Scene scene;
};

SimScan simulate(const std::string& name, std::uint64_t seed) {
  SimScan s;
  s.scene = sim::buildScene(sim::paperRoom(name));
  sim::TlsOptions o;
  o.points = 300000;
  o.seed = seed;
  s.cloud = sim::scanTls(s.scene, o);
  s.truth = sim::groundTruthJson(s.scene, s.cloud);
  return s;
}

sensor_msgs::PointCloud2 toMsg(const sim::SimulatedCloud& c, const std::string& frame, double stamp) {
  sensor_msgs::PointCloud2 msg;
  pcl::toROSMsg(c.cloud, msg);
  msg.header.frame_id = frame;
  msg.header.stamp = ros::Time(stamp);
  return msg;
}

class NodeletTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // A queue as long as the burst of StaleCloudsAreDroppedUnderABurst, so
    // that no cloud is lost before it reaches the nodelet: every drop is the
    // nodelet's. (The other tests send one cloud at a time.)
    pub_ = nh_.advertise<sensor_msgs::PointCloud2>("points", 8);
  }
  // Callbacks run on spinner threads: end the subscriptions (which waits for
  // callbacks under way) before the members they write to are destroyed.
  void TearDown() override {
    doors_sub_.shutdown();
    markers_sub_.shutdown();
  }
  void listen() {
    doors_sub_ = nh_.subscribe<DoorStateArray>("doors", 10, [this](const door_state_recognition::DoorStateArrayConstPtr& m) {
      std::lock_guard<std::mutex> l(rx_.m);
      rx_.doors.push_back(*m);
    });
    markers_sub_ = nh_.subscribe<visualization_msgs::MarkerArray>(
        "markers", 10, [this](const visualization_msgs::MarkerArrayConstPtr& m) {
          std::lock_guard<std::mutex> l(rx_.m);
          rx_.markers.push_back(*m);
        });
    ASSERT_TRUE(waitFor([this] { return pub_.getNumSubscribers() > 0; }, 20.0)) << "the nodelet never subscribed to points";
  }
  // Publishes and waits for the answer to this very cloud (matched by stamp).
  bool send(const sensor_msgs::PointCloud2& msg, DoorStateArray* answer, double seconds = 60.0) {
    pub_.publish(msg);
    return waitFor(
        [&] {
          std::lock_guard<std::mutex> l(rx_.m);
          for (const auto& d : rx_.doors)
            if (d.header.stamp == msg.header.stamp) {
              if (answer) *answer = d;
              return true;
            }
          return false;
        },
        seconds);
  }

  // The nodelet's diagnostics (key -> value) from the first message that
  // leaves it after `after` (the diagnostics go out once a second).
  std::map<std::string, std::string> diagnostics(const ros::WallTime& after, double seconds = 10.0) {
    std::mutex m;
    std::map<std::string, std::string> values;
    ros::Subscriber sub = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& a) {
          if (ros::WallTime::now() < after) return;
          std::lock_guard<std::mutex> l(m);
          for (const auto& st : a->status)
            if (st.name.find("door_state") != std::string::npos)
              for (const auto& kv : st.values) values[kv.key] = kv.value;
        });
    waitFor([&] { std::lock_guard<std::mutex> l(m); return !values.empty(); }, seconds);
    sub.shutdown();
    std::lock_guard<std::mutex> l(m);
    return values;
  }

  Received rx_;  // declared first, destroyed last
  ros::NodeHandle nh_;
  ros::Publisher pub_;
  ros::Subscriber doors_sub_, markers_sub_;
};

// Doors of a message matched to the truth by opening centre (0.5 m, horizontal).
void expectMatchesTruth(const DoorStateArray& msg, const nlohmann::json& truth, const Eigen::Isometry3d& truth_to_msg) {
  ASSERT_EQ(msg.doors.size(), truth["doors"].size());
  for (const auto& t : truth["doors"]) {
    const Eigen::Vector3d c = truth_to_msg * Eigen::Vector3d(t["opening_center"][0], t["opening_center"][1], t["opening_center"][2]);
    const door_state_recognition::DoorState* best = nullptr;
    for (const auto& d : msg.doors)
      if (std::hypot(d.opening_center.x - c.x(), d.opening_center.y - c.y()) < 0.5) best = &d;
    ASSERT_NE(best, nullptr) << "no door near the true one at " << c.transpose();
    const std::string state = t["state"];
    const int expected = state == "closed" ? 0 : state == "semi_open" ? 1 : 2;
    EXPECT_EQ(best->state, expected);
    EXPECT_NEAR(best->opening_angle * 180.0 / M_PI, t["opening_angle_deg"].get<double>(), 3.0);
    EXPECT_NEAR(std::hypot(best->wall_normal.x, best->wall_normal.y), 1.0, 1e-3);
    EXPECT_NEAR(best->wall_normal.z, 0.0, 1e-3);
  }
}

// Asks the nodelet's dynamic_reconfigure server to set one int parameter:
// whether the call went through (the config in force comes back in srv's response).
bool reconfigureInt(const std::string& name, int value, dynamic_reconfigure::Reconfigure& srv) {
  dynamic_reconfigure::IntParameter p;
  p.name = name;
  p.value = value;
  srv.request.config.ints.push_back(p);
  return ros::service::call("/door_state/set_parameters", srv);
}

}  // namespace

TEST_F(NodeletTest, SubscribesOnlyWhileSomeoneListens) {
  if (g_mode != "direct" && g_mode != "tf") GTEST_SKIP() << "the bag suite checks playback only";
  ros::WallDuration(1.0).sleep();
  EXPECT_EQ(pub_.getNumSubscribers(), 0u) << "subscribed to points with nobody listening";
  listen();
  EXPECT_EQ(pub_.getNumSubscribers(), 1u);
  doors_sub_.shutdown();
  markers_sub_.shutdown();
  EXPECT_TRUE(waitFor([this] { return pub_.getNumSubscribers() == 0; }, 10.0)) << "still subscribed after the last listener left";
}

TEST_F(NodeletTest, DoorsOfASimulatedScanMatchTheTruthWithStableIdsAndMarkers) {
  if (g_mode != "direct" && g_mode != "tf") GTEST_SKIP();
  listen();
  const SimScan scan = simulate("paper_house", 11);
  // direct: doors in the cloud's frame; tf: in `map`, the world of the simulator.
  const std::string frame = "tls_scanner";
  tf2_ros::StaticTransformBroadcaster tfb;
  if (g_mode == "tf") {
    geometry_msgs::TransformStamped t = tf2::eigenToTransform(scan.cloud.sensor_to_world);
    t.header.frame_id = "map";
    t.child_frame_id = "tls_scanner";
    t.header.stamp = ros::Time(0.5);
    tfb.sendTransform(t);
  }
  std::set<std::uint32_t> ids_seen;
  for (int k = 0; k < 3; ++k) {
    DoorStateArray answer;
    ASSERT_TRUE(send(toMsg(scan.cloud, frame, 10.0 + k), &answer)) << "no DoorStateArray for cloud " << k;
    EXPECT_EQ(answer.header.frame_id, g_mode == "tf" ? "map" : "tls_scanner");
    const Eigen::Isometry3d truth_to_msg = g_mode == "tf" ? scan.cloud.sensor_to_world : Eigen::Isometry3d::Identity();
    expectMatchesTruth(answer, scan.truth, truth_to_msg);
    for (const auto& d : answer.doors) ids_seen.insert(d.id);
  }
  EXPECT_EQ(ids_seen.size(), scan.truth["doors"].size()) << "ids changed between clouds of the same scene";
  ASSERT_TRUE(waitFor([this] { std::lock_guard<std::mutex> l(rx_.m); return !rx_.markers.empty(); }, 10.0));
  std::set<std::string> namespaces;
  {
    std::lock_guard<std::mutex> l(rx_.m);
    for (const auto& m : rx_.markers.back().markers) namespaces.insert(m.ns);
    EXPECT_EQ(rx_.markers.back().markers.front().action, visualization_msgs::Marker::DELETEALL);
  }
  for (const char* ns : {"wall_corners", "wall_lines", "door_corners", "leaf_lines", "labels", "reconstruction"})
    EXPECT_TRUE(namespaces.count(ns)) << "no marker in namespace " << ns;
}

// A map: a room scanned from three stations, merged into one cloud in
// `map` (the simulator's world), as a registered room or an accumulated map
// is published. With ~viewpoint none the nodelet infers where free space
// was seen from; each door of the room is reported in its state.
TEST_F(NodeletTest, AMergedRoomInTheMapFrameWithoutAViewpointGetsItsDoors) {
  if (g_mode != "map") GTEST_SKIP();
  listen();
  SimScan s;
  s.scene = sim::buildScene(sim::paperRoom("paper_multidoor"));
  sim::TlsOptions o;
  o.points = 600000;
  o.viewpoints = 3;
  o.seed = 11;
  s.cloud = sim::scanTls(s.scene, o);
  s.truth = sim::groundTruthJson(s.scene, s.cloud);
  sim::SimulatedCloud in_map = s.cloud;
  for (auto& q : in_map.cloud.points) q.getVector3fMap() = (s.cloud.sensor_to_world * q.getVector3fMap().cast<double>()).cast<float>();
  DoorStateArray answer;
  ASSERT_TRUE(send(toMsg(in_map, "map", 20.0), &answer)) << "no DoorStateArray for the map";
  EXPECT_EQ(answer.header.frame_id, "map");
  expectMatchesTruth(answer, s.truth, s.cloud.sensor_to_world);
}

namespace {

// A cloud of the given points with x, y, z only, FLOAT32 or FLOAT64.
sensor_msgs::PointCloud2 xyzCloud(const std::vector<Eigen::Vector3d>& pts, std::uint8_t type, const std::string& frame) {
  sensor_msgs::PointCloud2 m;
  m.header.frame_id = frame;
  const std::uint32_t size = type == sensor_msgs::PointField::FLOAT64 ? 8 : 4;
  for (std::uint32_t k = 0; k < 3; ++k) {
    sensor_msgs::PointField f;
    f.name = std::string(1, "xyz"[k]);
    f.offset = k * size;
    f.datatype = type;
    f.count = 1;
    m.fields.push_back(f);
  }
  m.height = 1;
  m.width = static_cast<std::uint32_t>(pts.size());
  m.point_step = 3 * size;
  m.row_step = m.width * m.point_step;
  m.is_dense = false;
  m.data.resize(static_cast<std::size_t>(m.row_step));
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      std::uint8_t* dst = &m.data[i * m.point_step + k * size];
      if (size == 8) {
        const double v = pts[i][k];
        std::memcpy(dst, &v, 8);
      } else {
        const float v = static_cast<float>(pts[i][k]);
        std::memcpy(dst, &v, 4);
      }
    }
  return m;
}

std::vector<Eigen::Vector3d> pointsOf(const sim::SimulatedCloud& c) {
  std::vector<Eigen::Vector3d> pts;
  for (const auto& p : c.cloud.points) pts.emplace_back(p.x, p.y, p.z);
  return pts;
}

struct RosoutLog {
  std::mutex m;
  std::vector<rosgraph_msgs::Log> logs;
  ros::Subscriber sub;
  void start(ros::NodeHandle& nh) {
    sub = nh.subscribe<rosgraph_msgs::Log>("/rosout", 1000, [this](const rosgraph_msgs::LogConstPtr& l) {
      std::lock_guard<std::mutex> g(m);
      logs.push_back(*l);
    });
  }
  // A message from the nodelet (node `node`) at `level` or above whose text holds every one of `words`.
  bool has(std::uint8_t level, const std::vector<std::string>& words, const std::string& node = "/door_state") {
    std::lock_guard<std::mutex> g(m);
    for (const auto& l : logs) {
      if (l.name != node || l.level < level) continue;
      bool all = true;
      for (const auto& w : words) all = all && l.msg.find(w) != std::string::npos;
      if (all) return true;
    }
    return false;
  }
  ~RosoutLog() { sub.shutdown(); }
};

}  // namespace

// Issue 6: the catalogue of hostile PointCloud2 messages. Each is answered
// with a DoorStateArray carrying its own header (stamp and frame): empty for
// a malformed or degenerate cloud, a valid one for an unusual but readable
// cloud; malformed ones are counted as refused in the diagnostics and logged
// as an error, degenerate ones as a warning; and a good cloud afterwards is
// still processed right.
TEST_F(NodeletTest, HostileCloudsAreAnsweredAndAGoodCloudStillWorks) {
  if (g_mode != "direct") GTEST_SKIP();
  RosoutLog rosout;
  rosout.start(nh_);
  listen();
  const SimScan scan = simulate("paper_livingroom", 5);
  const sensor_msgs::PointCloud2 good = toMsg(scan.cloud, "tls_scanner", 100.0);
  const std::vector<Eigen::Vector3d> pts = pointsOf(scan.cloud);
  const auto before = diagnostics(ros::WallTime::now());
  ASSERT_TRUE(before.count("clouds refused (malformed)"));

  enum class Expect { Refused, Degenerate, Valid, Truth };
  struct Case {
    std::string name;
    sensor_msgs::PointCloud2 msg;
    Expect expect;
  };
  std::vector<Case> cases;
  auto variant = [&](const std::string& name, Expect e, const std::function<void(sensor_msgs::PointCloud2&)>& spoil) {
    sensor_msgs::PointCloud2 m = good;
    spoil(m);
    cases.push_back({name, m, e});
  };
  auto made = [&](const std::string& name, Expect e, const std::vector<Eigen::Vector3d>& p,
                  std::uint8_t type = sensor_msgs::PointField::FLOAT32) {
    cases.push_back({name, xyzCloud(p, type, "tls_scanner"), e});
  };
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();

  // Malformed: refused by the conversion, without allocating for what the header promises.
  variant("data shorter than width*height*point_step", Expect::Refused, [](auto& m) { m.data.resize(m.data.size() / 2); });
  variant("data longer", Expect::Refused, [](auto& m) { m.data.resize(m.data.size() + 7); });
  variant("no z field", Expect::Refused, [](auto& m) { m.fields.erase(m.fields.begin() + 2); });
  variant("x as uint8", Expect::Refused, [](auto& m) { m.fields[0].datatype = sensor_msgs::PointField::UINT8; });
  variant("x as float64 overlapping y", Expect::Refused, [](auto& m) { m.fields[0].datatype = sensor_msgs::PointField::FLOAT64; });
  variant("x with count 3", Expect::Refused, [](auto& m) { m.fields[0].count = 3; });
  variant("x twice", Expect::Refused, [](auto& m) { m.fields.push_back(m.fields[0]); });
  variant("x beyond point_step", Expect::Refused, [](auto& m) { m.fields[0].offset = m.point_step; });
  variant("big-endian", Expect::Refused, [](auto& m) { m.is_bigendian = true; });
  variant("point_step smaller than the fields", Expect::Refused, [](auto& m) { m.point_step = 8; m.row_step = m.width * 8; m.data.resize(m.row_step); });
  variant("point_step 0", Expect::Refused, [](auto& m) { m.point_step = 0; m.row_step = 0; });
  variant("row_step inconsistent", Expect::Refused, [](auto& m) { m.row_step += 4; });
  variant("width*height overflowing", Expect::Refused, [](auto& m) { m.width = 0xFFFFFFFFu; m.height = 0xFFFFFFFFu; });
  // 20 million points promised by the header, the data of a 300k cloud:
  // refused on the size, before anything is allocated for them.
  variant("header claims 20M points, short data", Expect::Refused, [](auto& m) { m.width = 20000000; m.height = 1; m.row_step = m.width * m.point_step; });
  // 60 million points: above max_points (50 million) whatever the data.
  variant("header claims 60M points (> max_points)", Expect::Refused, [](auto& m) { m.width = 60000000; m.height = 1; m.row_step = m.width * m.point_step; });

  // Readable but degenerate: processed, no walls, an empty answer.
  variant("empty", Expect::Degenerate, [](auto& m) { m.width = 0; m.row_step = 0; m.data.clear(); });
  made("one point", Expect::Degenerate, {Eigen::Vector3d(1, 2, 0.5)});
  made("all NaN", Expect::Degenerate, std::vector<Eigen::Vector3d>(5000, Eigen::Vector3d(nan, nan, nan)));
  made("all Inf", Expect::Degenerate, std::vector<Eigen::Vector3d>(5000, Eigen::Vector3d(inf, -inf, inf)));
  made("all 1e30", Expect::Degenerate, std::vector<Eigen::Vector3d>(5000, Eigen::Vector3d(1e30, -1e30, 1e30)));
  made("every point identical", Expect::Degenerate, std::vector<Eigen::Vector3d>(5000, Eigen::Vector3d(1.5, -0.5, 1.0)));
  {
    std::vector<Eigen::Vector3d> line, plane;
    for (int i = 0; i < 20000; ++i) line.emplace_back(0.5 + 0.0002 * i, 1.0 + 0.0001 * i, 1.2);
    for (int i = 0; i < 200; ++i)
      for (int j = 0; j < 200; ++j) plane.emplace_back(-2.0 + 0.02 * i, -2.0 + 0.02 * j, -1.0);
    made("all points on one line", Expect::Degenerate, line);
    made("all points on one horizontal plane", Expect::Degenerate, plane);
  }

  // Readable and unusual: a valid answer.
  made("x, y, z as float64", Expect::Truth, pts, sensor_msgs::PointField::FLOAT64);
  {
    std::vector<Eigen::Vector3d> spiked = pts;
    for (std::size_t i = 0; i < spiked.size(); i += 50) spiked[i] = i % 150 == 0 ? Eigen::Vector3d(nan, 0, 0) : i % 100 == 0 ? Eigen::Vector3d(inf, 1, 1) : Eigen::Vector3d(1e30, 1e30, -1e30);
    made("2 % of the points NaN, Inf or 1e30", Expect::Truth, spiked);
    // The cloud's up axis is +x while the nodelet is told +z (refined within
    // 15 deg only): whatever it finds, the answer is well formed.
    std::vector<Eigen::Vector3d> tipped;
    for (const auto& p : pts) tipped.emplace_back(p.z(), p.y(), -p.x());
    made("wrong up axis (+x up, nodelet told +z)", Expect::Valid, tipped);
  }

  double stamp = 200.0;
  std::size_t refused = 0, degenerate = 0;
  for (auto& c : cases) {
    SCOPED_TRACE(c.name);
    c.msg.header.stamp = ros::Time(stamp += 1.0);
    DoorStateArray answer;
    ASSERT_TRUE(send(c.msg, &answer, 60.0)) << "no answer";
    EXPECT_EQ(answer.header.frame_id, c.msg.header.frame_id);
    switch (c.expect) {
      case Expect::Refused:
        ++refused;
        EXPECT_TRUE(answer.doors.empty());
        break;
      case Expect::Degenerate:
        ++degenerate;
        EXPECT_TRUE(answer.doors.empty());
        break;
      case Expect::Truth:
        expectMatchesTruth(answer, scan.truth, Eigen::Isometry3d::Identity());
        break;
      case Expect::Valid:
        for (const auto& d : answer.doors) {
          EXPECT_TRUE(std::isfinite(d.opening_angle) && std::isfinite(d.hinge.x) && std::isfinite(d.width));
          EXPECT_LE(d.state, 2);
        }
        break;
    }
  }
  sensor_msgs::PointCloud2 after = good;
  after.header.stamp = ros::Time(stamp + 1.0);
  DoorStateArray answer;
  ASSERT_TRUE(send(after, &answer)) << "the nodelet stopped answering after hostile input";
  expectMatchesTruth(answer, scan.truth, Eigen::Isometry3d::Identity());

  // Every malformed cloud was refused by the conversion (not by luck further
  // on), every degenerate one was processed and found no walls.
  const auto diag = diagnostics(ros::WallTime::now());
  auto delta = [&](const char* key) { return std::stoul(diag.at(key)) - std::stoul(before.at(key)); };
  EXPECT_EQ(delta("clouds refused (malformed)"), refused);
  EXPECT_GE(delta("clouds without walls"), degenerate);
  // Logged (throttled: at least once each), by the nodelet.
  EXPECT_TRUE(waitFor([&] { return rosout.has(rosgraph_msgs::Log::ERROR, {"malformed cloud"}); }, 10.0));
  EXPECT_TRUE(waitFor([&] { return rosout.has(rosgraph_msgs::Log::WARN, {"no walls"}); }, 10.0));
}

// max_points refuses a well-formed cloud above it (set low through
// dynamic_reconfigure, then set back).
TEST_F(NodeletTest, ACloudAboveMaxPointsIsRefused) {
  if (g_mode != "direct") GTEST_SKIP();
  listen();
  auto set = [&](int max_points) {
    dynamic_reconfigure::Reconfigure srv;
    return reconfigureInt("max_points", max_points, srv);
  };
  const auto before = diagnostics(ros::WallTime::now());
  ASSERT_TRUE(set(1000));
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 2000; ++i) pts.emplace_back(0.001 * i, 1.0, 0.5);
  sensor_msgs::PointCloud2 big = xyzCloud(pts, sensor_msgs::PointField::FLOAT32, "tls_scanner");
  big.header.stamp = ros::Time(700.0);
  DoorStateArray answer;
  const bool answered = send(big, &answer, 30.0);
  const auto diag = diagnostics(ros::WallTime::now());
  ASSERT_TRUE(set(50000000));
  ASSERT_TRUE(answered);
  EXPECT_TRUE(answer.doors.empty());
  EXPECT_EQ(std::stoul(diag.at("clouds refused (malformed)")), std::stoul(before.at("clouds refused (malformed)")) + 1);
  EXPECT_NE(diag.at("last error").find("max_points"), std::string::npos) << diag.at("last error");
}

TEST_F(NodeletTest, WithoutTfTheCloudIsDroppedAndProcessedOnceTfArrives) {
  if (g_mode != "tf") GTEST_SKIP();
  listen();
  const SimScan scan = simulate("paper_livingroom", 6);
  sensor_msgs::PointCloud2 msg = toMsg(scan.cloud, "unknown_sensor", 300.0);
  EXPECT_FALSE(send(msg, nullptr, 3.0)) << "a cloud without tf was answered";
  tf2_ros::StaticTransformBroadcaster tfb;
  geometry_msgs::TransformStamped t;
  t.header.frame_id = "map";
  t.child_frame_id = "unknown_sensor";
  t.transform.rotation.w = 1.0;
  tfb.sendTransform(t);
  ros::WallDuration(0.5).sleep();
  msg.header.stamp = ros::Time(301.0);
  DoorStateArray answer;
  EXPECT_TRUE(send(msg, &answer, 60.0)) << "no answer once the transform is known";
  EXPECT_EQ(answer.header.frame_id, "map");
  EXPECT_EQ(answer.doors.size(), 1u);
}

TEST_F(NodeletTest, ParametersChangeLiveThroughDynamicReconfigure) {
  if (g_mode != "direct") GTEST_SKIP();
  listen();
  const SimScan scan = simulate("paper_house", 11);  // one door open at 110.6 deg
  DoorStateArray before, after;
  ASSERT_TRUE(send(toMsg(scan.cloud, "tls_scanner", 400.0), &before));
  ASSERT_EQ(before.doors.size(), 1u);
  EXPECT_EQ(before.doors[0].state, door_state_recognition::DoorState::OPEN);
  auto set = [&](double open_from) {
    dynamic_reconfigure::Reconfigure srv;
    dynamic_reconfigure::DoubleParameter d;
    d.name = "open_from_deg";
    d.value = open_from;
    srv.request.config.doubles.push_back(d);
    return ros::service::call("/door_state/set_parameters", srv);
  };
  ASSERT_TRUE(set(115.0));
  ASSERT_TRUE(send(toMsg(scan.cloud, "tls_scanner", 401.0), &after));
  ASSERT_EQ(after.doors.size(), 1u);
  EXPECT_EQ(after.doors[0].state, door_state_recognition::DoorState::SEMI_OPEN) << "open_from_deg 115 not in force";
  ASSERT_TRUE(set(90.0));
}

// Issue 5: under a stream it cannot keep up with, the nodelet drops stale
// clouds instead of queueing them. A burst of clouds with distinct stamps,
// published faster than one is processed: fewer answers than clouds, the
// last cloud answered, answers in stamp order (never a stale one after a
// newer one), each cloud processed answered once, and every cloud the
// nodelet received but did not process counted in the diagnostics as a
// stale drop. No wall-clock limit is asserted.
//
// Where the clouds are dropped depends on the suite. roscpp's subscription
// queue (1) drops, uncounted, a cloud that arrives before the callback has
// taken the one before it. In the direct suite processing starts with the
// first cloud and takes both cores, and roscpp drops 1 or 2 of the 5 on
// this machine kind (five bursts received 4, 3, 3, 3, 3), sometimes all
// the stale ones: there only the accounting above is asserted (until
// 2026-11-25 this test asked a stale drop of the nodelet's own in both
// suites, and failed so: 600 601 604 answered, 3 received). In the tf
// suite the clouds wait in the tf filter for a transform that comes only
// after the whole burst, published 0.1 s apart (nothing is processed
// meanwhile, so the callback keeps up; published at once, one of the five
// was lost in each of three runs), and are then released at once: the
// nodelet must process at most two of them (the first taken and the newest)
// and drop and count the rest itself.
TEST_F(NodeletTest, StaleCloudsAreDroppedUnderABurst) {
  if (g_mode != "direct" && g_mode != "tf") GTEST_SKIP();
  const int n = 5;  // no longer than the tf filter's queue (~tf_queue_size 5)
  listen();
  const SimScan scan = simulate("paper_house", 11);
  const std::string frame = g_mode == "tf" ? "late_sensor" : "tls_scanner";
  const sensor_msgs::PointCloud2 base = toMsg(scan.cloud, frame, 0.0);
  const auto before = diagnostics(ros::WallTime::now());
  ASSERT_TRUE(before.count("clouds received") && before.count("clouds processed") && before.count("clouds dropped (stale)"))
      << "no cloud counters in the diagnostics";
  std::vector<sensor_msgs::PointCloud2::Ptr> burst;
  for (int k = 0; k < n; ++k) {
    burst.push_back(boost::make_shared<sensor_msgs::PointCloud2>(base));
    burst.back()->header.stamp = ros::Time(600.0 + k);
  }
  for (const auto& m : burst) {
    pub_.publish(m);
    if (g_mode == "tf") ros::WallDuration(0.1).sleep();
  }
  tf2_ros::StaticTransformBroadcaster tfb;
  if (g_mode == "tf") {
    ros::WallDuration(1.5).sleep();  // the whole burst waits in the tf filter
    ASSERT_EQ(rx_.count(), 0u) << "a cloud was processed without its transform";
    geometry_msgs::TransformStamped t = tf2::eigenToTransform(scan.cloud.sensor_to_world);
    t.header.frame_id = "map";
    t.child_frame_id = frame;
    tfb.sendTransform(t);
  }
  const ros::Time last = burst.back()->header.stamp;
  EXPECT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> l(rx_.m);
        for (const auto& d : rx_.doors)
          if (d.header.stamp == last) return true;
        return false;
      },
      120.0))
      << "the last cloud of the burst was never answered";
  // Anything still in flight would come within a few processing times.
  ros::WallDuration(3.0).sleep();
  std::vector<double> stamps;
  {
    std::lock_guard<std::mutex> l(rx_.m);
    for (const auto& d : rx_.doors) {
      stamps.push_back(d.header.stamp.toSec());
      EXPECT_EQ(d.doors.size(), 1u) << "a cloud of the burst was not processed right";
    }
  }
  const auto diag = diagnostics(ros::WallTime::now());
  auto delta = [&](const char* key) {
    return diag.count(key) ? static_cast<long>(std::stoul(diag.at(key))) - static_cast<long>(std::stoul(before.at(key))) : -1L;
  };
  const long received = delta("clouds received"), processed = delta("clouds processed"),
             stale = delta("clouds dropped (stale)");
  std::ostringstream seen;
  for (double s : stamps) seen << s << " ";
  seen << "(received " << received << ", processed " << processed << ", dropped stale " << stale << ")";
  SCOPED_TRACE("answered stamps: " + seen.str());
  RecordProperty("answered_stamps", seen.str());
  for (const auto& kv : diag) RecordProperty(kv.first, kv.second);
  ASSERT_FALSE(stamps.empty());
  EXPECT_LT(stamps.size(), static_cast<std::size_t>(n)) << "every cloud of the burst was processed: clouds are queued";
  EXPECT_EQ(stamps.back(), last.toSec()) << "a stale cloud was answered after the newest one";
  for (std::size_t i = 1; i < stamps.size(); ++i) EXPECT_LT(stamps[i - 1], stamps[i]) << "answers out of stamp order";
  EXPECT_EQ(processed, static_cast<long>(stamps.size())) << "a cloud processed was not answered, or answered twice";
  EXPECT_EQ(stale, received - processed) << "a cloud received and not processed was not counted as a stale drop";
  EXPECT_LE(received, n);
  if (g_mode == "tf") {
    EXPECT_GE(received, 3) << "fewer than 3 clouds of the burst reached the nodelet: its own dropping is untested";
    EXPECT_LE(processed, 2) << "more than 2 clouds of a burst released at once were processed: clouds are queued";
  }
}

// Issue 6: values the .cfg ranges let through but the pipeline refuses
// (out of its range, NaN, inconsistent with another parameter, an unknown up
// axis) are refused through dynamic_reconfigure as from YAML: a clear error
// naming the parameter, the previous configuration stays in force, and the
// server hands the previous values back (service response, parameter server).
TEST_F(NodeletTest, ReconfigureRefusesBadValuesAndKeepsThePreviousOnes) {
  if (g_mode != "direct") GTEST_SKIP();
  RosoutLog rosout;
  rosout.start(nh_);
  listen();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    std::string name;
    std::vector<std::pair<std::string, double>> doubles;
    std::vector<std::pair<std::string, std::string>> strs;
    std::string named;  // the refusal names this parameter
  };
  const std::vector<Case> cases = {
      // open_from_deg 115 alone is valid (and would make the 110.6 deg door
      // semi-open): it must not slip in with the refused voxel size.
      {"voxel_size 0.0005 (cfg: [0, 1]; pipeline: 0 or >= 0.001)", {{"voxel_size", 0.0005}, {"open_from_deg", 115.0}}, {}, "voxel_size"},
      {"wall_distance NaN", {{"wall_distance", nan}}, {}, "wall_distance"},
      {"closed_below_deg 50 above open_from_deg 30", {{"closed_below_deg", 50.0}, {"open_from_deg", 30.0}}, {}, "closed_below_deg"},
      {"door_min_width 1.3 above door_max_width 1.0", {{"door_min_width", 1.3}, {"door_max_width", 1.0}}, {}, "door_min_width"},
      {"up_axis 'sideways'", {}, {{"up_axis", "sideways"}}, "up_axis"},
  };
  const std::map<std::string, double> in_force = {{"voxel_size", 0.02}, {"open_from_deg", 90.0}, {"wall_distance", 0.03},
                                                  {"closed_below_deg", 5.0}, {"door_min_width", 0.6}, {"door_max_width", 1.4}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    dynamic_reconfigure::Reconfigure srv;
    for (const auto& [name, value] : c.doubles) {
      dynamic_reconfigure::DoubleParameter d;
      d.name = name;
      d.value = value;
      srv.request.config.doubles.push_back(d);
    }
    for (const auto& [name, value] : c.strs) {
      dynamic_reconfigure::StrParameter d;
      d.name = name;
      d.value = value;
      srv.request.config.strs.push_back(d);
    }
    ASSERT_TRUE(ros::service::call("/door_state/set_parameters", srv));
    // The response and the parameter server hold the values in force.
    for (const auto& d : srv.response.config.doubles)
      if (in_force.count(d.name)) EXPECT_EQ(d.value, in_force.at(d.name)) << d.name << " in the service response";
    for (const auto& d : srv.response.config.strs)
      if (d.name == "up_axis") EXPECT_EQ(d.value, "+z") << "up_axis in the service response";
    for (const auto& [name, value] : in_force) {
      double v = -1;
      EXPECT_TRUE(nh_.getParam("/door_state/" + name, v));
      EXPECT_EQ(v, value) << "/door_state/" << name << " on the parameter server";
    }
    std::string up;
    EXPECT_TRUE(nh_.getParam("/door_state/up_axis", up));
    EXPECT_EQ(up, "+z");
    EXPECT_TRUE(waitFor([&] { return rosout.has(rosgraph_msgs::Log::ERROR, {"parameters refused", c.named}); }, 10.0))
        << "no error naming " << c.named;
  }
  EXPECT_TRUE(rosout.has(rosgraph_msgs::Log::ERROR, {"wall_distance = NaN"}));
  // The previous parameters are in force: the 110.6 deg door is still open
  // (open_from_deg 115 of the first refused request did not slip in).
  const SimScan scan = simulate("paper_house", 11);
  DoorStateArray answer;
  ASSERT_TRUE(send(toMsg(scan.cloud, "tls_scanner", 800.0), &answer));
  ASSERT_EQ(answer.doors.size(), 1u);
  EXPECT_EQ(answer.doors[0].state, door_state_recognition::DoorState::OPEN);
}

// dynamic_reconfigure clamps a request to the .cfg range before the callback
// sees it (normal_k 1000 arrives as 200): the nodelet says so with a warning
// naming the parameter and the range. (It cannot tell a clamped request
// from one that asked for the end of the range itself: both are named.)
TEST_F(NodeletTest, AReconfigureRequestClampedToTheCfgRangeIsLogged) {
  if (g_mode != "direct") GTEST_SKIP();
  RosoutLog rosout;
  rosout.start(nh_);
  ros::WallDuration(1.0).sleep();  // the subscription to /rosout
  auto set = [&](int normal_k) {
    dynamic_reconfigure::Reconfigure srv;
    EXPECT_TRUE(reconfigureInt("normal_k", normal_k, srv));
    for (const auto& i : srv.response.config.ints)
      if (i.name == "normal_k") return i.value;
    return -1;
  };
  EXPECT_EQ(set(1000), 200) << "the server's clamp";
  EXPECT_TRUE(waitFor([&] { return rosout.has(rosgraph_msgs::Log::WARN, {"normal_k = 200", "[5, 200]", "clamp"}); }, 10.0))
      << "no warning that normal_k was clamped";
  EXPECT_EQ(set(16), 16);
}

namespace {

// The level and message of the first diagnostics status of `node` (e.g.
// "/door_state") seen within `seconds`; level -1 if none.
std::pair<int, std::string> diagnosticStatus(ros::NodeHandle& nh, const std::string& node, double seconds) {
  std::mutex m;
  std::pair<int, std::string> got{-1, ""};
  ros::Subscriber sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>("/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArrayConstPtr& a) {
    std::lock_guard<std::mutex> l(m);
    for (const auto& st : a->status)
      if (got.first < 0 && st.name.rfind(node.substr(1) + ":", 0) == 0) got = {st.level, st.message};
  });
  waitFor([&] { std::lock_guard<std::mutex> l(m); return got.first >= 0; }, seconds);
  sub.shutdown();
  std::lock_guard<std::mutex> l(m);
  return got;
}

}  // namespace

// Issue 1 (review 10): ~ parameters are checked as raw values before the
// dynamic_reconfigure server reads them (it would keep the default for a
// string where a number belongs, clamp -1 to 0 and 1000 to 200, and never
// see a misspelt name). /door_state was given one of each: it logs an error
// naming each parameter with its valid range (again every 10 s, so the test
// sees it whenever it subscribes), does not start (no dynamic_reconfigure
// server, nothing written back over the parameters, no subscription),
// stays up (its diagnostics come, at ERROR). /door_state_good, with good
// values and the nodelet's own names, starts as usual.
TEST(BadParameters, TheNodeletRefusesThemStaysUpAndSaysWhy) {
  if (g_mode != "bad_params") GTEST_SKIP();
  ros::NodeHandle nh;
  RosoutLog rosout;
  rosout.start(nh);
  const std::vector<std::vector<std::string>> named = {
      {"voxel_size", "0 or in [0.001, 1]"},
      {"normal_k", "[5, 200]"},
      {"wall_distance", "a string", "a number in [0.002, 0.5]", "2e-2"},
      {"voxel_sise", "unknown parameter"},
      {"random_seed", "2000000", "[0, 1000000]"},
      {"withdraw_not_found", "must be a bool"},
  };
  for (const auto& words : named) {
    SCOPED_TRACE(words.front());
    EXPECT_TRUE(waitFor([&] { return rosout.has(rosgraph_msgs::Log::ERROR, words); }, 25.0)) << "no error naming it";
  }
  // Not started: the parameters as given (the server would have written 0
  // over -1 and 200 over 1000), no set_parameters service, no subscriber.
  double voxel = 0;
  int k = 0;
  EXPECT_TRUE(nh.getParam("/door_state/voxel_size", voxel));
  EXPECT_EQ(voxel, -1.0);
  EXPECT_TRUE(nh.getParam("/door_state/normal_k", k));
  EXPECT_EQ(k, 1000);
  EXPECT_FALSE(ros::service::exists("/door_state/set_parameters", false));
  // Up, and saying so in its diagnostics.
  const auto bad = diagnosticStatus(nh, "/door_state", 10.0);
  EXPECT_EQ(bad.first, diagnostic_msgs::DiagnosticStatus::ERROR) << bad.second;
  EXPECT_NE(bad.second.find("parameters refused"), std::string::npos) << bad.second;
  EXPECT_NE(bad.second.find("voxel_sise"), std::string::npos) << bad.second;

  // The good one: started, its values in force, no refusal.
  EXPECT_TRUE(ros::service::waitForService("/door_state_good/set_parameters", ros::Duration(20.0)));
  EXPECT_TRUE(nh.getParam("/door_state_good/normal_k", k));
  EXPECT_EQ(k, 20);
  double wall_distance = 0;
  EXPECT_TRUE(nh.getParam("/door_state_good/wall_distance", wall_distance));
  EXPECT_EQ(wall_distance, 0.02);
  std::string up;
  EXPECT_TRUE(nh.getParam("/door_state_good/up_axis", up));
  EXPECT_EQ(up, "-y");
  const auto good = diagnosticStatus(nh, "/door_state_good", 10.0);
  EXPECT_EQ(good.first, diagnostic_msgs::DiagnosticStatus::OK) << good.second;
  EXPECT_FALSE(rosout.has(rosgraph_msgs::Log::ERROR, {"refused"}, "/door_state_good"));
}

TEST(Reconfigure, CfgDefaultsAreTheCodesDefaults) {
  // The .cfg, config/default.yaml and the code must agree (the YAML is
  // checked in test_pipeline): compare the generated config's defaults.
  const door_state_recognition::DoorStateConfig def = door_state_recognition::DoorStateConfig::__getDefault__();
  std::ostringstream os;
  os.precision(17);
  std::set<std::string> names;
  for (const auto& d : door_state_recognition::DoorStateConfig::__getParamDescriptions__()) {
    boost::any v;
    d->getValue(def, v);
    names.insert(d->name);
    os << d->name << ": ";
    if (d->type == "double") os << boost::any_cast<double>(v);
    else if (d->type == "int") os << boost::any_cast<int>(v);
    else os << '"' << boost::any_cast<std::string>(v) << '"';
    os << "\n";
  }
  const std::vector<std::string> all = dsr::parameterNames();
  EXPECT_EQ(names, std::set<std::string>(all.begin(), all.end())) << "the .cfg and the code list different parameters";
  EXPECT_EQ(dsr::dumpParameters(dsr::parseParameters(os.str(), dsr::Parameters(), "cfg")), dsr::dumpParameters(dsr::Parameters()));
}

// Door ids are matched across the up vector the pipeline found, not on x, y
// of the output frame: in a camera optical frame (up -y, ~fixed_frame empty)
// y is height and z is depth.
TEST(DoorTracker, MatchesAcrossTheUpVectorOfTheCloudsFrame) {
  const Eigen::Vector3d up_optical(0, -1, 0);
  {
    // Two doors one behind the other (same x and y, 2 m apart in depth z):
    // distinct doors, distinct ids.
    dsr::DoorTracker t;
    const std::uint32_t a = t.update({Eigen::Vector3d(0.0, 1.2, 2.0)}, up_optical).at(0);
    const std::uint32_t b = t.update({Eigen::Vector3d(0.0, 1.2, 4.0)}, up_optical).at(0);
    EXPECT_NE(a, b) << "a door 2 m deeper took the id of the one in front";
  }
  {
    // The same door whose centre is found 0.8 m higher (y) and 0.1 m off in
    // depth: the height is ignored, the same id.
    dsr::DoorTracker t;
    const std::uint32_t a = t.update({Eigen::Vector3d(0.3, 1.2, 2.0)}, up_optical).at(0);
    const std::uint32_t b = t.update({Eigen::Vector3d(0.3, 0.4, 2.1)}, up_optical).at(0);
    EXPECT_EQ(a, b) << "a height difference along up split one door into two";
  }
  {
    // z up (the default): as before.
    dsr::DoorTracker t;
    const std::uint32_t a = t.update({Eigen::Vector3d(2.0, 1.0, 0.0)}).at(0);
    EXPECT_EQ(t.update({Eigen::Vector3d(2.1, 1.0, 0.9)}).at(0), a);
    EXPECT_NE(t.update({Eigen::Vector3d(2.0, 3.0, 0.0)}).at(0), a);
  }
}

// The simulator's truth of the played bag: the file named by ~truth.
void readTruth(nlohmann::json& truth) {
  std::string path;
  ASSERT_TRUE(ros::NodeHandle("~").getParam("truth", path));
  std::ifstream in(path);
  ASSERT_TRUE(in.good()) << path;
  truth = nlohmann::json::parse(in);
}

TEST(BagPlayback, DoorsOfThePlayedBagMatchItsTruth) {
  if (g_mode != "bag") GTEST_SKIP();
  ros::NodeHandle nh;
  nlohmann::json truth;
  ASSERT_NO_FATAL_FAILURE(readTruth(truth));
  Received rx;
  ros::Subscriber sub = nh.subscribe<DoorStateArray>("doors", 10, [&](const door_state_recognition::DoorStateArrayConstPtr& m) {
    std::lock_guard<std::mutex> l(rx.m);
    rx.doors.push_back(*m);
  });
  ASSERT_TRUE(waitFor([&] { return rx.count() >= 2; }, 120.0)) << "fewer than two DoorStateArray from the bag";
  std::lock_guard<std::mutex> l(rx.m);
  // The bag's tf puts the cloud frame in `map`, the simulator's world.
  const auto& tr = truth["sensor_to_world"];
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(tr["translation"][0], tr["translation"][1], tr["translation"][2]);
  T.linear() = Eigen::Quaterniond(tr["rotation_xyzw"][3], tr["rotation_xyzw"][0], tr["rotation_xyzw"][1], tr["rotation_xyzw"][2])
                   .toRotationMatrix();
  for (const auto& msg : rx.doors) {
    EXPECT_EQ(msg.header.frame_id, "map");
    expectMatchesTruth(msg, truth, T);
  }
  // Consecutive clouds of the same scene: the same ids.
  ASSERT_FALSE(rx.doors[0].doors.empty());
  ASSERT_FALSE(rx.doors[1].doors.empty());
  EXPECT_EQ(rx.doors[0].doors[0].id, rx.doors[1].doors[0].id);
}

// A robot's drive (door_scene_sim --drive, its truth in `map`) played through
// door_state.launch with use_sim_time (drive_playback.test, drive_toggle.test
// where a door opens during the drive, drive_camera.test: an RGB-D camera
// in its optical frame): the last tracked_doors holds every
// door the robot passed within 3 m in its final true state, the angle within
// 5 deg (or NOT_CLOSED, bounded below its angle, where the leaf was out of
// sight), and each door kept one id over the drive.
TEST(DrivePlayback, TrackedDoorsOfTheDriveMatchItsTruth) {
  if (g_mode != "drive") GTEST_SKIP();
  ros::NodeHandle nh;
  nlohmann::json truth;
  ASSERT_NO_FATAL_FAILURE(readTruth(truth));
  Received rx;
  ros::WallTime last_at;
  ros::Subscriber sub =
      nh.subscribe<DoorStateArray>("tracked_doors", 50, [&](const door_state_recognition::DoorStateArrayConstPtr& m) {
        std::lock_guard<std::mutex> l(rx.m);
        rx.doors.push_back(*m);
        last_at = ros::WallTime::now();
      });
  // The bag is over when no message has come for 10 s (wall clock: the
  // simulated clock stops with the bag).
  ASSERT_TRUE(waitFor([&] { return rx.count() > 0; }, 120.0)) << "no tracked_doors from the drive";
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> l(rx.m);
        return (ros::WallTime::now() - last_at).toSec() > 10.0;
      },
      240.0));
  std::lock_guard<std::mutex> l(rx.m);
  const DoorStateArray& last = rx.doors.back();
  EXPECT_EQ(last.header.frame_id, "map");
  static const char* kStates[] = {"closed", "semi_open", "open", "not_closed"};
  const auto nearest = [](const DoorStateArray& msg, const nlohmann::json& t) -> const door_state_recognition::DoorState* {
    const door_state_recognition::DoorState* best = nullptr;
    double best_d = 0.5;
    for (const auto& d : msg.doors) {
      const double dist = std::hypot(d.opening_center.x - t["opening_center"][0].get<double>(),
                                     d.opening_center.y - t["opening_center"][1].get<double>());
      if (dist < best_d) best_d = dist, best = &d;
    }
    return best;
  };
  int passed = 0;
  for (std::size_t i = 0; i < truth["doors"].size(); ++i) {
    const auto& t = truth["doors"][i];
    if (!t.value("passed_within_3m", false)) continue;
    ++passed;
    SCOPED_TRACE("door " + std::to_string(i) + ": " + t["state"].get<std::string>() + " " +
                 std::to_string(t["opening_angle_deg"].get<double>()) + " deg");
    const door_state_recognition::DoorState* d = nearest(last, t);
    ASSERT_NE(d, nullptr) << "not in the last tracked_doors (" << last.doors.size() << " doors)";
    ASSERT_LT(d->state, 4);
    const double angle = d->opening_angle * 180.0 / M_PI, true_angle = t["opening_angle_deg"].get<double>();
    if (d->state == door_state_recognition::DoorState::NOT_CLOSED) {
      // A leaf out of sight (issue 20's rule): right where the door is not
      // closed and the bound lies below its angle.
      EXPECT_NE(t["state"].get<std::string>(), "closed");
      EXPECT_TRUE(d->angle_is_lower_bound);
      EXPECT_LE(angle, true_angle + 5.0);
    } else {
      EXPECT_EQ(std::string(kStates[d->state]), t["state"].get<std::string>());
      EXPECT_NEAR(angle, true_angle, 5.0);
    }
    EXPECT_GE(d->observations, 1u);
    // One id per door over the whole drive.
    std::set<std::uint32_t> ids;
    for (const auto& msg : rx.doors)
      if (const auto* e = nearest(msg, t)) ids.insert(e->id);
    EXPECT_EQ(ids.size(), 1u) << "the door changed id during the drive";
  }
  EXPECT_GT(passed, 0) << "the drive passed no door: the test proves nothing";
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_door_state_nodelet");
  ros::NodeHandle("~").param<std::string>("mode", g_mode, "direct");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int rc = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return rc;
}
