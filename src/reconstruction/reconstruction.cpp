#include "door_state_recognition/reconstruction/reconstruction.hpp"

#include <cmath>

namespace dsr {
namespace reconstruction {

pcl::PointCloud<pcl::PointXYZL> reconstruct(const std::vector<WallPatch>& walls,
                                            const std::vector<Opening>& openings, double spacing,
                                            const Eigen::Matrix3f& to_output) {
  pcl::PointCloud<pcl::PointXYZL> out;
  auto add = [&](const Eigen::Vector2d& xy, double z, std::uint32_t label) {
    const Eigen::Vector3f v =
        to_output * Eigen::Vector3f(static_cast<float>(xy.x()), static_cast<float>(xy.y()), static_cast<float>(z));
    pcl::PointXYZL q;
    q.x = v.x();
    q.y = v.y();
    q.z = v.z();
    q.label = label;
    out.push_back(q);
  };
  const std::size_t budget = 20000000;  // never more than this many points
  for (std::size_t w = 0; w < walls.size(); ++w) {
    const WallPatch& p = walls[w];
    // Up-sampling along the longest edge sets the step, as in the paper:
    // dis_up = L_m / N_up with N_up = L_m / spacing.
    const int ns = static_cast<int>(std::ceil((p.s_max - p.s_min) / spacing));
    const int nz = static_cast<int>(std::ceil((p.z_max - p.z_min) / spacing));
    if (static_cast<std::size_t>(ns) * nz > budget) continue;
    for (int i = 0; i <= ns; ++i) {
      const double s = p.s_min + i * spacing;
      for (int j = 0; j <= nz; ++j) {
        const double z = p.z_min + j * spacing;
        bool in_opening = false;
        for (const Opening& o : openings)
          in_opening |= o.wall == static_cast<int>(w) && s > o.s0 && s < o.s1 && z < o.z_top;
        if (!in_opening) add(p.point + s * p.direction, z, 1);
      }
    }
  }
  for (const Opening& o : openings) {
    const int na = static_cast<int>(std::ceil(o.leaf_length / spacing));
    const int nz = static_cast<int>(std::ceil((o.leaf_top - o.leaf_bottom) / spacing));
    if (na <= 0 || nz <= 0 || static_cast<std::size_t>(na) * nz > budget) continue;
    for (int i = 0; i <= na; ++i)
      for (int j = 0; j <= nz; ++j) add(o.hinge + (i * spacing) * o.leaf_direction, o.leaf_bottom + j * spacing, 2);
  }
  out.width = static_cast<std::uint32_t>(out.size());
  out.height = 1;
  return out;
}

}  // namespace reconstruction
}  // namespace dsr
