#include "door_state_recognition/tracking/door_fusion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>

namespace dsr {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// The opening centre a track is matched by is the mean of the last this
// many centres seen (a running mean that still follows a drifting map).
constexpr double kCentreMemory = 20.0;

Eigen::Vector3d unitUp(const Eigen::Vector3d& up) {
  const double n = up.norm();
  return std::isfinite(n) && n > 1e-9 ? Eigen::Vector3d(up / n) : Eigen::Vector3d::UnitZ();
}

Eigen::Vector3d across(const Eigen::Vector3d& v, const Eigen::Vector3d& up) { return v - v.dot(up) * up; }

// The wall's direction across up, unit; zero when there is none.
Eigen::Vector3d wallDirection(const DoorResult& d, const Eigen::Vector3d& up) {
  const Eigen::Vector3d w = across(d.wall_line_direction, up);
  const double n = w.norm();
  return std::isfinite(n) && n > 1e-6 ? Eigen::Vector3d(w / n) : Eigen::Vector3d::Zero();
}

bool usable(const DoorResult& d, const Eigen::Vector3d& up) {
  return d.opening_center.allFinite() && std::isfinite(d.opening_angle_deg) && !wallDirection(d, up).isZero();
}

}  // namespace

const char* toString(DoorFusion::Outcome o) {
  switch (o) {
    case DoorFusion::Outcome::Fused: return "fused";
    case DoorFusion::Outcome::Reset: return "reset (stamp went backwards)";
    case DoorFusion::Outcome::IgnoredOutOfOrder: return "ignored (older than the newest cloud fused)";
    case DoorFusion::Outcome::IgnoredBadStamp: return "ignored (stamp not finite)";
  }
  return "?";
}

void FusionOptions::validate() const {
  auto check = [](bool ok, const char* name, const char* range) {
    if (!ok) throw std::invalid_argument(std::string(name) + " out of range: " + range);
  };
  check(std::isfinite(forget_after_s) && forget_after_s > 0, "forget_after_s", "a number of seconds > 0");
  check(std::isfinite(state_change_deg) && state_change_deg > 0 && state_change_deg <= 180, "state_change_deg",
        "(0, 180] deg");
  check(std::isfinite(match_distance_m) && match_distance_m > 0, "match_distance_m", "> 0 m");
  check(std::isfinite(wall_angle_deg) && wall_angle_deg >= 0 && wall_angle_deg <= 90, "wall_angle_deg", "[0, 90] deg");
  check(std::isfinite(sure_confidence) && sure_confidence >= 0, "sure_confidence", ">= 0 (above 1: never)");
  check(std::isfinite(backwards_tolerance_s) && backwards_tolerance_s >= 0, "backwards_tolerance_s", ">= 0 s");
  check(std::isfinite(closed_below_deg) && std::isfinite(open_from_deg) && closed_below_deg >= 0 &&
            closed_below_deg <= open_from_deg && open_from_deg <= 180,
        "closed_below_deg/open_from_deg", "0 <= closed_below <= open_from <= 180 deg");
  check(std::isfinite(leaf_thickness) && leaf_thickness >= 0, "leaf_thickness", ">= 0 m");
}

DoorFusion::DoorFusion(const FusionOptions& options) : options_(options), newest_(kNaN) { options_.validate(); }

void DoorFusion::setOptions(const FusionOptions& options) {
  options.validate();
  options_ = options;
}

bool DoorFusion::drop(std::uint32_t id) {
  for (std::size_t k = 0; k < tracks_.size(); ++k)
    if (tracks_[k].id == id) {
      tracks_.erase(tracks_.begin() + static_cast<std::ptrdiff_t>(k));
      internal_.erase(internal_.begin() + static_cast<std::ptrdiff_t>(k));
      return true;
    }
  return false;
}

void DoorFusion::reset() {
  tracks_.clear();
  internal_.clear();
  newest_ = kNaN;
}

bool DoorFusion::sameWall(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
  return std::abs(a.dot(b)) >= std::cos(options_.wall_angle_deg * M_PI / 180.0) - 1e-12;
}

