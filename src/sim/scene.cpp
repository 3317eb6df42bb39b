#include "door_state_recognition/sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

namespace dsr {
namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSideGap = 0.004;    // leaf to jamb
constexpr double kBottomGap = 0.010;  // leaf to floor
constexpr double kTopGap = 0.003;     // leaf to head jamb

// Frame of wall i in the room frame: columns u (along), n (inward), z.
struct WallFrame {
  Eigen::Vector3d origin, u, n;
  double length;
  Eigen::Vector3d at(double s, double d, double z) const {
    return origin + s * u + d * n + z * Eigen::Vector3d::UnitZ();
  }
};

WallFrame wallFrame(const RoomSpec& r, int i) {
  static const double nx[4] = {0, -1, 0, 1}, ny[4] = {1, 0, -1, 0};
  WallFrame f;
  f.n = Eigen::Vector3d(nx[i], ny[i], 0);
  f.u = f.n.cross(Eigen::Vector3d::UnitZ());
  f.origin = -f.n * ((i % 2 == 0) ? r.depth / 2 : r.width / 2);
  f.length = (i % 2 == 0) ? r.width : r.depth;
  return f;
}

// Box spanning [s0,s1] x [d0,d1] x [z0,z1] of a wall frame, taken to the world.
Box wallBox(const Eigen::Isometry3d& room_to_world, const WallFrame& f, double s0, double s1,
            double d0, double d1, double z0, double z1, Surface surface, int owner) {
  Box b;
  Eigen::Matrix3d R;
  R.col(0) = f.u;
  R.col(1) = f.n;
  R.col(2) = Eigen::Vector3d::UnitZ();
  Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
  local.linear() = R;
  local.translation() = f.at((s0 + s1) / 2, (d0 + d1) / 2, (z0 + z1) / 2);
  b.pose = room_to_world * local;
  b.half = Eigen::Vector3d(std::abs(s1 - s0) / 2, std::abs(d1 - d0) / 2, std::abs(z1 - z0) / 2);
  b.surface = surface;
  b.owner = owner;
  return b;
}

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("scene: " + what);
}

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

bool Box::contains(const Eigen::Vector3d& p_world, double margin) const {
  const Eigen::Vector3d q = pose.inverse() * p_world;
  return (q.cwiseAbs() - half).maxCoeff() <= margin;
}

std::string DoorTruth::state(double closed_below_deg, double open_from_deg) const {
  if (angle_deg < closed_below_deg) return "closed";
  if (angle_deg < open_from_deg) return "semi_open";
  return "open";
}

bool Scene::isFree(const Eigen::Vector3d& p, double margin) const {
  const Eigen::Vector3d q = room_to_world.inverse() * p;
  if (std::abs(q.x()) > spec.width / 2 - margin || std::abs(q.y()) > spec.depth / 2 - margin ||
      q.z() < floor_z + margin || q.z() > ceiling_z - margin)
    return false;
  for (const Box& b : boxes)
    if (b.contains(p, margin)) return false;
  for (const DoorTruth& d : doors) {
    if (!d.swing_into_room) continue;
    const Eigen::Vector3d h = p - d.hinge;
    const Eigen::Vector2d flat(h.x(), h.y());
    if (flat.norm() < d.width + margin) return false;
  }
  return true;
}

