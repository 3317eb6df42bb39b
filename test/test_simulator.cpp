// Proves the scene simulator right: determinism, door geometry, the sensors'
// models and the ground truth's frame. Every randomised case names its seed.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "door_state_recognition/sim/ground_truth.hpp"
#include "door_state_recognition/sim/scene.hpp"
#include "door_state_recognition/sim/sensors.hpp"

using namespace dsr::sim;

namespace {

std::string seedTrace(std::uint64_t seed) { return "seed=" + std::to_string(seed); }

std::vector<Eigen::Vector3d> boxCorners(const Box& b) {
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < 8; ++i)
    out.push_back(b.pose * Eigen::Vector3d((i & 1 ? 1 : -1) * b.half.x(), (i & 2 ? 1 : -1) * b.half.y(),
                                           (i & 4 ? 1 : -1) * b.half.z()));
  return out;
}

const Box& leafOf(const Scene& s, int door) {
  for (const Box& b : s.boxes)
    if (b.surface == Surface::Leaf && b.owner == door) return b;
  throw std::runtime_error("no leaf");
}

// Coordinates of p in the frame of wall w: (s along, d along inward normal, z).
Eigen::Vector3d inWall(const Scene& s, int w, const Eigen::Vector3d& p) {
  const WallTruth& wt = s.walls[w];
  const Eigen::Vector3d q = p - wt.origin;
  return {q.dot(wt.axis), q.dot(wt.normal), q.z()};
}

// Unit normal of the best-fit plane through points (smallest eigenvector).
Eigen::Vector3d planeNormal(const std::vector<Eigen::Vector3d>& pts) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= pts.size();
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) C += (p - mean) * (p - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  return es.eigenvectors().col(0);
}

RoomSpec oneDoorRoom(double angle, bool hinge_left, bool into_room, double recess) {
  RoomSpec r;
  r.name = "test";
  r.width = 5;
  r.depth = 4;
  r.height = 2.6;
  r.yaw = 0.4;
  r.center = Eigen::Vector2d(1.0, -2.0);
  DoorSpec d;
  d.wall = 1;
  d.center = 0.3;
  d.width = 0.9;
  d.height = 2.05;
  d.angle_deg = angle;
  d.hinge_left = hinge_left;
  d.swing_into_room = into_room;
  d.recess = recess;
  r.doors.push_back(d);
  return r;
}

}  // namespace

TEST(Simulator, SameSeedSameCloudDifferentSeedDifferentCloud) {
  TlsOptions o;
  o.points = 20000;
  o.seed = 42;
  const Scene a = buildScene(randomRoom(42));
  const SimulatedCloud c1 = scanTls(a, o), c2 = scanTls(buildScene(randomRoom(42)), o);
  ASSERT_EQ(c1.cloud.size(), c2.cloud.size());
  ASSERT_GT(c1.cloud.size(), 15000u);
  for (std::size_t i = 0; i < c1.cloud.size(); ++i) {
    ASSERT_EQ(c1.cloud[i].x, c2.cloud[i].x) << "point " << i;
    ASSERT_EQ(c1.cloud[i].y, c2.cloud[i].y);
    ASSERT_EQ(c1.cloud[i].z, c2.cloud[i].z);
    ASSERT_EQ(c1.cloud[i].label, c2.cloud[i].label);
  }
  o.seed = 43;
  const SimulatedCloud c3 = scanTls(buildScene(randomRoom(43)), o);
  bool differ = c3.cloud.size() != c1.cloud.size();
  for (std::size_t i = 0; !differ && i < c1.cloud.size(); ++i) differ = c1.cloud[i].x != c3.cloud[i].x;
  EXPECT_TRUE(differ);
}