// The rules of the header, for one observation `o` of track `t`.
void DoorFusion::fuse(TrackedDoor& t, Internal& in, const DoorResult& o) const {
  DoorResult& e = t.door;
  const double change = options_.state_change_deg;
  Parameters states;  // only the thresholds stateOfBound reads
  states.closed_below_deg = options_.closed_below_deg;
  states.open_from_deg = options_.open_from_deg;
  auto setBound = [&](const DoorResult& d) {
    e = d;
    e.state = stateOfBound(e.opening_angle_deg, states);
    e.clear_width = clearWidth(e.width, e.opening_angle_deg, options_.leaf_thickness, options_.closed_below_deg);
  };
  auto takeOver = [&](const DoorResult& d) {
    if (d.angle_is_lower_bound) setBound(d);
    else e = d;
    in.pending.active = false;
  };
  if (e.angle_is_lower_bound) {
    if (!o.angle_is_lower_bound) return takeOver(o);       // a measured leaf beats a bound
    if (o.opening_angle_deg > e.opening_angle_deg) setBound(o);  // bounds combine: the largest holds
    else setBound(e);
    in.pending.active = false;
    return;
  }
  const double a = e.opening_angle_deg;
  const bool departs = o.angle_is_lower_bound ? o.opening_angle_deg > a + change : std::abs(o.opening_angle_deg - a) > change;
  if (!departs) {
    in.pending.active = false;
    if (!o.angle_is_lower_bound && o.confidence >= e.confidence) e = o;  // the best view so far
    return;
  }
  if (!o.angle_is_lower_bound && o.confidence >= options_.sure_confidence) return takeOver(o);
  const DoorResult& p = in.pending.door;
  const bool alike = in.pending.active && ((p.angle_is_lower_bound && o.angle_is_lower_bound) ||
                                           std::abs(p.opening_angle_deg - o.opening_angle_deg) <= change);
  if (alike) {
    // Confirmed: a measured leaf before a bound, of two bounds the larger.
    if (o.angle_is_lower_bound && !p.angle_is_lower_bound) return takeOver(p);
    if (o.angle_is_lower_bound && p.opening_angle_deg > o.opening_angle_deg) return takeOver(p);
    return takeOver(o);
  }
  in.pending.active = true;
  in.pending.door = o;
}

