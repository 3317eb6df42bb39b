// Where free space comes from (pipeline/sight.hpp): a viewpoint checked
// against the cloud, and stations inferred from the surfaces of a cloud
// that has none (rooms of several stations merged). Scenes with known
// truth, seeds printed.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "door_state_recognition/eval/evaluation.hpp"
#include "door_state_recognition/io/report.hpp"
#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/pipeline/sight.hpp"
#include "door_state_recognition/pipeline/viewpoint_choice.hpp"
#include "door_state_recognition/preprocess/camera.hpp"
#include "door_state_recognition/sim/drive.hpp"
#include "door_state_recognition/sim/lidar.hpp"
#include "door_state_recognition/sim/ground_truth.hpp"
#include "door_state_recognition/sim/registered.hpp"
#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/sim/sensors.hpp"
#include "xyz_cloud.hpp"

using namespace dsr;

namespace {

// A room of randomRoom(seed) scanned from `stations` positions, all their
// points in one cloud (the frame of the first station), as registered
// exports merge them.
struct Merged {
  sim::SimulatedCloud sim;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  nlohmann::json truth;
  eval::EvalResult score(const PipelineResult& r) const { return eval::evaluate(truth, io::reportJson(r, "sim"), 0.5, true); }
};

Merged merged(std::uint64_t seed, int stations, std::size_t rays_per_station, const sim::RandomSceneOptions& room = {}) {
  const sim::Scene scene = sim::buildScene(sim::randomRoom(seed, room));
  sim::TlsOptions o;
  o.seed = seed;
  o.viewpoints = stations;
  o.points = rays_per_station * static_cast<std::size_t>(stations);
  Merged m;
  m.sim = sim::scanTls(scene, o);
  m.cloud = xyz(m.sim.cloud);
  m.truth = sim::groundTruthJson(scene, m.sim);
  return m;
}

std::string doors(const PipelineResult& r) {
  std::ostringstream os;
  for (const auto& d : r.doors) os << " " << toString(d.state) << "@" << static_cast<int>(d.opening_angle_deg);
  return os.str();
}

// Cloud i of a drive, moved into map and run as the nodelet runs it (the
// sensor's origin the viewpoint), with the scene it shows.
struct DriveCloud {
  PipelineResult result;
  sim::Scene scene;
};
// The drive door_scene_sim --drive --sensor SENSOR --seed SEED plans.
sim::DrivePlan plannedDrive(const char* sensor, std::uint64_t seed) {
  sim::DriveOptions d;
  d.sensor = sensor;
  d.seed = seed;
  return sim::planDrive(sim::randomRoom(seed), d);
}

DriveCloud runDriveCloud(const sim::DrivePlan& plan, std::size_t i) {
  const sim::DriveFrame f = sim::simulateFrame(plan, i);
  pcl::PointCloud<pcl::PointXYZ> cloud = xyz(f.cloud.cloud);
  for (auto& q : cloud.points)
    if (std::isfinite(q.x)) q.getVector3fMap() = (f.cloud.sensor_to_world * q.getVector3fMap().cast<double>()).cast<float>();
  const Pipeline pipe{Parameters()};
  return {pipe.run(cloud, false, f.cloud.sensor_to_world.translation()), plan.scenes[static_cast<std::size_t>(f.scene_index)]};
}

// The doors a drive cloud reports where a true door is (within 0.5 m of its
// opening's centre); each other one a failure named by `where`.
int doorsAtTrueDoors(const DriveCloud& c, const std::string& where) {
  int at = 0;
  for (const DoorResult& door : c.result.doors) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const auto& t : c.scene.doors) nearest = std::min(nearest, (t.opening_center - door.opening_center).head<2>().norm());
    EXPECT_LT(nearest, 0.5) << where << ": a door where none is, at (" << door.opening_center.x() << ", "
                            << door.opening_center.y() << ")\n" << doors(c.result);
    at += nearest < 0.5;
  }
  return at;
}

}  // namespace

TEST(Sight, OneScansOwnViewpointIsCredibleAndAPointOutsideTheRoomIsNot) {
  const Parameters p;
  for (std::uint64_t seed = 3100; seed < 3104; ++seed) {
    const Merged one = merged(seed, 1, 200000);
    const sight::ViewpointCheck at_scanner = sight::checkViewpoint(one.cloud, Eigen::Vector3d::Zero(), p);
    EXPECT_TRUE(at_scanner.credible) << "seed " << seed << ": " << at_scanner.reason;
    EXPECT_LT(at_scanner.hidden_share, sight::kMaxHiddenShare) << "seed " << seed;
    EXPECT_GT(at_scanner.tested, 1000u) << "seed " << seed;
    // 12 m out along x, at the scanner's height: the room is seen from
    // outside its walls, its inside hidden behind them.
    const sight::ViewpointCheck outside = sight::checkViewpoint(one.cloud, Eigen::Vector3d(12, 0, 0), p);
    EXPECT_FALSE(outside.credible) << "seed " << seed << ": " << outside.reason;
  }
}

