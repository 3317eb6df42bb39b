// Where each input cloud was seen from, as door_state_cli's --viewpoint
// chooses it (auto | header | none | X,Y,Z), and the stations a Pipeline
// runs from that: the decision and its reasons in one place, the CLI a
// shell around it. ROS-free.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "door_state_recognition/pipeline/parameters.hpp"
#include "door_state_recognition/pipeline/pipeline.hpp"

namespace dsr {
namespace sight {

enum class ViewpointMode {
  Auto,    // each cloud's VIEWPOINT where credible for it (checkViewpoint), else none for all
  Header,  // each cloud's VIEWPOINT as given
  None,    // no viewpoint: the clouds as one, stations inferred
  Given,   // one position for the one cloud
};

struct InputCloud {
  const pcl::PointCloud<pcl::PointXYZ>* cloud = nullptr;  // its sensor_origin_ is its VIEWPOINT
  std::string name;                                        // in the notes and errors
  bool viewpoint_given = false;                            // io::CloudFrame::viewpoint_given
};

// The choice, and the clouds its stations point into (so neither copied
// nor moved: give chooseViewpoints one to fill).
struct ViewpointChoice {
  ViewpointChoice() = default;
  ViewpointChoice(const ViewpointChoice&) = delete;
  ViewpointChoice& operator=(const ViewpointChoice&) = delete;

  // Pipeline::runStations's stations, or with without_viewpoint the one
  // cloud (the inputs merged) for Pipeline::runWithoutViewpoint.
  std::vector<Station> stations;
  bool without_viewpoint = false;
  std::vector<std::string> notes;  // why, for the report's warnings
  std::vector<std::string> taken;  // "viewpoint (x, y, z) of NAME taken: why" where credible as it stands
  std::vector<pcl::PointCloud<pcl::PointXYZ>> seen;  // a station's points not hidden from its viewpoint
  pcl::PointCloud<pcl::PointXYZ> merged;             // the inputs as one cloud, without a viewpoint
};

// Fills `out` for `inputs` (read moved by `shift`, io::CloudFrame; `given`
// in the inputs' own frame, mode Given). Under Auto a georeferenced cloud
// (shift not zero) with no VIEWPOINT has none: no sensor stood at its
// origin. Throws std::invalid_argument for a viewpoint that is not finite
// or lies beyond max_abs_coordinate.
void chooseViewpoints(const std::vector<InputCloud>& inputs, ViewpointMode mode,
                      const std::optional<Eigen::Vector3d>& given, const Eigen::Vector3d& shift, const Parameters& p,
                      ViewpointChoice& out);

}  // namespace sight
}  // namespace dsr
