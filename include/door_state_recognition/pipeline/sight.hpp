// Where the rays that tell free space come from: the pipeline's one seam
// between "a sensor stood here" and "no one knows where it stood".
//
// A scan from one sensor carries its viewpoint: every point was seen along
// a straight ray from it, so the space before each point is free. A
// registered room, several stations merged, a SLAM or mesh export carries
// none (or a VIEWPOINT of 0 0 0 that is only the frame's origin): rays from
// a point where no scanner stood cross walls and leaves that other stations
// saw from behind, and the free space they tell is false.
//
// Without a viewpoint the stations are inferred from the cloud's own
// surfaces: positions inside the scanned space from which those surfaces are
// seen, each with the points it sees unoccluded (a point is occluded when
// another surface of the cloud lies before it on the ray). Along such a ray
// the cloud itself shows nothing in the way, so the free space it tells is
// what the geometry alone says; the rest of the pipeline runs unchanged, as
// on a survey of those stations (Pipeline::runStations).
//
// checkViewpoint tells whether a claimed viewpoint is credible for a cloud:
// a sensor sees every point it returns, so from the true viewpoint of one
// scan almost no point lies behind another surface; a merged cloud shows
// many points that only another station saw. ROS-free.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <string>
#include <optional>
#include <utility>
#include <vector>

#include "door_state_recognition/pipeline/parameters.hpp"

namespace dsr {
namespace sight {

struct ViewpointCheck {
  bool credible = false;
  // Not credible as it stands, but once the points hidden from it are left
  // out (kMaxHiddenShare < hidden_share <= kTakeVisibleUpTo).
  bool take_visible = false;
  double hidden_share = 0;  // of the points tested, those behind another surface seen from the viewpoint
  std::size_t tested = 0;
  std::string reason;       // why (for the report's warnings)
  // An organized cloud whose pixels' rays do not meet at the viewpoint but
  // at this point (a frame moved into another frame with its VIEWPOINT left
  // behind): where its sensor was; credible there.
  std::optional<Eigen::Vector3d> rays_meet;
};

// A point of a single scan lies behind another surface seen from its own
// viewpoint only at depth edges (mixed returns) and on grazing surfaces;
// above this share the cloud holds what other positions saw.
constexpr double kMaxHiddenShare = 0.02;
// Up to this share the viewpoint is taken and the points hidden from it left
// out (they are not rays from it): one scanner's cloud of a cluttered room
// hides 2-7 % of its points behind its own depth edges (the occluders'
// disks reach past an edge by their radius), a room merged from stations
// 5-11 % seen from one of them and 60-87 % from a map's origin (doc/results.md).
constexpr double kTakeVisibleUpTo = 0.05;

// Whether `viewpoint` is where one sensor stood that saw this whole cloud.
// An organized cloud (height > 1: a camera frame or a LiDAR's rings) is one
// sensor's by construction: credible where its pixels' rays meet (the
// angles between neighbouring pixels' rays alike along its rows); where
// they meet elsewhere, that point is given in rays_meet.
// With `visible` and take_visible: the cloud's points not hidden from the
// viewpoint.
ViewpointCheck checkViewpoint(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3d& viewpoint,
                              const Parameters& p, pcl::PointCloud<pcl::PointXYZ>* visible = nullptr);

struct InferredStations {
  std::vector<pcl::PointCloud<pcl::PointXYZ>> clouds;  // the points each station sees, input frame
  std::vector<Eigen::Vector3d> viewpoints;            // input frame
  // The first `main` stations each saw a station's worth of points no
  // earlier one saw; the others (minor) less, though still some: the
  // leaf of a door seen only from there (see inferStations).
  std::size_t main = 0;
  std::size_t unseen = 0;                             // points no inferred station sees (left out)
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();       // up used to place them, input frame
  std::vector<std::pair<std::string, double>> timing_ms;  // its steps, in order
};

// Stations inferred from the cloud's surfaces (see above). Candidates stand
// on a horizontal grid over the cloud's extent at a scanner's height; the
// one that sees the most points not yet seen is taken first, and so on while
// a candidate adds a share worth a station (main), then while one adds a
// smaller share, as a station seeing little the others did not (minor: a
// leaf swung out of the main stations' sight, into a corner a third
// scanner looked into, lies in that share). Empty when the cloud has too few
// points or no candidate sees enough of it.
InferredStations inferStations(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Parameters& p);

}  // namespace sight
}  // namespace dsr