TEST(Sight, TheViewpointChoiceTakesACredibleViewpointAndMergesWhereOneIsNot) {
  // chooseViewpoints as door_state_cli --viewpoint runs it: one scan under
  // auto is seen from its VIEWPOINT (said taken, no note); the same scan
  // with its VIEWPOINT 12 m outside the room, beside another, makes both
  // one cloud without a viewpoint (a note says which and why); none
  // merges them; a VIEWPOINT that is not finite is refused.
  const Parameters p;
  const Merged one = merged(3100, 1, 200000);
  pcl::PointCloud<pcl::PointXYZ> outside = one.cloud;
  outside.sensor_origin_ = Eigen::Vector4f(12, 0, 0, 0);
  {
    sight::ViewpointChoice c;
    sight::chooseViewpoints({{&one.cloud, "scan", false}}, sight::ViewpointMode::Auto, std::nullopt,
                            Eigen::Vector3d::Zero(), p, c);
    ASSERT_EQ(c.stations.size(), 1u);
    EXPECT_FALSE(c.without_viewpoint);
    EXPECT_EQ(c.stations[0].cloud, &one.cloud);
    EXPECT_TRUE(c.notes.empty());
    ASSERT_EQ(c.taken.size(), 1u);
    EXPECT_NE(c.taken[0].find("of scan taken"), std::string::npos) << c.taken[0];
  }
  for (const sight::ViewpointMode mode : {sight::ViewpointMode::Auto, sight::ViewpointMode::None}) {
    sight::ViewpointChoice c;
    sight::chooseViewpoints({{&one.cloud, "a", false}, {&outside, "b", true}}, mode, std::nullopt,
                            Eigen::Vector3d::Zero(), p, c);
    EXPECT_TRUE(c.without_viewpoint);
    ASSERT_EQ(c.stations.size(), 1u);
    EXPECT_EQ(c.stations[0].cloud->size(), 2 * one.cloud.size());
    if (mode == sight::ViewpointMode::Auto) {
      ASSERT_EQ(c.notes.size(), 1u);
      EXPECT_NE(c.notes[0].find("b's VIEWPOINT (12, 0, 0) is not credible"), std::string::npos) << c.notes[0];
    }
  }
  {
    sight::ViewpointChoice c;
    sight::chooseViewpoints({{&one.cloud, "scan", false}}, sight::ViewpointMode::Header, std::nullopt,
                            Eigen::Vector3d::Zero(), p, c);
    EXPECT_FALSE(c.without_viewpoint);
    EXPECT_TRUE(c.taken.empty() && c.notes.empty());
  }
  pcl::PointCloud<pcl::PointXYZ> nan = one.cloud;
  nan.sensor_origin_ = Eigen::Vector4f(std::numeric_limits<float>::quiet_NaN(), 0, 0, 0);
  sight::ViewpointChoice c;
  EXPECT_THROW(sight::chooseViewpoints({{&nan, "nan", true}}, sight::ViewpointMode::None, std::nullopt,
                                       Eigen::Vector3d::Zero(), p, c),
               std::invalid_argument);
}

TEST(Sight, AMergedRoomHidesPointsFromItsFirstStation) {
  // Three stations merged, checked at the first: the other two saw what
  // the first could not (behind furniture, leaves, jambs). The share is
  // above the single scan's in every room and refuses most of them.
  const Parameters p;
  int refused = 0;
  std::ostringstream log;
  for (std::uint64_t seed = 3100; seed < 3106; ++seed) {
    const Merged one = merged(seed, 1, 200000), three = merged(seed, 3, 200000);
    const sight::ViewpointCheck a = sight::checkViewpoint(one.cloud, Eigen::Vector3d::Zero(), p);
    const sight::ViewpointCheck b = sight::checkViewpoint(three.cloud, Eigen::Vector3d::Zero(), p);
    log << "seed " << seed << ": one station " << a.hidden_share << ", three merged " << b.hidden_share << "\n";
    EXPECT_GT(b.hidden_share, a.hidden_share) << "seed " << seed;
    refused += !b.credible;
  }
  SCOPED_TRACE(log.str());
  EXPECT_GE(refused, 4);
}

// One laser scan of a cluttered room (shelves, bookcases, chairs) hides a
// few per cent of its points behind its own depth edges (the occluders'
// disks reach past an edge by their radius): above kMaxHiddenShare, so not
// credible as it stands, yet its own. Its viewpoint is taken with those
// points left out (the CLI's auto; they are not rays from it); before, the
// scan ran without a viewpoint, from stations inferred, and room 1023's
// leaf swung away was bounded 14 deg above its true angle. Seen from 12 m
// out, outside the room, nearly everything is hidden: no viewpoint.
TEST(Sight, AClutteredScansOwnViewpointIsTakenWithoutThePointsHiddenFromIt) {
  const Parameters p;
  sim::RandomSceneOptions room;
  room.clutter = true;
  const Merged one = merged(1023, 1, 400000, room);
  pcl::PointCloud<pcl::PointXYZ> visible;
  const sight::ViewpointCheck at_scanner = sight::checkViewpoint(one.cloud, Eigen::Vector3d::Zero(), p, &visible);
  SCOPED_TRACE(at_scanner.reason);
  EXPECT_FALSE(at_scanner.credible);
  ASSERT_TRUE(at_scanner.take_visible);
  EXPECT_LT(visible.size(), one.cloud.size());
  EXPECT_GT(visible.size(), one.cloud.size() * 95 / 100);
  pcl::PointCloud<pcl::PointXYZ> none;
  const sight::ViewpointCheck outside = sight::checkViewpoint(one.cloud, Eigen::Vector3d(12, 0, 0), p, &none);
  EXPECT_FALSE(outside.credible);
  EXPECT_FALSE(outside.take_visible);
  EXPECT_TRUE(none.empty());
}

