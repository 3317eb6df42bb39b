// Recognition stage (paper 3.2 and 3.3.1): bounding-box corners of segments,
// boundary points by the normal-angle-gap criterion, and doorway candidates
// on each wall from what the sensor saw on, through and in front of the
// wall's plane. Levelled frame (z up). ROS-free.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "door_state_recognition/pipeline/parameters.hpp"
#include "door_state_recognition/segmentation/segmentation.hpp"

namespace dsr {
namespace recognition {

using segmentation::Points;

struct BoxCorners {
  std::array<Eigen::Vector3d, 8> corners;  // bottom four, then top four
  Eigen::Vector3d center, extents;         // extents along the box axes (full lengths)
  double volume = 0, height = 0;
  bool oriented = false;  // OBB (PCA axes, Gram-Schmidt) or AABB
};

// Paper 3.2.1: AABB when the segment's principal horizontal axis is parallel
// to a coordinate axis (within 2 deg), otherwise an OBB whose axes are the
// PCA axes made orthonormal by Gram-Schmidt. Heights are along z.
BoxCorners boundingBox(const Points& points, const std::vector<int>& indices);
// The eight corners (bottom four, then top four) of the box [lo, hi] along
// the axes e1, e2, e3, in the frame of the axes.
std::array<Eigen::Vector3d, 8> boxCorners(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3d& e1,
                                          const Eigen::Vector3d& e2, const Eigen::Vector3d& e3);

// Paper 3.3.1: a point is on the boundary when the largest angular gap
// between the projections of its k neighbours onto its tangent plane exceeds
// angle_deg. Returns one flag per entry of `indices`.
std::vector<char> boundaryPoints(const Points& points, const segmentation::Normals& normals,
                                 const segmentation::NeighbourGrid& grid, float radius,
                                 const std::vector<int>& indices, int k,
                                 double angle_deg);

struct Doorway {
  double s0 = 0, s1 = 0;   // jambs along the wall (WallPlane::along)
  double top = 0;          // z of the head of the opening (estimate)
  bool casing = false;     // trim found: legs on both sides, or one leg and the head
  bool paired = false;     // both legs found: the jambs s0, s1 are exact
  double face = 0, through = 0, front = 0, recess = 0;  // shares of body cells, see findDoorways
  double thickness = 0;    // wall thickness seen at the jambs (0: unknown)
  // Some body cell below 0.8 m above the floor is seen through: the opening
  // reaches down to where a window's sill would stand.
  bool low_through = false;
  // Of the observed body cells below 0.8 m, those without face seen through
  // or just behind the plane (a leaf swung away near its hinge).
  double low_past_share = 0;
  double set_back = 0;     // found as a panel this far behind the wall above and beside it (0: not so found)
  // Found only as the sensor-near end of a shadow wider than any door (a
  // leaf swung towards the sensor): its far jamb is a guess, and only that
  // leaf, hiding it, can make it a door (no trim is snapped to it).
  bool shadow_end = false;
  double width() const { return s1 - s0; }
  // A doorway beyond doubt, not a niche or a closed leaf: trim frames it,
  // or rays pass its plane over much of it, or, in a plain opening without
  // trim, the wall's face is absent over all of it and rays pass the plane
  // somewhere while the rest ends just behind it (the reveal, a leaf swung
  // away seen near its hinge). A niche's back or a closed leaf lets no ray
  // through. Such a doorway takes a leaf seen only in part (its length the
  // doorway's), and bounds an unseen one by free space.
  bool sure() const {
    return casing || through >= kSureThrough ||
           (face < kPlainOpeningFace && through >= kPlainOpeningThrough && through + recess >= kPlainOpeningSeen);
  }
  static constexpr double kSureThrough = 0.4, kPlainOpeningFace = 0.05, kPlainOpeningThrough = 0.1,
                          kPlainOpeningSeen = 0.8;
};

// Evidence grid over the wall plane (cells of grid_cell along the wall,
// 5 cm high). Every point is taken along its ray from the viewpoint to the
// plane: on the face (|d| <= face_tolerance), seen through it (behind by more
// than 0.3 m), recessed (behind by less), or occluding it (in front). Columns
// whose body (0.25-1.75 m above the floor) shows no face but through, recess
// or occlusion form openings; pairs of trim legs (face points standing out by
// casing_min_offset) form doorways even when a closed leaf is flush with the
// wall. Where the face is too noisy for either (a depth camera at range),
// runs of columns whose body lies well behind the same columns' wall above
// a door's head, level with it again on both sides, form doorways too
// (set_back). Candidates are door_min_width - 0.1 .. door_max_width + 0.1
// wide; a shadow wider than any door gives one from its end nearer the
// sensor (shadow_end), and a run too wide for a door, or one reaching an
// end of the grid, the part of it seen through between one of its ends and
// a shadow (a leaf's, beyond its hinge). In a camera frame, trim legs pair
// under a head seen only in the mean offset of its points, where no other
// candidate lies (depth noise hides trim point by point at a few metres).
// no_return_is_free: the cloud is an organized camera frame, where a body
// cell of a doorway without any return means nothing was there in range
// (counted as seen through). With the frame's view (view), such a cell
// inside the view also joins a doorway's run of open columns: the camera
// looked there and nothing was in range.
std::vector<Doorway> findDoorways(const Points& points, const segmentation::WallPlane& wall, double floor_z,
                                  double top_z, const Eigen::Vector3f& viewpoint, const Parameters& p,
                                  bool no_return_is_free = false, const segmentation::ViewTop* view = nullptr);

}  // namespace recognition
}  // namespace dsr
