// DoorFusion (issue 20): door states fused over the processed clouds of a
// drive, in a fixed frame. Doors are built by hand (what the pipeline
// reports in a fixed frame); each test names the rule of
// include/door_state_recognition/tracking/door_fusion.hpp it checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <vector>

#include "door_state_recognition/tracking/door_fusion.hpp"
#include "door_state_recognition/tracking/drive_tracker.hpp"

using dsr::DoorFusion;
using dsr::DoorResult;
using dsr::DoorStateKind;
using dsr::FusionOptions;
using dsr::TrackedDoor;

namespace {

// A door in the fixed frame (z up) on a wall along `wall`, its opening centre at `c`.
DoorResult door(const Eigen::Vector3d& c, double angle_deg, bool bound = false, double confidence = 0.6,
                const Eigen::Vector3d& wall = Eigen::Vector3d::UnitX()) {
  DoorResult d;
  d.opening_center = c;
  d.hinge = c - 0.45 * wall;
  d.opening_angle_deg = angle_deg;
  d.angle_is_lower_bound = bound;
  d.state = bound ? (angle_deg >= 90 ? DoorStateKind::Open : DoorStateKind::NotClosed)
                  : angle_deg < 5 ? DoorStateKind::Closed
                  : angle_deg < 90 ? DoorStateKind::SemiOpen
                                   : DoorStateKind::Open;
  d.confidence = bound ? 0.3 : confidence;
  d.width = 0.9;
  d.height = 2.0;
  d.clear_width = dsr::clearWidth(d.width, angle_deg, 0.04, 5.0);
  d.wall_line_point = c;
  d.wall_line_direction = wall;
  d.wall_normal = Eigen::Vector3d::UnitZ().cross(wall);
  return d;
}

const TrackedDoor* byId(const DoorFusion& f, std::uint32_t id) {
  for (const TrackedDoor& t : f.tracks())
    if (t.id == id) return &t;
  return nullptr;
}

const Eigen::Vector3d kA(1, 0, 0), kB(4, 0, 0);

}  // namespace

TEST(DoorFusion, AMeasuredLeafBeatsABoundAndABoundNeverReplacesAMeasuredLeaf) {
  DoorFusion f;
  const auto u0 = f.update({door(kA, 40, true)}, 1.0);
  ASSERT_EQ(f.tracks().size(), 1u);
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::NotClosed);
  EXPECT_TRUE(f.tracks()[0].door.angle_is_lower_bound);
  // The leaf comes into sight: measured at 110 deg (below the 40 deg bound's +20
  // or not, a measurement beats a bound at once).
  f.update({door(kA, 110)}, 2.0);
  ASSERT_EQ(f.tracks().size(), 1u);
  EXPECT_EQ(f.tracks()[0].id, u0.ids[0]);
  EXPECT_FALSE(f.tracks()[0].door.angle_is_lower_bound);
  EXPECT_DOUBLE_EQ(f.tracks()[0].door.opening_angle_deg, 110);
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::Open);
  // Out of sight again, bounded at 60 (consistent with 110): the measurement stays.
  f.update({door(kA, 60, true)}, 3.0);
  EXPECT_FALSE(f.tracks()[0].door.angle_is_lower_bound);
  EXPECT_DOUBLE_EQ(f.tracks()[0].door.opening_angle_deg, 110);
  EXPECT_EQ(f.tracks()[0].observations, 3u);
  EXPECT_DOUBLE_EQ(f.tracks()[0].last_seen, 3.0);
  EXPECT_DOUBLE_EQ(f.tracks()[0].first_seen, 1.0);
}

