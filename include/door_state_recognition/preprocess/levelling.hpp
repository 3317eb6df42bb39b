// Levelling: the up direction of a cloud, given as an axis or estimated from
// its surfaces, and the rotation that makes it +z. ROS-free.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace dsr {
namespace preprocess {

using Points = std::vector<Eigen::Vector3f>;

// "+z" -> (0,0,1) etc.; "auto" -> nullopt. Throws std::invalid_argument otherwise.
std::optional<Eigen::Vector3d> parseUpAxis(const std::string& axis);

// A proper rotation R with R * up = +z (up need not be unit).
Eigen::Matrix3d levellingRotation(const Eigen::Vector3d& up);

// Estimates the up direction of an unlevelled cloud seen from the origin:
// the direction most normals are parallel (floor, ceiling) or perpendicular
// (walls) to, signed so that furniture rests on the floor side. `normals`
// pairs with `points`. Returns nullopt when the cloud shows no structure.
// `upright`, where known, is the sensor's own rough up (a camera's image
// up): of the room's three axes the one nearest it is taken, signed like it.
std::optional<Eigen::Vector3d> estimateUp(const Points& points, const Points& normals, unsigned seed,
                                          const std::optional<Eigen::Vector3d>& upright = std::nullopt);

// Refines an approximate up axis (a camera frame is rarely exactly level):
// the mean normal of horizontal surfaces within max_deg of it, or else the
// direction perpendicular to the normals of the vertical surfaces. Returns
// the given axis when neither is seen.
Eigen::Vector3d refineUp(const Eigen::Vector3d& up, const Points& normals, double max_deg);

// The axis of the frame (+x ... -z) within max_deg of `dir`, or `dir`
// (normalized) when none is.
Eigen::Vector3d nearestFrameAxis(const Eigen::Vector3d& dir, double max_deg);

}  // namespace preprocess
}  // namespace dsr