TEST(Simulator, ClosedLeafLiesInsideItsOpening) {
  for (bool hinge_left : {true, false})
    for (bool into_room : {true, false})
      for (double recess : {0.0, 0.05}) {
        SCOPED_TRACE(::testing::Message() << "hinge_left=" << hinge_left << " into_room=" << into_room
                                          << " recess=" << recess);
        const Scene s = buildScene(oneDoorRoom(0.0, hinge_left, into_room, recess));
        const DoorSpec& d = s.spec.doors[0];
        const double t = s.spec.wall_thickness;
        for (const Eigen::Vector3d& c : boxCorners(leafOf(s, 0))) {
          const Eigen::Vector3d q = inWall(s, 1, c);
          EXPECT_GE(q.x(), d.center - d.width / 2 - 1e-9);
          EXPECT_LE(q.x(), d.center + d.width / 2 + 1e-9);
          EXPECT_GE(q.y(), -t - 1e-9);
          EXPECT_LE(q.y(), 1e-9);
          EXPECT_GE(q.z(), 0.0);
          EXPECT_LE(q.z(), d.height);
        }
        // The face on the swing side is flush with that wall face, or set back by the recess.
        double swing_face = into_room ? -1e9 : 1e9;
        for (const Eigen::Vector3d& c : boxCorners(leafOf(s, 0)))
          swing_face = into_room ? std::max(swing_face, inWall(s, 1, c).y()) : std::min(swing_face, inWall(s, 1, c).y());
        EXPECT_NEAR(swing_face, into_room ? -recess : -t + recess, 1e-9);
        EXPECT_EQ(s.doors[0].state(), "closed");
      }
}

TEST(Simulator, ScannedLeafPointsOfAClosedDoorLieInTheOpening) {
  const std::uint64_t seed = 7;
  SCOPED_TRACE(seedTrace(seed));
  const Scene s = buildScene(oneDoorRoom(0.0, true, false, 0.02));
  TlsOptions o;
  o.points = 200000;
  o.seed = seed;
  const SimulatedCloud c = scanTls(s, o);
  const DoorSpec& d = s.spec.doors[0];
  int leaf_points = 0;
  for (const auto& p : c.cloud) {
    if (p.label != static_cast<std::uint32_t>(Surface::Leaf)) continue;
    ++leaf_points;
    const Eigen::Vector3d q = inWall(s, 1, c.sensor_to_world * Eigen::Vector3d(p.x, p.y, p.z));
    EXPECT_GT(q.x(), d.center - d.width / 2 - 0.02);
    EXPECT_LT(q.x(), d.center + d.width / 2 + 0.02);
    EXPECT_GT(q.y(), -s.spec.wall_thickness - 0.02);
    EXPECT_LT(q.y(), 0.02);
  }
  EXPECT_GT(leaf_points, 200);
}

TEST(Simulator, DoorAtNinetyDegreesIsPerpendicularToItsWall) {
  for (bool hinge_left : {true, false})
    for (bool into_room : {true, false}) {
      SCOPED_TRACE(::testing::Message() << "hinge_left=" << hinge_left << " into_room=" << into_room);
      const Scene s = buildScene(oneDoorRoom(90.0, hinge_left, into_room, 0.0));
      const DoorTruth& g = s.doors[0];
      const Eigen::Vector3d along_leaf = (g.leaf_corners[1] - g.leaf_corners[0]).normalized();
      EXPECT_NEAR(along_leaf.dot(s.walls[1].axis), 0.0, 1e-9);
      EXPECT_NEAR(along_leaf.dot(g.wall_normal), 1.0, 1e-9);  // sticks out to its swing side
      EXPECT_EQ(g.state(), "open");
      if (!into_room) continue;  // the scanner sees only leaves in its own room well
      TlsOptions o;
      o.points = 300000;
      o.seed = 11;
      const SimulatedCloud c = scanTls(s, o);
      std::vector<Eigen::Vector3d> pts;
      for (const auto& p : c.cloud)
        if (p.label == static_cast<std::uint32_t>(Surface::Leaf)) pts.push_back(c.sensor_to_world * Eigen::Vector3d(p.x, p.y, p.z));
      ASSERT_GT(pts.size(), 200u);
      EXPECT_LT(std::abs(planeNormal(pts).dot(s.walls[1].normal)), 0.03);
    }
}