TEST(DoorFusion, BoundsFromSeveralPositionsCombineAndReachOpen) {
  DoorFusion f;
  f.update({door(kA, 44, true)}, 1.0);
  f.update({door(kA, 30, true)}, 2.0);  // a lower bound from elsewhere says less: 44 holds
  ASSERT_EQ(f.tracks().size(), 1u);
  EXPECT_DOUBLE_EQ(f.tracks()[0].door.opening_angle_deg, 44);
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::NotClosed);
  f.update({door(kA, 72, true)}, 3.0);
  EXPECT_DOUBLE_EQ(f.tracks()[0].door.opening_angle_deg, 72);
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::NotClosed);
  const double narrow = f.tracks()[0].door.clear_width;
  f.update({door(kA, 96, true)}, 4.0);  // the combined bound reaches open_from_deg
  EXPECT_DOUBLE_EQ(f.tracks()[0].door.opening_angle_deg, 96);
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::Open);
  EXPECT_TRUE(f.tracks()[0].door.angle_is_lower_bound);
  EXPECT_GT(f.tracks()[0].door.clear_width, narrow);
  EXPECT_EQ(f.tracks()[0].observations, 4u);
  // The fusion's own open_from_deg decides the state of a combined bound.
  FusionOptions o;
  o.open_from_deg = 100;
  DoorFusion g(o);
  g.update({door(kA, 96, true)}, 1.0);
  EXPECT_EQ(g.tracks()[0].door.state, DoorStateKind::NotClosed);
}

TEST(DoorFusion, AStateChangeTakesOverWithinTwoClouds) {
  DoorFusion f;  // state_change_deg 20, sure_confidence 0.9
  for (int k = 0; k < 5; ++k) f.update({door(kA, 0, false, 0.8)}, 1.0 + k);
  ASSERT_EQ(f.tracks()[0].door.state, DoorStateKind::Closed);
  // The door is opened to 60 deg: the first cloud that shows it keeps the
  // old state pending, the second takes it over.
  f.update({door(kA, 60, false, 0.7)}, 10.0);
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::Closed);
  f.update({door(kA, 62, false, 0.7)}, 11.0);
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::SemiOpen);
  EXPECT_NEAR(f.tracks()[0].door.opening_angle_deg, 62, 1e-12);
  // Closed again, seen surely (confidence >= sure_confidence): at once.
  f.update({door(kA, 0, false, 0.95)}, 12.0);
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::Closed);
  // Opened and then swung out of sight: two bounds far above the closed
  // leaf confirm each other (the larger holds).
  f.update({door(kA, 70, true)}, 13.0);
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::Closed);
  f.update({door(kA, 96, true)}, 14.0);
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::Open);
  EXPECT_TRUE(f.tracks()[0].door.angle_is_lower_bound);
  EXPECT_DOUBLE_EQ(f.tracks()[0].door.opening_angle_deg, 96);
  // Clouds that do not show the door leave a departure pending.
  DoorFusion g;
  g.update({door(kA, 10, false, 0.8)}, 1.0);
  g.update({door(kA, 80, false, 0.6)}, 2.0);
  g.update({door(kB, 0, false, 0.6)}, 3.0);  // another door only
  EXPECT_DOUBLE_EQ(g.tracks()[0].door.opening_angle_deg, 10);
  g.update({door(kA, 78, false, 0.6)}, 4.0);
  EXPECT_DOUBLE_EQ(g.tracks()[0].door.opening_angle_deg, 78);
}

TEST(DoorFusion, ASingleNoisyOutlierDoesNotFlipTheState) {
  DoorFusion f;
  f.update({door(kA, 30, false, 0.8)}, 1.0);
  f.update({door(kA, 110, false, 0.7)}, 2.0);  // one cloud off by 80 deg
  f.update({door(kA, 31, false, 0.7)}, 3.0);   // back in agreement: the departure is dropped
  f.update({door(kA, 108, false, 0.7)}, 4.0);  // another lone outlier, not confirmed by the last
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::SemiOpen);
  EXPECT_NEAR(f.tracks()[0].door.opening_angle_deg, 30, 1.5);
  // Two departures that disagree with each other confirm nothing.
  f.update({door(kA, 3, false, 0.7)}, 5.0);
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::SemiOpen);
  // Agreeing measurements within state_change_deg keep the most confident.
  f.update({door(kA, 34, false, 0.85)}, 6.0);
  EXPECT_DOUBLE_EQ(f.tracks()[0].door.opening_angle_deg, 34);
  f.update({door(kA, 45, false, 0.5)}, 7.0);
  EXPECT_DOUBLE_EQ(f.tracks()[0].door.opening_angle_deg, 34);
  EXPECT_EQ(f.tracks()[0].observations, 7u);
}

