#include "door_state_recognition/sim/registered.hpp"

#include <pcl/kdtree/kdtree_flann.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "room_frame.hpp"

namespace dsr {
namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("registered: " + what);
}

double gaussian(detail::Rng& rng) {
  const double u = std::max(1e-300, rng.uniform(0, 1)), v = rng.uniform(0, 1);
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2 * kPi * v);
}

// A hash grid of point indices in cubic cells.
class Grid {
 public:
  explicit Grid(double cell) : inv_(1.0 / cell) {}
  void insert(const Eigen::Vector3f& p, int index) { cells_[key(p)].push_back(index); }
  // Calls f(index) for every index in the 27 cells around p.
  template <class F>
  void around(const Eigen::Vector3f& p, F&& f) const {
    const long long x = cell(p.x()), y = cell(p.y()), z = cell(p.z());
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(pack(x + dx, y + dy, z + dz));
          if (it != cells_.end())
            for (const int i : it->second) f(i);
        }
  }

 private:
  long long cell(float v) const { return static_cast<long long>(std::floor(v * inv_)); }
  static std::uint64_t pack(long long x, long long y, long long z) {
    return (static_cast<std::uint64_t>(x & 0x1FFFFF) << 42) | (static_cast<std::uint64_t>(y & 0x1FFFFF) << 21) |
           static_cast<std::uint64_t>(z & 0x1FFFFF);
  }
  std::uint64_t key(const Eigen::Vector3f& p) const { return pack(cell(p.x()), cell(p.y()), cell(p.z())); }
  double inv_;
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

// Poisson-disk subset of `pts` (visited in `order`): no two kept closer than radius.
std::vector<int> poissonDisk(const std::vector<Eigen::Vector3f>& pts, const std::vector<int>& order, double radius) {
  Grid grid(radius);
  std::vector<int> kept;
  const float r2 = static_cast<float>(radius * radius);
  for (const int i : order) {
    bool near = false;
    grid.around(pts[i], [&](int j) { near = near || (pts[i] - pts[j]).squaredNorm() < r2; });
    if (near) continue;
    grid.insert(pts[i], i);
    kept.push_back(i);
  }
  return kept;
}

}  // namespace

MergedFrame mergedFrameFromString(const std::string& name) {
  if (name == "map") return MergedFrame::Map;
  if (name == "station0") return MergedFrame::Station0;
  throw std::invalid_argument("registered: frame must be map or station0, not '" + name + "'");
}

SimulatedCloud mergeStations(const Scene& scene, const SimulatedCloud& scan, const MergeOptions& o) {
  require(scan.sensor == "tls", "only a TLS scan's stations can be merged");
  require(scan.station.size() == scan.cloud.size(), "the scan lacks its points' stations");
  SimulatedCloud out = scan;
  out.cloud.sensor_origin_.setZero();
  out.cloud.sensor_orientation_.setIdentity();
  if (o.frame == MergedFrame::Station0) return out;

  detail::Rng rng(o.seed ^ 0x3A9F0C1D5EEDull);
  const RoomSpec& r = scene.spec;
  const double ox = rng.uniform(0.5, 2.0), oy = rng.uniform(0.5, 2.0), yaw = rng.uniform(-kPi, kPi);
  const Eigen::Vector3d origin_room(-r.width / 2 - r.wall_thickness - ox, -r.depth / 2 - r.wall_thickness - oy, scene.floor_z);
  const Eigen::Isometry3d map_to_world =
      scene.room_to_world * Eigen::Translation3d(origin_room) * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
  const Eigen::Isometry3d scan_to_map = map_to_world.inverse() * scan.sensor_to_world;
  const Eigen::Matrix3f R = scan_to_map.linear().cast<float>();
  const Eigen::Vector3f t = scan_to_map.translation().cast<float>();
  for (auto& p : out.cloud.points) p.getVector3fMap() = R * p.getVector3fMap() + t;
  out.sensor_to_world = map_to_world;
  out.frame_id = "map";
  return out;
}

SimulatedCloud voxelMap(const SimulatedCloud& in, double res) {
  require(res >= 0.01 && res <= 0.5, "voxel map resolution must lie in [0.01, 0.5] m");
  std::unordered_map<std::uint64_t, std::size_t> seen;  // voxel key -> index in the output
  SimulatedCloud out = in;
  out.cloud.clear();
  out.station.clear();
  for (std::size_t i = 0; i < in.cloud.size(); ++i) {
    const pcl::PointXYZL& q = in.cloud.points[i];
    if (!q.getVector3fMap().allFinite()) continue;
    const auto cell = [&](float v) { return static_cast<std::int64_t>(std::floor(v / res)); };
    const std::int64_t x = cell(q.x), y = cell(q.y), z = cell(q.z);
    const std::uint64_t key = (static_cast<std::uint64_t>(x & 0x1FFFFF) << 42) |
                              (static_cast<std::uint64_t>(y & 0x1FFFFF) << 21) | static_cast<std::uint64_t>(z & 0x1FFFFF);
    if (!seen.emplace(key, out.cloud.size()).second) continue;
    pcl::PointXYZL c;
    c.x = static_cast<float>((x + 0.5) * res), c.y = static_cast<float>((y + 0.5) * res), c.z = static_cast<float>((z + 0.5) * res);
    c.label = q.label;
    out.cloud.push_back(c);
    if (i < in.station.size()) out.station.push_back(in.station[i]);
  }
  out.cloud.width = static_cast<std::uint32_t>(out.cloud.size());
  out.cloud.height = 1;
  out.cloud.sensor_origin_.setZero();
  return out;
}

