// rostest driving DoorStateNodelet from the outside, as a user's node would.
// ~mode selects the suite:
//   direct  the nodelet works in the cloud's frame (~fixed_frame empty)
//   tf      the nodelet works in the fixed frame `map`
//   bag     a simulated bag is played by rosbag; ~truth is its ground truth
#include <gtest/gtest.h>
#include <pcl_conversions/pcl_conversions.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <diagnostic_msgs/DiagnosticArray.h>

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

}  // namespace

TEST_F(NodeletTest, SubscribesOnlyWhileSomeoneListens) {
  if (g_mode == "bag") GTEST_SKIP() << "the bag suite checks playback only";
  ros::WallDuration(1.0).sleep();
  EXPECT_EQ(pub_.getNumSubscribers(), 0u) << "subscribed to points with nobody listening";
  listen();
  EXPECT_EQ(pub_.getNumSubscribers(), 1u);
  doors_sub_.shutdown();
  markers_sub_.shutdown();
  EXPECT_TRUE(waitFor([this] { return pub_.getNumSubscribers() == 0; }, 10.0)) << "still subscribed after the last listener left";
}

TEST_F(NodeletTest, DoorsOfASimulatedScanMatchTheTruthWithStableIdsAndMarkers) {
  if (g_mode == "bag") GTEST_SKIP();
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

TEST_F(NodeletTest, MalformedCloudsAreAnsweredEmptyAndAGoodCloudStillWorks) {
  if (g_mode != "direct") GTEST_SKIP();
  listen();
  const SimScan scan = simulate("paper_livingroom", 5);
  const sensor_msgs::PointCloud2 good = toMsg(scan.cloud, "tls_scanner", 100.0);
  std::vector<std::pair<std::string, sensor_msgs::PointCloud2>> bad;
  auto variant = [&](const std::string& name, const std::function<void(sensor_msgs::PointCloud2&)>& spoil) {
    sensor_msgs::PointCloud2 m = good;
    spoil(m);
    bad.emplace_back(name, m);
  };
  variant("data shorter than width*height*point_step", [](auto& m) { m.data.resize(m.data.size() / 2); });
  variant("data longer", [](auto& m) { m.data.resize(m.data.size() + 7); });
  variant("no z field", [](auto& m) { m.fields.erase(m.fields.begin() + 2); });
  variant("x as uint8", [](auto& m) { m.fields[0].datatype = sensor_msgs::PointField::UINT8; });
  variant("point_step smaller than the fields", [](auto& m) { m.point_step = 8; m.row_step = m.width * 8; m.data.resize(m.row_step); });
  variant("width*height overflowing", [](auto& m) { m.width = 0xFFFFFFFFu; m.height = 0xFFFFFFFFu; });
  variant("empty", [](auto& m) { m.width = 0; m.row_step = 0; m.data.clear(); });
  variant("all NaN", [](auto& m) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (std::size_t i = 0; i + 12 <= m.data.size(); i += m.point_step)
      for (int k = 0; k < 3; ++k) std::memcpy(&m.data[i + 4 * k], &nan, 4);
  });
  double stamp = 200.0;
  for (auto& [name, msg] : bad) {
    SCOPED_TRACE(name);
    msg.header.stamp = ros::Time(stamp += 1.0);
    DoorStateArray answer;
    // An empty answer with the input's header, or none at all; never doors, never a crash.
    if (send(msg, &answer, 10.0)) {
      EXPECT_TRUE(answer.doors.empty());
      EXPECT_EQ(answer.header.frame_id, msg.header.frame_id);
    }
  }
  sensor_msgs::PointCloud2 after = good;
  after.header.stamp = ros::Time(stamp + 1.0);
  DoorStateArray answer;
  ASSERT_TRUE(send(after, &answer)) << "the nodelet stopped answering after malformed input";
  expectMatchesTruth(answer, scan.truth, Eigen::Isometry3d::Identity());
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
// newer one), and the drops counted in the diagnostics. In the tf suite the
// burst waits in the tf filter for a transform that comes only after the
// whole burst, so that every cloud of it is released at once: they must not
// all be processed one after the other. No wall-clock limit is asserted.
TEST_F(NodeletTest, StaleCloudsAreDroppedUnderABurst) {
  if (g_mode == "bag") GTEST_SKIP();
  const int n = 5;  // no longer than the tf filter's queue (~tf_queue_size 5)
  listen();
  const SimScan scan = simulate("paper_house", 11);
  const std::string frame = g_mode == "tf" ? "late_sensor" : "tls_scanner";
  const sensor_msgs::PointCloud2 base = toMsg(scan.cloud, frame, 0.0);
  std::vector<sensor_msgs::PointCloud2::Ptr> burst;
  for (int k = 0; k < n; ++k) {
    burst.push_back(boost::make_shared<sensor_msgs::PointCloud2>(base));
    burst.back()->header.stamp = ros::Time(600.0 + k);
  }
  for (const auto& m : burst) pub_.publish(m);
  tf2_ros::StaticTransformBroadcaster tfb;
  if (g_mode == "tf") {
    ros::WallDuration(2.0).sleep();  // the whole burst waits in the tf filter
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
  std::ostringstream seen;
  for (double s : stamps) seen << s << " ";
  SCOPED_TRACE("answered stamps: " + seen.str());
  RecordProperty("answered_stamps", seen.str());
  const auto diag = diagnostics(ros::WallTime::now());
  for (const auto& kv : diag) RecordProperty(kv.first, kv.second);
  ASSERT_FALSE(stamps.empty());
  EXPECT_LT(stamps.size(), static_cast<std::size_t>(n)) << "every cloud of the burst was processed: clouds are queued";
  EXPECT_EQ(stamps.back(), last.toSec()) << "a stale cloud was answered after the newest one";
  for (std::size_t i = 1; i < stamps.size(); ++i) EXPECT_LT(stamps[i - 1], stamps[i]) << "answers out of stamp order";
  ASSERT_TRUE(diag.count("clouds dropped (stale)")) << "no drop counter in the diagnostics";
  EXPECT_GE(std::stoul(diag.at("clouds dropped (stale)")), 1u);
  EXPECT_GE(std::stoul(diag.at("clouds processed")), stamps.size());
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

TEST(BagPlayback, DoorsOfThePlayedBagMatchItsTruth) {
  if (g_mode != "bag") GTEST_SKIP();
  ros::NodeHandle nh, pnh("~");
  std::string truth_path;
  ASSERT_TRUE(pnh.getParam("truth", truth_path));
  std::ifstream in(truth_path);
  ASSERT_TRUE(in.good()) << truth_path;
  nlohmann::json truth = nlohmann::json::parse(in);
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