TEST(Sight, AnOrganizedCloudIsItsSensorsOwn) {
  const sim::Scene scene = sim::buildScene(sim::randomRoom(3100));
  sim::RgbdOptions o;
  o.seed = 3100;
  const pcl::PointCloud<pcl::PointXYZ> frame = xyz(sim::captureRgbd(scene, o).cloud);
  ASSERT_GT(frame.height, 1u);
  Parameters p;
  p.up_axis = "-y";
  EXPECT_TRUE(sight::checkViewpoint(frame, Eigen::Vector3d::Zero(), p).credible);
}

// An organized cloud moved out of its sensor's frame with its VIEWPOINT left
// at 0 (a camera frame or a LiDAR sweep moved into base_link): its pixels'
// rays no longer meet there. Where they do meet is found (a camera's rows
// and columns, a LiDAR's columns are planes through the sensor; a LiDAR's
// rings cones about its axis), to the centimetre.
TEST(Sight, AnOrganizedCloudMovedOutOfItsSensorsFrameIsSeenFromWhereItsRaysMeet) {
  Parameters p;
  const Eigen::Vector3d shift(0.3, -1.2, 0.8);
  auto moved = [&](pcl::PointCloud<pcl::PointXYZ> c) {
    for (auto& q : c.points)
      if (q.getVector3fMap().allFinite()) q.getVector3fMap() += shift.cast<float>();
    return c;
  };
  const sim::Scene scene = sim::buildScene(sim::randomRoom(3100));
  sim::RgbdOptions ro;
  ro.seed = 3100;
  const pcl::PointCloud<pcl::PointXYZ> frame = xyz(sim::captureRgbd(scene, ro).cloud);
  sim::LidarOptions lo = sim::LidarOptions::preset(16);
  lo.seed = 3100;
  const pcl::PointCloud<pcl::PointXYZ> sweep = xyz(sim::scanLidar(scene, lo).cloud);
  for (const auto* c : {&frame, &sweep}) {
    SCOPED_TRACE(c == &frame ? "seed=3100 RGB-D frame" : "seed=3100 16-beam sweep");
    const sight::ViewpointCheck own = sight::checkViewpoint(*c, Eigen::Vector3d::Zero(), p);
    EXPECT_TRUE(own.credible) << own.reason;
    EXPECT_FALSE(own.rays_meet);
    const sight::ViewpointCheck away = sight::checkViewpoint(moved(*c), Eigen::Vector3d::Zero(), p);
    EXPECT_FALSE(away.credible) << away.reason;
    ASSERT_TRUE(away.rays_meet) << away.reason;
    EXPECT_LT((*away.rays_meet - shift).norm(), 0.01) << away.rays_meet->transpose();
  }
}

// preprocess::raySpacing: a depth camera's pixels lie 1/f rad apart (f =
// 525 px at 640x480), a rotating LiDAR's rings 45/63 deg (64 beams over
// +-22.5 deg) or 2 deg (16 beams over +-15 deg), its columns closer.
TEST(Sight, RaySpacingIsThePixelPitchOrTheRingPitch) {
  const sim::Scene scene = sim::buildScene(sim::randomRoom(3101));
  sim::RgbdOptions o;
  o.seed = 3101;
  // (off the optical axis neighbouring pixels subtend less: cos^2 of the angle off it)
  const double camera = preprocess::raySpacing(xyz(sim::captureRgbd(scene, o).cloud), Eigen::Vector3f::Zero());
  EXPECT_GE(camera, 0.8 / o.fx);
  EXPECT_LE(camera, 1.0 / o.fx);
  for (const int beams : {16, 64}) {
    sim::LidarOptions l = sim::LidarOptions::preset(beams);
    l.seed = 3101;
    const double pitch = (l.max_elevation_deg - l.min_elevation_deg) / (beams - 1) * M_PI / 180;
    EXPECT_NEAR(preprocess::raySpacing(xyz(sim::scanLidar(scene, l).cloud), Eigen::Vector3f::Zero()), pitch, 0.05 * pitch)
        << beams << " beams, seed 3101";
  }
  pcl::PointCloud<pcl::PointXYZ> unorganized = xyz(sim::captureRgbd(scene, o).cloud);
  unorganized.width = static_cast<std::uint32_t>(unorganized.size());
  unorganized.height = 1;
  EXPECT_EQ(preprocess::raySpacing(unorganized, Eigen::Vector3f::Zero()), 0.0);
}

// Two cupboards (1.9 and 2.2 m tall, 0.56 m deep) a door's width apart, the
// room's wall seen between them 0.56 m behind their fronts: a 64-beam LiDAR
// on a robot sees a plane with a gap, and what lies behind the gap is too
// shallow for a leaf out of sight (state/doors.cpp, depthBeyond) and deeper
// than a wall is thick for a closed one. Frames 0 and 3 of drive 1005 (in
// map, as the nodelet runs them) made it a door before.
TEST(Sight, AGapBetweenCupboardsIsNoDoorway) {
  const sim::DrivePlan plan = plannedDrive("lidar64", 1005);
  for (const std::size_t i : {std::size_t{0}, std::size_t{3}})
    doorsAtTrueDoors(runDriveCloud(plan, i), "drive 1005 frame " + std::to_string(i));
}