SimulatedCloud meshLike(const SimulatedCloud& in, const MeshLikeOptions& o) {
  require(o.vertices >= 100 && o.vertices <= 10000000, "mesh-like vertices must lie in [100, 1e7]");
  require(o.hole_fraction >= 0 && o.hole_fraction < 0.5, "hole fraction must lie in [0, 0.5)");
  require(o.smoothing >= 0 && o.smoothing <= 1, "smoothing must lie in [0, 1]");
  require(o.noise >= 0 && o.noise < 0.1, "noise must lie in [0, 0.1) m");
  std::vector<Eigen::Vector3f> pts;
  std::vector<int> src;
  pts.reserve(in.cloud.size());
  for (std::size_t i = 0; i < in.cloud.size(); ++i)
    if (in.cloud[i].getVector3fMap().allFinite()) {
      pts.push_back(in.cloud[i].getVector3fMap());
      src.push_back(static_cast<int>(i));
    }
  require(pts.size() >= 2 * o.vertices, "mesh-like needs a cloud of at least twice as many points as vertices (" +
                                            std::to_string(pts.size()) + " for " + std::to_string(o.vertices) + ")");
  detail::Rng rng(o.seed ^ 0x3E5B11CEull);

  std::vector<int> order(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) order[i] = static_cast<int>(i);
  for (std::size_t i = order.size(); i > 1; --i)  // Fisher-Yates with our own mapping
    std::swap(order[i - 1], order[static_cast<std::size_t>(rng.uniform(0, 1) * i) % i]);

  // Holes: round patches (8-30 cm radius) centred uniformly over the surface
  // (on a 10 cm Poisson-disk sample, not on the scan's uneven density) until
  // that share of the sample is cut.
  const std::vector<int> coarse = poissonDisk(pts, order, 0.1);
  std::vector<char> alive(pts.size(), 1), coarse_alive(coarse.size(), 1);
  std::size_t cut = 0;
  for (int patch = 0; patch < 5000 && cut < o.hole_fraction * coarse.size(); ++patch) {
    const Eigen::Vector3f c = pts[coarse[static_cast<std::size_t>(rng.uniform(0, 1) * coarse.size()) % coarse.size()]];
    const float r2 = static_cast<float>(std::pow(rng.uniform(0.08, 0.3), 2));
    for (std::size_t k = 0; k < coarse.size(); ++k)
      if (coarse_alive[k] && (pts[coarse[k]] - c).squaredNorm() < r2) {
        coarse_alive[k] = 0;
        ++cut;
      }
    for (std::size_t i = 0; i < pts.size(); ++i) alive[i] = alive[i] && (pts[i] - c).squaredNorm() >= r2;
  }
  order.erase(std::remove_if(order.begin(), order.end(), [&](int i) { return !alive[i]; }), order.end());

  // Poisson-disk radius for the count: count ~ area / radius^2, refined.
  double radius = 0.04;
  std::vector<int> kept = poissonDisk(pts, order, radius);
  for (int it = 0; it < 12; ++it) {
    const double ratio = static_cast<double>(kept.size()) / o.vertices;
    if (std::abs(ratio - 1.0) < 0.015) break;
    radius *= std::clamp(std::pow(ratio, 0.5), 0.5, 2.0);
    kept = poissonDisk(pts, order, radius);
  }
  std::sort(kept.begin(), kept.end());  // the source's order (by station, then ray)

  // One Laplacian step over the neighbours within 1.75 radius, then noise.
  const double reach = 1.75 * radius;
  Grid grid(reach);
  for (std::size_t k = 0; k < kept.size(); ++k) grid.insert(pts[kept[k]], static_cast<int>(k));
  const float reach2 = static_cast<float>(reach * reach);
  SimulatedCloud out = in;
  out.cloud.clear();
  out.station.clear();
  out.cloud.reserve(kept.size());
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const Eigen::Vector3f& p = pts[kept[k]];
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    int n = 0;
    grid.around(p, [&](int j) {
      if ((pts[kept[j]] - p).squaredNorm() < reach2) {
        sum += pts[kept[j]];
        ++n;
      }
    });
    Eigen::Vector3f q = p + static_cast<float>(o.smoothing) * (sum / static_cast<float>(n) - p);
    if (o.noise > 0) q += static_cast<float>(o.noise) * Eigen::Vector3f(gaussian(rng), gaussian(rng), gaussian(rng));
    pcl::PointXYZL v = in.cloud[src[kept[k]]];
    v.getVector3fMap() = q;
    out.cloud.push_back(v);
    if (!in.station.empty()) out.station.push_back(in.station[src[kept[k]]]);
  }
  out.cloud.is_dense = true;
  out.cloud.sensor_origin_.setZero();
  out.cloud.sensor_orientation_.setIdentity();
  return out;
}

double medianSpacing(const pcl::PointCloud<pcl::PointXYZL>& cloud) {
  if (cloud.size() < 2) return 0.0;
  pcl::KdTreeFLANN<pcl::PointXYZL> tree;
  tree.setInputCloud(cloud.makeShared());
  std::vector<double> d;
  d.reserve(cloud.size());
  std::vector<int> idx(2);
  std::vector<float> d2(2);
  for (const auto& p : cloud.points)
    if (tree.nearestKSearch(p, 2, idx, d2) == 2) d.push_back(std::sqrt(d2[1]));
  if (d.empty()) return 0.0;
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

}  // namespace sim
}  // namespace dsr
