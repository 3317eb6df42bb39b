// Writes a simulated cloud to a rosbag: sensor_msgs/PointCloud2 on /points
// and the static tf fixed_frame -> cloud frame on /tf_static (latched).
#pragma once

#include <string>

#include "door_state_recognition/sim/sensors.hpp"

namespace dsr {
namespace tools {

struct BagOptions {
  std::string fixed_frame = "map";
  int count = 3;          // copies of the cloud, consecutive stamps
  double rate_hz = 1.0;   // stamps 1/rate apart
  double start_time = 1000.0;
};

// Throws std::runtime_error when the bag cannot be written.
void writeBag(const std::string& path, const sim::SimulatedCloud& cloud, const BagOptions& options);

}  // namespace tools
}  // namespace dsr
