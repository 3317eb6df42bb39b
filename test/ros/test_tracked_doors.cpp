// rostest of `tracked_doors` (issue 20): the nodelet with ~fixed_frame map
// and ~forget_after_s 20 (test/ros/nodelet_tracked.test) is fed simulated
// laser scans (dsr::sim) of two rooms 30 m apart in `map`, from sensor
// frames whose static tf into `map` the test publishes, stamped so that the
// drive goes on, one door leaves the view and is forgotten, and then time
// goes backwards (a bag looped), and the sensor's pose jumps
// (relocalisation). Checked: one id per door, observations and last_seen, a
// door kept after it leaves the view, greyed markers, the forgetting, the
// resets with their warnings, and the nodelet alive after them.
#include <gtest/gtest.h>
#include <pcl_conversions/pcl_conversions.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "door_state_recognition/DoorStateArray.h"
#include "door_state_recognition/sim/ground_truth.hpp"
#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/sim/sensors.hpp"

using door_state_recognition::DoorState;
using door_state_recognition::DoorStateArray;
namespace sim = dsr::sim;

namespace {

bool waitFor(const std::function<bool()>& cond, double seconds) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::ok() && ros::WallTime::now() < end) {
    if (cond()) return true;
    ros::WallDuration(0.02).sleep();
  }
  return cond();
}

struct Scan {
  sim::SimulatedCloud cloud;
  nlohmann::json truth;
  std::string frame;
  Eigen::Isometry3d sensor_to_map;
};

// A laser scan of one of the paper's rooms; the room stands `shift` along x in map.
Scan scan(const std::string& room, std::uint64_t seed, const std::string& frame, double shift) {
  Scan s;
  const sim::Scene scene = sim::buildScene(sim::paperRoom(room));
  sim::TlsOptions o;
  o.points = 300000;
  o.seed = seed;
  s.cloud = sim::scanTls(scene, o);
  s.truth = sim::groundTruthJson(scene, s.cloud);
  s.frame = frame;
  s.sensor_to_map = Eigen::Translation3d(shift, 0, 0) * s.cloud.sensor_to_world;
  return s;
}

class TrackedDoors : public ::testing::Test {
 protected:
  void SetUp() override {
    pub_ = nh_.advertise<sensor_msgs::PointCloud2>("points", 4);
    tracked_sub_ = nh_.subscribe<DoorStateArray>("tracked_doors", 20, [this](const door_state_recognition::DoorStateArrayConstPtr& m) {
      std::lock_guard<std::mutex> l(m_);
      tracked_.push_back(*m);
    });
    doors_sub_ = nh_.subscribe<DoorStateArray>("doors", 20, [this](const door_state_recognition::DoorStateArrayConstPtr& m) {
      std::lock_guard<std::mutex> l(m_);
      doors_.push_back(*m);
    });
    markers_sub_ = nh_.subscribe<visualization_msgs::MarkerArray>("markers", 20, [this](const visualization_msgs::MarkerArrayConstPtr& m) {
      std::lock_guard<std::mutex> l(m_);
      markers_.push_back(*m);
    });
    rosout_sub_ = nh_.subscribe<rosgraph_msgs::Log>("/rosout", 1000, [this](const rosgraph_msgs::LogConstPtr& l) {
      std::lock_guard<std::mutex> g(m_);
      if (l->name == "/door_state") logs_.push_back(*l);
    });
  }
  void TearDown() override {
    tracked_sub_.shutdown();
    doors_sub_.shutdown();
    markers_sub_.shutdown();
    rosout_sub_.shutdown();
  }
  // Publishes the scan stamped `stamp`; the tracked_doors and doors answering it.
  bool send(const Scan& s, double stamp, DoorStateArray* tracked, DoorStateArray* doors) {
    sensor_msgs::PointCloud2 msg;
    pcl::toROSMsg(s.cloud.cloud, msg);
    msg.header.frame_id = s.frame;
    msg.header.stamp = ros::Time(stamp);
    pub_.publish(msg);
    auto find = [&](const std::vector<DoorStateArray>& all, DoorStateArray* out) {
      for (const auto& a : all)
        if (a.header.stamp == msg.header.stamp) {
          *out = a;
          return true;
        }
      return false;
    };
    return waitFor(
        [&] {
          std::lock_guard<std::mutex> l(m_);
          return find(tracked_, tracked) && find(doors_, doors);
        },
        60.0);
  }
  bool markersAt(double stamp, visualization_msgs::MarkerArray* out) {
    return waitFor(
        [&] {
          std::lock_guard<std::mutex> l(m_);
          for (const auto& a : markers_)
            if (a.markers.size() > 1 && a.markers.back().header.stamp == ros::Time(stamp)) {
              *out = a;
              return true;
            }
          return false;
        },
        10.0);
  }
  bool logged(std::uint8_t level, const std::string& words) {
    return waitFor(
        [&] {
          std::lock_guard<std::mutex> l(m_);
          for (const auto& g : logs_)
            if (g.level >= level && g.msg.find(words) != std::string::npos) return true;
          return false;
        },
        5.0);
  }

