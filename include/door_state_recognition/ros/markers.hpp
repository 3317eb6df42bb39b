// rviz markers of one pipeline result, in namespaces a user can toggle:
// wall_corners, door_corners, wall_lines, leaf_lines, reconstruction, labels.
// Colour by state: closed red, semi-open orange, open green. The array
// starts with a DELETEALL so that markers of doors no longer seen vanish.
#pragma once

#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include <cstdint>
#include <vector>

#include "door_state_recognition/pipeline/pipeline.hpp"

namespace dsr {
namespace ros_io {

std_msgs::ColorRGBA stateColour(DoorStateKind s);

visualization_msgs::MarkerArray makeMarkers(const PipelineResult& result, const std::vector<std::uint32_t>& ids,
                                           const std_msgs::Header& header);

}  // namespace ros_io
}  // namespace dsr
