// Door-state stage (paper 3.3.2-3.3.3, improved): the leaf is fitted as a
// rectangle turning about a hinge at one jamb of the doorway, towards either
// side of the wall; the opening angle is measured at the hinge from the
// closed position, in [0, 180] deg, and refined by a total-least-squares
// line through the leaf's points (any direction, unlike y = a x + b).
// Levelled frame. ROS-free.
#pragma once

#include <Eigen/Core>
#include <array>
#include <limits>
#include <vector>

#include "door_state_recognition/pipeline/parameters.hpp"
#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/recognition/recognition.hpp"

namespace dsr {
namespace state {

struct Line2 {
  Eigen::Vector2d point = Eigen::Vector2d::Zero();
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX();  // unit
};

// Total least squares: the line minimising perpendicular distances.
Line2 fitLine(const std::vector<Eigen::Vector2d>& points);

struct LeafFit {
  bool found = false;
  bool closed_in_band = false;  // a leaf fills the doorway inside the wall
  double angle_deg = 0;         // 0 closed .. 180
  bool hinge_at_s0 = true;      // hinge at the doorway's s0 jamb
  bool toward_viewer = true;    // swings to the viewer's side of the wall
  double coverage = 0;          // share of the leaf's cells holding points
  Eigen::Vector2d hinge = Eigen::Vector2d::Zero();      // x, y
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX(); // hinge -> latch, unit
  double length = 0, top_z = 0;
  double s_hinge = 0, s_latch = 0;  // the doorway's jambs along the wall, refined by the fit
  double face_d = 0;            // closed leaf: depth of its visible face (<= 0, behind the wall face)
  int handle_points = 0;        // closed leaf: points of a handle at the jamb that has more (0: none, or not sought)
  // Best hypothesis, found or not (for a leaf closed in the wall band with
  // the global search's best below closed_below_deg + 0.5, that search's best:
  // the local search is skipped).
  double best_angle_deg = 0, best_coverage = 0, best_contradiction = 0;
  int candidate_points = 0, candidate_rays = 0;  // points near the doorway, rays passing it
  // Leaf found off the wall: share of the points near the doorway that hide
  // it from the sensor (in front of the wall, sight line meeting the wall
  // inside the doorway) which lie on the leaf (0 when none or not computed).
  double occluders_explained = 0;
  // Points just before the leaf measured, on the sensor's side, per point
  // in its band (a plane through a shelf unit's contents: as many; a leaf:
  // none). Above 0.5 at 30 deg or more the leaf is not taken.
  double crowd_before = 0;
  // An open leaf measured shorter than its doorway: the share of the cells
  // of the rest of a leaf as long as the doorway is wide (past the measured
  // tip, at the same hinge and angle) that rays went through. A leaf seen
  // in part is hidden in the rest (by its jamb, furniture, the view's
  // edge); a cupboard's side at the jamb is seen past. 0 when not computed.
  double rest_seen_through = 0;
  // An open leaf: the share of the cells of a strip from its tip across
  // the side it opens to (5-45 cm) holding points: a passage runs there,
  // a cupboard's front stands there when its side was taken for the leaf.
  double front_at_tip = 0;
  // How densely the scan samples surfaces at the doorway: the share of the
  // 5 x 10 cm cells of the wall's face beside it (0.15-0.6 m beyond either
  // jamb, the better side) holding points, over kDenseWallCover, clamped to
  // [0.5, 1]. A leaf's coverage thresholds are scaled by it: a sparse scan
  // leaves a leaf's cells as empty as the wall's (25k rays a station: a
  // third to a half of a wall's cells 2-2.4 m off). 1 in a camera frame
  // (dense), and where neither side has half its columns on the wall's
  // extent with a point on its face (a side hidden by what stands in front
  // tells nothing).
  double sampling = 1.0;
  // No leaf found in a doorway beyond doubt: the least opening angle at
  // which a leaf of the doorway's width blocks no ray that went through
  // (hinge_at_s0 and toward_viewer say where); a lower bound of the opening
  // angle. NaN when not computed.
  double free_from_deg = std::numeric_limits<double>::quiet_NaN();
  // The same for each hinge and swing side (index 2 * (hinge at s1) +
  // (swings away from the viewer)): 180 where a leaf there blocks some ray
  // at every angle; free_from_deg is the least of them.
  std::array<double, 4> free_from_each{std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN(),
                                       std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  bool searched = true;  // false: skipped, no closed leaf could have made it a door (see fitLeaf)
  std::vector<int> inliers;
};

// `view` (a camera frame's extent) makes a leaf cut by the edge of the view
// judged by the part of it inside.
// `closed_band_only_above` > 0 says that only a closed leaf inside the wall
// covering more than that share of the doorway could make it a door (the
// caller found no other evidence): when the points in the wall band cover
// less, the search is skipped (searched = false, found = false).
LeafFit fitLeaf(const segmentation::Points& points, const segmentation::WallPlane& wall,
                const recognition::Doorway& doorway, double floor_z, double thickness,
                const Eigen::Vector3f& viewpoint, const Parameters& p, double closed_band_only_above = 0,
                const segmentation::ViewTop* view = nullptr);

DoorStateKind classify(double angle_deg, const Parameters& p);

}  // namespace state
}  // namespace dsr