TEST(Simulator, HandlesSitAtTheLatchEdgeOneMetreUpOnBothFaces) {
  // Every way round and at any angle: two handle boxes per leaf, centred
  // 1 m above the floor, 11 cm from the leaf's latch edge along it, 3 cm
  // off each face of the leaf. (The leaf's own third axis points down for
  // half the doors.) None without handles.
  for (const bool hinge_left : {true, false})
    for (const bool into_room : {true, false})
      for (const double angle : {0.0, 40.0, 110.0})
        for (const double height : {2.05, 2.15}) {
          RoomSpec r = oneDoorRoom(angle, hinge_left, into_room, 0.0);
          r.doors[0].height = height;
          const Scene s = buildScene(r);
          const DoorTruth& d = s.doors[0];
          const Eigen::Vector3d latch = d.leaf_corners[1], along = (d.leaf_corners[1] - d.leaf_corners[0]).normalized();
          const Eigen::Vector3d face = along.cross(Eigen::Vector3d::UnitZ());
          int handles = 0;
          for (const Box& b : s.boxes) {
            if (b.surface != Surface::Handle) continue;
            ++handles;
            EXPECT_EQ(b.owner, 0);
            const Eigen::Vector3d c = b.pose.translation();
            SCOPED_TRACE(::testing::Message() << "hinge_left=" << hinge_left << " into_room=" << into_room
                                              << " angle=" << angle << " height=" << height);
            EXPECT_NEAR(c.z(), 1.0, 1e-9);
            EXPECT_NEAR((latch - c).dot(along), 0.11, 0.01);
            EXPECT_NEAR(std::abs((c - latch).dot(face)), r.leaf_thickness / 2 + 0.03, 1e-9);
          }
          EXPECT_EQ(handles, 2);
          r.handles = false;
          const Scene bare = buildScene(r);
          EXPECT_TRUE(std::none_of(bare.boxes.begin(), bare.boxes.end(), [](const Box& b) { return b.surface == Surface::Handle; }));
        }
}

TEST(Simulator, OpeningAngleRotatesTheLeafAboutTheHinge) {
  for (double angle : {0.0, 30.0, 110.0, 180.0}) {
    const Scene s = buildScene(oneDoorRoom(angle, false, true, 0.0));
    const DoorTruth& g = s.doors[0];
    const Eigen::Vector3d closed_dir = -s.walls[1].axis;  // right hinge: towards -u
    const Eigen::Vector3d leaf_dir = (g.leaf_corners[1] - g.leaf_corners[0]).normalized();
    EXPECT_NEAR(std::acos(std::max(-1.0, std::min(1.0, leaf_dir.dot(closed_dir)))) * 180 / M_PI, angle, 1e-6);
    EXPECT_GE(leaf_dir.dot(g.wall_normal), -1e-9);  // never swings through the wall
  }
}

TEST(Simulator, StatesFollowTheThresholds) {
  DoorTruth d;
  d.angle_deg = 4.99;
  EXPECT_EQ(d.state(), "closed");
  d.angle_deg = 5.0;
  EXPECT_EQ(d.state(), "semi_open");
  d.angle_deg = 89.9;
  EXPECT_EQ(d.state(), "semi_open");
  d.angle_deg = 90.0;
  EXPECT_EQ(d.state(), "open");
}

TEST(Simulator, RgbdFrameFollowsThePinholeModel) {
  for (std::uint64_t seed : {3ull, 8ull, 21ull}) {
    SCOPED_TRACE(seedTrace(seed));
    const Scene s = buildScene(randomRoom(seed));
    RgbdOptions o;
    o.seed = seed;
    const SimulatedCloud c = captureRgbd(s, o);
    ASSERT_EQ(c.cloud.width, 640u);
    ASSERT_EQ(c.cloud.height, 480u);
    std::size_t finite = 0, ceiling = 0;
    for (std::uint32_t v = 0; v < c.cloud.height; ++v)
      for (std::uint32_t u = 0; u < c.cloud.width; ++u) {
        const auto& p = c.cloud.at(u, v);
        if (!std::isfinite(p.z)) continue;
        ++finite;
        ceiling += p.label == static_cast<std::uint32_t>(Surface::Ceiling);
        ASSERT_GE(p.z, o.min_range * 0.95);
        ASSERT_LE(p.z, o.max_range * 1.05);
        ASSERT_NEAR(o.fx * p.x / p.z + o.cx, u, 1e-2) << "u=" << u << " v=" << v;
        ASSERT_NEAR(o.fy * p.y / p.z + o.cy, v, 1e-2) << "u=" << u << " v=" << v;
      }
    EXPECT_GT(finite, 640u * 480u / 3);
    EXPECT_LT(finite, 640u * 480u);  // dropout and out-of-range returns are missing
    EXPECT_EQ(ceiling, 0u);
    // Optical frame: up is roughly -y.
    const Eigen::Vector3d up = c.sensor_to_world.linear().transpose() * Eigen::Vector3d::UnitZ();
    EXPECT_LT(up.y(), -0.8);
  }
}

