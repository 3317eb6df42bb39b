// Segmentation stage (paper 3.1): PCA normals and curvature, floor and
// ceiling from a height histogram, walls as RANSAC vertical planes of wall
// height, and region growing on normals and curvature. Works in a levelled
// frame (z up). ROS-free.
#pragma once

#include <pcl/point_types.h>

#include <Eigen/Core>
#include <optional>
#include <functional>
#include <vector>

#include "door_state_recognition/pipeline/parameters.hpp"
#include "door_state_recognition/segmentation/neighbour_grid.hpp"

namespace dsr {
namespace segmentation {

using Points = std::vector<Eigen::Vector3f>;

struct Normals {
  Points n;                      // unit, oriented towards the viewpoint
  std::vector<float> curvature;  // lambda0 / (lambda0 + lambda1 + lambda2)
};

// PCA normals and curvature from cell moments. A coarse level of cells twice
// the grid's gives every coarse cell the PCA of its 3 x 3 x 3 coarse block;
// where that is planar (curvature <= 0.02) its points take it, elsewhere
// (edges, corners, thin parts) the PCA of the 3 x 3 x 3 grid cells around,
// when those hold at least min(k, 8) points. `grid` must be built on
// `points` (or a rotated copy). Normals point towards `viewpoint` (same
// frame as `points`). An isolated point gets a zero normal and curvature 1.
Normals estimateNormals(const Points& points, const NeighbourGrid& grid, int k, const Eigen::Vector3f& viewpoint);

struct FloorCeiling {
  std::optional<double> floor, ceiling;  // z
};

// Peaks of the z histogram of horizontal-surface points: the lowest is the
// floor, the highest the ceiling (when they are at least min_room_height
// apart). A single peak is the floor when it lies below the viewpoint.
// A level that walls rise well above (more than 2% of the vertical points
// 0.3 m or more higher) is no ceiling: a desk or cupboard top, a shelf's
// underside, seen by a sensor that does not see the ceiling. Nor is one
// most of whose points have other points 8-60 cm straight below them: a
// LiDAR's top ring on the walls, not a ceiling over free space.
FloorCeiling findFloorCeiling(const Points& points, const Normals& normals, const Parameters& p, double viewpoint_z);

struct WallPlane {
  Eigen::Vector2d point;      // on the wall's line (x, y)
  Eigen::Vector2d direction;  // unit, along the wall
  Eigen::Vector2d normal;     // unit, horizontal, towards the viewpoint
  double s_min = 0, s_max = 0, z_min = 0, z_max = 0;
  std::vector<int> inliers;
  double signedDistance(const Eigen::Vector3f& p) const {
    return (Eigen::Vector2d(p.x(), p.y()) - point).dot(normal);
  }
  double along(const Eigen::Vector3f& p) const { return (Eigen::Vector2d(p.x(), p.y()) - point).dot(direction); }
};

// The top of what a sensor saw, by bearing from its viewpoint: the highest
// elevation (as tan) of any point in each bearing bin. A wall whose visible
// top is the highest thing seen on its bearings was cut by the edge of the
// view (a camera frame), not by its own height.
struct ViewTop {
  Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();
  std::vector<float> max_tan, min_tan;  // per bearing bin (+-inf where nothing); empty: not known
  // Unit directions (from viewpoint) of a camera's pixels without a return:
  // nothing was in range along them (preprocess::noReturnRays); may be empty.
  std::vector<Eigen::Vector3f> no_return;
  // The angle between neighbouring rays (rad, preprocess::raySpacing; 0:
  // unknown): a cell without a return farther than cell / ray_spacing lies
  // between rays (a LiDAR's rings), not looked at.
  float ray_spacing = 0;
  int bin(const Eigen::Vector3f& q) const;
  float tanElevation(const Eigen::Vector3f& q) const;
  // Within what the sensor saw: a bearing with returns, between the lowest
  // and highest seen on it (give or take `slack` in tan of elevation).
  bool inView(const Eigen::Vector3f& q, float slack = 0.02f) const;
  // The same over the bearing bins `bins` either side: a LiDAR's columns
  // (0.35 deg apart at 1024 a turn), thinned by the voxel grid, leave some
  // bins without their upper rings.
  bool inViewNear(const Eigen::Vector3f& q, int bins, float slack = 0.02f) const;
  // How many whole bearing bins (about 0.25 deg each) `angle` (rad) spans.
  int binsWithin(float angle) const;
};
ViewTop viewTop(const Points& points, const Eigen::Vector3f& viewpoint);

// Iterative 1-point RANSAC of vertical planes (a point and its normal
// propose a plane), refined by total least squares, split at gaps, kept when
// the segment spans wall_height_ratio of the room height and reaches near the
// ceiling (when seen) or the top of the view (`view`, when given).
// `height_top` is the ceiling or, without one, the top of the vertical structure.
// `on_wall`, when given, is called with each wall as soon as it is taken
// (its index in the result, in order), while the search goes on: from
// whichever thread runs the wall rules, inside findWalls's OpenMP region, so
// that it may start OpenMP tasks, which findWalls waits for before it returns.
using OnWall = std::function<void(std::size_t index, const WallPlane& wall)>;
std::vector<WallPlane> findWalls(const Points& points, const Normals& normals, double floor_z, double height_top,
                                 bool ceiling_known, const Eigen::Vector2d& viewpoint, const Parameters& p,
                                 const ViewTop* view = nullptr, const OnWall& on_wall = nullptr);

// The wall rules of findWalls for one plane's inliers: split along the wall
// at gaps wider than wall_gap (unless, seen from `viewpoint`, the gap shows
// no wall only because something in front hides it, and is seen through over
// no more than a doorway's width: points behind the plane, or the rays of
// `view`'s pixels without a return), and append to `walls` each segment that spans
// wall_height_ratio of the room, reaches near a known ceiling, is long
// enough and is not shadowed by a parallel wall found before. `direction`
// and `normal` (unit, horizontal) give the segment's frame.
void addWallSegments(const Points& points, const std::vector<int>& inliers, const Eigen::Vector2d& point,
                     const Eigen::Vector2d& direction, const Eigen::Vector2d& normal, double floor_z, double height_top,
                     bool ceiling_known, const Parameters& p, std::vector<WallPlane>& walls,
                     const ViewTop* view = nullptr, const Eigen::Vector2d* viewpoint = nullptr);

// Furniture standing against a wall, not walls: of `walls` (normals towards
// `viewpoint`), each that stands parallel in front of a longer wall, between
// it and the viewpoint, at a cupboard's or bookcase's depth (0.25-0.8 m: no
// room or corridor is that narrow), half its length or more along that
// wall's visible part. Such a "wall" is the fronts of cupboards, a gap
// between two of them its "doorway".
std::vector<char> furnitureFronts(const std::vector<WallPlane>& walls, const Eigen::Vector2d& viewpoint);

// Region growing (paper 3.1, [22]) over the points where mask != 0: a region
// grows to neighbours whose normals differ by less than region_angle_deg and
// continues from points whose curvature is below region_curvature. Regions
// smaller than min_region_points are dropped. Deterministic.
// It grows over the cells of the grid the normals were estimated on (whose
// points share a normal), to the 26 neighbouring cells.
std::vector<std::vector<int>> growRegions(const Points& points, const Normals& normals, const NeighbourGrid& grid,
                                         const std::vector<char>& mask, const Parameters& p);

}  // namespace segmentation
}  // namespace dsr