Scene buildScene(const RoomSpec& r) {
  require(r.width >= 1.0 && r.width <= 100 && r.depth >= 1.0 && r.depth <= 100,
          "room width and depth must lie in [1, 100] m");
  require(r.height >= 1.5 && r.height <= 20, "room height must lie in [1.5, 20] m");
  require(r.wall_thickness >= 0.05 && r.wall_thickness <= 1.0, "wall thickness must lie in [0.05, 1] m");
  require(r.leaf_thickness > 0.005 && r.leaf_thickness < r.wall_thickness,
          "leaf thickness must be positive and below the wall thickness");
  require(std::isfinite(r.yaw) && r.center.allFinite(), "yaw and centre must be finite");

  Scene scene;
  scene.spec = r;
  scene.floor_z = 0.0;
  scene.ceiling_z = r.height;
  scene.room_to_world = Eigen::Translation3d(r.center.x(), r.center.y(), 0.0) *
                        Eigen::AngleAxisd(r.yaw, Eigen::Vector3d::UnitZ());
  const Eigen::Isometry3d& T = scene.room_to_world;
  const double t = r.wall_thickness, H = r.height, cw = r.casing_width, cp = r.casing_depth;
  const double lt = r.leaf_thickness;

  // Doors per wall, validated and sorted along the wall.
  std::vector<std::vector<int>> doors_on(4);
  for (std::size_t i = 0; i < r.doors.size(); ++i) {
    const DoorSpec& d = r.doors[i];
    const std::string id = "door " + std::to_string(i) + ": ";
    require(d.wall >= 0 && d.wall < 4, id + "wall must be 0..3");
    const double L = wallFrame(r, d.wall).length;
    require(d.width >= 0.3 && d.width <= 3.0, id + "width must lie in [0.3, 3] m");
    require(d.height >= 1.0 && d.height + cw < H, id + "height must be >= 1 m and leave room for the casing below the ceiling");
    require(std::abs(d.center) + d.width / 2 + cw <= L / 2, id + "opening and casing must fit in the wall (centre " + num(d.center) + ")");
    require(d.angle_deg >= 0 && d.angle_deg <= 180, id + "angle must lie in [0, 180] deg");
    require(d.recess >= 0 && d.recess + lt <= t + 1e-9, id + "recess must lie in [0, wall thickness - leaf thickness]");
    doors_on[d.wall].push_back(static_cast<int>(i));
  }
  for (auto& list : doors_on) {
    std::sort(list.begin(), list.end(), [&](int a, int b) { return r.doors[a].center < r.doors[b].center; });
    for (std::size_t k = 1; k < list.size(); ++k) {
      const DoorSpec &a = r.doors[list[k - 1]], &b = r.doors[list[k]];
      require(b.center - b.width / 2 - cw >= a.center + a.width / 2 + cw,
              "doors " + std::to_string(list[k - 1]) + " and " + std::to_string(list[k]) + " overlap");
    }
  }

  // Floor and ceiling slabs, large enough to cover the adjacent rooms.
  const double ext_x = r.width / 2 + t + r.adjacent_depth + 0.5;
  const double ext_y = r.depth / 2 + t + r.adjacent_depth + 0.5;
  for (int k = 0; k < 2; ++k) {
    Box b;
    b.pose = T * Eigen::Translation3d(0, 0, k == 0 ? -0.05 : H + 0.05);
    b.half = Eigen::Vector3d(ext_x, ext_y, 0.05);
    b.surface = k == 0 ? Surface::Floor : Surface::Ceiling;
    scene.boxes.push_back(b);
  }

  scene.doors.resize(r.doors.size());
  for (int w = 0; w < 4; ++w) {
    const WallFrame f = wallFrame(r, w);
    const double L = f.length;
    WallTruth wt;
    wt.origin = T * f.origin;
    wt.axis = T.linear() * f.u;
    wt.normal = T.linear() * f.n;
    wt.length = L;
    scene.walls.push_back(wt);

    // Solid wall between openings, lintels above them.
    double s = -L / 2 - t;
    for (int di : doors_on[w]) {
      const DoorSpec& d = r.doors[di];
      const double a = d.center - d.width / 2, b = d.center + d.width / 2;
      if (a > s) scene.boxes.push_back(wallBox(T, f, s, a, -t, 0, 0, H, Surface::Wall, w));
      scene.boxes.push_back(wallBox(T, f, a, b, -t, 0, d.height, H, Surface::Wall, w));
      s = b;
    }
    scene.boxes.push_back(wallBox(T, f, s, L / 2 + t, -t, 0, 0, H, Surface::Wall, w));

    if (!doors_on[w].empty()) {  // the room behind, seen through the doorways
      const double A = r.adjacent_depth, e = L / 2 + t;
      scene.boxes.push_back(wallBox(T, f, -e - 0.1, e + 0.1, -t - A - 0.1, -t - A, 0, H, Surface::Adjacent, w));
      scene.boxes.push_back(wallBox(T, f, -e - 0.1, -e, -t - A, -t, 0, H, Surface::Adjacent, w));
      scene.boxes.push_back(wallBox(T, f, e, e + 0.1, -t - A, -t, 0, H, Surface::Adjacent, w));
      scene.boxes.push_back(wallBox(T, f, -0.9, 0.6, -t - A, -t - A + 0.85, 0, 0.9, Surface::Adjacent, w));
    }

    for (int di : doors_on[w]) {
      const DoorSpec& d = r.doors[di];
      const double a = d.center - d.width / 2, b = d.center + d.width / 2;
      // Casing trim on both faces: two legs and a head.
      for (int side = 0; side < 2; ++side) {
        const double d0 = side == 0 ? 0.0 : -t - cp, d1 = side == 0 ? cp : -t;
        scene.boxes.push_back(wallBox(T, f, a - cw, a, d0, d1, 0, d.height + cw, Surface::Casing, di));
        scene.boxes.push_back(wallBox(T, f, b, b + cw, d0, d1, 0, d.height + cw, Surface::Casing, di));
        scene.boxes.push_back(wallBox(T, f, a, b, d0, d1, d.height, d.height + cw, Surface::Casing, di));
      }
      // The leaf, rotated about its hinge axis towards its swing side.
      const double lw = d.width - 2 * kSideGap, lh = d.height - kBottomGap - kTopGap;
      const double s_h = d.hinge_left ? a + kSideGap : b - kSideGap;
      const Eigen::Vector3d e0 = d.hinge_left ? f.u : Eigen::Vector3d(-f.u);
      const Eigen::Vector3d m = d.swing_into_room ? f.n : Eigen::Vector3d(-f.n);
      const double d_h = d.swing_into_room ? -d.recess : -t + d.recess;
      const double th = d.angle_deg * kPi / 180.0;
      const Eigen::Vector3d e = std::cos(th) * e0 + std::sin(th) * m;
      const Eigen::Vector3d k = std::sin(th) * e0 - std::cos(th) * m;
      const Eigen::Vector3d hinge = f.at(s_h, d_h, 0);
      Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
      local.linear().col(0) = e;
      local.linear().col(1) = k;
      local.linear().col(2) = e.cross(k);
      local.translation() = hinge + e * (lw / 2) + k * (lt / 2) + Eigen::Vector3d::UnitZ() * (kBottomGap + lh / 2);
      Box leaf;
      leaf.pose = T * local;
      leaf.half = Eigen::Vector3d(lw / 2, lt / 2, lh / 2);
      leaf.surface = Surface::Leaf;
      leaf.owner = di;
      scene.boxes.push_back(leaf);
      if (r.handles && lh > 1.2 && lw > 0.35)
        for (const double side : {1.0, -1.0}) {
          // The leaf's third axis (e x k) points down for half the doors: the
          // handle's height is measured along the world's up.
          const double up = local.linear().col(2).z() > 0 ? 1.0 : -1.0;
          Box handle;
          handle.pose = leaf.pose * Eigen::Translation3d(lw / 2 - 0.11, side * (lt / 2 + 0.03), up * (1.0 - (kBottomGap + lh / 2)));
          handle.half = Eigen::Vector3d(0.06, 0.03, 0.012);
          handle.surface = Surface::Handle;
          handle.owner = di;
          scene.boxes.push_back(handle);
        }

      DoorTruth& g = scene.doors[di];
      g.opening_center = T * f.at(d.center, -t / 2, 0);
      g.hinge = T * hinge;
      g.wall_normal = T.linear() * m;
      g.wall_axis = T.linear() * f.u;
      g.width = d.width;
      g.height = d.height;
      g.angle_deg = d.angle_deg;
      g.swing_into_room = d.swing_into_room;
      g.hinge_left = d.hinge_left;
      g.recess = d.recess;
      g.wall = w;
      const Eigen::Vector3d mid = hinge + k * (lt / 2), z = Eigen::Vector3d::UnitZ();
      g.leaf_corners = {T * (mid + z * kBottomGap), T * (mid + e * lw + z * kBottomGap),
                        T * (mid + e * lw + z * (kBottomGap + lh)), T * (mid + z * (kBottomGap + lh))};
    }
  }

  // Furniture.
  for (std::size_t i = 0; i < r.furniture.size(); ++i) {
    const FurnitureSpec& fs = r.furniture[i];
    const std::string id = "furniture " + std::to_string(i) + ": ";
    require(fs.width > 0.05 && fs.depth > 0.05 && fs.height > 0.05 && fs.height < H,
            id + "size must be positive and below the ceiling");
    DecoyTruth dt;
    dt.kind = fs.kind;
    dt.height = fs.height;
    dt.width = fs.width;
    dt.depth = fs.depth;
    if (fs.kind == "table") {
      const Eigen::Vector3d c(fs.center, fs.offset, 0);
      auto add = [&](const Eigen::Vector3d& center, const Eigen::Vector3d& half) {
        Box b;
        b.pose = T * Eigen::Translation3d(center);
        b.half = half;
        b.surface = Surface::Furniture;
        b.owner = static_cast<int>(i);
        scene.boxes.push_back(b);
      };
      add(c + Eigen::Vector3d(0, 0, fs.height - 0.02), Eigen::Vector3d(fs.width / 2, fs.depth / 2, 0.02));
      for (int sx = -1; sx <= 1; sx += 2)
        for (int sy = -1; sy <= 1; sy += 2)
          add(c + Eigen::Vector3d(sx * (fs.width / 2 - 0.05), sy * (fs.depth / 2 - 0.05), (fs.height - 0.04) / 2),
              Eigen::Vector3d(0.025, 0.025, (fs.height - 0.04) / 2));
      dt.center = T * (c + Eigen::Vector3d(0, 0, fs.height / 2));
    } else {
      require(fs.wall >= 0 && fs.wall < 4, id + "wall must be 0..3");
      const WallFrame f = wallFrame(r, fs.wall);
      require(std::abs(fs.center) + fs.width / 2 <= f.length / 2, id + "must fit along its wall");
      const double gap = 0.01;
      scene.boxes.push_back(wallBox(T, f, fs.center - fs.width / 2, fs.center + fs.width / 2, gap,
                                    gap + fs.depth, 0, fs.height, Surface::Furniture, static_cast<int>(i)));
      dt.center = T * f.at(fs.center, gap + fs.depth / 2, fs.height / 2);
    }
    scene.decoys.push_back(dt);
  }
  return scene;
}

