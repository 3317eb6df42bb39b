#include "door_state_recognition/tracking/door_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace dsr {

std::vector<std::uint32_t> DoorTracker::update(const std::vector<Eigen::Vector3d>& centres, const Eigen::Vector3d& up_in) {
  // A zero or non-finite up falls back to z (the frame's own up by REP 103).
  const double n = up_in.norm();
  const Eigen::Vector3d up = std::isfinite(n) && n > 1e-9 ? Eigen::Vector3d(up_in / n) : Eigen::Vector3d::UnitZ();
  // Nearest pairs first, one-to-one.
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < centres.size(); ++i)
    for (std::size_t k = 0; k < tracks_.size(); ++k) {
      const Eigen::Vector3d delta = centres[i] - tracks_[k].centre;
      const double d = (delta - delta.dot(up) * up).norm();  // horizontal: across up
      if (d <= match_distance_) pairs.emplace_back(d, i, k);
    }
  std::sort(pairs.begin(), pairs.end());
  std::vector<std::uint32_t> ids(centres.size(), 0);
  std::vector<char> done(centres.size(), 0), seen(tracks_.size(), 0);
  for (const auto& [d, i, k] : pairs) {
    if (done[i] || seen[k]) continue;
    done[i] = seen[k] = 1;
    ids[i] = tracks_[k].id;
    tracks_[k].centre = centres[i];
    tracks_[k].missed = 0;
  }
  for (std::size_t k = 0; k < tracks_.size(); ++k)
    if (!seen[k]) ++tracks_[k].missed;
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(), [this](const Track& t) { return t.missed > forget_after_; }),
                tracks_.end());
  for (std::size_t i = 0; i < centres.size(); ++i)
    if (!done[i]) {
      ids[i] = next_id_++;
      tracks_.push_back({ids[i], centres[i], 0});
    }
  return ids;
}

}  // namespace dsr