// Two cupboards 0.41 and 0.58 m deep against a wall, 0.8 m apart: a 16-beam
// LiDAR sees their fronts as one plane (fitted through both, 5 deg off the
// wall) with a gap, and the wall behind it through the gap and above them. The
// plane stands in front of the longer wall at a cupboard's depth: furniture,
// not a wall (segmentation::furnitureFronts). Cloud 10 of drive 1008 (in map,
// as the nodelet runs it) made the gap a semi-open door at 11 deg before.
TEST(Sight, TheFrontsOfCupboardsAgainstAWallAreNoWall) {
  const DriveCloud c = runDriveCloud(plannedDrive("lidar16", 1008), 10);
  const int found = doorsAtTrueDoors(c, "drive 1008 frame 10");
  // (The open door's leaf is out of sight of this cloud: its doorway, seen
  // only through a few rings, is not always found.)
  EXPECT_GE(found, 1) << "drive 1008 frame 10: the semi-open door" << doors(c.result);
}

// A 16-beam LiDAR (+-15 deg, 0.7 m mast) 1.45 m from a closed door: no ring
// reaches the ceiling in the room, but the top ring's points on the walls,
// their normals turned upright, made a "ceiling" 1.35 m above the sensor,
// and no wall reaches it: the cloud had no wall (in 108 of drive 1004's 118
// clouds). A level with wall straight below it is no ceiling
// (segmentation/floor_ceiling.cpp). Cloud 60 of lidar16 drive 1004 (in
// map, as the nodelet runs it).
TEST(Sight, ALidarsTopRingOnTheWallsIsNoCeiling) {
  const DriveCloud c = runDriveCloud(plannedDrive("lidar16", 1004), 60);
  EXPECT_FALSE(c.result.ceiling) << "drive 1004 frame 60: a ceiling at " << *c.result.ceiling;
  EXPECT_GE(c.result.walls.size(), 2u) << "drive 1004 frame 60: the walls beside the robot";
}

// A wardrobe (1.07 m wide, 0.56 deep) against a wall, seen from the side:
// its side (with a table's edge beyond) is found as a wall 1 m long, and the
// free space past the side's corner, over the table, as a doorway whose
// "leaf", hinged at the corner, is the wardrobe's front at 89 deg. The
// doorway reaches 0.28 m past the last point of its "wall": no doorway lies
// past its wall's end. Cloud 102 of lidar64 drive 1033 (in map, as the
// nodelet runs it) made it a semi-open door before; its three doors stay.
TEST(Sight, NoDoorwayLiesPastItsWallsEnd) {
  const DriveCloud c = runDriveCloud(plannedDrive("lidar64", 1033), 102);
  const int found = doorsAtTrueDoors(c, "drive 1033 frame 102");
  EXPECT_EQ(found, 3) << "drive 1033 frame 102: its three doors" << doors(c.result);
}

// Two doorways 0.9 m apart on one wall, their heads out of a 16-beam
// LiDAR's view: the right trim leg of the one and the left of the other,
// paired across the wall between them, made that wall a closed door. Each
// leg has its own opening just beyond it: it is that doorway's casing and
// pairs with no other (recognition/doorway_trim.cpp). Cloud 18 of lidar16
// drive 1023 (in map, as the nodelet runs it): the two true doors only.
TEST(Sight, TheTrimsOfTwoNeighbouringDoorwaysMakeNoDoorBetweenThem) {
  const DriveCloud c = runDriveCloud(plannedDrive("lidar16", 1023), 18);
  const int found = doorsAtTrueDoors(c, "drive 1023 frame 18");
  EXPECT_EQ(found, 2) << "drive 1023 frame 18: its two doors" << doors(c.result);
}

// A LiDAR's walls are fitted where its noise lies well inside the inlier
// band: the refit passes past the third turn them by hundredths of a degree,
// and such a turn (taken before, segmentation/wall_search.cpp) moved which
// noise points sat at the band's edge: in clouds 12 and 21 of lidar64 drive
// 1018 (in map, as the nodelet runs them) the closed door on the west wall
// lost a trim leg and a "closed door" was paired from its other leg to the
// corner, 0.8 m off.
TEST(Sight, ALidarWallAlreadyFittedIsNotTurned) {
  const sim::DrivePlan plan = plannedDrive("lidar64", 1018);
  for (const std::size_t i : {std::size_t{12}, std::size_t{21}}) {
    const DriveCloud c = runDriveCloud(plan, i);
    const PipelineResult& r = c.result;
    const sim::Scene& scene = c.scene;
    ASSERT_EQ(scene.doors.size(), 1u);
    const Eigen::Vector3d truth = scene.doors[0].opening_center;
    int at_door = 0;
    for (const DoorResult& door : r.doors) {
      // (Frame 21's other false door, 1.4 m wide between the two cupboards
      // on the south wall, is another matter: one cloud only, the drive's
      // confirmation leaves it out.)
      const double off = (truth - door.opening_center).head<2>().norm();
      if (off > 1.5) continue;
      EXPECT_LT(off, 0.15) << "drive 1018 frame " << i << ": a door beside the closed one, at (" << door.opening_center.x()
                           << ", " << door.opening_center.y() << ")\n" << doors(r);
      at_door += off < 0.15;
    }
    EXPECT_EQ(at_door, 1) << "drive 1018 frame " << i << ": the closed door" << doors(r);
  }
}