TEST(Simulator, DepthNoiseGrowsWithRange) {
  // The same frame with and without noise: the depth residuals follow
  // sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2, small near, large far.
  const std::uint64_t seed = 12;
  SCOPED_TRACE(seedTrace(seed));
  const Scene s = buildScene(randomRoom(seed));
  RgbdOptions o;
  o.seed = seed;
  o.dropout = 0;
  o.noise = true;
  const SimulatedCloud noisy = captureRgbd(s, o);
  o.noise = false;
  const SimulatedCloud clean = captureRgbd(s, o);
  double sum[2] = {0, 0};
  std::size_t n[2] = {0, 0};
  for (std::size_t i = 0; i < clean.cloud.size(); ++i) {
    const double z = clean.cloud[i].z;
    if (!std::isfinite(z) || !std::isfinite(noisy.cloud[i].z)) continue;
    const int bucket = z < 2.0 ? 0 : (z > 3.0 && z < 4.5 ? 1 : -1);
    if (bucket < 0) continue;
    sum[bucket] += std::pow(noisy.cloud[i].z - z, 2);
    ++n[bucket];
  }
  ASSERT_GT(n[0], 1000u);
  ASSERT_GT(n[1], 1000u);
  const double near_rms = std::sqrt(sum[0] / n[0]), far_rms = std::sqrt(sum[1] / n[1]);
  EXPECT_LT(near_rms, 0.0012 + 0.0019 * std::pow(2.0 - 0.4, 2));
  EXPECT_GT(far_rms, 0.0012 + 0.0019 * std::pow(3.0 - 0.4, 2) * 0.9);
  EXPECT_LT(far_rms, 0.0012 + 0.0019 * std::pow(4.5 - 0.4, 2));
}

// ----------------------------------------------------------------- camera families

namespace {

// A frame of room `seed` under `model`, looking at door `door` (-1: the
// seed's) from `dist` m (0: drawn).
SimulatedCloud familyFrame(std::uint64_t seed, DepthModel model, bool noise = true, double dark_fraction = 0.35,
                           double dist = 0, int door = 0) {
  const Scene s = buildScene(randomRoom(seed));
  RgbdOptions o;
  o.seed = seed;
  o.depth_model = model;
  o.noise = noise;
  o.dropout = 0;
  o.dark_fraction = dark_fraction;
  o.target_door = door;
  if (model == DepthModel::TimeOfFlight) o.max_range = 10;
  if (model == DepthModel::ActiveStereo) o.max_range = 8;
  if (dist > 0) o.door_distance = dist;
  return captureRgbd(s, o);
}

std::size_t countLabel(const SimulatedCloud& c, Surface s) {
  std::size_t n = 0;
  for (const auto& p : c.cloud)
    n += std::isfinite(p.z) && p.label == static_cast<std::uint32_t>(s);
  return n;
}

}  // namespace