// ---------------------------------------------------------------------------
// Random rooms

namespace {

struct Rng {
  std::mt19937_64 gen;
  explicit Rng(std::uint64_t seed) : gen(seed) {}
  // Own mapping to [a, b): the standard distributions are not specified
  // bit-for-bit, and scenes must be the same on every machine.
  double uniform(double a, double b) { return a + (b - a) * ((gen() >> 11) * (1.0 / 9007199254740992.0)); }
  int integer(int a, int b) { return a + static_cast<int>((gen() >> 11) % static_cast<std::uint64_t>(b - a + 1)); }
  bool coin(double p = 0.5) { return uniform(0, 1) < p; }
};

double wallLength(const RoomSpec& r, int w) { return (w % 2 == 0) ? r.width : r.depth; }

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
};

Eigen::Vector2d wallPoint(const RoomSpec& r, int w, double s, double d) {
  return wallFrame(r, w).at(s, d, 0).head<2>();
}

Rect wallRect(const RoomSpec& r, int w, double s0, double s1, double d0, double d1) {
  const Eigen::Vector2d a = wallPoint(r, w, s0, d0), b = wallPoint(r, w, s1, d1);
  return {std::min(a.x(), b.x()), std::max(a.x(), b.x()), std::min(a.y(), b.y()), std::max(a.y(), b.y())};
}

