// Recognition: a segment's bounding box and its corners (AABB, or OBB on
// the principal horizontal axis).
#include "door_state_recognition/recognition/recognition.hpp"

#include <Eigen/Eigenvalues>
#include <array>
#include <cmath>

namespace dsr {
namespace recognition {

BoxCorners boundingBox(const Points& points, const std::vector<int>& idx) {
  BoxCorners b;
  if (idx.empty()) return b;
  // Principal horizontal axis of the segment.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int i : idx) mean += points[i].head<2>().cast<double>();
  mean /= static_cast<double>(idx.size());
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  for (int i : idx) {
    const Eigen::Vector2d d = points[i].head<2>().cast<double>() - mean;
    C += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  Eigen::Vector2d a = es.eigenvectors().col(1);
  const double ang = std::atan2(a.y(), a.x());
  const double to_axis = std::abs(std::remainder(ang, M_PI / 2));
  b.oriented = to_axis > 2.0 * M_PI / 180.0;
  // Gram-Schmidt: the axes are the principal horizontal axis, its
  // orthogonal complement in the horizontal plane, and z (levelled frame).
  Eigen::Vector3d e1 = b.oriented ? Eigen::Vector3d(a.x(), a.y(), 0).normalized() : Eigen::Vector3d::UnitX();
  Eigen::Vector3d e3 = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d e2 = e3.cross(e1);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  for (int i : idx) {
    const Eigen::Vector3d p = points[i].cast<double>();
    const Eigen::Vector3d q(p.dot(e1), p.dot(e2), p.dot(e3));
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  b.extents = hi - lo;
  b.volume = b.extents.prod();
  b.height = b.extents.z();
  const Eigen::Vector3d c = (lo + hi) / 2;
  b.center = c.x() * e1 + c.y() * e2 + c.z() * e3;
  b.corners = boxCorners(lo, hi, e1, e2, e3);
  return b;
}

std::array<Eigen::Vector3d, 8> boxCorners(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3d& e1,
                                          const Eigen::Vector3d& e2, const Eigen::Vector3d& e3) {
  std::array<Eigen::Vector3d, 8> corners;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d q((k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z());
    corners[k] = q.x() * e1 + q.y() * e2 + q.z() * e3;
  }
  return corners;
}

}  // namespace recognition
}  // namespace dsr
