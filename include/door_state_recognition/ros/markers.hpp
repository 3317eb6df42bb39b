// rviz markers of one pipeline result, in namespaces a user can toggle:
// wall_corners, door_corners, wall_lines, leaf_lines, reconstruction, labels.
// Colour by state: closed red, semi-open orange, open green, not closed
// (leaf unseen) yellow. The array starts with a DELETEALL so that markers of
// doors no longer seen vanish.
#pragma once

#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include <cstdint>
#include <vector>

#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/tracking/door_fusion.hpp"

namespace dsr {
namespace ros_io {

std_msgs::ColorRGBA stateColour(DoorStateKind s);

visualization_msgs::MarkerArray makeMarkers(const PipelineResult& result, const std::vector<std::uint32_t>& ids,
                                           const std_msgs::Header& header);

// The doors tracked over the drive (DoorFusion::tracks(), in the fixed frame
// of `header`), appended to `out` in namespaces tracked_leaf_lines and
// tracked_labels (marker id = track id): in their state's colour when the
// current cloud shows them, greyed (half way to grey, alpha 0.35) when not.
void addTrackedMarkers(const std::vector<TrackedDoor>& tracks, const std_msgs::Header& header,
                       visualization_msgs::MarkerArray& out);

}  // namespace ros_io
}  // namespace dsr