TEST(CameraFamilies, StructuredLightDepthComesInDisparityStepsThatGrowWithRangeSquared) {
  // Kinect v1: z = f b / d with d in 1/8 px (f 580 px, b 7.5 cm): every depth
  // is such a step, and neighbouring values are z^2 q / (f b) apart.
  const double fb = 580.0 * 0.075, q = 1.0 / 8;
  for (std::uint64_t seed : {1000ull, 1004ull}) {
    SCOPED_TRACE(seedTrace(seed));
    // A frame 1.3 m from the door, and one 4 m from it.
    std::vector<double> near, far;
    for (const double dist : {1.3, 4.0}) {
      const SimulatedCloud c = familyFrame(seed, DepthModel::StructuredLight, true, 0.35, dist, -1);
      for (const auto& p : c.cloud) {
        if (!std::isfinite(p.z)) continue;
        const double steps = fb / p.z / q;
        ASSERT_NEAR(steps, std::round(steps), 1e-3) << "z=" << p.z;
        if (dist < 2 && p.z > 1.2 && p.z < 1.6) near.push_back(p.z);
        if (dist > 2 && p.z > 3.8 && p.z < 4.3) far.push_back(p.z);
      }
    }
    ASSERT_GT(near.size(), 500u);
    ASSERT_GT(far.size(), 500u);
    auto smallestGap = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      v.erase(std::unique(v.begin(), v.end(), [](double a, double b) { return std::abs(a - b) < 1e-5; }), v.end());
      double g = 1e9;
      for (std::size_t i = 1; i < v.size(); ++i) g = std::min(g, v[i] - v[i - 1]);
      return g;
    };
    const double g_near = smallestGap(near), g_far = smallestGap(far);
    EXPECT_NEAR(g_near, 1.2 * 1.2 * q / fb, 0.25 * 1.2 * 1.2 * q / fb);  // ~4 mm at 1.2 m
    EXPECT_GT(g_far, 3.8 * 3.8 * q / fb * 0.9);                             // >= 4 cm at 3.8 m
    EXPECT_GT(g_far, 6 * g_near);
  }
}

TEST(CameraFamilies, TimeOfFlightSmearsDepthEdgesIntoFlyingPixels) {
  // Where a leaf or a jamb stands before a farther surface, a pixel's
  // footprint sees both: its depth lies in the gap between its neighbours,
  // away from either. A camera measuring the centre ray alone has (almost)
  // none such.
  for (std::uint64_t seed : {1001ull, 1010ull, 1013ull}) {
    SCOPED_TRACE(seedTrace(seed));
    auto flying = [](const SimulatedCloud& c) {
      std::size_t n = 0;
      const int W = c.cloud.width, H = c.cloud.height;
      for (int v = 1; v + 1 < H; ++v)
        for (int u = 1; u + 1 < W; ++u) {
          const double z = c.cloud.at(u, v).z, a = c.cloud.at(u - 1, v).z, b = c.cloud.at(u + 1, v).z;
          if (!std::isfinite(z) || !std::isfinite(a) || !std::isfinite(b)) continue;
          const double lo = std::min(a, b), hi = std::max(a, b);
          n += hi - lo > 0.5 && z > lo + 0.1 && z < hi - 0.1;
        }
      return n;
    };
    const SimulatedCloud tof = familyFrame(seed, DepthModel::TimeOfFlight, false);
    const Scene s = buildScene(randomRoom(seed));
    RgbdOptions o;
    o.seed = seed;
    o.noise = false;
    o.dropout = 0;
    o.target_door = 0;
    o.max_range = 10;
    const SimulatedCloud centre = captureRgbd(s, o);
    const std::size_t n_tof = flying(tof), n_centre = flying(centre);
    EXPECT_GT(n_tof, 40u);
    EXPECT_LT(n_centre * 10, n_tof) << n_centre << " vs " << n_tof;
    // Range beyond the structured-light camera's 4.5 m, as far as 10 m.
    double z_max = 0;
    for (const auto& p : tof.cloud)
      if (std::isfinite(p.z)) z_max = std::max<double>(z_max, p.z);
    EXPECT_LE(z_max, 10.0 * 1.05);
  }
}

TEST(CameraFamilies, TimeOfFlightMeasuresFartherInConcaveCorners) {
  // Multipath: near the floor's junction with the wall the depth is biased
  // away from the camera by a few cm; in the middle of the wall not.
  const std::uint64_t seed = 1002;
  SCOPED_TRACE(seedTrace(seed));
  const SimulatedCloud tof = familyFrame(seed, DepthModel::TimeOfFlight, false);
  const Scene s = buildScene(randomRoom(seed));
  double corner = 0, middle = 0;
  std::size_t nc = 0, nm = 0;
  for (const auto& p : tof.cloud) {
    if (!std::isfinite(p.z) || p.label != static_cast<std::uint32_t>(Surface::Wall)) continue;
    const Eigen::Vector3d pc(p.x, p.y, p.z), pw = tof.sensor_to_world * pc;
    // The true range along the ray: cast it again.
    const Eigen::Vector3d o = tof.sensor_to_world.translation(), dir = (pw - o).normalized();
    const RayHit h = castRay(s, o, dir, 20);
    if (!h.hit || h.surface != Surface::Wall) continue;
    const double bias = (pw - o).norm() - h.t;
    if (pw.z() < 0.04) corner += bias, ++nc;
    if (pw.z() > 1.0 && pw.z() < 1.4) middle += bias, ++nm;
  }
  ASSERT_GT(nc, 20u);
  ASSERT_GT(nm, 200u);
  EXPECT_GT(corner / nc, 0.015);
  EXPECT_LT(std::abs(middle / nm), 0.005);
}