// What a doorway shows beyond it is a room, not one surface parallel to the
// wall just behind its face. In lidar64 drive 1049 a cupboard and a
// wardrobe stand 0.9 m apart along a wall; their fronts were taken for a
// wall, the gap between them for a doorway "seen through" onto the room's
// wall 0.57 m behind, and a leaf at 9.5 deg found in it (clouds 30 and 60;
// the drive kept it as an open door from 24 clouds).
TEST(Sight, TheBackOfARecessBetweenCupboardsIsNoRoomBeyond) {
  const sim::DrivePlan plan = plannedDrive("lidar64", 1049);
  for (const std::size_t i : {std::size_t{30}, std::size_t{60}}) {
    const DriveCloud c = runDriveCloud(plan, i);
    const std::string where = "drive 1049 frame " + std::to_string(i);
    EXPECT_EQ(doorsAtTrueDoors(c, where), 3) << where << ": its three doors" << doors(c.result);
  }
}

// A jamb is wall: a wall's ends are where its face is seen 1 m above the
// floor or higher. In lidar64 drive 1077 a wardrobe's side (0.6 m) was
// taken for a wall, a table's side 1.1 m on in its line for the wall's
// other end, the room between them for a doorway seen through and the
// wardrobe's front for a leaf at 90 deg (clouds 174 and 180).
TEST(Sight, TheSideOfATableIsNoJamb) {
  const sim::DrivePlan plan = plannedDrive("lidar64", 1077);
  for (const std::size_t i : {std::size_t{174}, std::size_t{180}}) {
    const DriveCloud c = runDriveCloud(plan, i);
    const std::string where = "drive 1077 frame " + std::to_string(i);
    EXPECT_EQ(doorsAtTrueDoors(c, where), 2) << where << ": the two doors in view" << doors(c.result);
  }
}

// An occupancy map's export (OctoMap, a voxel SLAM map): the centres of
// occupied 10 cm voxels, nothing else. Neighbourhoods sized in 2 cm voxels
// held no surface (0 walls, 0 doors on every room); the voxel size now
// follows a cloud sparser than 2.4 voxels (half its spacing) and says so.
TEST(Sight, AnOccupancyMapsVoxelCentresGetTheirDoors) {
  const Pipeline pipe{Parameters()};
  std::vector<eval::EvalResult> all;
  std::ostringstream log;
  for (std::uint64_t seed = 3200; seed < 3204; ++seed) {
    const Merged m = merged(seed, 3, 150000);
    const sim::SimulatedCloud map = sim::voxelMap(m.sim, 0.1);
    const pcl::PointCloud<pcl::PointXYZ> cloud = xyz(map.cloud);
    const PipelineResult r = pipe.runWithoutViewpoint(cloud, false);
    const eval::EvalResult e = m.score(r);
    log << "seed " << seed << ": " << cloud.size() << " voxel centres, " << r.walls.size() << " walls, matched "
        << e.matched << "/" << e.true_doors << " reported" << doors(r) << "\n";
    bool said = false;
    for (const std::string& w : r.warnings) said |= w.find("sparse cloud") != std::string::npos;
    EXPECT_TRUE(said) << "seed " << seed;
    EXPECT_GE(r.walls.size(), 1u) << "seed " << seed;
    all.push_back(e);
  }
  const eval::EvalResult sum = eval::merge(all);
  SCOPED_TRACE(log.str());
  EXPECT_GE(sum.recall(), 0.3);
  EXPECT_GE(sum.precision(), 0.8);
}

TEST(Sight, WithoutAViewpointAMergedRoomGetsItsDoors) {
  // Rooms of three stations merged into one cloud, run without a viewpoint:
  // the stations are inferred from the surfaces. Doors out of every
  // inferred station's sight (leaves swung away behind their walls) may be
  // missed; no door may be invented and the states found must be right.
  const Pipeline pipe{Parameters()};
  std::vector<eval::EvalResult> all;
  std::ostringstream log;
  for (std::uint64_t seed = 3200; seed < 3206; ++seed) {
    const Merged m = merged(seed, 3, 200000);
    const PipelineResult r = pipe.runWithoutViewpoint(m.cloud, false);
    const eval::EvalResult e = m.score(r);
    log << "seed " << seed << ": " << r.stations.size() << " stations, matched " << e.matched << "/" << e.true_doors
        << " reported" << doors(r) << "\n";
    EXPECT_FALSE(r.viewpoint.has_value()) << "seed " << seed;
    EXPECT_FALSE(r.stations.empty()) << "seed " << seed;
    EXPECT_EQ(r.points_in, m.cloud.size()) << "seed " << seed;
    all.push_back(e);
  }
  const eval::EvalResult sum = eval::merge(all);
  SCOPED_TRACE(log.str());
  EXPECT_GE(sum.precision(), 0.95);
  EXPECT_GE(sum.recall(), 0.8);
  EXPECT_GE(sum.stateAccuracyMeasured(), 0.95);
  EXPECT_LE(sum.angleMaeMeasuredDeg(), 3.0);
}

