#include "door_state_recognition/preprocess/levelling.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace dsr {
namespace preprocess {

std::optional<Eigen::Vector3d> parseUpAxis(const std::string& a) {
  if (a == "auto") return std::nullopt;
  if (a.size() == 2 && (a[0] == '+' || a[0] == '-') && a[1] >= 'x' && a[1] <= 'z') {
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    v[a[1] - 'x'] = a[0] == '+' ? 1.0 : -1.0;
    return v;
  }
  throw std::invalid_argument("up axis must be one of +x -x +y -y +z -z auto, got '" + a + "'");
}

Eigen::Matrix3d levellingRotation(const Eigen::Vector3d& up) {
  return Eigen::Quaterniond::FromTwoVectors(up.normalized(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

namespace {

// The normals (x[i], y[i], z[i]), i < n, square to c or along it: |n.c| above
// 0.97 or below 0.05, n.c summed as Eigen sums a 3-vector's dot product
// (x cx + (y cy + z cz)), so bit for bit its value; many at a time (no FMA).
template <int kTag>
inline std::size_t squareCountBody(const float* x, const float* y, const float* z, std::size_t n, float cx, float cy,
                                   float cz) {
  unsigned s = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const float d = std::abs(x[i] * cx + (y[i] * cy + z[i] * cz));
    s += static_cast<unsigned>(d > 0.97f) + static_cast<unsigned>(d < 0.05f);
  }
  return s;
}
__attribute__((target("avx2"))) std::size_t squareCountAvx2(const float* x, const float* y, const float* z,
                                                             std::size_t n, float cx, float cy, float cz) {
  return squareCountBody<1>(x, y, z, n, cx, cy, cz);
}
std::size_t squareCount(const float* x, const float* y, const float* z, std::size_t n, const Eigen::Vector3f& c) {
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return squareCountAvx2(x, y, z, n, c.x(), c.y(), c.z());
  return squareCountBody<0>(x, y, z, n, c.x(), c.y(), c.z());
}

}  // namespace

std::optional<Eigen::Vector3d> estimateUp(const Points& points, const Points& normals, unsigned seed,
                                          const std::optional<Eigen::Vector3d>& upright) {
  if (points.size() < 50) return std::nullopt;
  // Candidate axes: a sample of normals, and cross products of pairs of them
  // (two walls give up even with no floor in view).
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
  std::vector<Eigen::Vector3f> cand;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3f& n = normals[pick(rng)];
    if (n.norm() > 0.5f) cand.push_back(n);  // isolated points have none
  }
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3f c = normals[pick(rng)].cross(normals[pick(rng)]);
    if (c.norm() > 0.5f) cand.push_back(c.normalized());
  }
  const std::size_t stride = std::max<std::size_t>(1, normals.size() / 20000);
  // The normals scored, as three arrays (read by every candidate).
  std::vector<float> sx, sy, sz;
  const std::size_t scored = (normals.size() + stride - 1) / stride;
  sx.reserve(scored), sy.reserve(scored), sz.reserve(scored);
  for (std::size_t i = 0; i < normals.size(); i += stride)
    sx.push_back(normals[i].x()), sy.push_back(normals[i].y()), sz.push_back(normals[i].z());
  auto score = [&](const Eigen::Vector3f& c) { return squareCount(sx.data(), sy.data(), sz.data(), sx.size(), c); };
  Eigen::Vector3f best = Eigen::Vector3f::UnitZ();
  std::size_t best_score = 0;
  std::vector<std::size_t> scores(cand.size());
  for (std::size_t k = 0; k < cand.size(); ++k) {
    scores[k] = score(cand[k]);
    if (scores[k] > best_score) {
      best_score = scores[k];
      best = cand[k];
    }
  }
  const bool has_upright = upright && upright->allFinite() && upright->norm() > 0;
  if (best_score < normals.size() / stride / 4) {
    // Too few normals square to any one axis (noisy or speckled depth): a
    // camera's upright image is the better guess, refined by the caller.
    if (has_upright) return upright->normalized();
    return std::nullopt;
  }
  // In a room of walls square to each other every one of its three axes
  // scores alike (each surface's normal is parallel or perpendicular to all
  // three): the best may be a wall's normal as well as up. A sensor's own
  // upright direction tells them apart where there is one: cameras are held
  // and mounted with the image upright (a robot's within its pitch, +-20
  // deg; a hand's within a few tens), never turned through 90 deg.
  if (has_upright) {
    const Eigen::Vector3f u = upright->normalized().cast<float>();
    // The room's second axis: the best candidate square to the first, or
    // else the upright direction made square to it.
    Eigen::Vector3f second = u - u.dot(best) * best;
    std::size_t second_score = 0;
    for (std::size_t k = 0; k < cand.size(); ++k)
      if (std::abs(cand[k].dot(best)) < 0.05f && scores[k] > second_score) {
        second_score = scores[k];
        second = cand[k];
      }
    second = (second - second.dot(best) * best).normalized();
    if (second.allFinite()) {
      const Eigen::Vector3f axes[3] = {best, second, best.cross(second)};
      const Eigen::Vector3f* nearest = &axes[0];
      for (const auto& a : axes)
        if (std::abs(a.dot(u)) > std::abs(nearest->dot(u))) nearest = &a;
      best = nearest->dot(u) >= 0 ? *nearest : Eigen::Vector3f(-*nearest);
    }
  }
  // Refine: average the normals of horizontal points (sign-aligned) if any.
  Eigen::Vector3d acc = Eigen::Vector3d::Zero();
  for (const auto& n : normals)
    if (std::abs(n.dot(best)) > 0.97f) acc += (n.dot(best) > 0 ? n : Eigen::Vector3f(-n)).cast<double>();
  Eigen::Vector3d up = acc.norm() > 10 ? acc.normalized() : best.cast<double>().normalized();
  if (has_upright) return up.dot(*upright) >= 0 ? up : Eigen::Vector3d(-up);

  // Sign: furniture and clutter rest on the floor. Compare the mass of
  // non-planar points in the lower and upper thirds of the height range.
  std::vector<double> h;
  h.reserve(points.size());
  for (const auto& p : points) h.push_back(p.cast<double>().dot(up));
  std::vector<double> sorted = h;
  std::sort(sorted.begin(), sorted.end());
  const double lo = sorted[sorted.size() / 50], hi = sorted[sorted.size() - 1 - sorted.size() / 50];
  const double third = (hi - lo) / 3;
  std::size_t below = 0, above = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double d = std::abs(normals[i].cast<double>().dot(up));
    if (d > 0.9 || d < 0.1) continue;  // planes: floor, ceiling, walls
    below += h[i] < lo + third;
    above += h[i] > hi - third;
  }
  // Near-planar clutter is rare in empty scans: fall back on the horizontal
  // surfaces below vs above the sensor (the sensor sits nearer the floor
  // than most ceilings are tall, and cameras rarely see the ceiling).
  if (below + above < 200) {
    below = above = 0;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (std::abs(normals[i].cast<double>().dot(up)) > 0.97) (h[i] < 0 ? below : above)++;
  }
  if (above > below) up = -up;
  return up;
}

