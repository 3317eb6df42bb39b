// Stable door ids across consecutive clouds: a door keeps its id while it is
// seen again within match_distance (opening centres, measured in the plane
// perpendicular to the up vector: the height of a centre is ignored) and for
// up to forget_after clouds without being seen.
// ROS-free.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace dsr {

class DoorTracker {
 public:
  explicit DoorTracker(double match_distance = 0.5, int forget_after = 10)
      : match_distance_(match_distance), forget_after_(forget_after) {}

  // centres: opening centres of this cloud's doors; up: the up vector of
  // their frame (the pipeline's PipelineResult::up; -y in a camera optical
  // frame). Distances are taken perpendicular to it. Returns one id per
  // centre, in order.
  std::vector<std::uint32_t> update(const std::vector<Eigen::Vector3d>& centres,
                                    const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());
  void reset() { tracks_.clear(); }
  std::size_t tracked() const { return tracks_.size(); }

 private:
  struct Track {
    std::uint32_t id;
    Eigen::Vector3d centre;
    int missed = 0;
  };
  double match_distance_;
  int forget_after_;
  std::uint32_t next_id_ = 0;
  std::vector<Track> tracks_;
};

}  // namespace dsr