TEST(Sight, ALeafOnlyAThirdScannerSawIsMeasuredFromAMinorStation) {
  // Rooms of three stations merged, clutter (tuning seeds): two positions
  // inferred see all but a few per cent of the points. In 2017 the rest
  // holds the leaf of the one door, swung away into the room beyond at
  // 80 deg, which a scanner looking through the doorway saw: with two
  // stations it was reported NOT_CLOSED at its free-space bound. A third
  // station (minor: it adds 3-8 % of the points) measures it.
  const Pipeline pipe{Parameters()};
  sim::RandomSceneOptions clutter;
  clutter.clutter = true;
  {
    const Merged m = merged(2017, 3, 400000 / 3, clutter);
    const PipelineResult r = pipe.runWithoutViewpoint(m.cloud, false);
    const eval::EvalResult e = m.score(r);
    SCOPED_TRACE("seed 2017: " + std::to_string(r.stations.size()) + " stations, reported" + doors(r));
    EXPECT_GE(r.stations.size(), 3u);
    EXPECT_EQ(e.matched, 1);
    EXPECT_EQ(e.reported_doors, 1);
    EXPECT_EQ(e.state_correct, 1);
    ASSERT_EQ(r.doors.size(), 1u);
    EXPECT_FALSE(r.doors[0].angle_is_lower_bound);
    EXPECT_NEAR(r.doors[0].opening_angle_deg, m.truth["doors"][0]["opening_angle_deg"].get<double>(), 3.0);
  }
}

TEST(Sight, AMinorStationsDoorsOnlyRefineTheOthers) {
  // A station inferred from few points of its own (a minor one) may stand
  // where no scanner stood, beyond a doorway in the next room, and see the
  // room's walls from behind: its doors only refine doors the other
  // stations found (Station::refine_only). Two rooms 50 m apart, each one
  // station's scan: with the second refine-only, the doors are the first
  // room's alone; with both main, both rooms'.
  auto scan = [](std::uint64_t seed, double shift, pcl::PointCloud<pcl::PointXYZ>& cloud) {
    sim::TlsOptions o;
    o.seed = seed;
    o.points = 200000;
    cloud = xyz(sim::scanTls(sim::buildScene(sim::randomRoom(seed)), o).cloud);
    for (auto& q : cloud.points) q.x += static_cast<float>(shift);
    return Eigen::Vector3d(shift, 0, 0);
  };
  pcl::PointCloud<pcl::PointXYZ> a, b;
  const Eigen::Vector3d va = scan(3300, 0.0, a), vb = scan(3301, 50.0, b);
  const Pipeline pipe{Parameters()};
  const std::size_t alone_a = pipe.run(a, false, va).doors.size(), alone_b = pipe.run(b, false, vb).doors.size();
  ASSERT_GE(alone_a, 1u);
  ASSERT_GE(alone_b, 1u);
  EXPECT_EQ(pipe.runStations({{&a, va}, {&b, vb, true}}, false).doors.size(), alone_a);
  EXPECT_EQ(pipe.runStations({{&a, va}, {&b, vb}}, false).doors.size(), alone_a + alone_b);
}

TEST(Sight, WithoutAViewpointBookcasesBesideDoorsAreNoDoors) {
  // Rooms with clutter (seeds of the tuning range), two stations merged, run
  // without a viewpoint. A bookcase against a wall looked like a closed door:
  // its back panel a few centimetres off the wall like a leaf, its side
  // panels' and top's edges at the wall like trim. Its shelves and books
  // stand 15-40 cm before the wall across its width, where nothing stands
  // before a door (state/doors.cpp, furnishedShare). Before that rule each
  // of these seeds reported one such false door (closed@2, semi_open@8).
  // Since trim must stand out of the wall's noise (doorway_trim.cpp, kLegZ),
  // 1007's bookcase makes no candidate at all: the rule is needed on the others.
  const Pipeline pipe{Parameters()};
  sim::RandomSceneOptions room;
  room.clutter = true;
  for (std::uint64_t seed : {1007ull, 1009ull, 1024ull}) {
    const Merged m = merged(seed, 2, 200000, room);
    const PipelineResult r = pipe.runWithoutViewpoint(m.cloud, false);
    const eval::EvalResult e = m.score(r);
    bool furniture = false;  // the rule was needed: a candidate turned down as furniture
    for (const auto& t : r.trace) furniture |= t.find("(furniture)") != std::string::npos;
    if (seed != 1007) EXPECT_TRUE(furniture) << "seed " << seed;
    EXPECT_EQ(e.unmatched_report.size(), 0u) << "seed " << seed << ": reported" << doors(r);
    EXPECT_EQ(e.matched, e.true_doors) << "seed " << seed << ": reported" << doors(r);
  }
}

// A cluttered room of three stations as a mesh-like export (40k vertices),
// run without a viewpoint, scored against its truth.
struct MeshRoom {
  nlohmann::json truth;
  PipelineResult result;
  eval::EvalResult score;
};

