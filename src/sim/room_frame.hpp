// Internal to the simulator: the frames of a room's walls (its four walls and
// a partition's two), the seeded random numbers of random rooms and the
// room-frame rectangles their placement tests use.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include "door_state_recognition/sim/scene.hpp"

namespace dsr {
namespace sim {
namespace detail {

// Frame of a wall in the room frame: u along, n inward (into the scanned
// room), z up; origin on the interior face, mid-length, on the floor. The
// wall's solid runs from d = -thickness to 0 and, along it, from
// -length/2 - ext_lo to length/2 + ext_hi (into the walls it meets).
struct WallFrame {
  Eigen::Vector3d origin, u, n;
  double length = 0, thickness = 0, ext_lo = 0, ext_hi = 0;
  Eigen::Vector3d at(double s, double d, double z) const {
    return origin + s * u + d * n + z * Eigen::Vector3d::UnitZ();
  }
};

// Walls 0..3 of the room, 4..5 of its partition. Throws std::invalid_argument
// for another index or 4..5 without a partition.
WallFrame wallFrame(const RoomSpec& r, int i);
int wallCount(const RoomSpec& r);  // 4, or 6 with a partition

// Signs of the partition's corner: (+1|-1 along x, +1|-1 along y).
Eigen::Vector2d cornerSigns(int corner);

// Axis-aligned rectangle in the room frame (walls are axis-aligned there).
struct Rect {
  double x0, x1, y0, y1;
  bool intersects(const Rect& o, double margin) const {
    return x0 < o.x1 + margin && o.x0 < x1 + margin && y0 < o.y1 + margin && o.y0 < y1 + margin;
  }
  double distanceTo(const Eigen::Vector2d& p) const {
    const double dx = std::max({x0 - p.x(), 0.0, p.x() - x1}), dy = std::max({y0 - p.y(), 0.0, p.y() - y1});
    return std::hypot(dx, dy);
  }
  bool contains(const Eigen::Vector2d& p, double margin) const {
    return p.x() > x0 - margin && p.x() < x1 + margin && p.y() > y0 - margin && p.y() < y1 + margin;
  }
};

Eigen::Vector2d wallPoint(const RoomSpec& r, int w, double s, double d);
Rect wallRect(const RoomSpec& r, int w, double s0, double s1, double d0, double d1);
// The partition's small room, room frame, from its interior faces to the
// room's wall faces. Requires r.partition.
Rect partitionRect(const RoomSpec& r);
// Footprint of a piece of furniture in the room frame (a chair: the square
// around its turning circle).
Rect furnitureRect(const RoomSpec& r, const FurnitureSpec& f);

struct Rng {
  std::mt19937_64 gen;
  explicit Rng(std::uint64_t seed) : gen(seed) {}
  // Own mapping to [a, b): the standard distributions are not specified
  // bit-for-bit, and scenes must be the same on every machine.
  double uniform(double a, double b) { return a + (b - a) * ((gen() >> 11) * (1.0 / 9007199254740992.0)); }
  int integer(int a, int b) { return a + static_cast<int>((gen() >> 11) % static_cast<std::uint64_t>(b - a + 1)); }
  bool coin(double p = 0.5) { return uniform(0, 1) < p; }
};

// Clutter along the walls of a random room (RandomSceneOptions::clutter):
// furniture beside doors and between them, a window-like gap with a low
// cabinet under it, chairs. Draws from its own stream of `seed`.
void addClutter(RoomSpec& r, std::uint64_t seed, bool corridor);

}  // namespace detail
}  // namespace sim
}  // namespace dsr
