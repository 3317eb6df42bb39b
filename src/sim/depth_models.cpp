// Depth error models of three RGB-D camera families, each from its published
// behaviour. The rays are those of sim::captureRgbd's pinhole camera; what
// differs is how a true range becomes a measured depth (or none).
//
// Structured light (Kinect v1-like). Depth is triangulated from the disparity
// of a projected IR pattern between projector and IR camera, baseline
// b = 7.5 cm, f = 580 px, disparity quantized to 1/8 px: z = f b / d, so the
// depth step is z^2 q / (f b) (3 mm at 1 m, 4.6 cm at 4 m) and a disparity
// noise of 0.07 px gives sigma(z) ~ z^2 (K. Khoshelham, S. O. Elberink,
// "Accuracy and resolution of Kinect depth data for indoor mapping
// applications", Sensors 12(2), 2012; the 0.07 px reproduces the sigma(z) of
// C. V. Nguyen, S. Izadi, D. Lovell, "Modeling Kinect sensor noise", 3DIMPVT
// 2012, which the default model uses). No depth where the projector's pattern
// cannot reach (its shadow beside depth edges, the projector 7.5 cm to the
// camera's right) nor on dark surfaces, which absorb the near-IR pattern
// (more often with range, as the pattern fades with z^2).
//
// Time of flight (Kinect v2 / Azure Kinect-like). Range from the phase of
// modulated light, measured per pixel: a pixel whose footprint spans a
// foreground and a background edge mixes both returns into a flying pixel
// between them (weighted by their amplitudes, ~ albedo / r^2); light bounced
// off one surface onto another lengthens the path in concave corners
// (multipath: a few cm at the corner, fading within ~25 cm); random noise
// ~ 0.5% of range, more on dark surfaces and towards the image border where
// the illumination falls off; returns to 8-12 m (H. Sarbolandi, D. Lefloch,
// A. Kolb, "Kinect range sensing: structured-light versus time-of-flight
// Kinect", CVIU 139, 2015; S. Fuchs, "Multipath interference compensation in
// time-of-flight camera images", ICPR 2010; Microsoft Azure Kinect DK
// hardware specification: random error <= 17 mm, systematic < 11 mm + 0.1%).
//
// Active stereo (RealSense D435-like). Two IR imagers 50 mm apart match a
// projected speckle pattern; the depth RMS error is z^2 * subpixel / (f b)
// with subpixel ~ 0.08 px (A. Grunnet-Jepsen, J. Sweetser, J. Woodfill,
// "Best-known-methods for tuning Intel RealSense D400 depth cameras for best
// performance", Intel white paper), half of it white and half a speckle field
// correlated over ~8 px (the matcher's window); a few mismatched pixels far
// off; no depth where the right imager cannot see the point (left of
// foreground edges), and holes in patches on dark or glossy surfaces, where
// the pattern is absorbed or mirrored away (same white paper).
#include "depth_models.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace dsr {
namespace sim {

DepthModel parseDepthModel(const std::string& name) {
  if (name == "default") return DepthModel::Default;
  if (name == "structured") return DepthModel::StructuredLight;
  if (name == "tof") return DepthModel::TimeOfFlight;
  if (name == "stereo") return DepthModel::ActiveStereo;
  throw std::invalid_argument("depth model must be default, structured, tof or stereo, not '" + name + "'");
}

const char* toString(DepthModel m) {
  switch (m) {
    case DepthModel::Default: return "default";
    case DepthModel::StructuredLight: return "structured";
    case DepthModel::TimeOfFlight: return "tof";
    case DepthModel::ActiveStereo: return "stereo";
  }
  return "default";
}

namespace detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Structured light (Kinect v1).
constexpr double kSlFocalPx = 580.0, kSlBaseline = 0.075, kSlStepPx = 1.0 / 8, kSlSigmaPx = 0.07;
// Time of flight.
constexpr double kTofAlbedoDark = 0.3, kTofMultipath = 0.03, kTofMultipathReach = 0.25;
// Active stereo (D435): baseline, white and speckle-field disparity noise.
constexpr double kStBaseline = 0.050, kStWhitePx = 0.06, kStSpecklePx = 0.06, kStSpeckleCell = 8.0,
                 kStMismatch = 0.001;

enum Stream : std::uint64_t { kPixel = 0x5E11, kDark = 0xDA2C, kBlock = 0xB10C, kSpeckle = 0x5BEC };

// Leaves and furniture are dark (or glossy) piece by piece, drawn by the seed.
bool darkPiece(const RgbdOptions& o, const RayHit& h) {
  if (h.surface != Surface::Leaf && h.surface != Surface::Furniture) return false;
  RayRandom r(o.seed, kDark + static_cast<std::uint64_t>(h.surface), static_cast<std::uint64_t>(h.owner + 1));
  return r.uniform() < o.dark_fraction;
}

// A uniform number shared by a block of 4 x 4 pixels: holes come in patches,
// as a pattern is lost over the matcher's window, not pixel by pixel.
double blockUniform(const RgbdOptions& o, int u, int v) {
  return RayRandom(o.seed, kBlock, static_cast<std::uint64_t>(v / 4) * 4096 + u / 4).uniform();
}

// A smooth random field (unit variance at its nodes), bilinear between nodes
// `cell` pixels apart: the speckle of a stereo matcher's correlation window.
double speckleField(const RgbdOptions& o, int u, int v, double cell) {
  const double x = u / cell, y = v / cell;
  const int i = static_cast<int>(x), j = static_cast<int>(y);
  const double a = x - i, b = y - j;
  auto node = [&](int ii, int jj) {
    return RayRandom(o.seed, kSpeckle, static_cast<std::uint64_t>(jj) * 65536 + ii).gaussian();
  };
  return (1 - a) * (1 - b) * node(i, j) + a * (1 - b) * node(i + 1, j) + (1 - a) * b * node(i, j + 1) +
         a * b * node(i + 1, j + 1);
}

// True when the point p (world) is hidden from an emitter or second imager
// at `from`: the shadow beside depth edges of triangulating cameras.
bool hiddenFrom(const RayCaster& cast, const Eigen::Vector3d& from, const Eigen::Vector3d& p) {
  const Eigen::Vector3d to = p - from;
  const double d = to.norm();
  return d > 0.01 && cast(from, to / d, d - 0.005).hit;
}

// Multipath of a time-of-flight camera: the extra path (m) of light bounced
// between the room's surfaces near a concave corner, for a point p (world)
// in the scanned room: largest at the junction of two of its planes (floor,
// ceiling, walls), fading within kTofMultipathReach of it.
double multipathBias(const Scene& scene, const Eigen::Vector3d& p, Surface s) {
  if (s == Surface::Adjacent || s == Surface::None) return 0.0;
  const Eigen::Vector3d q = scene.room_to_world.inverse() * p;
  const double hw = scene.spec.width / 2, hd = scene.spec.depth / 2;
  if (std::abs(q.x()) > hw + 0.05 || std::abs(q.y()) > hd + 0.05) return 0.0;  // beyond a doorway
  const double planes[6] = {q.z() - scene.floor_z, scene.ceiling_z - q.z(), hw - q.x(), hw + q.x(), hd - q.y(), hd + q.y()};
  // The plane the point lies on is no corner of its own: take the two nearest
  // and skip the nearest when the point is on it.
  double first = 1e9, second = 1e9;
  for (double d : planes) {
    const double a = std::abs(d);
    if (a < first) {
      second = first;
      first = a;
    } else if (a < second) {
      second = a;
    }
  }
  const double corner = first < 0.02 ? second : first;
  return kTofMultipath * std::exp(-corner / kTofMultipathReach);
}

}  // namespace

