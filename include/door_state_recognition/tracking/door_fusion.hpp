// Door states fused over a drive (issue 20): every door seen within
// forget_after_s, each with one id and its best current estimate, from the
// doors of each processed cloud already expressed in one fixed,
// gravity-aligned frame (REP 105: map, odom). ROS-free; the nodelet only
// calls it (DoorStateNodelet publishes `tracked_doors` from tracks()).
//
// Matching. A cloud's door is the track whose opening centre lies within
// match_distance_m of its own, measured across the up vector (the heights
// of the centres are ignored), and whose wall runs within wall_angle_deg of
// its wall's direction; nearest pairs first, one door to one track. A door
// matching no track starts one with a new id. Ids are never reused while
// the object lives (not even after reset()). Two tracks that come to lie
// within match_distance_m of each other along one wall (e.g. a door first
// seen off by a few decimetres) are one door: joined, the older id kept,
// unless both were seen in the same cloud (then they are two doors); the
// estimate kept is that of the track more clouds showed where the two
// agree within state_change_deg, else that of the one seen last.
//
// The estimate of a track, per observation o (this cloud's door):
//  - a measured leaf (o.angle_is_lower_bound false) beats a bound: a track
//    holding a bound takes o at once;
//  - bounds combine: a track holding a bound and o a bound keep the larger
//    (the largest angle every position's free space allows); the state is
//    NOT_CLOSED below open_from_deg, OPEN from it (stateOfBound), so
//    NOT_CLOSED becomes OPEN once the combined bound reaches open_from_deg;
//  - a track holding a measured angle A: an o within state_change_deg of it
//    agrees (a measured o replaces the estimate when at least as confident:
//    the best view so far; a bound at most A + state_change_deg says
//    nothing new); an o departing by more (a measured angle, or a bound
//    above A + state_change_deg) is a state change only when confirmed:
//    it takes over when the door's next observation departs alike (within
//    state_change_deg of the first departure), or at once when o is a
//    measured leaf of confidence >= sure_confidence. So a door opened or
//    closed shows its new state in the 2nd processed cloud that shows it
//    (the 1st for a leaf seen that surely), and one noisy cloud does not
//    flip it. An agreeing observation drops a pending departure; clouds
//    that do not show the door leave it pending.
// Every observation counts in `observations`, sets last_seen to its stamp
// and seen_now (the door is in this cloud); a track not seen for more than
// forget_after_s (by the stamps) is dropped.
//
// Bad input (each is a documented outcome of update(), never an exception
// for the content):
//  - a stamp not finite: the cloud is ignored (Outcome::IgnoredBadStamp);
//  - a stamp older than the newest fused one by more than
//    backwards_tolerance_s (a bag played again, looped with use_sim_time, a
//    restarted clock): every track is dropped (Outcome::Reset) and this
//    cloud starts the new ones;
//  - a stamp older than the newest but within backwards_tolerance_s (clouds
//    out of order): ignored for fusion (Outcome::IgnoredOutOfOrder), so
//    that last_seen never moves back; the tracks stay as they were, none
//    seen_now;
//  - a door with a non-finite centre, angle or wall direction is skipped.
// A relocalisation jump of the fixed frame is not seen here (doors arrive
// in the fixed frame already): the caller's concern (DoorStateNodelet
// calls reset() when its sensor moves in the fixed frame faster than
// ~max_sensor_speed between two processed clouds).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "door_state_recognition/pipeline/pipeline.hpp"

namespace dsr {

struct FusionOptions {
  double forget_after_s = 300.0;     // s; a door not seen this long (by stamps) is dropped
  double state_change_deg = 20.0;    // deg; a measurement departing further from the track is a state change
  double match_distance_m = 0.5;     // m, between opening centres across the up vector
  double wall_angle_deg = 30.0;      // deg, between the walls' directions for one door
  double sure_confidence = 0.9;      // a departing measured leaf this confident takes over at once
  double backwards_tolerance_s = 1.0;  // s; stamps further back reset the tracks
  // The pipeline's, for the states of bounds and clear widths (Parameters).
  double closed_below_deg = 5.0, open_from_deg = 90.0, leaf_thickness = 0.04;
  // Throws std::invalid_argument naming the first option out of range.
  void validate() const;
};

struct TrackedDoor {
  std::uint32_t id = 0;
  DoorResult door;  // best current estimate, in the fixed frame (door.id == id)
  double first_seen = 0, last_seen = 0;  // stamps, s
  std::uint32_t observations = 0;        // clouds that showed it
  bool seen_now = false;                 // shown by the last fused cloud
};

class DoorFusion {
 public:
  enum class Outcome { Fused, Reset, IgnoredOutOfOrder, IgnoredBadStamp };
  struct Update {
    Outcome outcome = Outcome::Fused;
    // Per door given, in order: the id of its track (0 and not tracked when
    // the cloud was ignored or the door skipped; see tracked).
    std::vector<std::uint32_t> ids;
    std::vector<char> tracked;
    std::size_t forgotten = 0;  // tracks dropped for age in this update
    std::size_t joined = 0;     // tracks joined into another in this update
  };

  // Throws std::invalid_argument for options out of range.
  explicit DoorFusion(const FusionOptions& options = FusionOptions());
  const FusionOptions& options() const { return options_; }
  // New options (e.g. parameters reconfigured); the tracks stay.
  void setOptions(const FusionOptions& options);

  // One processed cloud: its doors in the fixed frame, its stamp (s) and the
  // up vector of the fixed frame (zero or not finite: +z).
  Update update(const std::vector<DoorResult>& doors, double stamp,
                const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

  // Every door tracked, ordered by id.
  const std::vector<TrackedDoor>& tracks() const { return tracks_; }
  // Drops every track (ids go on counting).
  void reset();
  // Drops the track `id` (e.g. its doorway since measured as plain wall:
  // DriveTracker); false when there is none.
  bool drop(std::uint32_t id);
  // The newest stamp fused (NaN before the first cloud and after reset()).
  double newestStamp() const { return newest_; }

 private:
  struct Pending {
    bool active = false;
    DoorResult door;
  };
  struct Internal {
    Eigen::Vector3d centre;        // running mean of the opening centres seen
    Eigen::Vector3d wall_dir;      // horizontal unit
    Pending pending;
  };
  void fuse(TrackedDoor& t, Internal& in, const DoorResult& o) const;
  void joinNear(const Eigen::Vector3d& up, Update& u);
  bool sameWall(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;

  FusionOptions options_;
  std::vector<TrackedDoor> tracks_;
  std::vector<Internal> internal_;  // parallel to tracks_
  std::uint32_t next_id_ = 0;
  double newest_;
};

const char* toString(DoorFusion::Outcome o);

}  // namespace dsr
