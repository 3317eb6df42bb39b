// Ground truth of a simulated cloud as JSON, every coordinate in the cloud's
// own frame (the sensor frame). ROS-free.
#pragma once

#include <nlohmann/json.hpp>

#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/sim/sensors.hpp"

namespace dsr {
namespace sim {

// {"scene", "sensor", "frame_id", "up", "floor", "ceiling", "doors": [...],
//  "decoys": [...], "walls": [...], "sensor_origins": [...], "sensor_to_world": {...}}
// "floor"/"ceiling" are heights along "up" in the cloud frame (p . up).
// Door states use closed < 5 deg <= semi_open < 90 deg <= open.
// Each door's "in_view": sensorSeesDoor (sim/drive.hpp; true for a TLS);
// RGB-D and TLS, "leaf_in_view": leafInViewShare, the share of the leaf seen
// (a TLS: from any of its stations).
nlohmann::json groundTruthJson(const Scene& scene, const SimulatedCloud& cloud);

}  // namespace sim
}  // namespace dsr