TEST(DoorFusion, IdsAreStableOnePerDoorOverADrive) {
  DoorFusion f;
  // Two doors 3 m apart on one wall and one on a wall square to it, 0.3 m
  // from the first: seen from a moving robot, the centres wander by up to
  // 0.2 m and the heights differ (a camera's floor estimate).
  const Eigen::Vector3d kC(1.3, 0.3, 0);
  std::set<std::uint32_t> ids;
  for (int k = 0; k < 20; ++k) {
    const double w = 0.2 * std::sin(k * 1.3);
    std::vector<DoorResult> doors;
    if (k % 3 != 0) doors.push_back(door(kA + Eigen::Vector3d(w, 0.5 * w, 0.3 * w), 30));
    if (k % 2 == 0) doors.push_back(door(kB + Eigen::Vector3d(-w, 0, 0), 0));
    if (k > 5) doors.push_back(door(kC + Eigen::Vector3d(0, w, 0), 90, false, 0.6, Eigen::Vector3d::UnitY()));
    const auto u = f.update(doors, 1.0 + k);
    for (std::size_t i = 0; i < doors.size(); ++i) {
      EXPECT_TRUE(u.tracked[i]);
      ids.insert(u.ids[i]);
    }
  }
  EXPECT_EQ(ids.size(), 3u);
  EXPECT_EQ(f.tracks().size(), 3u);
  // A door first seen 0.45 m off its later position along the wall (two
  // tracks for a while) is joined into the older id once the centres come
  // within match_distance_m.
  DoorFusion g;
  const auto first = g.update({door(kA, 30)}, 1.0);
  g.update({door(kA + Eigen::Vector3d(0.7, 0, 0), 30)}, 2.0);  // too far: a second track
  ASSERT_EQ(g.tracks().size(), 2u);
  for (int k = 0; k < 4; ++k) g.update({door(kA + Eigen::Vector3d(0.3, 0, 0), 30)}, 3.0 + k);
  ASSERT_EQ(g.tracks().size(), 1u);
  EXPECT_EQ(g.tracks()[0].id, first.ids[0]);
  EXPECT_EQ(g.tracks()[0].observations, 6u);
}

TEST(DoorFusion, TwoTracksJoinedKeepTheEstimateMostCloudsAgreedOn) {
  // RGB-D drive 1016: a closed door shown by 19 clouds; one stray report
  // 0.54 m along the wall (semi-open 6 deg, a doorway misplaced) starts a
  // second track, a later report between the two joins it (nearest first),
  // and the two tracks, now within match_distance_m, are joined. The door
  // stands where 19 clouds put it: the joined track keeps that estimate.
  DoorFusion f;
  for (int k = 0; k < 19; ++k) f.update({door(kA, 0.1, false, 0.94)}, 1.0 + k);
  f.update({door(kA + Eigen::Vector3d(0.54, 0, 0), 6, false, 0.7)}, 30.0);
  ASSERT_EQ(f.tracks().size(), 2u);
  f.update({door(kA + Eigen::Vector3d(0.35, 0, 0), 2, false, 0.6)}, 31.0);
  ASSERT_EQ(f.tracks().size(), 1u);
  EXPECT_EQ(f.tracks()[0].observations, 21u);
  EXPECT_EQ(f.tracks()[0].door.state, DoorStateKind::Closed);
  EXPECT_LT((f.tracks()[0].door.opening_center - kA).norm(), 0.05);
  // Estimates that depart by more than state_change_deg: the door moved
  // since, and the one seen last holds, whatever the counts.
  DoorFusion g;
  for (int k = 0; k < 19; ++k) g.update({door(kA, 0.1, false, 0.94)}, 1.0 + k);
  g.update({door(kA + Eigen::Vector3d(0.54, 0, 0), 60, false, 0.7)}, 30.0);
  g.update({door(kA + Eigen::Vector3d(0.35, 0, 0), 60, false, 0.6)}, 31.0);
  ASSERT_EQ(g.tracks().size(), 1u);
  EXPECT_EQ(g.tracks()[0].door.state, DoorStateKind::SemiOpen);
  EXPECT_NEAR(g.tracks()[0].door.opening_angle_deg, 60, 1e-9);
}