Rect furnitureRect(const RoomSpec& r, const FurnitureSpec& f) {
  if (f.kind == "table")
    return {f.center - f.width / 2, f.center + f.width / 2, f.offset - f.depth / 2, f.offset + f.depth / 2};
  return wallRect(r, f.wall, f.center - f.width / 2, f.center + f.width / 2, 0.0, 0.01 + f.depth);
}

}  // namespace

RoomSpec randomRoom(std::uint64_t seed, const RandomSceneOptions& o) {
  Rng rng(seed);
  RoomSpec r;
  r.name = "random_" + std::to_string(seed);
  r.width = rng.uniform(4.0, 7.5);
  r.depth = rng.uniform(3.5, 6.0);
  r.height = rng.uniform(2.5, 3.2);
  r.yaw = rng.uniform(-kPi, kPi);
  r.center = Eigen::Vector2d(rng.uniform(-3, 3), rng.uniform(-3, 3));
  r.wall_thickness = rng.uniform(0.10, 0.25);

  const int n_doors = rng.integer(o.min_doors, o.max_doors);
  for (int attempt = 0; attempt < 200 && static_cast<int>(r.doors.size()) < n_doors; ++attempt) {
    DoorSpec d;
    d.wall = rng.integer(0, 3);
    d.width = rng.uniform(0.75, 1.0);
    d.height = rng.uniform(1.95, std::min(2.15, r.height - r.casing_width - 0.15));
    d.hinge_left = rng.coin();
    d.swing_into_room = rng.coin();
    d.angle_deg = rng.coin(o.closed_fraction) ? 0.0 : rng.uniform(o.min_angle_deg, o.max_angle_deg);
    const double max_recess = r.wall_thickness - r.leaf_thickness - 0.01;
    d.recess = (rng.coin() || max_recess < 0.01) ? 0.0 : rng.uniform(0.01, max_recess);
    const double L = wallLength(r, d.wall);
    const double room = L / 2 - d.width / 2 - r.casing_width - 0.3;
    if (room <= 0) continue;
    d.center = rng.uniform(-room, room);
    // Doorways (with casing) apart, and no leaf sweeping into another doorway.
    auto opening = [&](const DoorSpec& x) {
      return wallRect(r, x.wall, x.center - x.width / 2 - r.casing_width, x.center + x.width / 2 + r.casing_width,
                      -r.wall_thickness, 0.0);
    };
    auto sweepHits = [&](const DoorSpec& x, const DoorSpec& y) {
      if (!x.swing_into_room) return false;
      const double hs = x.hinge_left ? x.center - x.width / 2 : x.center + x.width / 2;
      return opening(y).distanceTo(wallPoint(r, x.wall, hs, 0.0)) < x.width + 0.2;
    };
    bool clash = false;
    for (const DoorSpec& other : r.doors)
      clash |= opening(d).intersects(opening(other), 0.3) || sweepHits(d, other) || sweepHits(other, d);
    if (!clash) r.doors.push_back(d);
  }

  // Tall cupboards and wardrobes against the walls, and a table, all clear
  // of every doorway and of every leaf's swing.
  auto clear = [&](const Rect& box) {
    for (const DoorSpec& d : r.doors) {
      const double a = d.center - d.width / 2 - r.casing_width, b = d.center + d.width / 2 + r.casing_width;
      if (box.intersects(wallRect(r, d.wall, a, b, 0.0, 0.3), 0.1)) return false;
      if (d.swing_into_room) {
        const Eigen::Vector2d hinge = wallPoint(r, d.wall, d.hinge_left ? a : b, 0.0);
        if (box.distanceTo(hinge) < d.width + 0.15) return false;
      }
    }
    for (const FurnitureSpec& g : r.furniture)
      if (box.intersects(furnitureRect(r, g), 0.05)) return false;
    return true;
  };
  const int n_decoys = rng.integer(o.min_decoys, o.max_decoys);
  int placed = 0;
  for (int attempt = 0; attempt < 200 && placed < n_decoys; ++attempt) {
    FurnitureSpec f;
    const bool wardrobe = rng.coin();
    f.kind = wardrobe ? "wardrobe" : "cupboard";
    f.wall = rng.integer(0, 3);
    f.width = wardrobe ? rng.uniform(1.0, 1.8) : rng.uniform(0.6, 1.1);
    f.depth = wardrobe ? rng.uniform(0.55, 0.65) : rng.uniform(0.35, 0.6);
    f.height = wardrobe ? rng.uniform(2.0, std::min(2.4, r.height - 0.1)) : rng.uniform(1.85, std::min(2.2, r.height - 0.1));
    const double room = wallLength(r, f.wall) / 2 - f.width / 2 - 0.05;
    if (room <= 0) continue;
    f.center = rng.uniform(-room, room);
    if (clear(furnitureRect(r, f))) {
      r.furniture.push_back(f);
      ++placed;
    }
  }
  for (int attempt = 0; o.table && attempt < 50; ++attempt) {
    FurnitureSpec tbl;
    tbl.kind = "table";
    tbl.width = rng.uniform(1.0, 1.5);
    tbl.depth = rng.uniform(0.6, 0.8);
    tbl.height = 0.75;
    const double bx = r.width / 2 - tbl.width / 2 - 0.7, by = r.depth / 2 - tbl.depth / 2 - 0.7;
    if (bx <= 0 || by <= 0) break;
    tbl.center = rng.uniform(-bx, bx);
    tbl.offset = rng.uniform(-by, by);
    if (clear(furnitureRect(r, tbl))) {
      r.furniture.push_back(tbl);
      break;
    }
  }
  return r;
}

