// Scene model of the simulator: a room built of oriented boxes (walls with
// door openings, casing trim, door leaves, furniture, adjacent rooms), with the
// ground truth of every door and decoy. ROS-free.
//
// World frame: gravity-aligned, z up, floor at z = 0, metres.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace dsr {
namespace sim {

// What a surface is; written as the `label` field of simulated points.
enum class Surface : std::uint32_t {
  None = 0,
  Floor = 1,
  Ceiling = 2,
  Wall = 3,
  Casing = 4,
  Leaf = 5,
  Furniture = 6,
  Adjacent = 7,  // anything of a room seen through a doorway
  Handle = 8,    // a door's lever handle, on both faces of its leaf
};

// An oriented box: points p_world = pose * p_local, |p_local(i)| <= half(i).
struct Box {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  Eigen::Vector3d half = Eigen::Vector3d::Zero();
  Surface surface = Surface::None;
  int owner = -1;  // door index for Leaf/Casing, furniture index, wall index
  bool contains(const Eigen::Vector3d& p_world, double margin = 0.0) const;
};

struct DoorSpec {
  int wall = 0;              // 0..3, see RoomSpec; 4..5 a partition's walls
  double center = 0.0;       // along the wall from its middle, metres
  double width = 0.9;        // clear opening, metres
  double height = 2.05;      // clear opening, metres
  double angle_deg = 0.0;    // 0 closed .. 180 flat against the wall
  bool hinge_left = true;    // hinge at the wall's -u end of the opening (u: wall axis)
  bool swing_into_room = true;  // leaf swings into the scanned room (towards the viewer)
  double recess = 0.0;       // closed leaf set back from the face on its swing side
};

// Kinds: solid boxes against a wall (cupboard, wardrobe, cabinet,
// low_cabinet); open-front shelving against a wall (shelf, bookcase: side
// panels, back, boards, rows of books); a desk against a wall (top, legs, a
// drawer pedestal); free-standing: table (legs) and chair (seat, back, legs,
// turned by `yaw`).
struct FurnitureSpec {
  std::string kind = "cupboard";
  int wall = 0;                   // wall it stands against (0..5; ignored by table and chair)
  double center = 0.0;            // along the wall (table, chair: x in room frame)
  double offset = 0.0;            // table, chair: y in room frame
  double gap = 0.01;              // against a wall: its back this far from the wall's face
  double yaw = 0.0;               // chair: its back's outward normal from the room's +x, radians
  double width = 1.0, depth = 0.5, height = 2.0;
  std::uint32_t detail_seed = 0;  // shelving: the rows of books
};

// A window-like gap in a wall: an opening from `sill` to `head` above the
// floor (nothing in it), no casing.
struct WindowSpec {
  int wall = 0;  // 0..3
  double center = 0.0, width = 1.2;
  double sill = 0.9, head = 2.1;
};

// A partition: a small room (a bathroom) in a corner of the room, closed by
// two interior walls. Corner c lies between walls (c + 3) % 4 and c: 0 at
// (-x, -y), 1 at (+x, -y), 2 at (+x, +y), 3 at (-x, +y) of the room frame.
// Wall 4 runs parallel to the room's y axis, size_x from the corner's x
// wall; wall 5 parallel to the x axis, size_y from the corner's y wall.
// Their interior face (inward normal) faces the scanned room; their
// thickness lies in the small room. A door in wall 4 or 5 is a DoorSpec with
// that wall index; swing_into_room then means into the scanned room.
struct PartitionSpec {
  int corner = 2;
  double size_x = 2.0, size_y = 2.0;  // outer size of the small room, interior face to the room's wall face
  double thickness = 0.10;
};

// Room: interior [-width/2, width/2] x [-depth/2, depth/2] in the room frame,
// which is yawed by `yaw` and shifted by `center` in the world.
// Walls: 0 at y = -depth/2, 1 at x = +width/2, 2 at y = +depth/2,
// 3 at x = -width/2. Wall axis u = n x z with n the inward normal.
struct RoomSpec {
  std::string name = "room";
  double width = 5.0, depth = 4.0, height = 2.7;
  double yaw = 0.0;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double wall_thickness = 0.15;
  double casing_width = 0.07, casing_depth = 0.018;
  double leaf_thickness = 0.04;
  double adjacent_depth = 3.0;  // depth of the room behind a wall with a door
  // A lever handle on both faces of every leaf, at the latch edge: 12 cm
  // long, standing 6 cm off the face, 2.4 cm high, 1 m above the floor.
  bool handles = true;
  std::vector<DoorSpec> doors;
  std::vector<FurnitureSpec> furniture;
  std::vector<WindowSpec> windows;
  std::optional<PartitionSpec> partition;
  // Where the laser scanner stands (room frame, z above the floor); unset:
  // drawn by the seed among the free positions.
  std::optional<Eigen::Vector3d> scanner;
};

struct DoorTruth {
  Eigen::Vector3d opening_center;  // middle of the doorway on the floor (mid wall thickness)
  Eigen::Vector3d hinge;           // foot of the hinge axis on the floor
  Eigen::Vector3d wall_normal;     // horizontal unit, towards the side the leaf swings to
  Eigen::Vector3d wall_axis;       // horizontal unit along the wall
  double width = 0, height = 0, angle_deg = 0;
  bool swing_into_room = true, hinge_left = true;
  double recess = 0;
  int wall = 0;                    // 0..3, or 4..5 for a partition's door
  std::array<Eigen::Vector3d, 4> leaf_corners;  // mid-thickness: hinge-bottom, latch-bottom, latch-top, hinge-top
  std::string state(double closed_below_deg = 5.0, double open_from_deg = 90.0) const;
};

struct DecoyTruth {
  std::string kind;  // a furniture kind, or "window"
  Eigen::Vector3d center;  // centre of the box
  double height = 0;
  double width = 0, depth = 0;
};

struct WallTruth {
  Eigen::Vector3d origin;  // interior face, middle of the wall, on the floor
  Eigen::Vector3d axis;    // u, horizontal unit along the wall
  Eigen::Vector3d normal;  // inward (into the scanned room)
  double length = 0;       // interior length
};

struct Scene {
  RoomSpec spec;
  double floor_z = 0.0, ceiling_z = 2.7;
  std::vector<Box> boxes;
  std::vector<DoorTruth> doors;
  std::vector<DecoyTruth> decoys;
  std::vector<WallTruth> walls;  // 0..3 the room's, 4..5 a partition's
  Eigen::Isometry3d room_to_world = Eigen::Isometry3d::Identity();
  // True when p (world) is inside the scanned room's free space: inside the
  // interior and outside a partition's small room, not within `margin` of any
  // box, and clear of inward door swings.
  bool isFree(const Eigen::Vector3d& p, double margin) const;
};

// Builds the boxes and the truth of a room. Throws std::invalid_argument for
// a spec that cannot be built (door outside its wall, overlapping doors,
// opening taller than the room, angle outside [0, 180], ...).
Scene buildScene(const RoomSpec& spec);

// Options of the random scene generator.
struct RandomSceneOptions {
  int min_doors = 1, max_doors = 3;
  double min_angle_deg = 0.0, max_angle_deg = 130.0;
  int min_decoys = 1, max_decoys = 2;  // tall cupboards / wardrobes
  bool table = true;
  double closed_fraction = 0.3;        // share of doors drawn exactly closed
  // Clutter along the walls: desks (with chairs), bookcases, shelves and
  // cupboards against the walls beside doors (0-30 cm from the casing) and
  // between them, a window-like gap with a low cabinet under it, a chair or
  // two; never in a doorway or a leaf's swing.
  bool clutter = false;
  // A bathroom-like small room in a corner: two interior walls, a door in one.
  bool partition = false;
  // A corridor instead of a room: 6-12 m long, 1.5-2.2 m wide, its doors
  // (at least 2, at most max_doors + 2) along the two long walls (0 and 2),
  // swinging into the rooms behind more often than into the corridor.
  bool corridor = false;
  // Door joinery as other rooms have it: per room, no casing at all (a third
  // of rooms: leaves in plain openings, as many simulators and modern
  // interiors build them) or casing 4-10 cm wide standing 0.8-3 cm off the
  // wall; leaves 3-5.5 cm thick. Drawn from a stream of its own.
  bool varied_doors = false;
};

// A random, valid room: size, yaw, doors (hinge side, swing side, angle,
// flush or recessed), tall cupboards/wardrobes and a table; with the options,
// clutter, a partition or a corridor. Deterministic for a seed; the room
// without those options is the same as before they existed.
RoomSpec randomRoom(std::uint64_t seed, const RandomSceneOptions& options = {});

// Scenes shaped like the seed paper's three: "paper_livingroom" (one closed
// door and one other object on a wall), "paper_house" (a door open ~110 deg),
// "paper_multidoor" (two semi-open doors at ~7 and ~25 deg). Throws
// std::invalid_argument for another name.
RoomSpec paperRoom(const std::string& name);
std::vector<std::string> paperRoomNames();

}  // namespace sim
}  // namespace dsr
