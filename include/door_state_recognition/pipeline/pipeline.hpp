// The door-state pipeline: one object, configured by one Parameters struct,
// running the stages in order:
//   preprocess   (sanitise, voxel grid; then, once the normals are known,
//                 level to a gravity-aligned frame)
//   segmentation (neighbour grid, PCA normals, floor/ceiling histogram,
//                 RANSAC walls, region growing)
//   recognition  (AABB/OBB corners, doorway evidence on each wall)
//   state        (leaf fit at the hinge, opening angle, state; state::findDoors
//                 runs recognition and state and decides which doorways are doors)
//   reconstruction (walls with their doorways and leaves as they stand)
// Results are reported in the input's frame. ROS-free.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "door_state_recognition/pipeline/parameters.hpp"

namespace dsr {

// NotClosed: rays pass through the doorway but its leaf was not seen; free
// space bounds the opening angle from below, under open_from_deg (semi-open
// and open cannot be told). The values are those of DoorState.msg.
enum class DoorStateKind { Closed = 0, SemiOpen = 1, Open = 2, NotClosed = 3 };
const char* toString(DoorStateKind s);
enum class Swing { TowardViewer, AwayFromViewer, Unknown };
const char* toString(Swing s);

struct WallResult {
  int id = 0;
  std::array<Eigen::Vector3d, 8> corners;  // box of the wall's points
  double height = 0, length = 0;
  Eigen::Vector3d line_point, line_direction;  // on the floor, unit
  Eigen::Vector3d normal;                       // horizontal, towards the sensor
  std::size_t points = 0;
};

struct DoorResult {
  int id = 0;
  std::optional<int> wall_id;
  DoorStateKind state = DoorStateKind::Closed;
  double opening_angle_deg = 0;
  // The leaf was not seen: free space puts it at opening_angle_deg or more
  // (at least unseen_leaf_min_bound_deg), e.g. swung behind its wall out of
  // the sensor's sight. The state is then NotClosed below open_from_deg,
  // Open from it (stateOfBound).
  bool angle_is_lower_bound = false;
  double confidence = 0;
  Eigen::Vector3d hinge = Eigen::Vector3d::Zero(), opening_center = Eigen::Vector3d::Zero();
  Eigen::Vector3d wall_normal = Eigen::Vector3d::Zero();  // horizontal unit, towards the side the leaf swings to
  double width = 0, height = 0;
  // The free passage through the doorway as observed, metres (clearWidth):
  // the doorway's width less what the leaf takes at its angle; for a bound
  // (angle_is_lower_bound) what a leaf at the bound leaves, so at least this.
  double clear_width = 0;
  std::array<Eigen::Vector3d, 4> leaf_corners{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                              Eigen::Vector3d::Zero()};  // hinge-bottom, latch-bottom, latch-top, hinge-top
  Swing swing = Swing::Unknown;
  // Trim (casing) was seen around the doorway: its legs stand out of the
  // wall's face at both jambs. What tells the door's own doorway from the
  // wall beside it when both claim one leaf (surerReport).
  bool casing = false;
  // The wall's face was seen spanning the doorway above it (its head): what
  // tells a doorway in a wall from a gap onto a far surface when both claim
  // one leaf (leavesOverlap).
  bool head_seen = false;
  // Fitted lines on the floor plane (the paper's 3.3.2), for display.
  Eigen::Vector3d wall_line_point = Eigen::Vector3d::Zero(), wall_line_direction = Eigen::Vector3d::Zero(),
                  leaf_line_point = Eigen::Vector3d::Zero(), leaf_line_direction = Eigen::Vector3d::Zero();
  // A bound (angle_is_lower_bound): the least angle free space leaves a
  // leaf hinged at each jamb and swung to each side (four, in the input
  // frame; the bound is the least). Several stations' bounds of one door
  // combine side by side (combineBounds).
  struct SideBound {
    Eigen::Vector3d hinge;  // foot of the hinge on the floor
    Eigen::Vector3d along;  // horizontal unit, from the hinge to the latch jamb
    Eigen::Vector3d swing;  // horizontal unit, the side the leaf swings to
    double bound_deg = 180;
  };
  std::vector<SideBound> side_bounds;
};

// Bounds of one door from several stations (`others`: the other stations'
// reports of it, bounds too): a leaf out of sight of every station stands
// where none of their rays passes, so each hinge and swing side takes the
// largest of its bounds (sides the same within 0.3 m at the hinge); the
// door's bound is the least over its sides, `d` rebuilt at it where that
// is larger than its own (a bound past 170 deg is left: no side left free).
void combineBounds(DoorResult& d, const std::vector<const DoorResult*>& others, const Parameters& p);

// The free passage width (m) a leaf leaves in its doorway, seen along the
// doorway's normal (what passes straight through): a leaf of length `width`
// and thickness `leaf_thickness` hinged at one jamb and swung by `angle_deg`
// from closed takes width*cos(angle) + leaf_thickness*sin(angle) of the
// doorway (cos clamped at 0 past 90 deg: the leaf then stands outside the
// doorway but for its thickness at the hinge), so
//   clear_width = max(0, width - width*max(0, cos(angle)) - leaf_thickness*sin(angle)),
// and 0 for a closed door (angle < closed_below_deg). At 90 deg: width -
// leaf_thickness; at 180: width. Non-finite or negative input gives 0.
double clearWidth(double width, double angle_deg, double leaf_thickness, double closed_below_deg);

// Two reports claim one leaf: hinges within 0.2 m and leaves parallel
// (within 18 deg). A leaf swung towards the sensor hides the wall beside
// its hinge, which then looks like a doorway of its own holding the same
// leaf at 180 deg less its angle.
bool sameLeaf(const DoorResult& a, const DoorResult& b);
// Two reports put their leaves in one place: on the floor, the two leaves'
// lines (hinge to latch) parallel within 20 deg, the middle of one within
// 0.15 m of the other's line, and the two overlapping along it by 40 % of
// the shorter or more, whichever end each takes for its hinge. A leaf is a
// solid slab: two doors cannot hold leaves there at once (two leaves of a
// double door meet end to end, they do not overlap). One leaf claimed by a
// doorway on each of two walls (the wall holding it and a wall beyond it,
// hinged at opposite ends) is one door.
bool leavesOverlap(const DoorResult& a, const DoorResult& b);
// Of two reports of one door (or of one leaf), whether `a` is the one to
// keep over `b`: a leaf measured over one only bounded; of two bounds the
// larger (each is a true lower bound); where the two claim one leaf from
// doorways on either side of its hinge (centres more than 0.4 m apart), the
// doorway framed by trim (`casing`: a door's own mark; the wall beside the
// hinge has none); else the surer (confidence).
bool surerReport(const DoorResult& a, const DoorResult& b);

// The state of a door whose leaf was not seen and whose angle free space
// bounds from below at `bound_deg`: NotClosed below open_from_deg, Open from it.
DoorStateKind stateOfBound(double bound_deg, const Parameters& p);

struct SegmentResult {  // a region of region growing that is neither wall nor door
  int id = 0;
  std::array<Eigen::Vector3d, 8> corners;
  double height = 0, volume = 0;
  bool oriented_box = false;  // OBB (true) or AABB
};

struct PipelineResult {
  std::size_t points_in = 0, points_used = 0;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // in the input frame
  std::optional<double> floor, ceiling;            // heights along up (p . up)
  std::vector<WallResult> walls;
  std::vector<DoorResult> doors;
  std::vector<SegmentResult> others;
  std::vector<std::pair<std::string, double>> timing_ms;  // stage -> ms, in order; "total" last
  std::vector<std::string> warnings;                       // e.g. "no ceiling in view"
  // Where the rays that told free space came from: the one viewpoint of a
  // run(), or none (a survey's several stations, or stations inferred from
  // the cloud's surfaces by runWithoutViewpoint), listed in `stations`.
  std::optional<Eigen::Vector3d> viewpoint;
  std::vector<Eigen::Vector3d> stations;
  std::vector<std::string> trace;  // every wall and doorway candidate with the decision taken on it
  // Reconstruction: walls with doorways and leaves, input frame; label 1 wall, 2 leaf.
  pcl::PointCloud<pcl::PointXYZL> reconstruction;
};

// Moves every position of a result by `offset` (walls, doors, leaves, other
// segments, lines, viewpoint and stations; floor and ceiling heights along
// `up`): a cloud read in a frame moved near its points (io::CloudFrame)
// reported in its own. The reconstruction cloud (float) is left as it is.
void translate(PipelineResult& result, const Eigen::Vector3d& offset);

// One scan position of a survey: its scan, in the frame every station of the
// survey shares, and where the scanner stood in that frame.
struct Station {
  const pcl::PointCloud<pcl::PointXYZ>* cloud = nullptr;
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();
  // Its doors only refine doors other stations found (a station inferred
  // from few points of its own: runWithoutViewpoint), never add one.
  bool refine_only = false;
  // Inferred from the cloud's surfaces (runWithoutViewpoint), not given:
  // its rays are a guess (no scanner stood there; a ray to a point another
  // scanner saw may cross what none saw), so its bounds combine with other
  // stations' only door by door, never side by side (combineBounds).
  bool inferred = false;
};

class Pipeline {
 public:
  // Throws std::invalid_argument when a parameter is out of range.
  explicit Pipeline(const Parameters& parameters);
  const Parameters& parameters() const { return params_; }

