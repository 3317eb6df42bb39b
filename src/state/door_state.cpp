#include "door_state_recognition/state/door_state.hpp"
#include "leaf_internal.hpp"

#include <Eigen/Eigenvalues>
#include <utility>

namespace dsr {
namespace state {

Line2 fitLine(const std::vector<Eigen::Vector2d>& pts) {
  Line2 l;
  if (pts.empty()) return l;
  for (const auto& q : pts) l.point += q;
  l.point /= static_cast<double>(pts.size());
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  for (const auto& q : pts) C += (q - l.point) * (q - l.point).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  l.direction = es.eigenvectors().col(1).normalized();
  return l;
}

DoorStateKind classify(double angle_deg, const Parameters& p) {
  if (angle_deg < p.closed_below_deg) return DoorStateKind::Closed;
  if (angle_deg < p.open_from_deg) return DoorStateKind::SemiOpen;
  return DoorStateKind::Open;
}

LeafFit fitLeaf(const segmentation::Points& points, const segmentation::WallPlane& wall,
                const recognition::Doorway& door, double floor_z, double t, const Eigen::Vector3f& viewpoint,
                const Parameters& p, double closed_band_only_above, const segmentation::ViewTop* view) {
  detail::LeafSearch leaf(points, wall, door, floor_z, t, viewpoint, p, closed_band_only_above, view);
  leaf.gather();
  if (!leaf.bandEvidence()) return std::move(leaf.fit);
  leaf.searchHinges();
  leaf.closedInBand();
  leaf.measureLeaf();
  leaf.freeSpaceBound();
  leaf.placeLeaf();
  return std::move(leaf.fit);
}

}  // namespace state
}  // namespace dsr
