// The pipeline's result as the report JSON of door_state_cli (input frame,
// metres and degrees). ROS-free.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "door_state_recognition/pipeline/pipeline.hpp"

namespace dsr {
namespace io {

nlohmann::json reportJson(const PipelineResult& result, const std::string& input_name);

}  // namespace io
}  // namespace dsr
