// Clutter along the walls of a random room: what offices and bedrooms put
// beside and between their doors. Pieces stand against a wall (desks with a
// chair, bookcases, shelves, cupboards), from right next to a doorway's casing
// (0-30 cm from it) to the middle of a wall; a window-like gap gets a low
// cabinet under it. Nothing stands in a doorway, in front of one (the way
// through, 0.9 m deep), or where a leaf swings.
#include <cmath>
#include <string>

#include "room_frame.hpp"

namespace dsr {
namespace sim {
namespace detail {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSwingMargin = 0.03;  // beyond the leaf's width, from the hinge jamb
constexpr double kWayThrough = 0.9;    // depth kept clear in front of a doorway

// True when a footprint keeps clear of every doorway, the way through it,
// every leaf swinging into the room, the partition's small room, the other
// furniture and (for pieces taller than a window's sill against its wall)
// every window.
bool clearOfAll(const RoomSpec& r, const Rect& box, int wall, double height) {
  for (const DoorSpec& d : r.doors) {
    const double a = d.center - d.width / 2, b = d.center + d.width / 2, cw = r.casing_width;
    if (box.intersects(wallRect(r, d.wall, a - cw, b + cw, -0.5, kWayThrough), 0.0)) return false;
    if (d.swing_into_room) {
      const Eigen::Vector2d hinge = wallPoint(r, d.wall, d.hinge_left ? a : b, 0.0);
      if (box.distanceTo(hinge) < d.width + kSwingMargin) return false;
    }
  }
  if (r.partition && box.intersects(partitionRect(r), 0.0)) return false;
  for (const FurnitureSpec& g : r.furniture)
    if (box.intersects(furnitureRect(r, g), 0.03)) return false;
  for (const WindowSpec& w : r.windows)
    if (w.wall == wall && height > w.sill - 0.02 &&
        box.intersects(wallRect(r, w.wall, w.center - w.width / 2, w.center + w.width / 2, 0.0, 0.05), 0.0))
      return false;
  // Inside the room.
  const Rect room{-r.width / 2, r.width / 2, -r.depth / 2, r.depth / 2};
  return box.x0 >= room.x0 - 1e-9 && box.x1 <= room.x1 + 1e-9 && box.y0 >= room.y0 - 1e-9 && box.y1 <= room.y1 + 1e-9;
}

// A piece of a kind against `wall`, sized by the seed; centre left at 0.
FurnitureSpec drawPiece(Rng& rng, const std::string& kind, int wall, double room_height, bool corridor) {
  FurnitureSpec f;
  f.kind = kind;
  f.wall = wall;
  f.gap = rng.uniform(0.005, 0.05);
  f.detail_seed = static_cast<std::uint32_t>(rng.gen() & 0xffffffffu);
  const double top = room_height - 0.1;
  if (kind == "desk") {
    f.width = rng.uniform(1.1, 1.8);
    f.depth = rng.uniform(0.6, 0.8);
    f.height = rng.uniform(0.72, 0.76);
  } else if (kind == "bookcase") {
    f.width = rng.uniform(0.6, 1.0);
    f.depth = rng.uniform(0.28, 0.4);
    f.height = std::min(top, rng.uniform(1.8, 2.2));
  } else if (kind == "shelf") {
    f.width = rng.uniform(0.8, 1.2);
    f.depth = rng.uniform(0.3, 0.45);
    f.height = std::min(top, rng.uniform(1.0, 2.0));
  } else {  // cupboard
    f.width = rng.uniform(0.6, 1.2);
    f.depth = rng.uniform(0.4, 0.6);
    f.height = std::min(top, rng.uniform(1.8, 2.2));
  }
  if (corridor) f.depth = std::min(f.depth, 0.35);
  return f;
}

// A chair in front of a desk (pulled out, turned a little), if it fits.
void chairAt(RoomSpec& r, Rng& rng, const FurnitureSpec& desk) {
  const WallFrame f = wallFrame(r, desk.wall);
  FurnitureSpec c;
  c.kind = "chair";
  c.width = rng.uniform(0.42, 0.5);
  c.depth = rng.uniform(0.42, 0.5);
  c.height = rng.uniform(0.85, 1.0);
  const double reach = 0.5 * std::hypot(c.width, c.depth);
  const Eigen::Vector3d p = f.at(desk.center + rng.uniform(-0.25, 0.25) * desk.width, desk.gap + desk.depth + reach + rng.uniform(0.04, 0.3), 0);
  c.center = p.x();
  c.offset = p.y();
  c.yaw = std::atan2(f.n.y(), f.n.x()) + rng.uniform(-0.5, 0.5);  // its back towards the room
  if (clearOfAll(r, furnitureRect(r, c), -1, c.height)) r.furniture.push_back(c);
}

bool placeAgainstWall(RoomSpec& r, Rng& rng, FurnitureSpec f) {
  const double L = wallFrame(r, f.wall).length;
  if (std::abs(f.center) + f.width / 2 > L / 2) return false;
  if (!clearOfAll(r, furnitureRect(r, f), f.wall, f.height)) return false;
  r.furniture.push_back(f);
  if (f.kind == "desk") chairAt(r, rng, f);
  return true;
}

std::string drawKind(Rng& rng, bool corridor) {
  static const char* room_kinds[] = {"desk", "bookcase", "bookcase", "shelf", "cupboard"};
  static const char* corridor_kinds[] = {"bookcase", "shelf", "cupboard"};
  return corridor ? corridor_kinds[rng.integer(0, 2)] : room_kinds[rng.integer(0, 4)];
}

}  // namespace

void addClutter(RoomSpec& r, std::uint64_t seed, bool corridor) {
  Rng rng(seed ^ 0xC1A77E12D00Dull);
  const int walls = wallCount(r);

  // A window-like gap in a wall without doors near it, with a low cabinet
  // under it (rooms only).
  for (int attempt = 0; !corridor && attempt < 30; ++attempt) {
    WindowSpec w;
    w.wall = rng.integer(0, 3);
    w.width = rng.uniform(0.9, 1.6);
    w.sill = rng.uniform(0.85, 1.0);
    w.head = rng.uniform(2.0, std::min(2.2, r.height - 0.2));
    const double room = wallFrame(r, w.wall).length / 2 - w.width / 2 - 0.3;
    if (room <= 0) continue;
    w.center = rng.uniform(-room, room);
    const Rect gap = wallRect(r, w.wall, w.center - w.width / 2, w.center + w.width / 2, -r.wall_thickness, 0.05);
    bool ok = !r.partition || !gap.intersects(partitionRect(r), 0.1);
    for (const DoorSpec& d : r.doors)
      ok = ok && !gap.intersects(wallRect(r, d.wall, d.center - d.width / 2 - r.casing_width,
                                          d.center + d.width / 2 + r.casing_width, -r.wall_thickness, 0.05), 0.3);
    for (const FurnitureSpec& g : r.furniture)  // nothing tall already in front of it
      ok = ok && (g.height < w.sill || !gap.intersects(furnitureRect(r, g), 0.0));
    if (!ok) continue;
    r.windows.push_back(w);
    FurnitureSpec c;
    c.kind = "low_cabinet";
    c.wall = w.wall;
    c.gap = rng.uniform(0.005, 0.05);
    c.width = std::max(0.6, w.width + rng.uniform(-0.3, 0.3));
    c.depth = rng.uniform(0.4, 0.5);
    c.height = std::min(w.sill - 0.05, rng.uniform(0.72, 0.86));
    c.center = w.center + rng.uniform(-0.15, 0.15);
    placeAgainstWall(r, rng, c);
    break;
  }

  // Beside every doorway (in the partition's walls too): on each side with
  // probability 0.75 (a corridor, kept passable: 0.25), a piece 0-30 cm from
  // the casing; where a leaf swings into the room over that side, beyond its
  // swing instead (between doors).
  const std::vector<DoorSpec> doors = r.doors;
  for (const DoorSpec& d : doors) {
    for (const int side : {-1, 1}) {
      if (!rng.coin(corridor ? 0.25 : 0.75)) continue;
      FurnitureSpec f = drawPiece(rng, drawKind(rng, corridor), d.wall, r.height, corridor);
      const double edge = d.center + side * (d.width / 2 + r.casing_width);  // outer edge of the casing
      f.center = edge + side * (rng.uniform(0.005, 0.3) + f.width / 2);
      const bool hinge_side = (side < 0) == d.hinge_left;
      if (d.swing_into_room && hinge_side)
        f.center = edge - side * r.casing_width + side * (d.width + kSwingMargin + 0.01 + rng.uniform(0.0, 0.25) + f.width / 2);
      placeAgainstWall(r, rng, f);
    }
  }

  // Between doors and along the other walls: two to four more pieces (a
  // corridor: up to two).
  const int more = corridor ? rng.integer(0, 2) : rng.integer(2, 4);
  int placed = 0;
  for (int attempt = 0; attempt < 80 && placed < more; ++attempt) {
    FurnitureSpec f = drawPiece(rng, drawKind(rng, corridor), rng.integer(0, walls - 1), r.height, corridor);
    const double room = wallFrame(r, f.wall).length / 2 - f.width / 2;
    if (room <= 0) continue;
    f.center = rng.uniform(-room, room);
    placed += placeAgainstWall(r, rng, f) ? 1 : 0;
  }

  // A chair left standing somewhere in the room.
  for (int attempt = 0; !corridor && attempt < 30; ++attempt) {
    FurnitureSpec c;
    c.kind = "chair";
    c.width = rng.uniform(0.42, 0.5);
    c.depth = rng.uniform(0.42, 0.5);
    c.height = rng.uniform(0.85, 1.0);
    c.center = rng.uniform(-r.width / 2 + 0.5, r.width / 2 - 0.5);
    c.offset = rng.uniform(-r.depth / 2 + 0.5, r.depth / 2 - 0.5);
    c.yaw = rng.uniform(-kPi, kPi);
    if (clearOfAll(r, furnitureRect(r, c), -1, c.height)) {
      r.furniture.push_back(c);
      break;
    }
  }
}

}  // namespace detail
}  // namespace sim
}  // namespace dsr