TEST(DoorFusion, TwoDoorsSeenInOneCloudAreNeverOne) {
  DoorFusion f;
  // Two doors 0.45 m apart in one cloud (a double door): two tracks.
  const auto u = f.update({door(kA, 30), door(kA + Eigen::Vector3d(0.45, 0, 0), 0)}, 1.0);
  EXPECT_NE(u.ids[0], u.ids[1]);
  f.update({door(kA, 30), door(kA + Eigen::Vector3d(0.45, 0, 0), 0)}, 2.0);
  EXPECT_EQ(f.tracks().size(), 2u);
}

TEST(DoorFusion, ADoorNotSeenForForgetAfterIsForgotten) {
  FusionOptions o;
  o.forget_after_s = 10;
  DoorFusion f(o);
  const auto u = f.update({door(kA, 30), door(kB, 0)}, 100.0);
  for (int k = 1; k <= 10; ++k) f.update({door(kB, 0)}, 100.0 + k);
  // At 110 s door A was last seen 10 s ago: kept, not seen now.
  ASSERT_NE(byId(f, u.ids[0]), nullptr);
  EXPECT_FALSE(byId(f, u.ids[0])->seen_now);
  EXPECT_TRUE(byId(f, u.ids[1])->seen_now);
  EXPECT_DOUBLE_EQ(byId(f, u.ids[0])->last_seen, 100.0);
  const auto later = f.update({door(kB, 0)}, 110.5);
  EXPECT_EQ(byId(f, u.ids[0]), nullptr);
  EXPECT_EQ(later.forgotten, 1u);
  EXPECT_NE(byId(f, u.ids[1]), nullptr);
  // Seen again later: a new track, a new id.
  const auto again = f.update({door(kA, 30), door(kB, 0)}, 111.0);
  EXPECT_NE(again.ids[0], u.ids[0]);
  EXPECT_EQ(again.ids[1], u.ids[1]);
}

TEST(DoorFusion, TimeGoingBackwardsResetsAndOutOfOrderCloudsAreIgnored) {
  DoorFusion f;  // backwards_tolerance_s 1
  const auto u = f.update({door(kA, 30), door(kB, 0)}, 50.0);
  f.update({door(kA, 30)}, 51.0);
  // Out of order within the tolerance: ignored, last_seen does not move back.
  const auto late = f.update({door(kA, 80, false, 0.95)}, 50.5);
  EXPECT_EQ(late.outcome, DoorFusion::Outcome::IgnoredOutOfOrder);
  EXPECT_FALSE(late.tracked[0]);
  ASSERT_EQ(f.tracks().size(), 2u);
  EXPECT_DOUBLE_EQ(byId(f, u.ids[0])->last_seen, 51.0);
  EXPECT_DOUBLE_EQ(byId(f, u.ids[0])->door.opening_angle_deg, 30);
  EXPECT_EQ(byId(f, u.ids[0])->observations, 2u);
  EXPECT_FALSE(byId(f, u.ids[0])->seen_now);
  // A NaN stamp: ignored.
  EXPECT_EQ(f.update({door(kA, 30)}, std::nan("")).outcome, DoorFusion::Outcome::IgnoredBadStamp);
  EXPECT_EQ(f.tracks().size(), 2u);
  // The bag starts again at 10 s: every track dropped, this cloud starts anew.
  const auto reset = f.update({door(kB, 0)}, 10.0);
  EXPECT_EQ(reset.outcome, DoorFusion::Outcome::Reset);
  ASSERT_EQ(f.tracks().size(), 1u);
  EXPECT_EQ(f.tracks()[0].observations, 1u);
  EXPECT_DOUBLE_EQ(f.tracks()[0].last_seen, 10.0);
  EXPECT_NE(reset.ids[0], u.ids[1]) << "ids are not reused after a reset";
  EXPECT_DOUBLE_EQ(f.newestStamp(), 10.0);
  EXPECT_EQ(f.update({door(kB, 0)}, 11.0).outcome, DoorFusion::Outcome::Fused);
  EXPECT_EQ(f.tracks()[0].observations, 2u);
}

