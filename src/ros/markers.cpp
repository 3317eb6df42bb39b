#include "door_state_recognition/ros/markers.hpp"

#include <cmath>

#include <tf2_eigen/tf2_eigen.h>
#include <cstdio>

namespace dsr {
namespace ros_io {
namespace {

std_msgs::ColorRGBA rgba(float r, float g, float b, float a = 1.0f) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

// Eigen expressions evaluated once, then tf2's conversion.
geometry_msgs::Point pt(const Eigen::Vector3d& v) { return tf2::toMsg(v); }

visualization_msgs::Marker base(const std_msgs::Header& h, const std::string& ns, int id, int type) {
  visualization_msgs::Marker m;
  m.header = h;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.scale.x = m.scale.y = m.scale.z = 0.05;
  m.color = rgba(0.8f, 0.8f, 0.8f);
  return m;
}

}  // namespace

std_msgs::ColorRGBA stateColour(DoorStateKind s) {
  switch (s) {
    case DoorStateKind::Closed: return rgba(0.9f, 0.15f, 0.15f);
    case DoorStateKind::SemiOpen: return rgba(1.0f, 0.6f, 0.0f);
    case DoorStateKind::Open: return rgba(0.2f, 0.8f, 0.2f);
    case DoorStateKind::NotClosed: return rgba(0.95f, 0.9f, 0.1f);
  }
  return rgba(1, 1, 1);
}

visualization_msgs::MarkerArray makeMarkers(const PipelineResult& r, const std::vector<std::uint32_t>& ids,
                                           const std_msgs::Header& h) {
  visualization_msgs::MarkerArray out;
  visualization_msgs::Marker clear;
  clear.header = h;
  clear.action = visualization_msgs::Marker::DELETEALL;
  out.markers.push_back(clear);

  // Corner points of every wall box.
  auto walls = base(h, "wall_corners", 0, visualization_msgs::Marker::SPHERE_LIST);
  walls.scale.x = walls.scale.y = walls.scale.z = 0.08;
  walls.color = rgba(0.2f, 0.4f, 1.0f);
  for (const WallResult& w : r.walls)
    for (const auto& c : w.corners) walls.points.push_back(pt(c));
  if (!walls.points.empty()) out.markers.push_back(walls);

  // Fitted wall lines on the floor.
  auto lines = base(h, "wall_lines", 0, visualization_msgs::Marker::LINE_LIST);
  lines.scale.x = 0.03;
  lines.color = rgba(0.2f, 0.4f, 1.0f);
  for (const WallResult& w : r.walls) {
    lines.points.push_back(pt(w.line_point));
    lines.points.push_back(pt(w.line_point + w.length * w.line_direction));
  }
  if (!lines.points.empty()) out.markers.push_back(lines);

  for (std::size_t i = 0; i < r.doors.size(); ++i) {
    const DoorResult& d = r.doors[i];
    const int id = static_cast<int>(i < ids.size() ? ids[i] : d.id);
    const std_msgs::ColorRGBA colour = stateColour(d.state);
    auto corners = base(h, "door_corners", id, visualization_msgs::Marker::SPHERE_LIST);
    corners.scale.x = corners.scale.y = corners.scale.z = 0.08;
    corners.color = colour;
    // The leaf's box: its four mid-plane corners, half a leaf thickness to either side.
    Eigen::Vector3d across = (d.leaf_corners[1] - d.leaf_corners[0]).cross(d.leaf_corners[3] - d.leaf_corners[0]);
    across = across.norm() > 1e-9 ? Eigen::Vector3d(across.normalized() * 0.02) : Eigen::Vector3d::Zero();
    for (const auto& c : d.leaf_corners) {
      corners.points.push_back(pt(c + across));
      corners.points.push_back(pt(c - across));
    }
    out.markers.push_back(corners);

    auto leaf = base(h, "leaf_lines", id, visualization_msgs::Marker::LINE_LIST);
    leaf.scale.x = 0.04;
    leaf.color = colour;
    leaf.points.push_back(pt(d.leaf_corners[0]));
    leaf.points.push_back(pt(d.leaf_corners[1]));
    out.markers.push_back(leaf);

    auto label = base(h, "labels", id, visualization_msgs::Marker::TEXT_VIEW_FACING);
    label.scale.z = 0.2;
    label.color = colour;
    label.pose.position = pt(0.5 * (d.leaf_corners[2] + d.leaf_corners[3]));
    char text[96];
    std::snprintf(text, sizeof text, "door %d: %s %.0f deg", id, toString(d.state), d.opening_angle_deg);
    label.text = text;
    out.markers.push_back(label);
  }

  // The reconstruction: walls grey, leaves in their state's colour.
  if (!r.reconstruction.empty()) {
    auto rec = base(h, "reconstruction", 0, visualization_msgs::Marker::POINTS);
    rec.scale.x = rec.scale.y = 0.02;
    rec.color = rgba(0.7f, 0.7f, 0.7f, 0.6f);
    const std::size_t stride = std::max<std::size_t>(1, r.reconstruction.size() / 200000);
    for (std::size_t i = 0; i < r.reconstruction.size(); i += stride) {
      const auto& q = r.reconstruction[i];
      rec.points.push_back(pt(Eigen::Vector3d(q.x, q.y, q.z)));
      rec.colors.push_back(q.label == 2 ? rgba(1.0f, 0.6f, 0.0f) : rgba(0.7f, 0.7f, 0.7f, 0.6f));
    }
    out.markers.push_back(rec);
  }
  return out;
}

void addTrackedMarkers(const std::vector<TrackedDoor>& tracks, const std_msgs::Header& h,
                       visualization_msgs::MarkerArray& out) {
  for (const TrackedDoor& t : tracks) {
    const DoorResult& d = t.door;
    std_msgs::ColorRGBA colour = stateColour(d.state);
    if (!t.seen_now) {
      colour.r = 0.5f * (colour.r + 0.6f);
      colour.g = 0.5f * (colour.g + 0.6f);
      colour.b = 0.5f * (colour.b + 0.6f);
      colour.a = 0.35f;
    }
    const int id = static_cast<int>(t.id);
    auto leaf = base(h, "tracked_leaf_lines", id, visualization_msgs::Marker::LINE_LIST);
    leaf.scale.x = 0.06;
    leaf.color = colour;
    leaf.points.push_back(pt(d.leaf_corners[0]));
    leaf.points.push_back(pt(d.leaf_corners[1]));
    leaf.points.push_back(pt(d.leaf_corners[0]));
    leaf.points.push_back(pt(d.leaf_corners[3]));
    out.markers.push_back(leaf);

    auto label = base(h, "tracked_labels", id, visualization_msgs::Marker::TEXT_VIEW_FACING);
    label.scale.z = 0.2;
    label.color = colour;
    label.pose.position = pt(0.5 * (d.leaf_corners[2] + d.leaf_corners[3]) + Eigen::Vector3d(0, 0, 0.25));
    char text[128];
    std::snprintf(text, sizeof text, "tracked %u: %s %s%.0f deg, %u obs%s", t.id, toString(d.state),
                  d.angle_is_lower_bound ? ">= " : "", d.opening_angle_deg, t.observations,
                  t.seen_now ? "" : " (not in view)");
    label.text = text;
    out.markers.push_back(label);
  }
}

}  // namespace ros_io
}  // namespace dsr
