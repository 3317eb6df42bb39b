#include "door_state_recognition/sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

#include "room_frame.hpp"

namespace dsr {
namespace sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSideGap = 0.004;    // leaf to jamb
constexpr double kBottomGap = 0.010;  // leaf to floor
constexpr double kTopGap = 0.003;     // leaf to head jamb

using detail::Rect;
using detail::WallFrame;
using detail::wallFrame;

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

namespace detail {

Eigen::Vector2d cornerSigns(int corner) {
  return {(corner == 1 || corner == 2) ? 1.0 : -1.0, corner >= 2 ? 1.0 : -1.0};
}

int wallCount(const RoomSpec& r) { return r.partition ? 6 : 4; }

WallFrame wallFrame(const RoomSpec& r, int i) {
  WallFrame f;
  if (i >= 0 && i < 4) {
    static const double nx[4] = {0, -1, 0, 1}, ny[4] = {1, 0, -1, 0};
    f.n = Eigen::Vector3d(nx[i], ny[i], 0);
    f.u = f.n.cross(Eigen::Vector3d::UnitZ());
    f.origin = -f.n * ((i % 2 == 0) ? r.depth / 2 : r.width / 2);
    f.length = (i % 2 == 0) ? r.width : r.depth;
    f.thickness = f.ext_lo = f.ext_hi = r.wall_thickness;
    return f;
  }
  require((i == 4 || i == 5) && r.partition.has_value(), "wall " + std::to_string(i) + " does not exist (0..3, 4..5 with a partition)");
  const PartitionSpec& p = *r.partition;
  const Eigen::Vector2d sg = cornerSigns(p.corner);
  const double sx = sg.x(), sy = sg.y();
  f.thickness = p.thickness;
  if (i == 4) {  // parallel to y, facing -sx; junction with wall 5 at s = -sx sy L/2
    f.n = Eigen::Vector3d(-sx, 0, 0);
    f.origin = Eigen::Vector3d(sx * (r.width / 2 - p.size_x), sy * (r.depth / 2 - p.size_y / 2), 0);
    f.length = p.size_y;
    const bool junction_lo = sx * sy > 0;
    f.ext_lo = junction_lo ? 0.0 : r.wall_thickness;
    f.ext_hi = junction_lo ? r.wall_thickness : 0.0;
  } else {  // parallel to x, facing -sy; junction with wall 4 at s = +sx sy L/2
    f.n = Eigen::Vector3d(0, -sy, 0);
    f.origin = Eigen::Vector3d(sx * (r.width / 2 - p.size_x / 2), sy * (r.depth / 2 - p.size_y), 0);
    f.length = p.size_x;
    const bool junction_hi = sx * sy > 0;
    f.ext_lo = junction_hi ? r.wall_thickness : 0.0;
    f.ext_hi = junction_hi ? 0.0 : r.wall_thickness;
  }
  f.u = f.n.cross(Eigen::Vector3d::UnitZ());
  return f;
}

Eigen::Vector2d wallPoint(const RoomSpec& r, int w, double s, double d) { return wallFrame(r, w).at(s, d, 0).head<2>(); }

Rect wallRect(const RoomSpec& r, int w, double s0, double s1, double d0, double d1) {
  const Eigen::Vector2d a = wallPoint(r, w, s0, d0), b = wallPoint(r, w, s1, d1);
  return {std::min(a.x(), b.x()), std::max(a.x(), b.x()), std::min(a.y(), b.y()), std::max(a.y(), b.y())};
}

Rect partitionRect(const RoomSpec& r) {
  const PartitionSpec& p = *r.partition;
  const Eigen::Vector2d sg = cornerSigns(p.corner);
  const double xa = sg.x() * r.width / 2, xb = sg.x() * (r.width / 2 - p.size_x);
  const double ya = sg.y() * r.depth / 2, yb = sg.y() * (r.depth / 2 - p.size_y);
  return {std::min(xa, xb), std::max(xa, xb), std::min(ya, yb), std::max(ya, yb)};
}

Rect furnitureRect(const RoomSpec& r, const FurnitureSpec& f) {
  if (f.kind == "table")
    return {f.center - f.width / 2, f.center + f.width / 2, f.offset - f.depth / 2, f.offset + f.depth / 2};
  if (f.kind == "chair") {
    const double h = 0.5 * std::hypot(f.width, f.depth);
    return {f.center - h, f.center + h, f.offset - h, f.offset + h};
  }
  return wallRect(r, f.wall, f.center - f.width / 2, f.center + f.width / 2, 0.0, f.gap + f.depth);
}

}  // namespace detail

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
  if (spec.partition && detail::partitionRect(spec).contains(q.head<2>(), margin)) return false;
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

namespace {

// An opening of a wall: a doorway (from the floor) or a window-like gap.
struct Opening {
  double a, b, sill, head;
  int door;  // index into RoomSpec::doors, -1 for a window
};

// Boxes of a piece of furniture in the room frame (its owner index set by the caller).
void furnitureBoxes(const RoomSpec& r, const FurnitureSpec& fs, const Eigen::Isometry3d& T, int owner,
                    std::vector<Box>& out) {
  auto add = [&](const Eigen::Isometry3d& local, const Eigen::Vector3d& center, const Eigen::Vector3d& half) {
    Box b;
    b.pose = T * local * Eigen::Translation3d(center);
    b.half = half;
    b.surface = Surface::Furniture;
    b.owner = owner;
    out.push_back(b);
  };
  if (fs.kind == "table" || fs.kind == "chair") {
    const Eigen::Vector3d c(fs.center, fs.offset, 0);
    if (fs.kind == "table") {
      const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
      add(I, c + Eigen::Vector3d(0, 0, fs.height - 0.02), Eigen::Vector3d(fs.width / 2, fs.depth / 2, 0.02));
      for (int sx = -1; sx <= 1; sx += 2)
        for (int sy = -1; sy <= 1; sy += 2)
          add(I, c + Eigen::Vector3d(sx * (fs.width / 2 - 0.05), sy * (fs.depth / 2 - 0.05), (fs.height - 0.04) / 2),
              Eigen::Vector3d(0.025, 0.025, (fs.height - 0.04) / 2));
      return;
    }
    Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
    local.translation() = c;
    // Chair: local x along its width, -y towards its back (the back's
    // outward normal is `yaw` from the room's +x).
    local.linear() = Eigen::AngleAxisd(fs.yaw + kPi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const double seat = 0.46, w = fs.width / 2, dp = fs.depth / 2;
    add(local, Eigen::Vector3d(0, 0, seat - 0.015), Eigen::Vector3d(w, dp, 0.015));
    for (int sx = -1; sx <= 1; sx += 2)
      for (int sy = -1; sy <= 1; sy += 2)
        add(local, Eigen::Vector3d(sx * (w - 0.02), sy * (dp - 0.02), (seat - 0.03) / 2), Eigen::Vector3d(0.012, 0.012, (seat - 0.03) / 2));
    add(local, Eigen::Vector3d(0, dp - 0.015, (seat + fs.height) / 2), Eigen::Vector3d(w, 0.015, (fs.height - seat) / 2));
    return;
  }
  const WallFrame f = wallFrame(r, fs.wall);
  const double s0 = fs.center - fs.width / 2, s1 = fs.center + fs.width / 2, d0 = fs.gap, d1 = fs.gap + fs.depth;
  const double h = fs.height;
  auto part = [&](double a0, double a1, double b0, double b1, double z0, double z1) {
    Box b = wallBox(T, f, a0, a1, b0, b1, z0, z1, Surface::Furniture, owner);
    out.push_back(b);
  };
  if (fs.kind == "desk") {
    part(s0, s1, d0, d1, h - 0.03, h);  // top
    const bool left = fs.detail_seed % 2 == 0;
    const double p0 = left ? s0 + 0.02 : s1 - 0.42, p1 = left ? s0 + 0.42 : s1 - 0.02;
    part(p0, p1, d0 + 0.03, d1 - 0.06, 0.0, h - 0.03);  // drawer pedestal
    for (const double s : {left ? s1 - 0.05 : s0 + 0.05})
      for (const double d : {d0 + 0.05, d1 - 0.05}) part(s - 0.025, s + 0.025, d - 0.025, d + 0.025, 0.0, h - 0.03);
    part(left ? p1 : s0 + 0.05, left ? s1 - 0.05 : p0, d0 + 0.02, d0 + 0.04, 0.35, h - 0.03);  // modesty panel
    return;
  }
  if (fs.kind == "shelf" || fs.kind == "bookcase") {
    const double p = 0.018;
    part(s0, s0 + p, d0, d1, 0, h);  // side panels
    part(s1 - p, s1, d0, d1, 0, h);
    part(s0, s1, d0, d0 + 0.008, 0, h);  // back
    part(s0 + p, s1 - p, d0, d1, h - p, h);  // top
    part(s0 + p, s1 - p, d0, d1, 0, 0.08);   // plinth
    const int n = std::max(2, static_cast<int>(std::lround((h - 0.1) / 0.36)));
    const double step = (h - 0.08 - p) / n;
    detail::Rng rng(0xB00C5ull ^ (static_cast<std::uint64_t>(fs.detail_seed) * 0x9E3779B97F4A7C15ull));
    for (int k = 0; k < n; ++k) {
      const double z = 0.08 + k * step;  // top of the board below this compartment
      if (k > 0) part(s0 + p, s1 - p, d0 + 0.008, d1 - 0.01, z - p, z);
      // Rows of books: one to three blocks standing on the board, against the back.
      double s = s0 + p + rng.uniform(0.0, 0.15);
      const int blocks = rng.integer(fs.kind == "shelf" ? 0 : 1, 3);
      for (int b = 0; b < blocks && s < s1 - p - 0.12; ++b) {
        const double len = std::min(rng.uniform(0.1, 0.45), s1 - p - s);
        const double bh = std::min(rng.uniform(0.16, 0.32), step - p - 0.03);
        const double bd = std::min(rng.uniform(0.15, 0.28), fs.depth - 0.03);
        if (bh > 0.05 && len > 0.05) part(s, s + len, d0 + 0.008, d0 + 0.008 + bd, z, z + bh);
        s += len + rng.uniform(0.0, 0.2);
      }
    }
    return;
  }
  part(s0, s1, d0, d1, 0, h);  // a solid piece: cupboard, wardrobe, cabinet
}

}  // namespace

Scene buildScene(const RoomSpec& r) {
  require(r.width >= 1.0 && r.width <= 100 && r.depth >= 1.0 && r.depth <= 100,
          "room width and depth must lie in [1, 100] m");
  require(r.height >= 1.5 && r.height <= 20, "room height must lie in [1.5, 20] m");
  require(r.wall_thickness >= 0.05 && r.wall_thickness <= 1.0, "wall thickness must lie in [0.05, 1] m");
  require(r.leaf_thickness > 0.005 && r.leaf_thickness < r.wall_thickness,
          "leaf thickness must be positive and below the wall thickness");
  require(std::isfinite(r.yaw) && r.center.allFinite(), "yaw and centre must be finite");
  if (r.partition) {
    const PartitionSpec& p = *r.partition;
    require(p.corner >= 0 && p.corner < 4, "partition corner must be 0..3");
    require(p.thickness >= 0.05 && p.thickness <= r.wall_thickness && p.thickness > r.leaf_thickness,
            "partition thickness must lie in [0.05 m, wall thickness] and exceed the leaf's");
    require(p.size_x >= 1.0 && p.size_y >= 1.0 && p.size_x <= r.width - 1.0 && p.size_y <= r.depth - 1.0,
            "partition must be at least 1 m each way and leave 1 m of the room");
  }
  const int n_walls = detail::wallCount(r);

  Scene scene;
  scene.spec = r;
  scene.floor_z = 0.0;
  scene.ceiling_z = r.height;
  scene.room_to_world = Eigen::Translation3d(r.center.x(), r.center.y(), 0.0) *
                        Eigen::AngleAxisd(r.yaw, Eigen::Vector3d::UnitZ());
  const Eigen::Isometry3d& T = scene.room_to_world;
  const double H = r.height, cw = r.casing_width, cp = r.casing_depth;
  const double lt = r.leaf_thickness;

  // Openings per wall (doors and windows), validated and sorted along the wall.
  std::vector<std::vector<Opening>> openings(n_walls);
  for (std::size_t i = 0; i < r.doors.size(); ++i) {
    const DoorSpec& d = r.doors[i];
    const std::string id = "door " + std::to_string(i) + ": ";
    require(d.wall >= 0 && d.wall < n_walls, id + (r.partition ? "wall must be 0..5" : "wall must be 0..3"));
    const WallFrame f = wallFrame(r, d.wall);
    const double L = f.length;
    require(d.width >= 0.3 && d.width <= 3.0, id + "width must lie in [0.3, 3] m");
    require(d.height >= 1.0 && d.height + cw < H, id + "height must be >= 1 m and leave room for the casing below the ceiling");
    require(std::abs(d.center) + d.width / 2 + cw <= L / 2, id + "opening and casing must fit in the wall (centre " + num(d.center) + ")");
    require(d.angle_deg >= 0 && d.angle_deg <= 180, id + "angle must lie in [0, 180] deg");
    require(d.recess >= 0 && d.recess + lt <= f.thickness + 1e-9, id + "recess must lie in [0, wall thickness - leaf thickness]");
    openings[d.wall].push_back({d.center - d.width / 2 - cw, d.center + d.width / 2 + cw, 0.0, d.height, static_cast<int>(i)});
  }
  for (std::size_t i = 0; i < r.windows.size(); ++i) {
    const WindowSpec& w = r.windows[i];
    const std::string id = "window " + std::to_string(i) + ": ";
    require(w.wall >= 0 && w.wall < 4, id + "wall must be 0..3");
    require(w.width >= 0.2 && std::abs(w.center) + w.width / 2 <= wallFrame(r, w.wall).length / 2,
            id + "must be at least 0.2 m wide and fit in its wall");
    require(w.sill >= 0.1 && w.head > w.sill + 0.1 && w.head < H, id + "needs 0.1 m <= sill < head - 0.1 m, head below the ceiling");
    openings[w.wall].push_back({w.center - w.width / 2, w.center + w.width / 2, w.sill, w.head, -1});
  }
  for (auto& list : openings) {
    std::sort(list.begin(), list.end(), [](const Opening& a, const Opening& b) { return a.a < b.a; });
    for (std::size_t k = 1; k < list.size(); ++k) {
      auto name = [](const Opening& o) { return o.door >= 0 ? "door " + std::to_string(o.door) : std::string("a window"); };
      require(list[k].a >= list[k - 1].b, name(list[k - 1]) + " and " + name(list[k]) + " overlap");
    }
  }
  if (r.partition) {  // nothing of the room's own walls inside the small room
    const Rect small = detail::partitionRect(r);
    for (int w = 0; w < 4; ++w)
      for (const Opening& o : openings[w])
        require(!detail::wallRect(r, w, o.a, o.b, 0.0, 0.01).intersects(small, 0.0),
                (o.door >= 0 ? "door " + std::to_string(o.door) : std::string("a window")) + " opens into the partition's small room");
  }

  // Floor and ceiling slabs, large enough to cover the adjacent rooms.
  const double t = r.wall_thickness;
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
  for (int w = 0; w < n_walls; ++w) {
    const WallFrame f = wallFrame(r, w);
    const double L = f.length, tw = f.thickness;
    WallTruth wt;
    wt.origin = T * f.origin;
    wt.axis = T.linear() * f.u;
    wt.normal = T.linear() * f.n;
    wt.length = L;
    scene.walls.push_back(wt);

    // Solid wall between openings, lintels above them, sills below windows.
    double s = -L / 2 - f.ext_lo;
    bool has_door = false;
    for (const Opening& o : openings[w]) {
      const double a = o.door >= 0 ? o.a + cw : o.a, b = o.door >= 0 ? o.b - cw : o.b;
      if (a > s) scene.boxes.push_back(wallBox(T, f, s, a, -tw, 0, 0, H, Surface::Wall, w));
      if (o.sill > 0) scene.boxes.push_back(wallBox(T, f, a, b, -tw, 0, 0, o.sill, Surface::Wall, w));
      scene.boxes.push_back(wallBox(T, f, a, b, -tw, 0, o.head, H, Surface::Wall, w));
      s = b;
      has_door |= o.door >= 0;
      if (o.door < 0) {
        DecoyTruth dt;
        dt.kind = "window";
        dt.center = T * f.at((a + b) / 2, -tw / 2, (o.sill + o.head) / 2);
        dt.height = o.head - o.sill;
        dt.width = b - a;
        dt.depth = tw;
        scene.decoys.push_back(dt);
      }
    }
    scene.boxes.push_back(wallBox(T, f, s, L / 2 + f.ext_hi, -tw, 0, 0, H, Surface::Wall, w));

    if (has_door && w < 4) {  // the room behind, seen through the doorways
      const double A = r.adjacent_depth, e = L / 2 + t;
      scene.boxes.push_back(wallBox(T, f, -e - 0.1, e + 0.1, -t - A - 0.1, -t - A, 0, H, Surface::Adjacent, w));
      scene.boxes.push_back(wallBox(T, f, -e - 0.1, -e, -t - A, -t, 0, H, Surface::Adjacent, w));
      scene.boxes.push_back(wallBox(T, f, e, e + 0.1, -t - A, -t, 0, H, Surface::Adjacent, w));
      scene.boxes.push_back(wallBox(T, f, -0.9, 0.6, -t - A, -t - A + 0.85, 0, 0.9, Surface::Adjacent, w));
    }

    for (const Opening& o : openings[w]) {
      if (o.door < 0) continue;
      const int di = o.door;
      const DoorSpec& d = r.doors[di];
      const double a = d.center - d.width / 2, b = d.center + d.width / 2;
      // Casing trim on both faces: two legs and a head (none in a plain opening).
      for (int side = 0; side < 2 && cw > 0 && cp > 0; ++side) {
        const double d0 = side == 0 ? 0.0 : -tw - cp, d1 = side == 0 ? cp : -tw;
        scene.boxes.push_back(wallBox(T, f, a - cw, a, d0, d1, 0, d.height + cw, Surface::Casing, di));
        scene.boxes.push_back(wallBox(T, f, b, b + cw, d0, d1, 0, d.height + cw, Surface::Casing, di));
        scene.boxes.push_back(wallBox(T, f, a, b, d0, d1, d.height, d.height + cw, Surface::Casing, di));
      }
      // The leaf, rotated about its hinge axis towards its swing side.
      const double lw = d.width - 2 * kSideGap, lh = d.height - kBottomGap - kTopGap;
      const double s_h = d.hinge_left ? a + kSideGap : b - kSideGap;
      const Eigen::Vector3d e0 = d.hinge_left ? f.u : Eigen::Vector3d(-f.u);
      const Eigen::Vector3d m = d.swing_into_room ? f.n : Eigen::Vector3d(-f.n);
      const double d_h = d.swing_into_room ? -d.recess : -tw + d.recess;
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
      g.opening_center = T * f.at(d.center, -tw / 2, 0);
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
    require(std::isfinite(fs.yaw) && fs.gap >= 0.0 && fs.gap <= 1.0, id + "gap must lie in [0, 1] m and yaw be finite");
    DecoyTruth dt;
    dt.kind = fs.kind;
    dt.height = fs.height;
    dt.width = fs.width;
    dt.depth = fs.depth;
    if (fs.kind == "table" || fs.kind == "chair") {
      require(fs.kind == "table" || (fs.width >= 0.3 && fs.depth >= 0.3 && fs.height > 0.6), id + "a chair needs 0.3 m x 0.3 m and a back above its seat");
      dt.center = T * Eigen::Vector3d(fs.center, fs.offset, fs.height / 2);
    } else {
      require(fs.wall >= 0 && fs.wall < n_walls, id + (r.partition ? "wall must be 0..5" : "wall must be 0..3"));
      const WallFrame f = wallFrame(r, fs.wall);
      require(std::abs(fs.center) + fs.width / 2 <= f.length / 2, id + "must fit along its wall");
      require(fs.kind != "desk" || (fs.width >= 0.9 && fs.depth >= 0.4 && fs.height >= 0.5), id + "a desk needs 0.9 m x 0.4 m x 0.5 m");
      require((fs.kind != "shelf" && fs.kind != "bookcase") || (fs.width >= 0.3 && fs.depth >= 0.15 && fs.height >= 0.4),
              id + "shelving needs 0.3 m x 0.15 m x 0.4 m");
      dt.center = T * f.at(fs.center, fs.gap + fs.depth / 2, fs.height / 2);
    }
    furnitureBoxes(r, fs, T, static_cast<int>(i), scene.boxes);
    scene.decoys.push_back(dt);
  }
  return scene;
}

// ---------------------------------------------------------------------------
// Random rooms

namespace {

using detail::furnitureRect;
using detail::Rng;
using detail::wallPoint;
using detail::wallRect;

double wallLength(const RoomSpec& r, int w) { return wallFrame(r, w).length; }

// The leaf of a door seen from above: hinge and latch ends in the room frame.
std::pair<Eigen::Vector2d, Eigen::Vector2d> leafSegment(const RoomSpec& r, const DoorSpec& d) {
  const WallFrame f = wallFrame(r, d.wall);
  const double s_h = d.hinge_left ? d.center - d.width / 2 : d.center + d.width / 2;
  const Eigen::Vector3d e0 = d.hinge_left ? f.u : Eigen::Vector3d(-f.u);
  const Eigen::Vector3d m = d.swing_into_room ? f.n : Eigen::Vector3d(-f.n);
  const double th = d.angle_deg * kPi / 180.0;
  const Eigen::Vector3d h = f.at(s_h, d.swing_into_room ? -d.recess : -f.thickness + d.recess, 0);
  const Eigen::Vector3d e = h + d.width * (std::cos(th) * e0 + std::sin(th) * m);
  return {h.head<2>(), e.head<2>()};
}

double segmentDistance(const std::pair<Eigen::Vector2d, Eigen::Vector2d>& a, const std::pair<Eigen::Vector2d, Eigen::Vector2d>& b) {
  auto pointSeg = [](const Eigen::Vector2d& p, const Eigen::Vector2d& s0, const Eigen::Vector2d& s1) {
    const Eigen::Vector2d d = s1 - s0;
    const double t = std::clamp((p - s0).dot(d) / std::max(1e-12, d.squaredNorm()), 0.0, 1.0);
    return (s0 + t * d - p).norm();
  };
  auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); };
  const Eigen::Vector2d r = a.second - a.first, s = b.second - b.first, q = b.first - a.first;
  const double den = cross(r, s);
  if (std::abs(den) > 1e-12) {
    const double t = cross(q, s) / den, u = cross(q, r) / den;
    if (t >= 0 && t <= 1 && u >= 0 && u <= 1) return 0.0;
  }
  return std::min({pointSeg(a.first, b.first, b.second), pointSeg(a.second, b.first, b.second),
                   pointSeg(b.first, a.first, a.second), pointSeg(b.second, a.first, a.second)});
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
  // Options draw from streams of their own: without them the room is as it
  // always was for its seed.
  const bool extras = o.clutter || o.partition || o.corridor;
  Rng extra(seed ^ 0x5CE4E0C0FFEEull);
  if (o.varied_doors) {
    Rng joinery(seed ^ 0xD00425EEDull);
    const bool casing = !joinery.coin(1.0 / 3.0);
    r.casing_width = casing ? joinery.uniform(0.04, 0.10) : 0.0;
    r.casing_depth = casing ? joinery.uniform(0.008, 0.03) : 0.0;
    r.leaf_thickness = joinery.uniform(0.03, 0.055);
  }
  if (o.corridor) {
    r.name = "corridor_" + std::to_string(seed);
    r.width = extra.uniform(6.0, 12.0);
    r.depth = extra.uniform(1.5, 2.2);
  }
  if (o.partition && !o.corridor) {
    // A bathroom-like small room in a corner, its door in one of its two walls.
    PartitionSpec p;
    p.corner = extra.integer(0, 3);
    p.size_x = extra.uniform(1.7, std::min(2.6, r.width / 2));
    p.size_y = extra.uniform(1.7, std::min(2.4, r.depth / 2));
    p.thickness = std::min(0.10, r.wall_thickness);
    r.partition = p;
    DoorSpec d;
    d.wall = extra.coin() ? 4 : 5;
    d.width = extra.uniform(0.7, 0.85);
    d.height = extra.uniform(1.95, std::min(2.1, r.height - r.casing_width - 0.15));
    d.hinge_left = extra.coin();
    d.swing_into_room = extra.coin();
    // A bathroom's door opens against a stop at about a right angle at most.
    d.angle_deg = extra.coin(o.closed_fraction) ? 0.0 : extra.uniform(o.min_angle_deg, std::min(o.max_angle_deg, 100.0));
    const double max_recess = p.thickness - r.leaf_thickness - 0.01;
    d.recess = (extra.coin() || max_recess < 0.01) ? 0.0 : extra.uniform(0.01, max_recess);
    const double room = wallLength(r, d.wall) / 2 - d.width / 2 - r.casing_width - 0.2;
    d.center = room > 0 ? extra.uniform(-room, room) : 0.0;
    r.doors.push_back(d);
  }

  const int n_doors = o.corridor ? rng.integer(std::max(2, o.min_doors), std::min(12, std::max(2, o.max_doors) + 2))
                                 : rng.integer(o.min_doors, o.max_doors) + static_cast<int>(r.doors.size());
  for (int attempt = 0; attempt < 200 && static_cast<int>(r.doors.size()) < n_doors; ++attempt) {
    DoorSpec d;
    d.wall = rng.integer(0, 3);
    if (o.corridor) d.wall = (d.wall % 2) * 2;  // the long walls
    d.width = rng.uniform(0.75, 1.0);
    d.height = rng.uniform(1.95, std::min(2.15, r.height - r.casing_width - 0.15));
    d.hinge_left = rng.coin();
    d.swing_into_room = rng.coin();
    // Doors of rooms on a corridor open into the rooms more often than not.
    if (o.corridor) d.swing_into_room = extra.coin(0.3);
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
                      -wallFrame(r, x.wall).thickness, 0.0);
    };
    auto sweepHits = [&](const DoorSpec& x, const DoorSpec& y) {
      if (!x.swing_into_room) return false;
      const double hs = x.hinge_left ? x.center - x.width / 2 : x.center + x.width / 2;
      return opening(y).distanceTo(wallPoint(r, x.wall, hs, 0.0)) < x.width + 0.2;
    };
    bool clash = false;
    for (const DoorSpec& other : r.doors) {
      clash |= opening(d).intersects(opening(other), 0.3) || sweepHits(d, other) || sweepHits(other, d);
      // With the options: leaves on the same side of the walls keep 10 cm
      // apart (corridors are narrow; a partition's door meets the room's).
      if (extras && d.swing_into_room == other.swing_into_room && (d.swing_into_room || d.wall == other.wall))
        clash |= segmentDistance(leafSegment(r, d), leafSegment(r, other)) < 0.1;
    }
    if (r.partition) {  // not into the small room, no leaf sweeping into it
      const detail::Rect small = detail::partitionRect(r);
      clash |= opening(d).intersects(small, 0.3);
      const double hs = d.hinge_left ? d.center - d.width / 2 : d.center + d.width / 2;
      clash |= d.swing_into_room && small.distanceTo(wallPoint(r, d.wall, hs, 0.0)) < d.width + 0.1;
    }
    if (!clash) r.doors.push_back(d);
  }

