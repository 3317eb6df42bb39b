// Recognition: the paper's boundary points by the angular gap between
// neighbours (boundaryPoints).
#include "door_state_recognition/recognition/recognition.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace dsr {
namespace recognition {

std::vector<char> boundaryPoints(const Points& points, const segmentation::Normals& normals,
                                 const segmentation::NeighbourGrid& grid, float radius,
                                 const std::vector<int>& indices, int k, double angle_deg) {
  std::vector<char> out(indices.size(), 0);
  const double thr = angle_deg * M_PI / 180.0;
  if (k < 3) return out;
  std::vector<int> within;
  std::vector<float> d2;
  std::vector<std::pair<float, int>> near;
  std::vector<double> angles;
  for (std::size_t j = 0; j < indices.size(); ++j) {
    const int i = indices[j];
    const Eigen::Vector3d p = points[i].cast<double>(), n = normals.n[i].cast<double>();
    // Tangent basis (u, v) of the plane perpendicular to n.
    Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
    // The k nearest within the radius.
    grid.within(i, radius, within, d2);
    near.clear();
    for (std::size_t m = 0; m < within.size(); ++m) near.push_back({d2[m], within[m]});
    if (static_cast<int>(near.size()) > k - 1) {
      std::nth_element(near.begin(), near.begin() + (k - 1), near.end());
      near.resize(k - 1);
    }
    angles.clear();
    for (const auto& nb : near) {
      const Eigen::Vector3d d = points[nb.second].cast<double>() - p;
      const Eigen::Vector3d proj = d - d.dot(n) * n;  // onto the tangent plane
      if (proj.squaredNorm() < 1e-12) continue;
      angles.push_back(std::atan2(proj.dot(v), proj.dot(u)));
    }
    if (angles.size() < 2) {
      out[j] = 1;
      continue;
    }
    std::sort(angles.begin(), angles.end());
    double gap = 2 * M_PI - (angles.back() - angles.front());
    for (std::size_t m = 1; m < angles.size(); ++m) gap = std::max(gap, angles[m] - angles[m - 1]);
    out[j] = gap > thr;
  }
  return out;
}

}  // namespace recognition
}  // namespace dsr