DoorFusion::Update DoorFusion::update(const std::vector<DoorResult>& doors, double stamp, const Eigen::Vector3d& up_in) {
  Update u;
  u.ids.assign(doors.size(), 0);
  u.tracked.assign(doors.size(), 0);
  if (!std::isfinite(stamp)) {
    u.outcome = Outcome::IgnoredBadStamp;
    for (TrackedDoor& t : tracks_) t.seen_now = false;
    return u;
  }
  if (std::isfinite(newest_) && stamp < newest_) {
    if (stamp >= newest_ - options_.backwards_tolerance_s) {
      u.outcome = Outcome::IgnoredOutOfOrder;
      for (TrackedDoor& t : tracks_) t.seen_now = false;
      return u;
    }
    tracks_.clear();
    internal_.clear();
    u.outcome = Outcome::Reset;
  }
  newest_ = stamp;
  const Eigen::Vector3d up = unitUp(up_in);
  for (TrackedDoor& t : tracks_) t.seen_now = false;

  // Nearest pairs first, one-to-one, on one wall.
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < doors.size(); ++i) {
    if (!usable(doors[i], up)) continue;
    const Eigen::Vector3d w = wallDirection(doors[i], up);
    for (std::size_t k = 0; k < tracks_.size(); ++k) {
      const double d = across(doors[i].opening_center - internal_[k].centre, up).norm();
      if (d <= options_.match_distance_m && sameWall(w, internal_[k].wall_dir)) pairs.emplace_back(d, i, k);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<char> done(doors.size(), 0), taken(tracks_.size(), 0);
  for (const auto& [d, i, k] : pairs) {
    if (done[i] || taken[k]) continue;
    done[i] = taken[k] = 1;
    TrackedDoor& t = tracks_[k];
    Internal& in = internal_[k];
    fuse(t, in, doors[i]);
    t.door.id = static_cast<int>(t.id);
    ++t.observations;
    t.last_seen = stamp;
    t.seen_now = true;
    in.centre += (doors[i].opening_center - in.centre) / std::min<double>(t.observations, kCentreMemory);
    in.wall_dir = wallDirection(t.door, up);
    u.ids[i] = t.id;
    u.tracked[i] = 1;
  }
  for (std::size_t i = 0; i < doors.size(); ++i) {
    if (done[i] || !usable(doors[i], up)) continue;
    TrackedDoor t;
    t.id = next_id_++;
    t.door = doors[i];
    if (t.door.angle_is_lower_bound) {  // the state and width by this object's thresholds
      Parameters states;
      states.closed_below_deg = options_.closed_below_deg;
      states.open_from_deg = options_.open_from_deg;
      t.door.state = stateOfBound(t.door.opening_angle_deg, states);
      t.door.clear_width =
          clearWidth(t.door.width, t.door.opening_angle_deg, options_.leaf_thickness, options_.closed_below_deg);
    }
    t.door.id = static_cast<int>(t.id);
    t.first_seen = t.last_seen = stamp;
    t.observations = 1;
    t.seen_now = true;
    tracks_.push_back(t);
    internal_.push_back({doors[i].opening_center, wallDirection(doors[i], up), {}});
    u.ids[i] = t.id;
    u.tracked[i] = 1;
  }
  joinNear(up, u);
  // Forgetting, by the stamps.
  for (std::size_t k = tracks_.size(); k-- > 0;)
    if (stamp - tracks_[k].last_seen > options_.forget_after_s) {
      tracks_.erase(tracks_.begin() + static_cast<std::ptrdiff_t>(k));
      internal_.erase(internal_.begin() + static_cast<std::ptrdiff_t>(k));
      ++u.forgotten;
    }
  return u;
}

// Two tracks of one door (near along one wall, not both in this cloud):
// joined into the older, whose estimate becomes the better of the two: a
// measured leaf before a bound; of two bounds the larger; of two measured
// leaves that agree (within state_change_deg) the one shown by more clouds
// (a door stands where most clouds put it: a track started by one stray
// report off by a few decimetres does not move it), of two that depart the
// one seen last (the door moved since).
void DoorFusion::joinNear(const Eigen::Vector3d& up, Update& u) {
  for (std::size_t a = 0; a < tracks_.size(); ++a)
    for (std::size_t b = a + 1; b < tracks_.size();) {
      TrackedDoor &ta = tracks_[a], &tb = tracks_[b];
      const bool near = across(internal_[a].centre - internal_[b].centre, up).norm() <= options_.match_distance_m &&
                        sameWall(internal_[a].wall_dir, internal_[b].wall_dir);
      if (!near || (ta.seen_now && tb.seen_now)) {
        ++b;
        continue;
      }
      const DoorResult &ea = ta.door, &eb = tb.door;
      const bool agree = std::abs(ea.opening_angle_deg - eb.opening_angle_deg) <= options_.state_change_deg;
      const bool b_better = ea.angle_is_lower_bound != eb.angle_is_lower_bound ? ea.angle_is_lower_bound
                            : ea.angle_is_lower_bound ? eb.opening_angle_deg > ea.opening_angle_deg
                            : agree && ta.observations != tb.observations ? tb.observations > ta.observations
                                                                         : tb.last_seen > ta.last_seen;
      if (b_better) {
        ta.door = eb;
        ta.door.id = static_cast<int>(ta.id);
        internal_[a].pending = internal_[b].pending;
      }
      const double wa = ta.observations, wb = tb.observations;
      internal_[a].centre = (wa * internal_[a].centre + wb * internal_[b].centre) / std::max(1.0, wa + wb);
      ta.observations += tb.observations;
      ta.first_seen = std::min(ta.first_seen, tb.first_seen);
      ta.last_seen = std::max(ta.last_seen, tb.last_seen);
      ta.seen_now = ta.seen_now || tb.seen_now;
      for (std::size_t i = 0; i < u.ids.size(); ++i)
        if (u.tracked[i] && u.ids[i] == tb.id) u.ids[i] = ta.id;
      tracks_.erase(tracks_.begin() + static_cast<std::ptrdiff_t>(b));
      internal_.erase(internal_.begin() + static_cast<std::ptrdiff_t>(b));
      ++u.joined;
    }
}

}  // namespace dsr