  // Tall cupboards and wardrobes against the walls, and a table, all clear
  // of every doorway and of every leaf's swing.
  auto clear = [&](const detail::Rect& box) {
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
    if (r.partition && box.intersects(detail::partitionRect(r), 0.0)) return false;
    return true;
  };
  const int n_decoys = rng.integer(o.min_decoys, o.max_decoys);
  int placed = 0;
  for (int attempt = 0; attempt < 200 && placed < n_decoys; ++attempt) {
    FurnitureSpec f;
    const bool wardrobe = rng.coin() && !o.corridor;
    f.kind = wardrobe ? "wardrobe" : "cupboard";
    f.wall = rng.integer(0, 3);
    f.width = wardrobe ? rng.uniform(1.0, 1.8) : rng.uniform(0.6, 1.1);
    f.depth = wardrobe ? rng.uniform(0.55, 0.65) : rng.uniform(0.35, 0.6);
    if (o.corridor) f.depth = std::min(f.depth, 0.4);
    f.height = wardrobe ? rng.uniform(2.0, std::min(2.4, r.height - 0.1)) : rng.uniform(1.85, std::min(2.2, r.height - 0.1));
    const double room = wallLength(r, f.wall) / 2 - f.width / 2 - 0.05;
    if (room <= 0) continue;
    f.center = rng.uniform(-room, room);
    if (clear(furnitureRect(r, f))) {
      r.furniture.push_back(f);
      ++placed;
    }
  }
  for (int attempt = 0; o.table && !o.corridor && attempt < 50; ++attempt) {
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
  if (o.clutter) detail::addClutter(r, seed, o.corridor);
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
