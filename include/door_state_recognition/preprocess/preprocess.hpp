// Preprocessing stage: drop garbage points, level the cloud so that z is up,
// voxel-downsample. ROS-free.
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

// Finite points with every |coordinate| <= max_abs, as float vectors.
Points sanitize(const pcl::PointCloud<pcl::PointXYZ>& cloud, double max_abs);

// One point (the centroid) per occupied cubic voxel of edge `leaf`; the
// output order is deterministic. leaf <= 0 returns the input.
Points voxelDownsample(const Points& points, double leaf);

// voxelDownsample(sanitize(cloud, max_abs), leaf) in one pass, without the
// copy; `kept` (if given) receives the number of points sanitize keeps.
Points sanitizeAndDownsample(const pcl::PointCloud<pcl::PointXYZ>& cloud, double max_abs, double leaf,
                             std::size_t* kept = nullptr);

// An organized frame from a pinhole camera at `viewpoint`: the camera is
// fitted to the pixels with a return (direct linear transform, pixel column
// and row against the point), and the unit directions of the rays of the
// pixels without one (every `step`-th row and column) are returned, in the
// cloud's frame. Empty when the cloud is not organized or no pinhole camera
// fits its pixels to within a pixel (an organized scan of another kind).
Points noReturnRays(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3f& viewpoint, int step = 2);

// Estimates the up direction of an unlevelled cloud seen from the origin:
// the direction most normals are parallel (floor, ceiling) or perpendicular
// (walls) to, signed so that furniture rests on the floor side. `normals`
// pairs with `points`. Returns nullopt when the cloud shows no structure.
std::optional<Eigen::Vector3d> estimateUp(const Points& points, const Points& normals, unsigned seed);

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
