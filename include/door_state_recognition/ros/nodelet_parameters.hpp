// The nodelet's ~ parameters: checked as they stand on the parameter server
// before dynamic_reconfigure reads them, and a DoorStateConfig turned into
// the YAML that dsr::parseParameters (and `door_state_cli --config`) reads.
#pragma once

#include <ros/node_handle.h>

#include <string>
#include <vector>

#include "door_state_recognition/DoorStateConfig.h"

namespace door_state_recognition {

// A dynamic_reconfigure config as YAML `name: value`, for dsr::parseParameters.
std::string toYaml(const DoorStateConfig& config);

// Names the double parameters of `config` that are NaN or infinite: the
// generated __clamp__ lets NaN through (every comparison with it is false).
// Empty when all are finite.
std::string nonFinite(const DoorStateConfig& config);

// Checks every ~ parameter as it stands on the parameter server, before the
// dynamic_reconfigure server reads them: that server ignores a value of the
// wrong type (the default stays), clamps a number to the .cfg range and
// never sees an unknown name. Here each of these is a problem, named with
// what would be valid: an unknown name (not a pipeline parameter nor one of
// the nodelet's own), a wrong type (a double parameter takes an int or a
// double), a value outside the .cfg range or refused by the pipeline's own
// validation (dsr::parseParameters, as `door_state_cli --config` reads its
// YAML). Returns one line per problem; none: all good.
std::vector<std::string> checkPrivateParameters(const ros::NodeHandle& pnh);

// The parameters that `config` sets, relative to `before`, to an end of its
// .cfg range: "name = value (the upper end of [min, max])", comma-separated.
// dynamic_reconfigure clamps a request to the range before the callback sees
// it, and does not say so: a value asked beyond the range arrives as the end
// of the range. The callback cannot tell a clamped request from one that asked
// for the end itself, so this names both.
std::string atRangeEnd(const DoorStateConfig& config, const DoorStateConfig& before);

}  // namespace door_state_recognition