MeshRoom meshLikeRoom(std::uint64_t seed) {
  sim::RandomSceneOptions room;
  room.clutter = true;
  const sim::Scene scene = sim::buildScene(sim::randomRoom(seed, room));
  sim::TlsOptions o;
  o.seed = seed;
  o.viewpoints = 3;
  o.points = 400000;
  const sim::SimulatedCloud merged = sim::mergeStations(scene, sim::scanTls(scene, o), {sim::MergedFrame::Map, seed});
  sim::MeshLikeOptions mesh;
  mesh.vertices = 40000;
  mesh.seed = seed;
  const sim::SimulatedCloud cloud = sim::meshLike(merged, mesh);
  MeshRoom m;
  m.truth = sim::groundTruthJson(scene, cloud);
  m.result = Pipeline{Parameters()}.runWithoutViewpoint(xyz(cloud.cloud), false);
  m.score = eval::evaluate(m.truth, io::reportJson(m.result, "sim"), 0.5, true);
  return m;
}

TEST(Sight, AStationStandsWhereItsScannerSawTheFloorAround) {
  // Tuning seed 2007. The wall behind bookcases and a low cabinet was never
  // scanned: a position inferred beyond that wall, in the next room, where
  // only a wedge of floor through a doorway was seen, looked through those
  // holes and read the furniture's backs as three doors (closed@3,
  // semi_open@60, semi_open@90). A scanner sees the floor around where it
  // stands, out to the first wall or furniture (inferred_stations.cpp).
  const MeshRoom m = meshLikeRoom(2007);
  SCOPED_TRACE("seed 2007: " + std::to_string(m.result.stations.size()) + " stations, reported" + doors(m.result));
  EXPECT_EQ(m.score.matched, m.score.true_doors);
  EXPECT_LE(m.score.unmatched_report.size(), 1u);  // one bookcase is still taken (open@90)
}

TEST(Sight, AWindowSeenThroughAboveFurnitureIsNoDoorway) {
  // Tuning seeds 2000 and 2012: a window over a low cabinet, seen through
  // above it, no leaf in sight: reported not_closed@54 and open@116 at the
  // free-space bound. A doorway reaches the floor; under the window the
  // rays met the cabinet's front (state/doors.cpp, kUnseenLowPast).
  for (std::uint64_t seed : {2000ull, 2012ull}) {
    const MeshRoom m = meshLikeRoom(seed);
    SCOPED_TRACE("seed " + std::to_string(seed) + ": reported" + doors(m.result));
    for (const auto& w : m.truth["decoys"]) {
      if (w["kind"] != "window") continue;
      const Eigen::Vector2d c(w["center"][0].get<double>(), w["center"][1].get<double>());
      for (const auto& d : m.result.doors)
        EXPECT_GT((d.opening_center.head<2>() - c).norm(), 0.5) << "a door at the window";
    }
    EXPECT_EQ(m.score.matched, m.score.true_doors);
  }
}

TEST(Sight, ACupboardsSideAtAJambIsNoLeaf) {
  // Tuning seeds 2005 and 2007 (mesh-like, clutter): a doorway seen
  // through, its leaf swung away out of sight, a cupboard against the wall
  // at its jamb. The cupboard's side, half a door wide, was measured as the
  // leaf (open@94, hinge 1.24 m off; @82, 1.17 m off). A leaf is as wide as
  // its doorway: rays pass where the rest of such a leaf would stand
  // (state/leaf_internal.hpp, kRestSeenThrough).
  for (std::uint64_t seed : {2005ull, 2007ull}) {
    const MeshRoom m = meshLikeRoom(seed);
    SCOPED_TRACE("seed " + std::to_string(seed) + ": reported" + doors(m.result));
    ASSERT_GT(m.score.matched, 0);
    for (const eval::DoorMatch& match : m.score.matches) {
      if (match.angle_is_lower_bound) continue;
      EXPECT_LT(match.hinge_error_m, 0.3) << "true door " << match.truth_index << ": a leaf measured off its hinge";
    }
  }
}

TEST(Sight, AWardrobesSideIsNoLeafWhereItsFrontStandsBeforeTheDoorway) {
  // Lidar64 drive 1077 (tuning range 1040-1079), in the room behind its
  // open door: a wardrobe against the wall, its side read as a leaf at 89
  // deg towards the sensor, hinged at the wall, the wall hidden behind the
  // wardrobe read as its doorway: a false door tracked for 9 clouds.
  // Before an open leaf's tip, on the side of the doorway it opens, a
  // passage runs; there the wardrobe's front stands (state/leaf_internal.hpp,
  // kTipFront).
  const sim::DrivePlan plan = plannedDrive("lidar64", 1077);
  for (std::size_t i : {216u, 222u, 228u, 234u, 240u}) {
    const DriveCloud c = runDriveCloud(plan, i);
    doorsAtTrueDoors(c, "drive 1077, cloud " + std::to_string(i));
  }
}

