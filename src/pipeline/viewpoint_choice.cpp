// Pipeline: the viewpoint each input is seen from (chooseViewpoints).
#include "door_state_recognition/pipeline/viewpoint_choice.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "door_state_recognition/pipeline/sight.hpp"

namespace dsr {
namespace sight {

void chooseViewpoints(const std::vector<InputCloud>& inputs, ViewpointMode mode,
                      const std::optional<Eigen::Vector3d>& given, const Eigen::Vector3d& shift, const Parameters& p,
                      ViewpointChoice& out) {
  if (inputs.empty()) throw std::invalid_argument("no input cloud");
  if (mode == ViewpointMode::Given && (!given || inputs.size() != 1))
    throw std::invalid_argument("a given viewpoint is one position for one cloud");
  out.without_viewpoint = mode == ViewpointMode::None;
  // No VIEWPOINT in a georeferenced file: no sensor stood at its origin.
  if (mode == ViewpointMode::Auto && !shift.isZero() &&
      std::none_of(inputs.begin(), inputs.end(), [](const InputCloud& c) { return c.viewpoint_given; })) {
    out.without_viewpoint = true;
    out.notes.push_back("viewpoint: no VIEWPOINT in a georeferenced cloud; run without a viewpoint");
  }
  // Each input seen from its VIEWPOINT (the origin where none is given) or
  // from the given position, in the frame it was read into.
  for (const InputCloud& in : inputs) {
    const Eigen::Vector3d vp = out.without_viewpoint && !shift.isZero() ? Eigen::Vector3d::Zero()
                               : mode == ViewpointMode::Given        ? Eigen::Vector3d(*given - shift)
                                                                     : in.cloud->sensor_origin_.head<3>().cast<double>();
    if (!vp.allFinite() || vp.cwiseAbs().maxCoeff() > p.max_abs_coordinate) {
      if (mode == ViewpointMode::Given) throw std::invalid_argument("--viewpoint lies beyond max_abs_coordinate");
      if (!in.viewpoint_given && !shift.isZero())  // the origin of a georeferenced file, far from its points
        throw std::invalid_argument(in.name + " has no VIEWPOINT (or 0 0 0) and lies far from the origin "
                                    "(georeferenced): --viewpoint header has no position to take; use "
                                    "--viewpoint auto, none or X,Y,Z");
      throw std::invalid_argument(in.name + ": VIEWPOINT lies beyond max_abs_coordinate or is not finite");
    }
    out.stations.push_back({in.cloud, vp});
  }
  // Under auto each VIEWPOINT is checked; a station's points hidden from
  // it, where few (its depth edges in a cluttered room), are left out: the
  // rest are its rays.
  out.seen.resize(inputs.size());
  if (mode == ViewpointMode::Auto)
    for (std::size_t k = 0; k < inputs.size() && !out.without_viewpoint; ++k) {
      const ViewpointCheck check = checkViewpoint(*inputs[k].cloud, out.stations[k].viewpoint, p, &out.seen[k]);
      const Eigen::Vector3d& vp = out.stations[k].viewpoint;
      char at[120];
      std::snprintf(at, sizeof at, "(%.3g, %.3g, %.3g)", vp.x(), vp.y(), vp.z());
      const std::string whose = "viewpoint: " + inputs[k].name + "'s VIEWPOINT " + at;
      if (check.rays_meet) {  // an organized frame moved out of its sensor's frame: seen from its sensor
        out.stations[k].viewpoint = *check.rays_meet;
        out.notes.push_back(whose + ": " + check.reason + "; taken where they meet");
      } else if (check.take_visible) {
        out.notes.push_back(whose + " taken, the " + std::to_string(inputs[k].cloud->size() - out.seen[k].size()) +
                            " points hidden from it left out: " + check.reason);
        out.stations[k].cloud = &out.seen[k];
      } else if (!check.credible) {
        out.without_viewpoint = true;
        out.notes.push_back(whose + " is not credible: " + check.reason + "; run without a viewpoint");
      } else {
        out.taken.push_back(std::string("viewpoint ") + at + " of " + inputs[k].name + " taken: " + check.reason);
      }
    }
  // Without a viewpoint the inputs are one cloud.
  if (out.without_viewpoint && inputs.size() > 1) {
    for (const InputCloud& in : inputs) out.merged += *in.cloud;
    out.stations.assign(1, {&out.merged, Eigen::Vector3d::Zero()});
  }
}

}  // namespace sight
}  // namespace dsr
