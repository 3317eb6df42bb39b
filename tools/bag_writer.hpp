// Writes simulated clouds to rosbags: one scan (sensor_msgs/PointCloud2 on
// /points and the static tf fixed_frame -> cloud frame on /tf_static,
// latched), or a robot's drive (/points in the sensor frame, /tf map ->
// base_link, /tf_static base_link -> sensor frame, /clock).
#pragma once

#include <string>

#include "door_state_recognition/sim/drive.hpp"
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

// A drive: every frame of the plan simulated in turn and written at
// start_time + t: /clock (rosgraph_msgs/Clock every 10 ms and at every cloud),
// /tf (map -> base_link at each cloud's stamp), /points (the cloud, in the
// sensor frame, stamped at its pose's time, recorded 1 ms later), and once,
// latched, /tf_static base_link -> sensor frame. fixed_frame names map.
// `each` (may be empty) is given every frame after it is written. Throws
// std::runtime_error when the bag cannot be written.
void writeDriveBag(const std::string& path, const sim::DrivePlan& plan, const BagOptions& options,
                   const std::function<void(const sim::DriveFrame&)>& each = {});

}  // namespace tools
}  // namespace dsr