TEST(DoorFusion, MalformedDoorsAndOptionsAreRefusedCleanly) {
  DoorFusion f;
  DoorResult nan_centre = door(kA, 30);
  nan_centre.opening_center.x() = std::nan("");
  DoorResult no_wall = door(kB, 30);
  no_wall.wall_line_direction = Eigen::Vector3d::UnitZ();  // nothing across up
  DoorResult nan_angle = door(Eigen::Vector3d(8, 0, 0), std::nan(""));
  const auto u = f.update({nan_centre, no_wall, nan_angle, door(Eigen::Vector3d(12, 0, 0), 10)}, 1.0,
                          Eigen::Vector3d::Zero());  // a zero up: +z
  EXPECT_FALSE(u.tracked[0]);
  EXPECT_FALSE(u.tracked[1]);
  EXPECT_FALSE(u.tracked[2]);
  EXPECT_TRUE(u.tracked[3]);
  EXPECT_EQ(f.tracks().size(), 1u);
  using Spoil = void (*)(FusionOptions&);
  for (Spoil bad : std::vector<Spoil>{+[](FusionOptions& o) { o.forget_after_s = 0; },
                                      +[](FusionOptions& o) { o.state_change_deg = -1; },
                                      +[](FusionOptions& o) { o.match_distance_m = std::nan(""); },
                                      +[](FusionOptions& o) { o.open_from_deg = 3; }}) {
    FusionOptions o;
    bad(o);
    EXPECT_THROW(DoorFusion{o}, std::invalid_argument);
    EXPECT_THROW(f.setOptions(o), std::invalid_argument);
  }
  EXPECT_EQ(f.tracks().size(), 1u);
}

TEST(ClearWidth, TheDoorwayLessWhatTheLeafTakes) {
  // width*(1 - max(0, cos a)) - thickness*sin a, 0 when closed.
  EXPECT_DOUBLE_EQ(dsr::clearWidth(0.9, 0, 0.04, 5), 0.0);
  EXPECT_DOUBLE_EQ(dsr::clearWidth(0.9, 4.9, 0.04, 5), 0.0);
  EXPECT_NEAR(dsr::clearWidth(0.9, 90, 0.04, 5), 0.86, 1e-12);
  EXPECT_NEAR(dsr::clearWidth(0.9, 180, 0.04, 5), 0.9, 1e-12);
  EXPECT_NEAR(dsr::clearWidth(0.9, 60, 0.04, 5), 0.9 - 0.45 - 0.04 * std::sin(M_PI / 3), 1e-12);
  EXPECT_NEAR(dsr::clearWidth(0.9, 120, 0.04, 5), 0.9 - 0.04 * std::sin(2 * M_PI / 3), 1e-12);
  // A leaf barely ajar with a thick leaf leaves nothing, never a negative width.
  EXPECT_DOUBLE_EQ(dsr::clearWidth(0.9, 6, 0.3, 5), 0.0);
  EXPECT_DOUBLE_EQ(dsr::clearWidth(std::nan(""), 60, 0.04, 5), 0.0);
  EXPECT_DOUBLE_EQ(dsr::clearWidth(0.9, std::nan(""), 0.04, 5), 0.0);
  // Grows with the angle up to 180 deg.
  double last = -1;
  for (int a = 5; a <= 180; a += 5) {
    const double w = dsr::clearWidth(0.9, a, 0.04, 5);
    EXPECT_GE(w, last - 1e-12) << a << " deg";
    last = w;
  }
}