  std::mutex m_;
  std::vector<DoorStateArray> tracked_, doors_;
  std::vector<visualization_msgs::MarkerArray> markers_;
  std::vector<rosgraph_msgs::Log> logs_;
  ros::NodeHandle nh_;
  ros::Publisher pub_;
  ros::Subscriber tracked_sub_, doors_sub_, markers_sub_, rosout_sub_;
};

// The door of `msg` within 0.5 m (horizontally) of `c`, or null.
const DoorState* near(const DoorStateArray& msg, const Eigen::Vector3d& c) {
  for (const auto& d : msg.doors)
    if (std::hypot(d.opening_center.x - c.x(), d.opening_center.y - c.y()) < 0.5) return &d;
  return nullptr;
}

Eigen::Vector3d centreInMap(const Scan& s, const nlohmann::json& door) {
  // Truth is in the sensor frame of the scan.
  return s.sensor_to_map * Eigen::Vector3d(door["opening_center"][0], door["opening_center"][1], door["opening_center"][2]);
}

}  // namespace

TEST_F(TrackedDoors, OneIdPerDoorKeptOutOfViewForgottenAndResetWhenTimeGoesBack) {
  // The house (one door open about 110 deg) from two scanner poses, and the
  // two-door room 30 m further along x.
  const Scan house_a = scan("paper_house", 11, "scanner_a", 0.0);
  const Scan house_b = scan("paper_house", 12, "scanner_b", 0.0);
  const Scan far = scan("paper_multidoor", 11, "scanner_c", 30.0);
  // The house scan again from a frame 8 m off in map: a relocalisation jump.
  Scan jumped_scan = house_a;
  jumped_scan.frame = "scanner_d";
  jumped_scan.sensor_to_map = Eigen::Translation3d(0, 8, 0) * house_a.sensor_to_map;
  const Scan& jumped = jumped_scan;
  tf2_ros::StaticTransformBroadcaster tfb;
  std::vector<geometry_msgs::TransformStamped> tfs;
  for (const Scan* s : {&house_a, &house_b, &far, &jumped}) {
    geometry_msgs::TransformStamped t = tf2::eigenToTransform(s->sensor_to_map);
    t.header.frame_id = "map";
    t.child_frame_id = s->frame;
    t.header.stamp = ros::Time(1.0);
    tfs.push_back(t);
  }
  tfb.sendTransform(tfs);
  ASSERT_TRUE(waitFor([this] { return pub_.getNumSubscribers() > 0; }, 20.0)) << "the nodelet never subscribed to points";
  ASSERT_EQ(house_a.truth["doors"].size(), 1u);
  const Eigen::Vector3d house_door = centreInMap(house_a, house_a.truth["doors"][0]);
  const double house_angle = house_a.truth["doors"][0]["opening_angle_deg"].get<double>();

  // 1. The house from pose a.
  DoorStateArray tracked, doors;
  ASSERT_TRUE(send(house_a, 100.0, &tracked, &doors)) << "no answer to cloud 1";
  EXPECT_EQ(tracked.header.frame_id, "map");
  ASSERT_EQ(tracked.doors.size(), 1u);
  const DoorState* h = near(tracked, house_door);
  ASSERT_NE(h, nullptr) << "the house door is not tracked where it stands";
  const std::uint32_t house_id = h->id;
  EXPECT_EQ(h->observations, 1u);
  EXPECT_EQ(h->last_seen, ros::Time(100.0));
  EXPECT_EQ(h->state, DoorState::OPEN);
  EXPECT_NEAR(h->opening_angle * 180 / M_PI, house_angle, 3.0);
  EXPECT_GT(h->clear_width, 0.5 * h->width);
  ASSERT_EQ(doors.doors.size(), 1u);
  EXPECT_EQ(doors.doors[0].observations, 1u);
  EXPECT_EQ(doors.doors[0].last_seen, ros::Time(100.0));

  // 2. The house from pose b: the same id, two observations.
  ASSERT_TRUE(send(house_b, 103.0, &tracked, &doors)) << "no answer to cloud 2";
  ASSERT_EQ(tracked.doors.size(), 1u);
  EXPECT_EQ(tracked.doors[0].id, house_id);
  EXPECT_EQ(tracked.doors[0].observations, 2u);
  EXPECT_EQ(tracked.doors[0].last_seen, ros::Time(103.0));

  // 3. The far room: `doors` holds its doors only; tracked_doors keeps the
  // house door (last seen at 103, greyed in the markers) beside them. (The
  // robot drove 30 m in 12 s: under ~max_sensor_speed, no relocalisation.)
  ASSERT_TRUE(send(far, 115.0, &tracked, &doors)) << "no answer to cloud 3";
  const std::size_t n_far = doors.doors.size();
  ASSERT_GE(n_far, 1u) << "no door found in the far room";
  EXPECT_LE(n_far, far.truth["doors"].size());
  for (const auto& d : doors.doors) {
    EXPECT_GT(d.opening_center.x, 20.0) << "doors holds a door not in this cloud";
    bool matches_truth = false;
    for (const auto& t : far.truth["doors"]) matches_truth = matches_truth || near(doors, centreInMap(far, t)) == &d;
    EXPECT_TRUE(matches_truth) << "a far door at " << d.opening_center.x << ", " << d.opening_center.y << " is no true door";
  }
  ASSERT_EQ(tracked.doors.size(), 1 + n_far);
  h = near(tracked, house_door);
  ASSERT_NE(h, nullptr) << "the house door left tracked_doors when it left the view";
  EXPECT_EQ(h->id, house_id);
  EXPECT_EQ(h->observations, 2u);
  EXPECT_EQ(h->last_seen, ros::Time(103.0));
  std::set<std::uint32_t> far_ids;
  for (const auto& d : tracked.doors)
    if (&d != h) {
      EXPECT_EQ(d.last_seen, ros::Time(115.0));
      EXPECT_EQ(d.observations, 1u);
      far_ids.insert(d.id);
    }
  EXPECT_EQ(far_ids.size(), n_far);
  EXPECT_EQ(far_ids.count(house_id), 0u);
  visualization_msgs::MarkerArray markers;
  ASSERT_TRUE(markersAt(115.0, &markers)) << "no markers for cloud 3";
  int greyed = 0, vivid = 0;
  for (const auto& m : markers.markers) {
    if (m.ns != "tracked_leaf_lines") continue;
    if (m.id == static_cast<int>(house_id)) greyed += m.color.a < 0.5f;
    else vivid += m.color.a == 1.0f;
  }
  EXPECT_EQ(greyed, 1) << "the house door, not in view, is not greyed";
  EXPECT_EQ(vivid, static_cast<int>(n_far));

  // 4. The far room again at 125: ~forget_after_s is 20, the house door
  // (last seen 22 s before) is forgotten; the far doors keep their ids.
  ASSERT_TRUE(send(far, 125.0, &tracked, &doors)) << "no answer to cloud 4";
  EXPECT_EQ(near(tracked, house_door), nullptr) << "the house door was not forgotten";
  ASSERT_EQ(tracked.doors.size(), n_far);
  for (const auto& d : tracked.doors) {
    EXPECT_EQ(far_ids.count(d.id), 1u) << "a far door changed id";
    EXPECT_EQ(d.observations, 2u);
  }

  // 5. Time goes back 75 s (the bag starts again): the tracks are reset,
  // with a warning; the house door comes back with a new id.
  ASSERT_TRUE(send(house_a, 50.0, &tracked, &doors)) << "no answer after time went backwards";
  ASSERT_EQ(tracked.doors.size(), 1u);
  EXPECT_EQ(tracked.doors[0].observations, 1u);
  EXPECT_EQ(tracked.doors[0].last_seen, ros::Time(50.0));
  EXPECT_NE(tracked.doors[0].id, house_id);
  EXPECT_EQ(far_ids.count(tracked.doors[0].id), 0u);
  EXPECT_TRUE(logged(rosgraph_msgs::Log::WARN, "tracked_doors reset")) << "no warning on the reset";
  const std::uint32_t new_id = tracked.doors[0].id;
  ASSERT_TRUE(send(house_b, 53.0, &tracked, &doors)) << "the nodelet stopped answering after the reset";
  ASSERT_EQ(tracked.doors.size(), 1u);
  EXPECT_EQ(tracked.doors[0].id, new_id);
  EXPECT_EQ(tracked.doors[0].observations, 2u);

  // 6. The sensor jumps 8 m in map within 1 s (relocalisation): the tracks
  // are reset with a warning, no door is duplicated: the one door, where
  // the new pose puts it, with a new id.
  ASSERT_TRUE(send(jumped, 54.0, &tracked, &doors)) << "no answer after the relocalisation";
  ASSERT_EQ(tracked.doors.size(), 1u);
  EXPECT_NE(near(tracked, house_door + Eigen::Vector3d(0, 8, 0)), nullptr);
  EXPECT_NE(tracked.doors[0].id, new_id);
  EXPECT_EQ(tracked.doors[0].observations, 1u);
  EXPECT_TRUE(logged(rosgraph_msgs::Log::WARN, "relocalisation")) << "no warning on the relocalisation";
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracked_doors");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int rc = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return rc;
}
