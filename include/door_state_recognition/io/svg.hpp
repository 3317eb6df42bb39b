// A plan (top view) of a pipeline result as plain SVG: the points thinned to a
// grey density, the walls, the doorways and each leaf drawn from its hinge at
// its angle with its swing arc, coloured by state, labelled with id, state and
// angle; scaled in metres with a scale bar. No plotting library. ROS-free.
//
// The plan's axes: u and v, horizontal unit vectors of the input frame with
// u x v = up (the result's up), so the view is from above. The root <svg>
// element carries them as data-plan-up, data-plan-u, data-plan-v ("x y z"),
// and every drawing in metres sits in <g id="plan"> whose transform is
// translate(ox,oy) scale(s,-s): a point p of the input frame is drawn at
// (p.u, p.v) in that group. Each door's elements carry data-door="id", each
// wall's data-wall="id"; a leaf whose angle is a lower bound is dashed.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "door_state_recognition/pipeline/pipeline.hpp"

namespace dsr {
namespace io {

struct PlanOptions {
  std::string title;                          // shown at the top (e.g. the input's name)
  std::vector<Eigen::Vector3d> viewpoints;    // sensor positions to mark (input frame)
  double cell = 0;  // density cell in metres (at least the extent / 2000); 0: the extent / 250, at least 0.04
  int max_width_px = 1000, max_height_px = 800;
};

// The plan's horizontal axes for an up vector: u along the input's x (its y
// when x is nearly up) made horizontal, v = up x u.
void planAxes(const Eigen::Vector3d& up, Eigen::Vector3d& u, Eigen::Vector3d& v);

// The state's colour ("#rrggbb") by its name: closed red, semi_open orange,
// open green, not_closed purple; any other name a colour of its own from its
// characters, so a new state is still drawn and told apart.
std::string stateColour(const std::string& state_name);

// The SVG document. `clouds` are the points to thin (a survey's stations, or
// none); points within 0.1 m of the floor or the ceiling (where known) are
// left out, so what stands in the room shows.
std::string planSvg(const PipelineResult& result, const std::vector<const pcl::PointCloud<pcl::PointXYZ>*>& clouds,
                    const PlanOptions& options = {});

// Writes planSvg to `path`; throws std::runtime_error naming the path and the
// system's reason when it cannot be written.
void writePlanSvg(const std::string& path, const PipelineResult& result,
                  const std::vector<const pcl::PointCloud<pcl::PointXYZ>*>& clouds, const PlanOptions& options = {});

}  // namespace io
}  // namespace dsr
