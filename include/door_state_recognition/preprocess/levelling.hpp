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

// The share of the normals (of at most 4000 spread over them; those of
// isolated points, zero, left out) parallel (|n . up| > 0.97) or square
// (< 0.05) to `up`: floor, ceiling and walls make most of a room's normals
// so when `up` is the room's; a camera pitched 40 deg off a given axis
// leaves a few percent.
double squareShare(const Points& normals, const Eigen::Vector3d& up);

// A given up axis that the cloud's surfaces contradict: where no floor was
// seen after levelling or few normals are square to `used` (the given axis
// as refined; under kDoubtShare), the up the surfaces show (estimateUp) is
// found, and where it lies more than max_deg from `given` and holds
// kDoubtRatio times the square normals, its angle from `given` in degrees
// (a camera pitched beyond the refinement's reach). nullopt otherwise.
// Costs an estimateUp only on such clouds.
std::optional<double> givenUpContradicted(const Points& points, const Points& normals, const Eigen::Vector3d& given,
                                          const Eigen::Vector3d& used, double max_deg, bool floor_seen,
                                          unsigned seed, const std::optional<Eigen::Vector3d>& upright);

// The axis of the frame (+x ... -z) within max_deg of `dir`, or `dir`
// (normalized) when none is.
Eigen::Vector3d nearestFrameAxis(const Eigen::Vector3d& dir, double max_deg);

}  // namespace preprocess
}  // namespace dsr