  // Runs every stage. Non-finite points are dropped. Never throws for the
  // content of the cloud (an empty or degenerate cloud gives zero doors and a
  // warning); throws std::invalid_argument for a cloud above max_points or
  // a viewpoint not finite or beyond max_abs_coordinate.
  // `viewpoint` is where the sensor was, in the cloud's frame (the origin for
  // a cloud in its sensor's frame; the sensor's position once the cloud has
  // been moved into a fixed frame): rays from it tell free space.
  PipelineResult run(const pcl::PointCloud<pcl::PointXYZ>& cloud, bool with_reconstruction = true,
                     const Eigen::Vector3d& viewpoint = Eigen::Vector3d::Zero()) const;

  // A survey of several stations (src/pipeline/stations.cpp): each station's
  // scan is run alone, its rays from its own viewpoint, and the results are
  // merged: walls on one line joined, a door seen from several stations
  // reported once, from the station that measured its leaf best (a measured
  // angle before a lower bound, then the higher confidence; of bounds the
  // largest, held against unseen_leaf_min_bound_deg only after the merge,
  // so that two stations' bounds combine). Swing is told
  // from the first station. One station is run(). Throws
  // std::invalid_argument for no station, a null cloud, a viewpoint not
  // finite or beyond max_abs_coordinate, or more than max_points in all.
  PipelineResult runStations(const std::vector<Station>& stations, bool with_reconstruction = true) const;

  // A cloud whose viewpoint no one knows (a registered room, stations merged,
  // a map, a mesh export): the stations are inferred from its own surfaces
  // (sight::inferStations, src/pipeline/sight.cpp) and run as a survey. The
  // result's `viewpoint` is empty and `stations` lists the inferred ones.
  // Throws std::invalid_argument for a cloud above max_points.
  PipelineResult runWithoutViewpoint(const pcl::PointCloud<pcl::PointXYZ>& cloud, bool with_reconstruction = true) const;

 private:
  Parameters params_;
};

}  // namespace dsr
