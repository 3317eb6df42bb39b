// The door stage (recognition + state): doorways on every wall, the leaf in
// each, and the decision that makes a doorway with its leaf a door. Shared by
// dsr::Pipeline and the stock-PCL baseline, so that both decide alike.
// Works in the levelled frame; reports in the input frame. ROS-free.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "door_state_recognition/pipeline/parameters.hpp"
#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/recognition/recognition.hpp"
#include "door_state_recognition/reconstruction/reconstruction.hpp"
#include "door_state_recognition/segmentation/segmentation.hpp"

namespace dsr {
namespace state {

struct DoorStage {
  std::vector<DoorResult> doors;                    // ids 0..n-1, input frame
  std::vector<char> is_leaf;                        // per point: on a found leaf
  std::vector<reconstruction::Opening> openings;    // for the reconstruction
  std::vector<std::string> trace;                   // every doorway and the decision on it
};

// `top_z` is the ceiling when `ceiling_known`, else the top of the vertical
// structure seen (then door heights are not judged against it).
// `to_input` rotates the levelled frame back to the input's. `organized`: a
// camera frame, where no return in range means free space; its extent is
// `view` when the caller has made it (else made here). Doorways and
// leaves are searched over the cores; decisions follow in wall order.
// `doorways`, when given, holds each wall's doorways as
// recognition::findDoorways finds them with these arguments (the caller
// sought them already); else they are sought here.
DoorStage findDoors(const segmentation::Points& pts, const std::vector<segmentation::WallPlane>& walls, double floor_z,
                    double top_z, bool ceiling_known, const Eigen::Vector3f& viewpoint, const Eigen::Matrix3d& to_input,
                    bool organized, const Parameters& p, const segmentation::ViewTop* view = nullptr,
                    const std::vector<std::vector<recognition::Doorway>>* doorways = nullptr);

}  // namespace state
}  // namespace dsr