TEST(CameraFamilies, ActiveStereoErrorGrowsWithRangeSquared) {
  // RMS error = z^2 subpixel / (f b): the robust spread of depth errors at
  // 3.5-4.5 m is (4/1.5)^2 ~ 7 times that at 1-2 m.
  const std::uint64_t seed = 1005;
  SCOPED_TRACE(seedTrace(seed));
  std::vector<double> rel[2];  // error / z^2
  std::vector<double> err[2];
  for (const double dist : {1.4, 4.0}) {  // the door 1.4 m and 4 m away
    const SimulatedCloud noisy = familyFrame(seed, DepthModel::ActiveStereo, true, 0.0, dist, -1);
    const SimulatedCloud clean = familyFrame(seed, DepthModel::ActiveStereo, false, 0.0, dist, -1);
    for (std::size_t i = 0; i < clean.cloud.size(); ++i) {
    const double z = clean.cloud[i].z, zn = noisy.cloud[i].z;
    if (!std::isfinite(z) || !std::isfinite(zn)) continue;
    const int b = z >= 1.0 && z < 2.0 ? 0 : (z >= 3.5 && z < 4.5 ? 1 : -1);
    if (b < 0) continue;
    err[b].push_back(zn - z);
    rel[b].push_back((zn - z) / (z * z));
    }
  }
  auto robustSigma = [](std::vector<double> v) {
    for (double& x : v) x = std::abs(x);
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return 1.4826 * v[v.size() / 2];
  };
  ASSERT_GT(err[0].size(), 2000u);
  ASSERT_GT(err[1].size(), 2000u);
  const double s_near = robustSigma(err[0]), s_far = robustSigma(err[1]);
  EXPECT_GT(s_far / s_near, 4.0);
  // z^2-normalised, both ranges give the same spread, near 0.08 px / (f b).
  const double k_near = robustSigma(rel[0]), k_far = robustSigma(rel[1]), k = 0.08 / (525.0 * 0.05);
  EXPECT_NEAR(k_near / k_far, 1.0, 0.3);
  EXPECT_NEAR(k_far, k, 0.4 * k);
}

TEST(CameraFamilies, DarkLeavesLoseTheirReturnsToStereoAndStructuredLight) {
  // The same frames with every leaf and furniture piece dark, and none:
  // dark leaves keep under 70% of their returns, walls keep all of theirs.
  for (const DepthModel m : {DepthModel::ActiveStereo, DepthModel::StructuredLight})
    for (std::uint64_t seed : {1003ull, 1017ull}) {
      SCOPED_TRACE(seedTrace(seed) + " model=" + toString(m));
      const SimulatedCloud dark = familyFrame(seed, m, true, 1.0), light = familyFrame(seed, m, true, 0.0);
      const std::size_t leaf_dark = countLabel(dark, Surface::Leaf), leaf_light = countLabel(light, Surface::Leaf);
      ASSERT_GT(leaf_light, 2000u);
      EXPECT_LT(leaf_dark, 0.7 * leaf_light);
      EXPECT_EQ(countLabel(dark, Surface::Wall), countLabel(light, Surface::Wall));
    }
}