// DriveTracker (tracking/drive_tracker.hpp): the relocalisation rule and the
// pipeline's thresholds, on top of DoorFusion.
TEST(DriveTracker, ASensorJumpBeyondMaxSpeedResetsTheTracksAndAnUnknownSensorIsNotJudged) {
  dsr::DriveTrackerOptions o;
  o.max_sensor_speed = 1.0;  // m/s, + 0.5 m slack
  dsr::DriveTracker t(o);
  dsr::PipelineResult r;
  r.doors = {door(kA, 40)};
  const dsr::Parameters p;
  EXPECT_FALSE(t.fuse(r, 1.0, p, Eigen::Vector3d(0, 0, 1)).relocalised);
  EXPECT_FALSE(t.fuse(r, 2.0, p, Eigen::Vector3d(1.4, 0, 1)).relocalised);  // 1.4 m in 1 s <= 1.5 m
  ASSERT_EQ(t.tracks().size(), 1u);
  const std::uint32_t id = t.tracks()[0].id;
  EXPECT_FALSE(t.fuse(r, 3.0, p, std::nullopt).relocalised);  // no sensor: nothing to judge
  const dsr::DriveTracker::Step s = t.fuse(r, 3.5, p, Eigen::Vector3d(1.4, 5, 1));  // 5 m in 1.5 s since the last known
  EXPECT_TRUE(s.relocalised);
  EXPECT_NEAR(s.moved_m, 5.0, 1e-12);
  EXPECT_NEAR(s.dt_s, 1.5, 1e-12);
  ASSERT_EQ(t.tracks().size(), 1u);  // the door seen in the jumping cloud starts a new track
  EXPECT_NE(t.tracks()[0].id, id);
  EXPECT_EQ(t.tracks()[0].observations, 1u);
  // 0: never judged.
  o.max_sensor_speed = 0;
  dsr::DriveTracker never(o);
  never.fuse(r, 1.0, p, Eigen::Vector3d::Zero());
  EXPECT_FALSE(never.fuse(r, 1.1, p, Eigen::Vector3d(100, 0, 0)).relocalised);
  o.max_sensor_speed = -1;
  EXPECT_THROW(dsr::DriveTracker{o}, std::invalid_argument);
}

