#include "door_state_recognition/io/report.hpp"

namespace dsr {
namespace io {
namespace {

nlohmann::json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

template <std::size_t N>
nlohmann::json corners(const std::array<Eigen::Vector3d, N>& c) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& v : c) a.push_back(vec(v));
  return a;
}

nlohmann::json optional(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); }

}  // namespace

nlohmann::json reportJson(const PipelineResult& r, const std::string& input) {
  nlohmann::json j;
  j["input"] = input;
  j["points_in"] = r.points_in;
  j["points_used"] = r.points_used;
  j["up"] = vec(r.up);
  // Where the rays came from: the viewpoint, or null (a survey's or inferred stations, listed).
  j["viewpoint"] = r.viewpoint ? vec(*r.viewpoint) : nlohmann::json(nullptr);
  j["stations"] = nlohmann::json::array();
  for (const Eigen::Vector3d& s : r.stations) j["stations"].push_back(vec(s));
  j["floor"] = optional(r.floor);
  j["ceiling"] = optional(r.ceiling);
  j["walls"] = nlohmann::json::array();
  for (const WallResult& w : r.walls)
    j["walls"].push_back({{"id", w.id},
                          {"corners", corners(w.corners)},
                          {"height", w.height},
                          {"length", w.length},
                          {"line", {{"point", vec(w.line_point)}, {"direction", vec(w.line_direction)}}}});
  j["doors"] = nlohmann::json::array();
  for (const DoorResult& d : r.doors)
    j["doors"].push_back({{"id", d.id},
                          {"wall_id", d.wall_id ? nlohmann::json(*d.wall_id) : nlohmann::json(nullptr)},
                          {"state", toString(d.state)},
                          {"opening_angle_deg", d.opening_angle_deg},
                          {"angle_is_lower_bound", d.angle_is_lower_bound},
                          {"confidence", d.confidence},
                          {"hinge", vec(d.hinge)},
                          {"opening_center", vec(d.opening_center)},
                          {"width", d.width},
                          {"height", d.height},
                          {"clear_width", d.clear_width},
                          {"leaf_corners", corners(d.leaf_corners)},
                          {"swing", toString(d.swing)},
                          {"wall_normal", vec(d.wall_normal)}});
  j["others"] = nlohmann::json::array();
  for (const SegmentResult& s : r.others)
    j["others"].push_back({{"id", s.id}, {"corners", corners(s.corners)}, {"height", s.height}});
  nlohmann::json t = nlohmann::json::object();
  for (const auto& kv : r.timing_ms) t[kv.first] = kv.second;
  j["timing_ms"] = t;
  j["warnings"] = r.warnings;
  return j;
}

}  // namespace io
}  // namespace dsr