Eigen::Vector3d refineUp(const Eigen::Vector3d& up_in, const Points& normals, double max_deg) {
  const Eigen::Vector3d up = up_in.normalized();
  const double cos_max = std::cos(max_deg * M_PI / 180.0);
  // Horizontal surfaces: their mean normal, re-selected around the refined
  // axis in narrowing windows. The widest takes in the normals of other
  // surfaces' edges and of clutter, which pull the mean off; the narrower
  // keep the floor's and the ceiling's.
  Eigen::Vector3d current = up;
  bool horizontal = false;
  for (const double window : {max_deg, std::min(max_deg, 10.0), std::min(max_deg, 5.0), 3.0}) {
    const double cos_window = std::cos(window * M_PI / 180.0);
    Eigen::Vector3d acc = Eigen::Vector3d::Zero();
    std::size_t n = 0;
    for (const auto& nf : normals) {
      const Eigen::Vector3d nd = nf.cast<double>();
      const double c = nd.dot(current);
      if (std::abs(c) < cos_window) continue;
      acc += c > 0 ? nd : Eigen::Vector3d(-nd);
      ++n;
    }
    if (n < 200) break;
    current = acc.normalized();
    horizontal = true;
  }
  if (horizontal && current.dot(up) >= cos_max) return current;
  // Walls: up is the direction least present among vertical-surface normals.
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  std::size_t n = 0;
  for (const auto& nf : normals) {
    const Eigen::Vector3d nd = nf.cast<double>();
    if (std::abs(nd.dot(up)) > std::sin(max_deg * M_PI / 180.0)) continue;
    C += nd * nd.transpose();
    ++n;
  }
  if (n < 500) return up;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  Eigen::Vector3d v = es.eigenvectors().col(0);
  // Walls of one direction only (a camera facing one wall): up may lie
  // anywhere in their plane, and the least present direction is noise. The
  // given axis made square to their normal keeps what they tell (a camera's
  // pitch) and the rest (a turn about their normal) as given.
  if (es.eigenvalues()(1) < 0.1 * es.eigenvalues()(2)) {
    const Eigen::Vector3d wall = es.eigenvectors().col(2);
    v = (up - up.dot(wall) * wall).normalized();
  }
  if (v.dot(up) < 0) v = -v;
  return v.dot(up) >= cos_max ? v : up;
}