std::vector<std::string> paperRoomNames() { return {"paper_livingroom", "paper_house", "paper_multidoor"}; }

RoomSpec paperRoom(const std::string& name) {
  RoomSpec r;
  r.name = name;
  if (name == "paper_livingroom") {  // Table 1: wall 2.33 m, door 1.86 m, other object 0.82 m; closed
    r.width = 5.0;
    r.depth = 4.5;
    r.height = 2.33;
    r.yaw = 0.3;
    DoorSpec d;
    d.wall = 2;
    d.center = -1.2;
    d.width = 0.8;
    d.height = 1.86;
    d.angle_deg = 0;
    r.doors.push_back(d);
    FurnitureSpec f;
    f.kind = "cabinet";
    f.wall = 2;
    f.center = 1.0;
    f.width = 1.4;
    f.depth = 0.45;
    f.height = 0.82;
    r.furniture.push_back(f);
    r.scanner = Eigen::Vector3d(0.3, -0.5, 1.4);
  } else if (name == "paper_house") {  // wall 2.83 m, door 2.16 m open at ~110 deg
    r.width = 6.0;
    r.depth = 5.0;
    r.height = 2.83;
    r.yaw = -0.5;
    DoorSpec d;
    d.wall = 1;
    d.center = 0.8;
    d.width = 0.9;
    d.height = 2.16;
    d.angle_deg = 110.6;
    d.swing_into_room = true;
    r.doors.push_back(d);
    r.scanner = Eigen::Vector3d(0.5, 1.8, 1.5);
  } else if (name == "paper_multidoor") {  // wall 2.83 m, doors 2.31 m at ~7 and ~25 deg
    r.width = 7.0;
    r.depth = 5.0;
    r.height = 2.83;
    r.yaw = 0.0;
    DoorSpec a;
    a.wall = 0;
    a.center = -1.8;
    a.width = 0.9;
    a.height = 2.31;
    a.angle_deg = 7.2;
    a.hinge_left = true;
    r.doors.push_back(a);
    DoorSpec b = a;
    b.center = 1.5;
    b.angle_deg = 25.3;
    b.hinge_left = false;
    r.doors.push_back(b);
    r.scanner = Eigen::Vector3d(0.0, 0.8, 1.5);
  } else {
    throw std::invalid_argument("unknown paper scene '" + name + "' (known: paper_livingroom, paper_house, paper_multidoor)");
  }
  return r;
}

}  // namespace sim
}  // namespace dsr