void renderDepthModel(const Scene& scene, const RgbdOptions& o, const Eigen::Isometry3d& camera_to_world,
                      const RayCaster& cast, pcl::PointCloud<pcl::PointXYZL>& cloud) {
  const int W = o.width, H = o.height;
  const std::size_t n = static_cast<std::size_t>(W) * H;
  const Eigen::Matrix3d R = camera_to_world.linear();
  const Eigen::Vector3d cam = camera_to_world.translation();
  const double cos_max = std::cos(o.max_incidence_deg * kPi / 180);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto rayCam = [&](double u, double v) { return Eigen::Vector3d((u - o.cx) / o.fx, (v - o.cy) / o.fy, 1.0); };

  // The centre ray of every pixel: the surface hit and its true depth (NaN:
  // nothing in range, too near, or too grazing to return).
  std::vector<RayHit> hit(n);
  std::vector<double> z_true(n, nan);
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * W + u;
      const Eigen::Vector3d rc = rayCam(u, v), dir = (R * rc).normalized();
      const RayHit h = cast(cam, dir, o.max_range * rc.norm());
      if (!h.hit) continue;
      const double z = h.t / rc.norm();
      if (z < o.min_range || std::abs(h.normal.dot(dir)) < cos_max) continue;
      hit[i] = h;
      z_true[i] = z;
    }

  cloud.width = W;
  cloud.height = H;
  cloud.is_dense = false;
  cloud.points.resize(n);
  const double rnorm2 = 1.0 / (o.cx * o.cx + o.cy * o.cy);
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * W + u;
      pcl::PointXYZL& q = cloud.points[i];
      q.x = q.y = q.z = static_cast<float>(nan);
      q.label = 0;
      RayRandom r(o.seed, kPixel, i);
      const Eigen::Vector3d rc = rayCam(u, v), dir = (R * rc).normalized();
      double z = z_true[i];
      RayHit h = hit[i];

      if (o.depth_model == DepthModel::TimeOfFlight) {
        // An edge pixel: a neighbour's return differs by more than the pixel's
        // footprint could explain, or one of the two has none.
        bool edge = false;
        const double tol = 0.04 + 0.02 * (std::isfinite(z) ? z : 0.0);
        const int du[4] = {1, -1, 0, 0}, dv[4] = {0, 0, 1, -1};
        for (int k = 0; k < 4 && !edge; ++k) {
          const int uu = u + du[k], vv = v + dv[k];
          if (uu < 0 || vv < 0 || uu >= W || vv >= H) continue;
          const double zn = z_true[static_cast<std::size_t>(vv) * W + uu];
          edge = std::isfinite(z) != std::isfinite(zn) || (std::isfinite(z) && std::abs(zn - z) > tol);
        }
        if (edge) {
          // The pixel's footprint in 3 x 3 sub-rays: the returns mix,
          // weighted by their amplitudes (albedo / range^2), into one range.
          double wsum = 0, rsum = 0, wbest = 0;
          for (int a = -1; a <= 1; ++a)
            for (int b = -1; b <= 1; ++b) {
              const Eigen::Vector3d rs = rayCam(u + a / 3.0, v + b / 3.0), ds = (R * rs).normalized();
              const RayHit hs = cast(cam, ds, o.max_range * rs.norm());
              if (!hs.hit || std::abs(hs.normal.dot(ds)) < cos_max) continue;
              const double w = (darkPiece(o, hs) ? kTofAlbedoDark : 1.0) / (hs.t * hs.t);
              wsum += w;
              rsum += w * hs.t;
              if (w > wbest) {
                wbest = w;
                if (!h.hit) h = hs;
              }
            }
          if (wsum <= 0) continue;
          z = rsum / wsum / rc.norm();
          if (z < o.min_range) continue;
        }
      }
      if (!std::isfinite(z)) continue;
      if (o.dropout > 0 && r.uniform() < o.dropout) continue;
      const bool dark = darkPiece(o, h);
      const Eigen::Vector3d p = cam + dir * (z * rc.norm());
      double zm = z;
      switch (o.depth_model) {
        case DepthModel::StructuredLight: {
          if (hiddenFrom(cast, cam + R.col(0) * kSlBaseline, p)) continue;  // the projector's shadow
          if (dark && blockUniform(o, u, v) < std::min(0.9, 0.2 + 0.15 * z)) continue;
          const double fb = kSlFocalPx * kSlBaseline;
          const double d = fb / z + (o.noise ? kSlSigmaPx * r.gaussian() : 0.0);
          const double dq = std::round(d / kSlStepPx) * kSlStepPx;
          if (dq < kSlStepPx) continue;
          zm = fb / dq;
          break;
        }
        case DepthModel::TimeOfFlight: {
          // Dark surfaces return too little light beyond a few metres.
          const double albedo = dark ? kTofAlbedoDark : 1.0;
          if (albedo / (z * z) < (0.5 + r.uniform()) / 144.0) continue;
          const double r2 = ((u - o.cx) * (u - o.cx) + (v - o.cy) * (v - o.cy)) * rnorm2;
          const double sigma = (0.002 + 0.004 * z) * (dark ? 1.8 : 1.0) * (1 + 0.5 * r2);
          const double range = z * rc.norm() + multipathBias(scene, p, h.surface) + (o.noise ? sigma * r.gaussian() : 0.0);
          zm = range / rc.norm();
          break;
        }
        case DepthModel::ActiveStereo: {
          if (hiddenFrom(cast, cam + R.col(0) * kStBaseline, p)) continue;  // the right imager's shadow
          if (dark && blockUniform(o, u, v) < std::min(0.95, 0.45 + 0.1 * z)) continue;
          const double fb = o.fx * kStBaseline;
          double d = fb / z;
          if (o.noise) {
            d += kStWhitePx * r.gaussian() + kStSpecklePx * speckleField(o, u, v, kStSpeckleCell);
            if (r.uniform() < kStMismatch) d += (r.uniform() < 0.5 ? -1 : 1) * (0.5 + 2.5 * r.uniform());
          }
          if (d < 0.5) continue;
          zm = fb / d;
          break;
        }
        case DepthModel::Default: break;
      }
      if (!(zm >= o.min_range)) continue;
      q.x = static_cast<float>(rc.x() * zm);
      q.y = static_cast<float>(rc.y() * zm);
      q.z = static_cast<float>(zm);
      q.label = static_cast<std::uint32_t>(h.surface);
    }
}

}  // namespace detail
}  // namespace sim
}  // namespace dsr