// Confirmation (DriveTrackerOptions::confirm_clouds, confirm_spread_m): a
// door of one cloud is not published; one found again from another place is,
// with the id it had, and stays published.
TEST(DriveTracker, ATrackIsPublishedOnlyOnceAnotherCloudShowsIt) {
  dsr::PipelineResult one, none;
  one.doors = {door(kA, 0)};
  const dsr::Parameters p;
  // The defaults: 2 clouds, from anywhere.
  dsr::DriveTracker d;
  d.fuse(one, 1.0, p, Eigen::Vector3d(0, 0, 1));
  EXPECT_TRUE(d.published().empty());  // one cloud: a false door of one sweep looks the same
  d.fuse(one, 1.1, p, Eigen::Vector3d(0, 0, 1));
  ASSERT_EQ(d.published().size(), 1u);
  EXPECT_EQ(d.published()[0].id, d.tracks()[0].id);
  // 2 clouds, 0.3 m apart.
  dsr::DriveTrackerOptions far;
  far.confirm_spread_m = 0.3;
  dsr::DriveTracker t(far);
  t.fuse(one, 1.0, p, Eigen::Vector3d(0, 0, 1));
  ASSERT_EQ(t.tracks().size(), 1u);
  EXPECT_TRUE(t.published().empty());
  t.fuse(one, 1.1, p, Eigen::Vector3d(0.1, 0, 1));  // again, but from (almost) the same place
  EXPECT_TRUE(t.published().empty());
  EXPECT_NEAR(t.spread(t.tracks()[0].id), 0.1, 1e-12);
  t.fuse(none, 1.2, p, Eigen::Vector3d(0.2, 0, 1));  // a cloud not showing it moves nothing
  EXPECT_TRUE(t.published().empty());
  t.fuse(one, 1.3, p, Eigen::Vector3d(0.1, 0.3, 1));  // 0.316 m from where it was first seen
  ASSERT_EQ(t.published().size(), 1u);
  const std::uint32_t id = t.published()[0].id;
  EXPECT_EQ(id, t.tracks()[0].id);
  EXPECT_TRUE(t.confirmed(id));
  t.fuse(none, 1.4, p, Eigen::Vector3d(0.3, 0, 1));
  EXPECT_EQ(t.published().size(), 1u);  // confirmed stays so
  // A sensor never known: the clouds alone confirm.
  dsr::DriveTracker unknown(far);
  unknown.fuse(one, 1.0, p, std::nullopt);
  EXPECT_TRUE(unknown.published().empty());
  unknown.fuse(one, 2.0, p, std::nullopt);
  EXPECT_EQ(unknown.published().size(), 1u);
  // 1 and 0: every track at once (before confirmation).
  dsr::DriveTrackerOptions o;
  o.confirm_clouds = 1;
  o.confirm_spread_m = 0;
  dsr::DriveTracker all(o);
  all.fuse(one, 1.0, p, Eigen::Vector3d::Zero());
  EXPECT_EQ(all.published().size(), 1u);
  o.confirm_clouds = 0;
  EXPECT_THROW(dsr::DriveTracker{o}, std::invalid_argument);
  o.confirm_clouds = 2;
  o.confirm_spread_m = -1;
  EXPECT_THROW(dsr::DriveTracker{o}, std::invalid_argument);
}

TEST(DriveTracker, ThePipelinesThresholdsDecideTheStatesOfBounds) {
  dsr::DriveTracker t;
  dsr::PipelineResult r;
  r.doors = {door(kA, 70, true)};
  dsr::Parameters p;
  p.open_from_deg = 60;  // a 70 deg bound is OPEN by these thresholds
  t.fuse(r, 1.0, p, std::nullopt);
  ASSERT_EQ(t.tracks().size(), 1u);
  EXPECT_EQ(t.tracks()[0].door.state, DoorStateKind::Open);
  EXPECT_DOUBLE_EQ(t.fusion().options().open_from_deg, 60);
}

TEST(DriveTracker, RunMovesTheCloudIntoTheFixedFrame) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back(pcl::PointXYZ(1, 0, 0));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translate(Eigen::Vector3d(0, 2, 1)).rotate(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  const dsr::Pipeline pipeline{dsr::Parameters()};
  const dsr::PipelineResult r = dsr::DriveTracker::run(pipeline, cloud, T, false);
  EXPECT_NEAR(cloud[0].x, 0, 1e-6);
  EXPECT_NEAR(cloud[0].y, 3, 1e-6);
  EXPECT_NEAR(cloud[0].z, 1, 1e-6);
  ASSERT_TRUE(r.viewpoint.has_value());
  EXPECT_NEAR((*r.viewpoint - Eigen::Vector3d(0, 2, 1)).norm(), 0, 1e-12);
  EXPECT_TRUE(r.doors.empty());
}

namespace {

// A wall at x = 2 (y in [-2, 2], z from -1, the floor, to 1.5) seen from the
// origin, every 2 cm; with `doorway`, rays through |y| < 0.45, z < 1 end on
// a wall behind it at x = 4.
pcl::PointCloud<pcl::PointXYZ> wallCloud(bool doorway) {
  pcl::PointCloud<pcl::PointXYZ> c;
  for (double y = -2; y <= 2; y += 0.02)
    for (double z = -1; z <= 1.5; z += 0.02) {
      const bool through = doorway && std::abs(y) < 0.45 && z < 1.0;
      c.push_back(through ? pcl::PointXYZ(4, 2 * y, 2 * z) : pcl::PointXYZ(2, y, z));
    }
  return c;
}

}  // namespace

