// Clouds as registered exports and reconstructed meshes deliver them: several
// stations' scans merged into one cloud with no scanner position (VIEWPOINT
// 0 0 0 in its header, as registration software writes it), and such a cloud
// resampled as the vertices of a reconstructed mesh. ROS-free; deterministic
// for a seed.
#pragma once

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <string>

#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/sim/sensors.hpp"

namespace dsr {
namespace sim {

enum class MergedFrame {
  // z up, floor at z = 0, origin on the floor 0.5-2 m beyond the outer corner
  // of walls 3 and 0 (outside the scanned room, at no station), yaw drawn by
  // the seed: the frame's origin, VIEWPOINT 0 0 0, is no scanner position.
  Map,
  // The first station's frame (today's union of stations): VIEWPOINT 0 0 0 is
  // station 0's position, as an export in its first station's frame has it.
  Station0,
};

// Parses "map" | "station0"; throws std::invalid_argument otherwise.
MergedFrame mergedFrameFromString(const std::string& name);

struct MergeOptions {
  MergedFrame frame = MergedFrame::Map;
  std::uint64_t seed = 1;
};

// Every station's points of a TLS scan (scanTls, any number of stations) in
// one cloud in the chosen frame: frame_id "map" (or the scan's own),
// sensor_to_world the frame's pose, sensor_origin_ zero, the overlaps as the
// stations gave them (no thinning). `station` and `viewpoints_world` are
// kept. Throws std::invalid_argument for a cloud that is not a TLS scan.
SimulatedCloud mergeStations(const Scene& scene, const SimulatedCloud& scan, const MergeOptions& options);

struct MeshLikeOptions {
  std::size_t vertices = 40000;  // about this many (within 2% when reachable)
  double hole_fraction = 0.05;   // share of the surface lost in round holes 16-60 cm across
  double smoothing = 0.5;        // one Laplacian step toward the neighbours' mean (rounds corners)
  double noise = 0.002;          // Gaussian sigma added after smoothing, metres
  std::uint64_t seed = 1;
};

// The cloud resampled as the vertices of a mesh reconstructed from it:
// holes cut first (random round patches), then Poisson-disk vertices (no two
// closer than a radius found for the count), one smoothing step (corners and
// thin parts pulled in), a little noise. Same frame, VIEWPOINT zero; each
// vertex keeps its source point's label and station. Throws
// std::invalid_argument for fewer than 100 or more than 1e7 vertices, or a
// cloud with fewer points than asked for.
SimulatedCloud meshLike(const SimulatedCloud& cloud, const MeshLikeOptions& options);

// The cloud as an occupancy map exports it (OctoMap, a voxel SLAM map): the
// centre of every voxel of edge `resolution` holding a point, nothing else.
// Same frame, VIEWPOINT zero; each centre keeps the label and station of the
// voxel's first point. Throws std::invalid_argument for a resolution outside
// [0.01, 0.5] m.
SimulatedCloud voxelMap(const SimulatedCloud& cloud, double resolution);

// Median distance from a point to its nearest neighbour (0 below 2 points).
double medianSpacing(const pcl::PointCloud<pcl::PointXYZL>& cloud);

}  // namespace sim
}  // namespace dsr