TEST(CameraFamilies, TriangulatingCamerasLoseTheShadowOfTheirBaselineBesideDepthEdges) {
  // No structured-light return where the projector, 7.5 cm to the camera's
  // right, cannot light the point: pixels just left of a foreground edge.
  const std::uint64_t seed = 1001;
  SCOPED_TRACE(seedTrace(seed));
  const SimulatedCloud sl = familyFrame(seed, DepthModel::StructuredLight, false, 0.0);
  const SimulatedCloud tof = familyFrame(seed, DepthModel::TimeOfFlight, false, 0.0);
  std::size_t missing_sl = 0, missing_tof = 0;
  for (std::size_t i = 0; i < sl.cloud.size(); ++i) {
    missing_sl += !std::isfinite(sl.cloud[i].z) && std::isfinite(tof.cloud[i].z) && tof.cloud[i].z < 4.4;
    missing_tof += std::isfinite(sl.cloud[i].z) && !std::isfinite(tof.cloud[i].z);
  }
  EXPECT_GT(missing_sl, 200u);
  EXPECT_LT(missing_tof, missing_sl / 10);
}

TEST(CameraFamilies, PoseOptionsAreHonouredAndRobotPosesStayInTheirRanges) {
  const Scene s = buildScene(randomRoom(1007));
  RgbdOptions o;
  o.seed = 1007;
  o.camera_height = 0.35;
  o.pitch_deg = 8.0;
  o.roll_deg = -4.0;
  o.door_distance = 2.0;
  o.target_door = 0;
  const SimulatedCloud c = captureRgbd(s, o);
  const Eigen::Matrix3d R = c.sensor_to_world.linear();
  EXPECT_NEAR(c.sensor_to_world.translation().z(), 0.35, 1e-9);
  EXPECT_NEAR(std::asin(R.col(2).z()) * 180 / M_PI, 8.0, 1e-6);
  // Roll: the image's x axis tilts out of the horizontal by the roll.
  EXPECT_NEAR(std::abs(std::asin(R.col(0).z())) * 180 / M_PI, 4.0, 0.1);
  const DoorTruth& d = s.doors[0];
  const Eigen::Vector3d face = d.opening_center + s.walls[d.wall].normal * (s.spec.wall_thickness / 2);
  EXPECT_NEAR((c.sensor_to_world.translation() - face).dot(s.walls[d.wall].normal), 2.0, 1e-9);
  EXPECT_THROW(
      {
        RgbdOptions bad;
        bad.pitch_deg = 80;
        captureRgbd(s, bad);
      },
      std::invalid_argument);
  for (std::uint64_t seed = 1000; seed < 1020; ++seed) {
    SCOPED_TRACE(seedTrace(seed));
    const Scene sc = buildScene(randomRoom(seed));
    RgbdOptions r;
    r.seed = seed;
    r.robot_camera = true;
    r.depth_model = DepthModel::TimeOfFlight;
    const SimulatedCloud f = captureRgbd(sc, r);
    const Eigen::Matrix3d Rf = f.sensor_to_world.linear();
    const double h = f.sensor_to_world.translation().z(), pitch = std::asin(Rf.col(2).z()) * 180 / M_PI;
    EXPECT_GE(h, 0.3);
    EXPECT_LE(h, 1.6);
    EXPECT_GE(pitch, -20.0 - 1e-9);
    EXPECT_LE(pitch, 10.0 + 1e-9);
    EXPECT_LE(std::abs(std::asin(Rf.col(0).z())) * 180 / M_PI, 5.0 + 1e-6);
  }
}

TEST(Simulator, RandomRoomsBuildAndHoldWhatTheyPromise) {
  for (std::uint64_t seed = 100; seed < 160; ++seed) {
    SCOPED_TRACE(seedTrace(seed));
    const RoomSpec r = randomRoom(seed);
    Scene s;
    ASSERT_NO_THROW(s = buildScene(r));
    EXPECT_GE(s.doors.size(), 1u);
    EXPECT_LE(s.doors.size(), 3u);
    int tall = 0;
    for (const DecoyTruth& d : s.decoys) tall += (d.kind == "cupboard" || d.kind == "wardrobe") && d.height >= 1.85;
    EXPECT_GE(tall, 1);
    // No furniture inside a leaf's swing or a doorway: leaf corners are clear of furniture boxes.
    for (std::size_t i = 0; i < s.doors.size(); ++i)
      for (const Box& b : s.boxes)
        if (b.surface == Surface::Furniture)
          for (const auto& c : boxCorners(leafOf(s, static_cast<int>(i)))) EXPECT_FALSE(b.contains(c)) << "door " << i;
  }
}

