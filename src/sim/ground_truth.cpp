#include "door_state_recognition/sim/ground_truth.hpp"

#include "door_state_recognition/sim/drive.hpp"
#include "door_state_recognition/sim/lidar.hpp"

namespace dsr {
namespace sim {
namespace {

nlohmann::json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

nlohmann::json groundTruthJson(const Scene& scene, const SimulatedCloud& cloud) {
  const Eigen::Isometry3d W2S = cloud.sensor_to_world.inverse();
  const Eigen::Matrix3d R = W2S.linear();
  const Eigen::Vector3d up = R * Eigen::Vector3d::UnitZ();
  const double offset = cloud.sensor_to_world.translation().z();  // height of the cloud origin

  nlohmann::json j;
  j["scene"] = scene.spec.name;
  j["sensor"] = cloud.sensor;
  j["frame_id"] = cloud.frame_id;
  j["up"] = vec(up);
  j["floor"] = scene.floor_z - offset;
  j["ceiling"] = scene.ceiling_z - offset;
  bool ceiling_seen = false;
  for (const auto& p : cloud.cloud.points) ceiling_seen |= p.label == static_cast<std::uint32_t>(Surface::Ceiling);
  j["ceiling_in_view"] = ceiling_seen;

  j["doors"] = nlohmann::json::array();
  for (const DoorTruth& d : scene.doors) {
    nlohmann::json door;
    door["opening_center"] = vec(W2S * d.opening_center);
    door["hinge"] = vec(W2S * d.hinge);
    door["width"] = d.width;
    door["height"] = d.height;
    door["opening_angle_deg"] = d.angle_deg;
    door["state"] = d.state();
    door["swing"] = d.swing_into_room ? "toward_viewer" : "away_from_viewer";
    door["hinge_side"] = d.hinge_left ? "left" : "right";
    door["recess"] = d.recess;
    // The room's joinery (door_scene_sim --varied-doors varies it).
    door["casing_width"] = scene.spec.casing_width;
    door["casing_depth"] = scene.spec.casing_depth;
    door["leaf_thickness"] = scene.spec.leaf_thickness;
    door["wall"] = d.wall;
    door["wall_normal"] = vec(R * d.wall_normal);
    // A camera sees a door when part of its doorway is in the image with a
    // clear sight line, a rotating LiDAR as lidarSeesDoor (both
    // sensorSeesDoor); a terrestrial scanner sees every door.
    const int k = static_cast<int>(&d - scene.doors.data());
    const bool camera = cloud.sensor == "rgbd" && cloud.lidar_beams == 0;
    door["in_view"] = camera || cloud.lidar_beams > 0 ? sensorSeesDoor(scene, cloud, k) : true;
    if (camera || cloud.sensor == "tls") door["leaf_in_view"] = leafInViewShare(scene, cloud, k);
    nlohmann::json corners = nlohmann::json::array();
    for (const auto& c : d.leaf_corners) corners.push_back(vec(W2S * c));
    door["leaf_corners"] = corners;
    j["doors"].push_back(door);
  }
  j["decoys"] = nlohmann::json::array();
  for (const DecoyTruth& d : scene.decoys)
    j["decoys"].push_back({{"kind", d.kind}, {"center", vec(W2S * d.center)}, {"height", d.height},
                           {"width", d.width}, {"depth", d.depth}});
  j["walls"] = nlohmann::json::array();
  for (std::size_t i = 0; i < scene.walls.size(); ++i) {
    const WallTruth& w = scene.walls[i];
    j["walls"].push_back({{"id", i}, {"origin", vec(W2S * w.origin)}, {"axis", vec(R * w.axis)},
                          {"normal", vec(R * w.normal)}, {"length", w.length}});
  }
  j["sensor_origins"] = nlohmann::json::array();
  for (const auto& v : cloud.viewpoints_world) j["sensor_origins"].push_back(vec(W2S * v));
  const Eigen::Quaterniond q(cloud.sensor_to_world.linear());
  j["sensor_to_world"] = {{"translation", vec(cloud.sensor_to_world.translation())},
                          {"rotation_xyzw", {q.x(), q.y(), q.z(), q.w()}}};
  return j;
}

}  // namespace sim
}  // namespace dsr