// Withdrawal (DriveTrackerOptions::disprove): a track whose doorway later
// clouds look at (rays reach its rectangle: ending on the wall there, or
// passing through it) without showing the door is withdrawn after 6 misses
// per observation, but kept: found again in confirm_clouds clouds it comes
// back with the id it had, never a second one (issue 20: one id per door per
// drive). Clouds that do not reach the doorway are no misses.
TEST(DriveTracker, ADoorwayLookedAtAndNotFoundIsWithdrawnAndComesBackWithItsId) {
  for (const bool looked_at : {true, false}) {
    for (const bool doorway : {false, true}) {
      dsr::DriveTrackerOptions o;
      o.confirm_clouds = 1;
      dsr::DriveTracker t(o);
      ASSERT_TRUE(t.options().disprove) << "on by default";
      dsr::PipelineResult r;
      r.doors = {door(Eigen::Vector3d(2, 0, -1), 0.0, false, 0.6, Eigen::Vector3d::UnitY())};
      const dsr::Parameters p;
      t.fuse(r, 1.0, p, Eigen::Vector3d::Zero());
      ASSERT_EQ(t.published().size(), 1u);
      const std::uint32_t id = t.published()[0].id;
      const dsr::Pipeline pipeline{p};
      std::size_t withdrawn = 0;
      const std::string what = std::string(doorway ? "an open doorway" : "a plain wall") +
                               (looked_at ? " looked at" : " out of the clouds");
      for (int k = 0; k < 6; ++k) {
        pcl::PointCloud<pcl::PointXYZ> c = wallCloud(doorway);
        if (!looked_at)  // the part of the scene away from the doorway only
          c.erase(std::remove_if(c.begin(), c.end(), [](const pcl::PointXYZ& q) { return std::abs(q.y) < 1.2 * q.x / 2; }),
                  c.end());
        const auto step = t.process(pipeline, c, Eigen::Isometry3d::Identity(), 2.0 + k, false);
        withdrawn += step.step.disproved;
        if (k < 5) {
          EXPECT_EQ(t.published().size(), 1u) << what << ": withdrawn after " << k + 1 << " clouds: 6 are needed";
        }
      }
      EXPECT_EQ(withdrawn, looked_at ? 1u : 0u) << what;
      EXPECT_EQ(t.published().size(), looked_at ? 0u : 1u) << what;
      ASSERT_EQ(t.tracks().size(), 1u) << what << ": a withdrawn track is kept";
      // Found again: published at once (confirm_clouds 1), with its id.
      t.fuse(r, 9.0, p, Eigen::Vector3d::Zero());
      ASSERT_EQ(t.published().size(), 1u) << what;
      EXPECT_EQ(t.published()[0].id, id) << what;
      EXPECT_EQ(t.tracks().size(), 1u) << what;
    }
  }
  // Off (the nodelet's ~withdraw_not_found false): never withdrawn.
  dsr::DriveTrackerOptions off;
  off.confirm_clouds = 1;
  off.disprove = false;
  dsr::DriveTracker t(off);
  dsr::PipelineResult r;
  r.doors = {door(Eigen::Vector3d(2, 0, -1), 0.0, false, 0.6, Eigen::Vector3d::UnitY())};
  const dsr::Parameters p;
  t.fuse(r, 1.0, p, Eigen::Vector3d::Zero());
  const dsr::Pipeline pipeline{p};
  for (int k = 0; k < 8; ++k) {
    pcl::PointCloud<pcl::PointXYZ> c = wallCloud(false);
    t.process(pipeline, c, Eigen::Isometry3d::Identity(), 2.0 + k, false);
  }
  EXPECT_EQ(t.published().size(), 1u);
}