TEST(Simulator, SeveralDoorsPerWallAndAdjacentRoomVisible) {
  const Scene s = buildScene(paperRoom("paper_multidoor"));
  ASSERT_EQ(s.doors.size(), 2u);
  EXPECT_EQ(s.doors[0].wall, s.doors[1].wall);
  TlsOptions o;
  o.points = 200000;
  const SimulatedCloud c = scanTls(s, o);
  std::size_t adjacent = 0;
  for (const auto& p : c.cloud) adjacent += p.label == static_cast<std::uint32_t>(Surface::Adjacent);
  EXPECT_GT(adjacent, 50u);  // seen through the ajar doors
}

TEST(Simulator, RejectsImpossibleScenes) {
  RoomSpec r = oneDoorRoom(0, true, true, 0);
  r.doors[0].center = 10;  // outside its wall
  EXPECT_THROW(buildScene(r), std::invalid_argument);
  r = oneDoorRoom(200, true, true, 0);
  EXPECT_THROW(buildScene(r), std::invalid_argument);
  r = oneDoorRoom(0, true, true, 0);
  r.doors.push_back(r.doors[0]);  // same place twice
  EXPECT_THROW(buildScene(r), std::invalid_argument);
  r = oneDoorRoom(0, true, true, 0);
  r.doors[0].height = 3.0;  // taller than the room
  EXPECT_THROW(buildScene(r), std::invalid_argument);
  r = oneDoorRoom(0, true, true, 0.5);  // recess deeper than the wall
  EXPECT_THROW(buildScene(r), std::invalid_argument);
  TlsOptions o;
  o.points = 10;
  EXPECT_THROW(scanTls(buildScene(oneDoorRoom(0, true, true, 0)), o), std::invalid_argument);
}

TEST(Simulator, RayCastMeetsTheWallAtItsDistance) {
  RoomSpec r;
  r.width = 6;
  r.depth = 4;
  r.height = 2.5;
  const Scene s = buildScene(r);
  const RayHit h = castRay(s, Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 0), 100);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.t, 3.0, 1e-9);
  EXPECT_EQ(h.surface, Surface::Wall);
  EXPECT_NEAR(h.normal.x(), -1.0, 1e-9);
  const RayHit up = castRay(s, Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, 1), 100);
  EXPECT_NEAR(up.t, 1.5, 1e-9);
  EXPECT_EQ(up.surface, Surface::Ceiling);
}

TEST(GroundTruth, IsExpressedInTheCloudFrame) {
  const std::uint64_t seed = 31;
  SCOPED_TRACE(seedTrace(seed));
  const Scene s = buildScene(randomRoom(seed));
  for (const std::string sensor : {"tls", "rgbd"}) {
    SimulatedCloud c;
    if (sensor == "tls") {
      TlsOptions o;
      o.points = 5000;
      o.seed = seed;
      c = scanTls(s, o);
    } else {
      RgbdOptions o;
      o.seed = seed;
      c = captureRgbd(s, o);
    }
    const nlohmann::json j = groundTruthJson(s, c);
    EXPECT_EQ(j["sensor"], sensor);
    ASSERT_EQ(j["doors"].size(), s.doors.size());
    for (std::size_t i = 0; i < s.doors.size(); ++i) {
      const auto& oc = j["doors"][i]["opening_center"];
      const Eigen::Vector3d back = c.sensor_to_world * Eigen::Vector3d(oc[0], oc[1], oc[2]);
      EXPECT_LT((back - s.doors[i].opening_center).norm(), 1e-9);
      EXPECT_EQ(j["doors"][i]["state"], s.doors[i].state());
    }
    const Eigen::Vector3d up(j["up"][0], j["up"][1], j["up"][2]);
    EXPECT_NEAR(up.norm(), 1.0, 1e-9);
    // The floor height along up matches the opening centre (on the floor).
    const auto& oc = j["doors"][0]["opening_center"];
    EXPECT_NEAR(up.dot(Eigen::Vector3d(oc[0], oc[1], oc[2])), j["floor"].get<double>(), 1e-9);
    if (sensor == "tls") EXPECT_NEAR(up.z(), 1.0, 1e-12);
  }
}