// A leaf swung towards a station hides the wall beside its hinge. Seen
// from a station inferred off the scanners' positions, rays pass there
// through the wall's missing points, and that stretch looks like a doorway
// holding the same leaf at 180 deg less its angle. Each of these rooms of
// the tuning range (clutter, two stations merged) reported such a second
// door in the merged2-400k-clutter-2000 sweep (door_scene_sim --merge, in
// map: semi_open@52 beside open@128, @64 beside @116, @84 beside @96, @105
// beside @75); in the first station's frame, as here, 2013 still does
// without the rule. One leaf is one door: of two reports claiming it, the
// doorway framed by trim is the door's (sameLeaf, surerReport).
TEST(Sight, OneLeafIsOneDoorNotAlsoTheWallInItsShadow) {
  const Pipeline pipe{Parameters()};
  sim::RandomSceneOptions room;
  room.clutter = true;
  for (std::uint64_t seed : {2006ull, 2008ull, 2013ull, 2022ull}) {
    const Merged m = merged(seed, 2, 200000, room);
    const PipelineResult r = pipe.runWithoutViewpoint(m.cloud, false);
    const eval::EvalResult e = m.score(r);
    EXPECT_EQ(e.unmatched_report.size(), 0u) << "seed " << seed << ": reported" << doors(r);
    for (std::size_t i = 0; i < r.doors.size(); ++i)
      for (std::size_t j = i + 1; j < r.doors.size(); ++j)
        EXPECT_FALSE(sameLeaf(r.doors[i], r.doors[j])) << "seed " << seed << ": reported" << doors(r);
  }
  // The rule itself: the same leaf (hinges 5 cm apart, leaves parallel)
  // claimed from doorways 0.8 m apart goes to the one with trim, however
  // sure the other; without a shared leaf the surer wins; a measured leaf
  // always beats a bound.
  DoorResult framed, shadow;
  framed.hinge = Eigen::Vector3d(0, 0, 0);
  shadow.hinge = Eigen::Vector3d(0.05, 0, 0);
  framed.leaf_line_direction = shadow.leaf_line_direction = Eigen::Vector3d(0.6, 0.8, 0);
  framed.opening_center = Eigen::Vector3d(-0.45, 0, 0);
  shadow.opening_center = Eigen::Vector3d(0.4, 0, 0);
  framed.casing = true;
  framed.confidence = 0.84;
  shadow.confidence = 0.96;
  EXPECT_TRUE(sameLeaf(framed, shadow));
  EXPECT_TRUE(surerReport(framed, shadow));
  EXPECT_FALSE(surerReport(shadow, framed));
  DoorResult elsewhere = shadow;
  elsewhere.hinge = Eigen::Vector3d(2.0, 0, 0);
  EXPECT_FALSE(sameLeaf(framed, elsewhere));
  EXPECT_TRUE(surerReport(elsewhere, framed));
  framed.angle_is_lower_bound = true;
  EXPECT_TRUE(surerReport(shadow, framed));
}

TEST(Sight, NoViewpointOnASingleScanStillFindsItsDoors) {
  const Pipeline pipe{Parameters()};
  for (std::uint64_t seed = 3300; seed < 3303; ++seed) {
    const Merged m = merged(seed, 1, 300000);
    const PipelineResult with = pipe.run(m.cloud, false), without = pipe.runWithoutViewpoint(m.cloud, false);
    const eval::EvalResult a = m.score(with), b = m.score(without);
    EXPECT_GE(b.matched, a.matched) << "seed " << seed << ": with" << doors(with) << ", without" << doors(without);
    EXPECT_EQ(b.unmatched_report.size(), 0u) << "seed " << seed << ": without" << doors(without);
    EXPECT_EQ(b.state_correct, b.matched) << "seed " << seed << ": without" << doors(without);
    ASSERT_TRUE(with.viewpoint.has_value());
    EXPECT_TRUE(with.viewpoint->isZero());
  }
}

TEST(Sight, CloudsWithoutRoomsGiveZeroDoorsAndAWarning) {
  const Pipeline pipe{Parameters()};
  // A floor alone: no vertical structure.
  pcl::PointCloud<pcl::PointXYZ> floor;
  for (int i = 0; i < 200; ++i)
    for (int j = 0; j < 200; ++j) floor.push_back(pcl::PointXYZ(0.02f * i, 0.02f * j, 0));
  const PipelineResult a = pipe.runWithoutViewpoint(floor, true);
  EXPECT_TRUE(a.doors.empty());
  EXPECT_FALSE(a.warnings.empty());
  // Empty, and a handful of points.
  const PipelineResult b = pipe.runWithoutViewpoint(pcl::PointCloud<pcl::PointXYZ>(), true);
  EXPECT_TRUE(b.doors.empty());
  EXPECT_FALSE(b.warnings.empty());
  pcl::PointCloud<pcl::PointXYZ> few;
  few.push_back(pcl::PointXYZ(1, 2, 3));
  few.push_back(pcl::PointXYZ(std::numeric_limits<float>::quiet_NaN(), 0, 0));
  EXPECT_TRUE(pipe.runWithoutViewpoint(few, true).doors.empty());
  // Too many points are refused, as run() refuses them.
  Parameters small;
  small.max_points = 1000;
  EXPECT_THROW(Pipeline(small).runWithoutViewpoint(floor, false), std::invalid_argument);
  // A merged room in millimetres read as metres: said so (not "no enclosed
  // free space"); the same room in metres is not.
  Merged m = merged(3200, 2, 100000);
  const PipelineResult in_m = pipe.runWithoutViewpoint(m.cloud, false);
  for (auto& q : m.cloud.points) q.getVector3fMap() *= 1000.0f;
  const PipelineResult in_mm = pipe.runWithoutViewpoint(m.cloud, false);
  auto says = [](const PipelineResult& r) {
    return std::any_of(r.warnings.begin(), r.warnings.end(),
                       [](const std::string& w) { return w.find("millimetres read as metres") != std::string::npos; });
  };
  EXPECT_TRUE(says(in_mm));
  EXPECT_TRUE(in_mm.doors.empty());
  EXPECT_FALSE(says(in_m));
  EXPECT_FALSE(in_m.doors.empty());
}