double squareShare(const Points& normals, const Eigen::Vector3d& up) {
  const Eigen::Vector3f u = up.normalized().cast<float>();
  const std::size_t stride = std::max<std::size_t>(1, normals.size() / 4000);
  std::size_t square = 0, seen = 0;
  for (std::size_t i = 0; i < normals.size(); i += stride) {
    if (normals[i].squaredNorm() < 0.25f) continue;
    const float d = std::abs(normals[i].dot(u));
    square += (d > 0.97f) + (d < 0.05f);
    ++seen;
  }
  return seen > 0 ? static_cast<double>(square) / static_cast<double>(seen) : 0.0;
}

namespace {
// Below this share of square normals, or where no floor was seen, a given
// axis is checked (a room seen with its own up: 0.07-0.95 over 240
// robot-camera frames of four depth families, LiDAR sweeps, laser and
// mesh rooms; cameras pitched 40 deg off the given axis, refined as far as
// it reaches: 0.03-0.09, most with no floor seen).
constexpr double kDoubtShare = 0.05;
// ... and contradicted where the estimate holds this many times more (and
// 0.3 of all at least): the 240 frames' estimates held at most 6.3 times
// their axis's share, and only within 7 deg of it.
constexpr double kDoubtRatio = 10.0, kDoubtMinShare = 0.3;
}  // namespace

std::optional<double> givenUpContradicted(const Points& points, const Points& normals, const Eigen::Vector3d& given,
                                          const Eigen::Vector3d& used, double max_deg, bool floor_seen,
                                          unsigned seed, const std::optional<Eigen::Vector3d>& upright) {
  const double share = squareShare(normals, used);
  if (share >= kDoubtShare && floor_seen) return std::nullopt;
  const std::optional<Eigen::Vector3d> est = estimateUp(points, normals, seed, upright);
  if (!est) return std::nullopt;
  const double est_share = squareShare(normals, *est);
  const double deg = std::acos(std::min(1.0, std::abs(est->normalized().dot(given.normalized())))) * 180.0 / M_PI;
  if (deg <= max_deg || est_share < kDoubtMinShare || est_share < kDoubtRatio * share) return std::nullopt;
  return deg;
}

Eigen::Vector3d nearestFrameAxis(const Eigen::Vector3d& dir, double max_deg) {
  const Eigen::Vector3d d = dir.normalized();
  Eigen::Index k = 0;
  d.cwiseAbs().maxCoeff(&k);
  const Eigen::Vector3d axis = Eigen::Vector3d::Unit(k) * (d[k] > 0 ? 1.0 : -1.0);
  return d.dot(axis) >= std::cos(max_deg * M_PI / 180.0) ? axis : d;
}
}  // namespace preprocess
}  // namespace dsr
