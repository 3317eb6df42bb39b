#include "door_state_recognition/state/door_state.hpp"
#include "door_state_recognition/util/floor.hpp"
#include "door_state_recognition/util/first_error.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>

namespace dsr {
namespace state {

Line2 fitLine(const std::vector<Eigen::Vector2d>& pts) {
  Line2 l;
  if (pts.empty()) return l;
  for (const auto& q : pts) l.point += q;
  l.point /= static_cast<double>(pts.size());
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  for (const auto& q : pts) C += (q - l.point) * (q - l.point).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  l.direction = es.eigenvectors().col(1).normalized();
  return l;
}

DoorStateKind classify(double angle_deg, const Parameters& p) {
  if (angle_deg < p.closed_below_deg) return DoorStateKind::Closed;
  if (angle_deg < p.open_from_deg) return DoorStateKind::SemiOpen;
  return DoorStateKind::Open;
}

namespace {

// atan2 in degrees to within 0.001 deg (a minimax polynomial on [0, 1]);
// the angle index widens every arc by kBearingSlackDeg to stay exact.
double fastAtan2Deg(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double mx = std::max(ax, ay);
  if (mx == 0) return 0;
  const double t = std::min(ax, ay) / mx, t2 = t * t;
  double a = t * (0.9998660 + t2 * (-0.3302995 + t2 * (0.1801410 + t2 * (-0.0851330 + 0.0208351 * t2))));
  if (ay > ax) a = M_PI / 2 - a;
  if (x < 0) a = M_PI - a;
  if (y < 0) a = -a;
  return a * (180 / M_PI);
}
constexpr double kBearingSlackDeg = 0.01;
// A ray is tested outright at this many angles needed or fewer, its arc not worked out.
constexpr int kOutrightAngles = 6;
// A leaf whose best hypothesis at the jambs holds points in fewer of its
// cells is sought with hinges outwards of them too.
constexpr double kRetryBelowCoverage = 0.5;
// A wall's face seen this densely (share of its 5 x 10 cm cells holding
// points) or more is sampled densely enough for the coverage thresholds as
// they stand (LeafFit::sampling).
constexpr double kDenseWallCover = 0.9;

// An upper bound of asin(x), x in [0, 1], within 2% for x <= 0.5: asin's
// series x + x^3/6 + 3x^5/40 + ... has no coefficient above 1/6 after the
// first, so it is at most x + x^3 / (6 (1 - x^2)); capped at pi / 2. An arc
// widened by it holds every angle asin's would (the tests decide).
inline double asinAbove(double x) {
  if (x >= 1) return M_PI / 2;
  return std::min(M_PI / 2, x + x * x * x / (6 * (1 - x * x)));
}

// f(0) ... f(n - 1) as OpenMP tasks: run by the threads of the enclosing
// parallel region as they come free (findDoors runs doorways over the cores,
// so one doorway's search is shared by a core left idle), or in turn outside
// one. The first exception thrown is rethrown here.
template <class F>
void forEachTask(std::size_t n, const F& f) {
  util::FirstError error;
#pragma omp taskloop grainsize(1) shared(error, f)
  for (long long i = 0; i < static_cast<long long>(n); ++i) error.run([&] { f(static_cast<std::size_t>(i)); });
  error.rethrow();
}

// Where a sensor ray from v (height vz) along r (rising dz over its length)
// crosses the line P + a e of a leaf's mid-plane: a along the leaf and the
// height z; false when it does not, or only past lam_max of its length.
inline bool crossLeaf(const Eigen::Vector2d& v, const Eigen::Vector2d& r, double vz, double dz, double lam_max,
                      const Eigen::Vector2d& P, const Eigen::Vector2d& e, double& a, double& z) {
  const double denom = r.x() * e.y() - r.y() * e.x();
  if (std::abs(denom) < 1e-9) return false;
  const Eigen::Vector2d w = P - v;
  const double lam = (w.x() * e.y() - w.y() * e.x()) / denom;
  a = (w.x() * r.y() - w.y() * r.x()) / denom;
  if (lam <= 0 || lam > lam_max) return false;
  z = vz + lam * dz;
  return true;
}

// Free space as a range image: the nearest return in each bin of bearing and
// elevation seen from the sensor (in wall coordinates: s along, d towards
// the viewer). A surface at a point nearer than the nearest return of the
// point's bin (by more than kFreeMargin) would have been seen there instead:
// the point is free. Unlike counting the rays that cross a leaf, this rules
// out a leaf seen edge-on, which few rays cross though every bin it would
// fill shows the wall or the room beyond it.
constexpr double kRangeBinDeg = 0.5, kFreeMargin = 0.06;
class RangeImage {
 public:
  RangeImage(const Eigen::Vector2d& v, double vz, double az0) : v_(v), vz_(vz), az0_(az0) {
    near_.assign(static_cast<std::size_t>(kAz) * kEl, std::numeric_limits<float>::infinity());
  }
  void add(const Eigen::Vector2d& q, double qz) {
    double r;
    const int b = bin(q, qz, r);
    if (b >= 0) near_[b] = std::min(near_[b], static_cast<float>(r));
  }
  // The point is free: its bin holds a return farther than it by kFreeMargin.
  bool free(const Eigen::Vector2d& q, double qz) const {
    double r;
    const int b = bin(q, qz, r);
    return b >= 0 && std::isfinite(near_[b]) && near_[b] > r + kFreeMargin;
  }

 private:
  static constexpr int kAz = static_cast<int>(360 / kRangeBinDeg), kEl = static_cast<int>(180 / kRangeBinDeg);
  int bin(const Eigen::Vector2d& q, double qz, double& range) const {
    const Eigen::Vector2d r = q - v_;
    const double h = r.norm(), dz = qz - vz_;
    range = std::hypot(h, dz);
    if (range < 1e-6) return -1;
    double az = std::atan2(r.y(), r.x()) - az0_;  // relative to the doorway's bearing: no wrap near it
    if (az < -M_PI) az += 2 * M_PI;
    if (az >= M_PI) az -= 2 * M_PI;
    const double el = std::atan2(dz, h);
    const int a = std::clamp(static_cast<int>((az + M_PI) * 180 / M_PI / kRangeBinDeg), 0, kAz - 1);
    const int e = std::clamp(static_cast<int>((el + M_PI / 2) * 180 / M_PI / kRangeBinDeg), 0, kEl - 1);
    return e * kAz + a;
  }
  Eigen::Vector2d v_;
  double vz_, az0_;
  std::vector<float> near_;
};

struct Local {  // a point in wall coordinates: s along, d towards the viewer
  double s, d;
  int zbin, index;
};

}  // namespace

LeafFit fitLeaf(const segmentation::Points& points, const segmentation::WallPlane& wall,
                const recognition::Doorway& door, double floor_z, double t, const Eigen::Vector3f& viewpoint,
                const Parameters& p, double closed_band_only_above, const segmentation::ViewTop* view) {
  LeafFit fit;
  const double w = door.width(), L = std::max(0.1, w - 0.008), lt = p.leaf_thickness, tol = p.leaf_tolerance;
  const double z0 = floor_z + 0.25;
  const double z1 = floor_z + std::min(1.75, (std::isfinite(door.top) ? door.top - floor_z : 2.0) - 0.1);
  const double zbin = 0.1, abin = 0.05;
  const int nz = std::max(1, static_cast<int>((z1 - z0) / zbin));
  const double s_mid = (door.s0 + door.s1) / 2, reach = w + 0.25;
  // A leaf may be longer than the doorway seen (a leaf ajar hides its own
  // doorway): hypotheses reach up to the widest door from either jamb.
  const double Lmax = door.paired ? L + 0.05 : std::max(L, p.door_max_width), reach_h = Lmax + 0.15;
  // std::hypot(x, y) <= reach_h, calling hypot only where the squares are too close to tell.
  const double reach_h2 = reach_h * reach_h;
  auto withinReach = [&](double x, double y) {
    if (std::abs(x) > reach_h) return false;  // hypot(x, y) >= |x|
    const double r2 = x * x + y * y;
    if (r2 < reach_h2 * (1 - 1e-9)) return true;
    if (r2 > reach_h2 * (1 + 1e-9)) return false;
    return std::hypot(x, y) <= reach_h;
  };
  auto nearJamb = [&](double s, double d) {
    if (std::abs(d + t / 2) > reach_h) return false;
    return withinReach(s - door.s0, d + t / 2) || withinReach(s - door.s1, d + t / 2);
  };

  // The points near the doorway (and those in the wall band inside it), and
  // the rays passing near it: two passes over every point, independent, so
  // run at once when both are needed (one is not when the band's points
  // alone can end the search, below).
  std::vector<Local> pts, band;
  // The wall's face beside the doorway, 0.15-0.6 m beyond each jamb: its
  // cells holding points (see LeafFit::sampling). Not in a camera frame.
  constexpr double kSideFrom = 0.15, kSideTo = 0.6;
  const int side_cols = static_cast<int>(std::lround((kSideTo - kSideFrom) / abin));
  std::vector<char> side_cells(view ? 0 : static_cast<std::size_t>(2 * side_cols * nz), 0);
  auto gatherPoints = [&] {
    // Lists of this task's own, moved out when done (see gatherRayPart).
    std::vector<Local> near, in_band;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto& q = points[i];
      if (q.z() < z0 || q.z() >= z1) continue;
      const double s = wall.along(q), d = wall.signedDistance(q);
      if (!side_cells.empty() && std::abs(d) <= p.face_tolerance) {
        const double out0 = door.s0 - s, out1 = s - door.s1;  // beyond each jamb
        const int side = out0 >= kSideFrom && out0 < kSideTo ? 0 : out1 >= kSideFrom && out1 < kSideTo ? 1 : -1;
        if (side >= 0) {
          const int col = std::min(side_cols - 1, static_cast<int>(((side == 0 ? out0 : out1) - kSideFrom) / abin));
          const int zb = std::min(nz - 1, static_cast<int>((q.z() - z0) / zbin));
          side_cells[(static_cast<std::size_t>(side) * side_cols + col) * nz + zb] = 1;
        }
      }
      if (!nearJamb(s, d)) continue;
      const int zb = std::min(nz - 1, static_cast<int>((q.z() - z0) / zbin));
      const bool inside = s > door.s0 + 0.03 && s < door.s1 - 0.03;
      const bool in_wall_band = d > -t - 0.03 && d < p.face_tolerance + 0.01;
      // A closed leaf may sit deeper than the estimated thickness (jambs unseen).
      if (inside && d > -std::max(t, 0.3) - 0.03 && d < p.face_tolerance + 0.01) in_band.push_back({s, d, zb, static_cast<int>(i)});
      if (in_wall_band && !inside) continue;  // wall, trim and jambs beside the doorway
      near.push_back({s, d, zb, static_cast<int>(i)});
    }
    pts.swap(near);
    band.swap(in_band);
  };

  // Rays from the sensor that pass near the doorway: a leaf cannot stand
  // where a ray went through to something farther away (free space).
  // Every ray starts at the sensor, (s, d) = vsd at height vsz: a ray holds
  // only its end (the searches read every ray at every hinge; a compact ray
  // spares the memory traffic).
  struct Ray {
    Eigen::Vector2d q;  // (s, d) of the point
    double qz, len;
  };
  std::vector<Ray> rays;
  const Eigen::Vector2d vsd(wall.along(viewpoint), wall.signedDistance(viewpoint));
  const double vsz = viewpoint.z();
  const Eigen::Vector2d dc(s_mid, -t / 2);
  // A return whose ray from the sensor passes near the doorway: its (s, d)
  // and the ray's squared length in the wall's plan.
  auto nearDoorway = [&](const Eigen::Vector3f& q, Eigen::Vector2d& qsd, double& len2) {
    qsd = Eigen::Vector2d(wall.along(q), wall.signedDistance(q));
    const Eigen::Vector2d r = qsd - vsd;
    len2 = r.squaredNorm();
    if (len2 < 1e-6) return false;
    const double lam = std::clamp((dc - vsd).dot(r) / len2, 0.0, 1.0);
    return !((vsd + lam * r - dc).norm() > reach + Lmax);
  };
  // The rays in kRayParts parts of the points (tasks), joined in order.
  constexpr int kRayParts = 5;
  std::vector<std::vector<Ray>> ray_parts(kRayParts);
  // Each part (and the points' pass) fills lists of its own task, moved out
  // when done: the ends of lists side by side, written at every ray, would
  // share cache lines between the cores (false sharing).
  auto gatherRayPart = [&](int k) {
    const std::size_t i0 = points.size() * k / kRayParts, i1 = points.size() * (k + 1) / kRayParts;
    std::vector<Ray> part;
    part.reserve(i1 - i0);  // only what is used is touched
    for (std::size_t i = i0; i < i1; ++i) {
      const auto& q = points[i];
      Eigen::Vector2d qsd;
      double len2;
      if (nearDoorway(q, qsd, len2)) part.push_back({qsd, q.z(), std::sqrt(len2)});
    }
    ray_parts[k].swap(part);
  };
  // Joined, every stride-th kept: enough rays to see free space at 5 cm x
  // 10 cm cells; more only cost time.
  auto joinRays = [&] {
    std::size_t total = 0;
    for (const auto& part : ray_parts) total += part.size();
    const std::size_t stride = total > 15000 ? (total + 14999) / 15000 : 1;
    rays.reserve((total + stride - 1) / stride);
    std::size_t at = 0;  // index in the joined list of the part's first ray
    for (auto& part : ray_parts) {
      for (std::size_t i = (stride - at % stride) % stride; i < part.size(); i += stride) rays.push_back(part[i]);
      at += part.size();
      std::vector<Ray>().swap(part);
    }
  };
  const bool rays_needed = closed_band_only_above <= 0;
  if (rays_needed) {
    forEachTask(1 + kRayParts, [&](std::size_t i) { i == 0 ? gatherPoints() : gatherRayPart(static_cast<int>(i) - 1); });
    joinRays();
  } else {
    gatherPoints();
  }

  // A closed leaf anywhere inside the wall's thickness (flush or recessed).
  // Its cells holding points: (leaf bin, z bin) pairs, counted once each.
  const double expected = static_cast<double>(std::max(1, static_cast<int>(std::ceil(L / abin)))) * nz;
  std::vector<std::pair<int, int>> band_cells;
  std::vector<Eigen::Vector2d> band_xy;
  for (const Local& q : band) {
    band_cells.push_back({static_cast<int>((q.s - door.s0) / abin), q.zbin});
    band_xy.emplace_back(q.s, q.d);
  }
  // How many distinct cells: marked on a map over the cells' range (or,
  // were it large, by sorting).
  std::size_t band_distinct = 0;
  if (!band_cells.empty()) {
    int a_lo = band_cells.front().first, a_hi = a_lo, z_lo = band_cells.front().second, z_hi = z_lo;
    for (const auto& c : band_cells) {
      a_lo = std::min(a_lo, c.first), a_hi = std::max(a_hi, c.first);
      z_lo = std::min(z_lo, c.second), z_hi = std::max(z_hi, c.second);
    }
    const double span = (static_cast<double>(a_hi) - a_lo + 1) * (static_cast<double>(z_hi) - z_lo + 1);
    if (span <= 4.0 * static_cast<double>(band_cells.size()) + 4096) {
      const std::size_t zn = static_cast<std::size_t>(z_hi - z_lo + 1);
      std::vector<char> mark(static_cast<std::size_t>(span), 0);
      for (const auto& c : band_cells) {
        char& m = mark[static_cast<std::size_t>(c.first - a_lo) * zn + static_cast<std::size_t>(c.second - z_lo)];
        band_distinct += !m;
        m = 1;
      }
    } else {
      std::sort(band_cells.begin(), band_cells.end());
      band_distinct = static_cast<std::size_t>(std::unique(band_cells.begin(), band_cells.end()) - band_cells.begin());
    }
  }
  const double band_cov = std::min(1.0, band_distinct / expected);
  if (!side_cells.empty()) {
    double best_side = -1;
    for (int side = 0; side < 2; ++side) {
      int cols_on_wall = 0, held = 0;
      for (int col = 0; col < side_cols; ++col) {
        const double out = kSideFrom + (col + 0.5) * abin, sc = side == 0 ? door.s0 - out : door.s1 + out;
        if (sc < wall.s_min || sc > wall.s_max) continue;
        ++cols_on_wall;
        for (int zb = 0; zb < nz; ++zb) held += side_cells[(static_cast<std::size_t>(side) * side_cols + col) * nz + zb];
      }
      // A side without a single point on its face was hidden (furniture in
      // front, a leaf's shadow), not sampled: it tells nothing.
      if (cols_on_wall >= side_cols / 2 && held > 0)
        best_side = std::max(best_side, static_cast<double>(held) / (cols_on_wall * nz));
    }
    if (best_side >= 0) fit.sampling = std::clamp(best_side / kDenseWallCover, 0.5, 1.0);
  }
  fit.candidate_points = static_cast<int>(pts.size());
  if (closed_band_only_above > 0 && band_cov <= closed_band_only_above) {
    fit.searched = false;
    fit.best_coverage = band_cov;
    return fit;
  }
  if (!rays_needed) {
    forEachTask(kRayParts, [&](std::size_t k) { gatherRayPart(static_cast<int>(k)); });
    joinRays();
  }

  // Exhaustive search over hinge side, swing side and angle: cells of the
  // leaf holding points (support) against cells rays went through (contradiction).
  const int na = std::max(1, static_cast<int>(std::ceil(L / abin)));
  const int na_max = std::max(na, static_cast<int>(std::ceil(Lmax / abin)));
  // With both trim legs seen the leaf spans the doorway; otherwise its length is sought.
  const int na_min = door.paired ? std::max(1, na - 1)
                                 : std::min(na, std::max(1, static_cast<int>(std::floor((p.door_min_width - 0.05) / abin))));
  struct Score {
    double score = -1e9;
    int cells = 0, contra = 0, bins = 0;
  };
  // One hypothesis: hinge at (s_h, d_h), closed direction e0 along the wall,
  // swing side m, angle th. Support (cells holding points) against
  // contradiction (cells rays went through), with the best leaf length: the
  // shortest reaching the largest sum of support minus twice contradiction.
  // The angles of one hinge and swing are scored together: a point lies
  // within the leaf's band only for angles near its own bearing from the
  // hinge, and a ray crosses the leaf only for angles within the arc its
  // chord subtends, so each point and ray is tested (exactly, below) only at
  // the angles of its arc, widened by kBearingSlackDeg; the result is the
  // same as testing every point and ray at every angle.
  const double band_hw = lt + tol;  // farthest a supporting point lies off the hinge line
  const double r_pts = std::hypot(Lmax, band_hw), r_rays = std::hypot(Lmax, lt / 2);
  const std::size_t cells = static_cast<std::size_t>(na_max) * nz;
  // One hinge over the angles start + i step (i < count): points first
  // (support), then rays (contradiction) at the angles still needed, then
  // the scores (an angle not needed scores -infinity).
  struct HingeRun {
    double s_h = 0, d_h = 0, e0 = 1, m = 1, start = 0, step = 1;
    int count = 0;
    std::vector<int> sup, con;  // per angle: leaf bin
    std::vector<Score> scores;
  };
  auto bound = [&](const HingeRun& w, int ai) {  // no length of the leaf at angle ai scores more
    int total = 0;
    for (int i = 0; i < na_max; ++i) total += w.sup[static_cast<std::size_t>(ai) * na_max + i];
    return total;
  };
  auto axes = [&](const HingeRun& w, std::vector<Eigen::Vector2d>& E, std::vector<Eigen::Vector2d>& K,
                  std::vector<Eigen::Vector2d>& P) {
    E.resize(w.count);
    K.resize(w.count);
    P.resize(w.count);
    const Eigen::Vector2d H(w.s_h, w.d_h);
    for (int ai = 0; ai < w.count; ++ai) {
      const double th = (w.start + ai * w.step) * M_PI / 180;
      E[ai] = Eigen::Vector2d(std::cos(th) * w.e0, std::sin(th) * w.m);
      K[ai] = Eigen::Vector2d(std::sin(th) * w.e0, -std::cos(th) * w.m);
      P[ai] = H + K[ai] * (lt / 2);  // the leaf's mid-plane
    }
  };
  // f(i) for every angle start + i step of w within [lo, hi] degrees, modulo
  // 360, and with i in [first, last] (f is not called outside it).
  auto forArc = [&](const HingeRun& w, double lo, double hi, auto&& f, int first = 0, int last = -1) {
    if (last < 0) last = w.count - 1;
    const double end = w.start + (w.count - 1) * w.step;
    for (double shift = -360; shift <= 360; shift += 360) {
      const double a = lo + shift, b = hi + shift;
      if (b < w.start - w.step || a > end + w.step) continue;  // no angle of the run
      const int i0 = std::max(first, util::ceilToInt((a - w.start) / w.step - 1e-9));
      const int i1 = std::min(last, util::floorToInt((b - w.start) / w.step + 1e-9));
      for (int i = i0; i <= i1; ++i) f(i);
    }
  };
  auto scorePoints = [&](HingeRun& w) {
    std::vector<char> seen(w.count * cells, 0);  // per angle: leaf bin x z bin
    w.sup.assign(static_cast<std::size_t>(w.count) * na_max, 0);
    std::vector<Eigen::Vector2d> E, K, P;
    axes(w, E, K, P);
    for (const Local& q : pts) {
      const Eigen::Vector2d r(q.s - w.s_h, q.d - w.d_h);
      const double rho = r.norm();
      if (rho > r_pts) continue;
      auto test = [&](int ai) {
        const double a = r.dot(E[ai]), b = r.dot(K[ai]);
        if (a < 0.02 || a >= Lmax || b < -tol || b > lt + tol) return;
        const int ab = std::min(na_max - 1, static_cast<int>(a / abin));
        char& f = seen[ai * cells + static_cast<std::size_t>(ab) * nz + q.zbin];
        if (!f) f = 1, ++w.sup[static_cast<std::size_t>(ai) * na_max + ab];
      };
      if (rho <= band_hw) {
        for (int ai = 0; ai < w.count; ++ai) test(ai);
        continue;
      }
      // b = rho sin(th - c) lies in [-tol, lt + tol] only for th - c within
      // [-asin(tol / rho), asin((lt + tol) / rho)].
      const double c = fastAtan2Deg(w.m * r.y(), w.e0 * r.x());
      // A short run of angles (the local search) often lies wholly inside
      // that arc: x <= asin(x) tells so without asin (testing more angles
      // than the arc holds is always safe; the test decides).
      const double end = w.start + (w.count - 1) * w.step, deg = 180 / M_PI;
      if (c - tol / rho * deg <= w.start && c + band_hw / rho * deg >= end) {
        for (int ai = 0; ai < w.count; ++ai) test(ai);
        continue;
      }
      const double below = asinAbove(tol / rho) * 180 / M_PI + kBearingSlackDeg;
      const double above = asinAbove(band_hw / rho) * 180 / M_PI + kBearingSlackDeg;
      forArc(w, c - below, c + above, test);
    }
  };
  // The cells (per angle: leaf bin x z bin) that rays [r0, r1) go through,
  // marked in blocked; the count of each leaf bin's is its contradiction.
  auto markRays = [&](const HingeRun& w, const std::vector<char>* need, std::size_t r0, std::size_t r1,
                      std::vector<char>& blocked) {
    // The angles needed lie in [first, last]: a test outside would return at once.
    int first = 0, last = w.count - 1;
    if (need) {
      while (first <= last && !(*need)[first]) ++first;
      while (last >= first && !(*need)[last]) --last;
      if (first > last) return;
    }
    std::vector<Eigen::Vector2d> E, K, P;
    axes(w, E, K, P);
    const Eigen::Vector2d H(w.s_h, w.d_h);
    // With few angles needed a ray on the chord is tested at each of them
    // outright: cheaper than working out its arc (the test decides either way).
    int needed = 0;
    for (int ai = first; ai <= last; ++ai) needed += !need || (*need)[ai];
    const bool outright = needed <= kOutrightAngles;
    for (std::size_t ri = r0; ri < r1; ++ri) {
      const Ray& ray = rays[ri];
      // The part of the ray that counts: from the sensor to 6 cm before its point.
      const Eigen::Vector2d A = vsd, B = ray.q - (0.06 / ray.len) * (ray.q - vsd);
      const Eigen::Vector2d u = B - A, w0 = A - H;
      const double uu = u.squaredNorm();
      if (uu < 1e-12) continue;
      // Chord within the disc the leaf's mid-line can reach.
      const double bq = w0.dot(u), cq = w0.squaredNorm() - r_rays * r_rays, disc = bq * bq - uu * cq;
      if (disc <= 0) continue;
      const double sq = std::sqrt(disc);
      const double t0 = std::max(0.0, (-bq - sq) / uu), t1 = std::min(1.0, (-bq + sq) / uu);
      if (t0 >= t1) continue;
      // Every crossing with a leaf lies on that chord: a ray passing above or
      // below the leaf's heights there crosses none (1 mm spares rounding).
      const double lam_max = 1 - 0.06 / ray.len, dz = ray.qz - vsz;
      const double za = vsz + t0 * lam_max * dz, zb = vsz + t1 * lam_max * dz;
      if (std::max(za, zb) < z0 - 1e-3 || std::min(za, zb) >= z1 + 1e-3) continue;
      const Eigen::Vector2d r = ray.q - vsd;
      auto test = [&](int ai) {
        if (need && !(*need)[ai]) return;
        double a, z;
        if (!crossLeaf(vsd, r, vsz, dz, lam_max, P[ai], E[ai], a, z) || a < 0.05 || a >= Lmax || z < z0 || z >= z1)
          return;
        const int ab = std::min(na_max - 1, static_cast<int>(a / abin));
        blocked[ai * cells + static_cast<std::size_t>(ab) * nz + std::min(nz - 1, static_cast<int>((z - z0) / zbin))] = 1;
      };
      if (outright) {
        for (int ai = first; ai <= last; ++ai) test(ai);
        continue;
      }
      const double tc = std::clamp(-bq / uu, t0, t1);
      const double rho_min = (w0 + tc * u).norm();
      if (rho_min <= std::max(0.05, lt / 2)) {
        for (int ai = first; ai <= last; ++ai) test(ai);
        continue;
      }
      const double c0 = fastAtan2Deg(w.m * (w0 + t0 * u).y(), w.e0 * (w0 + t0 * u).x());
      const double c1 = fastAtan2Deg(w.m * (w0 + t1 * u).y(), w.e0 * (w0 + t1 * u).x());
      // remainder(c1 - c0, 360) for |c1 - c0| <= 360 (exact, as remainder is).
      const double diff = c1 - c0;
      const double span = diff > 180 ? diff - 360 : diff < -180 ? diff + 360 : diff;
      const double lo = c0 + std::min(0.0, span), hi = lo + std::abs(span);
      // The leaf's mid-line passes a point X of the chord (bearing c, distance
      // rho) at th = c + asin(lt / 2 / rho): the arc widens on one side only.
      const double dl = asinAbove(std::min(1.0, lt / 2 / rho_min)) * 180 / M_PI + kBearingSlackDeg;
      forArc(w, lo - kBearingSlackDeg, hi + dl, test, first, last);
    }
  };
  // Each leaf bin's contradiction at the angles needed (0 at the others, never read).
  auto tallyRays = [&](HingeRun& w, const std::vector<char>* need, const std::vector<char>& blocked) {
    w.con.assign(static_cast<std::size_t>(w.count) * na_max, 0);
    for (int ai = 0; ai < w.count; ++ai)
      for (int ab = 0; ab < na_max && (!need || (*need)[ai]); ++ab) {
        const char* b = &blocked[ai * cells + static_cast<std::size_t>(ab) * nz];
        int n = 0;
        for (int zb = 0; zb < nz; ++zb) n += b[zb];
        w.con[static_cast<std::size_t>(ai) * na_max + ab] = n;
      }
  };
  auto scoreRays = [&](HingeRun& w, const std::vector<char>* need) {
    std::vector<char> blocked(w.count * cells, 0);
    markRays(w, need, 0, rays.size(), blocked);
    tallyRays(w, need, blocked);
  };
  auto finishScores = [&](HingeRun& w, const std::vector<char>* need) {
    w.scores.assign(w.count, Score());
    for (int ai = 0; ai < w.count; ++ai) {
      Score& out = w.scores[ai];
      if (need && !(*need)[ai]) {
        out.score = -std::numeric_limits<double>::infinity();
        continue;
      }
      int acc = 0, cells_seen = 0, contra = 0;
      for (int i = 0; i < na_max; ++i) {
        const std::size_t j = static_cast<std::size_t>(ai) * na_max + i;
        acc += w.sup[j] - 2 * w.con[j];
        cells_seen += w.sup[j];
        contra += w.con[j];
        if (i + 1 >= na_min && acc > out.score) out = {static_cast<double>(acc), cells_seen, contra, i + 1};
      }
    }
  };

  // The hinges of the local search all at once: the same angles at hinges
  // 2 cm apart along the wall (w[i].s_h = s_center + (i - reach) 0.02, one
  // d_h). For one point or ray and one angle, the tests below are linear in
  // the hinge's position along the wall: each passes only on an interval of
  // it, so each point and ray is tested (exactly, as scorePoints and
  // scoreRays test it) only at the hinges of that interval, widened by
  // kShiftSlack; the result is the same as testing it at every hinge. The
  // angles are the tasks (over the cores).
  // Points (support) when need is null; else rays (contradiction) at the
  // hinges and angles where (*need)[hinge][angle].
  auto scoreShifts = [&](std::vector<HingeRun>& ws, int reach, double s_center, const std::vector<std::vector<char>>* need) {
    const int ns = static_cast<int>(ws.size()), count = ws.front().count;
    const double d_h = ws.front().d_h;
    std::vector<std::vector<Eigen::Vector2d>> E(ns), K(ns), P(ns);
    for (int i = 0; i < ns; ++i) {
      axes(ws[i], E[i], K[i], P[i]);
      (need ? ws[i].con : ws[i].sup).assign(static_cast<std::size_t>(count) * na_max, 0);
    }
    // Rounding moves the ends of an interval by far less than a micrometre
    // (coefficients below kTiny are not used, and rays within 1e-3 of
    // parallel to the leaf are tested at every hinge): widened by a whole
    // hinge step, an interval holds every hinge a test could pass at.
    constexpr double kShiftSlack = 0.02, kTiny = 1e-3;
    // Hinges i whose s_h lies within [lo, hi], as [i0, i1] (empty: i0 > i1).
    auto hingeRange = [&](double lo, double hi, int& i0, int& i1) {
      const double f0 = std::max(-1.0, (lo - s_center) / 0.02 + reach), f1 = std::min(static_cast<double>(ns), (hi - s_center) / 0.02 + reach);
      i0 = std::max(0, static_cast<int>(std::ceil(f0)));
      i1 = std::min(ns - 1, static_cast<int>(std::floor(f1)));
    };
    // x with c0 + c1 x in [lo, hi], widened by kShiftSlack, intersected into
    // [xlo, xhi] (no bound when c1 is too small to tell).
    auto clip = [&](double c0, double c1, double lo, double hi, double& xlo, double& xhi) {
      if (std::abs(c1) < kTiny) return;
      double a = (lo - c0) / c1, b = (hi - c0) / c1;
      if (a > b) std::swap(a, b);
      xlo = std::max(xlo, a - kShiftSlack);
      xhi = std::min(xhi, b + kShiftSlack);
    };
    const double inf = std::numeric_limits<double>::infinity();
    forEachTask(static_cast<std::size_t>(count), [&](std::size_t task) {
      const int ai = static_cast<int>(task);
      std::vector<char> seen(static_cast<std::size_t>(ns) * cells, 0), blocked(static_cast<std::size_t>(ns) * cells, 0);
      const Eigen::Vector2d Ea = E[0][ai], Ka = K[0][ai];
      if (!need) {
        for (const Local& q : pts) {
          // r = (q.s - s_h, q.d - d_h): a = r.E and b = r.K are linear in x = q.s - s_h.
          const double dy = q.d - d_h;
          double xlo = -inf, xhi = inf;
          clip(dy * Ea.y(), Ea.x(), 0.02, Lmax, xlo, xhi);
          clip(dy * Ka.y(), Ka.x(), -tol, lt + tol, xlo, xhi);
          if (xlo > xhi) continue;
          int i0, i1;
          hingeRange(q.s - xhi, q.s - xlo, i0, i1);
          for (int i = i0; i <= i1; ++i) {
            const HingeRun& w = ws[i];
            const Eigen::Vector2d r(q.s - w.s_h, q.d - w.d_h);
            const double a = r.dot(E[i][ai]), b = r.dot(K[i][ai]);
            if (a < 0.02 || a >= Lmax || b < -tol || b > lt + tol) continue;
            const int ab = std::min(na_max - 1, static_cast<int>(a / abin));
            char& f = seen[static_cast<std::size_t>(i) * cells + static_cast<std::size_t>(ab) * nz + q.zbin];
            if (!f) f = 1, ++ws[i].sup[static_cast<std::size_t>(ai) * na_max + ab];
          }
        }
        return;
      }
      bool any = false;
      for (int i = 0; i < ns; ++i) any |= (*need)[i][ai] != 0;
      if (!any) return;
      for (const Ray& ray : rays) {
        const Eigen::Vector2d r = ray.q - vsd;
        const double denom = r.x() * Ea.y() - r.y() * Ea.x();
        if (std::abs(denom) < 1e-9) continue;  // crossLeaf: parallel, crosses at no hinge
        const double lam_max = 1 - 0.06 / ray.len, dz = ray.qz - vsz;
        // w = P - v: w.y the same at every hinge, w.x = s_h + (K.x lt / 2 - v.x) =: s_h + off.
        const double wy = P[0][ai].y() - vsd.y(), off = Ka.x() * (lt / 2) - vsd.x();
        // lam = (w.x E.y - w.y E.x) / denom in (0, lam_max], and z = vz + lam dz in [z0, z1).
        double llo = 0, lhi = lam_max;
        if (std::abs(dz) >= kTiny) {
          double za = (z0 - vsz) / dz, zb = (z1 - vsz) / dz;
          if (za > zb) std::swap(za, zb);
          llo = std::max(llo, za), lhi = std::min(lhi, zb);
        }
        if (llo > lhi + 1e-9) continue;
        double xlo = -inf, xhi = inf;  // x = w.x
        if (std::abs(denom) >= kTiny) {
          clip(-wy * Ea.x() / denom, Ea.y() / denom, llo, lhi, xlo, xhi);
          // a = (w.x r.y - w.y r.x) / denom in [0.05, Lmax).
          clip(-wy * r.x() / denom, r.y() / denom, 0.05, Lmax, xlo, xhi);
          if (xlo > xhi) continue;
        }
        int i0, i1;
        hingeRange(xlo - off, xhi - off, i0, i1);
        for (int i = i0; i <= i1; ++i) {
          if (!(*need)[i][ai]) continue;
          double a, z;
          if (!crossLeaf(vsd, r, vsz, dz, lam_max, P[i][ai], E[i][ai], a, z) || a < 0.05 || a >= Lmax || z < z0 ||
              z >= z1)
            continue;
          const int ab = std::min(na_max - 1, static_cast<int>(a / abin));
          char& f = blocked[static_cast<std::size_t>(i) * cells + static_cast<std::size_t>(ab) * nz +
                            std::min(nz - 1, static_cast<int>((z - z0) / zbin))];
          if (!f) f = 1, ++ws[i].con[static_cast<std::size_t>(ai) * na_max + ab];
        }
      }
    });
  };

  // A leaf swung towards the sensor hangs at its recess behind the face,
  // which jambs seen only in part can put deeper than the wall measured
  // there: its recesses go to the default wall thickness at least. Not in
  // a camera frame, whose depth noise a deeper hinge line fits as well.
  const double t_toward = view ? t : std::max(t, p.default_wall_thickness);
  std::vector<double> recess_steps;
  for (double r = 0.0; r + lt <= t_toward + 1e-9 && recess_steps.size() < 4; r += 0.05) recess_steps.push_back(r);
  struct Hinge {
    int h, sw;
    double rec;
    double out = 0;  // the hinge this far outwards of its jamb (away from the doorway)
  };
  // A doorway sought from the end of a shadow wider than a door nearer the
  // sensor (Doorway::shadow_end) is there only as the leaf hinged at that
  // end and swung towards the sensor.
  const int shadow_h = std::abs(vsd.x() - door.s0) < std::abs(vsd.x() - door.s1) ? 0 : 1;
  auto hingesAt = [&](double out) {
    std::vector<Hinge> hs;
    for (int h = 0; h < 2; ++h)
      for (int sw = 0; sw < 2; ++sw)
        for (double rec : recess_steps) {
          if (rec > 0 && rec + lt > (sw == 0 ? t_toward : t)) continue;
          if (door.shadow_end && (h != shadow_h || sw != 0)) continue;
          hs.push_back({h, sw, rec, out});
        }
    return hs;
  };
  Score best;
  int best_h = 0, best_sw = 0;
  double best_deg = 0, best_recess = 0, best_s = door.s0;
  // The hinges given, every 2 deg; the best replaced by a hypothesis that
  // scores more. `lower`: the exact score of a hypothesis already scored
  // (rays are tested only where support could beat it).
  auto globalSearch = [&](const std::vector<Hinge>& hinges, double lower) {
    std::vector<HingeRun> global(hinges.size());
    for (std::size_t i = 0; i < hinges.size(); ++i) {
      const Hinge& g = hinges[i];
      HingeRun& w = global[i];
      w.s_h = g.h == 0 ? door.s0 - g.out : door.s1 + g.out, w.e0 = g.h == 0 ? 1.0 : -1.0;
      w.m = g.sw == 0 ? 1.0 : -1.0, w.d_h = g.sw == 0 ? -g.rec : -t + g.rec;
      // Beyond 170 deg a leaf lies flat on its wall and cannot be told from it.
      w.start = 0.0, w.step = 2.0, w.count = 86;  // every 2 deg, refined below
    }
    forEachTask(global.size(), [&](std::size_t i) { scorePoints(global[i]); });
    if (!global.empty() && !std::isfinite(lower)) {
      std::size_t bi = 0;
      int ba = 0, bb = -1;
      for (std::size_t i = 0; i < global.size(); ++i)
        for (int ai = 0; ai < global[i].count; ++ai)
          if (bound(global[i], ai) > bb) bb = bound(global[i], ai), bi = i, ba = ai;
      HingeRun probe = global[bi];
      std::vector<char> only(probe.count, 0);
      only[ba] = 1;
      // Its rays in two halves at once, the cells they block joined.
      std::vector<char> blocked(probe.count * cells, 0), blocked2(probe.count * cells, 0);
      const std::size_t mid = rays.size() / 2;
      forEachTask(2, [&](std::size_t h) {
        markRays(probe, &only, h == 0 ? 0 : mid, h == 0 ? mid : rays.size(), h == 0 ? blocked : blocked2);
      });
      for (std::size_t k = 0; k < blocked.size(); ++k) blocked[k] |= blocked2[k];
      tallyRays(probe, &only, blocked);
      finishScores(probe, &only);
      lower = probe.scores[ba].score;
    }
    forEachTask(global.size(), [&](std::size_t i) {
      HingeRun& w = global[i];
      std::vector<char> need(w.count, 0);
      bool any = false;
      for (int ai = 0; ai < w.count; ++ai) any |= (need[ai] = bound(w, ai) >= lower) != 0;
      // A hinge none of whose angles can be the best needs no rays at all
      // (most hinges: the bound leaves a few dozen of a thousand hypotheses).
      if (any) {
        scoreRays(w, &need);
      } else {
        w.con.assign(static_cast<std::size_t>(w.count) * na_max, 0);
      }
      finishScores(w, &need);
    });
    for (std::size_t i = 0; i < hinges.size(); ++i) {
      const Hinge& g = hinges[i];
      for (int ai = 0; ai < 86; ++ai) {
        const Score& sc = global[i].scores[ai];
        if (sc.score > best.score)
          best = sc, best_h = g.h, best_sw = g.sw, best_deg = 2.0 * ai, best_recess = g.rec, best_s = global[i].s_h;
      }
    }
  };
  // Global search: hinge at either jamb, either swing side, hinge on the
  // face or set back (recess), every 2 deg. The hinges are scored as tasks
  // (over the cores), the best taken in order. Support bounds a hypothesis's
  // score from above (contradiction only lowers it): rays are tested only at
  // the angles whose bound reaches the exact score of the best-bounded one,
  // the others cannot be the best.
  globalSearch(hingesAt(0.0), -std::numeric_limits<double>::infinity());
  // The doorway seen can end short of the hinge or run past it: a leaf
  // ajar hides the jamb at its hinge from a sensor on its swing side, and a
  // leaf swung past 90 deg towards the sensor shadows the wall beyond its
  // hinge, which then looks like doorway. Either way no angle at the jamb
  // fits the leaf. Where the best fits poorly and no trim pair fixes the
  // jambs, hinges up to 40 cm outwards and inwards of each jamb too (10 cm
  // apart, leaving at least the narrowest door between them). Not in a
  // camera frame: there a leaf is often seen only in part, and hinges moved
  // off the jambs fitted wrong leaves better (rgbd sweeps 2000 and 3000).
  if (!view && !door.paired && best.bins > 0 && best.cells < kRetryBelowCoverage * best.bins * nz) {
    std::vector<Hinge> more;
    for (int k = -4; k <= 4; ++k) {
      const double out = 0.1 * k;
      if (k == 0 || w + std::min(0.0, out) < p.door_min_width) continue;
      const std::vector<Hinge> at = hingesAt(out);
      more.insert(more.end(), at.begin(), at.end());
    }
    // Rays only where support could beat the best so far and reach the
    // least a leaf is taken with (half min_leaf_coverage, times sampling, of the shortest
    // leaf's cells, in a doorway beyond doubt): where no leaf is seen (a
    // doorway seen through, its leaf out of sight) that leaves few or none.
    globalSearch(more, std::max(best.score, 0.5 * p.min_leaf_coverage * fit.sampling * na_min * nz));
  }
  // Local search: the jamb seen from the wall can be off where a leaf hides
  // or shadows its own doorway; move the hinge along the wall and the angle.
  // It moves the angle by 2.5 deg at most: with the wall band full enough for
  // a closed leaf (band_cov >= 0.55, below) and the best angle below
  // closed_below_deg + 0.5, the leaf is taken closed in the band whatever it
  // finds, and nothing it finds is used (but best_*, which then tell the
  // global search's best): skipped.
  const bool closed_in_band_for_sure = band_cov >= 0.55 && best_deg + 2.5 < p.closed_below_deg + 3;
  if (!closed_in_band_for_sure) {
    const double e0 = best_h == 0 ? 1.0 : -1.0, m = best_sw == 0 ? 1.0 : -1.0;
    const double d_h = best_sw == 0 ? -best_recess : -t + best_recess;
    const double s_center = best_s, deg_center = best_deg;
    const int reach_steps = door.paired ? 3 : 15;  // 2 cm steps
    const double start = deg_center - 2.5, step = 0.5;
    std::vector<HingeRun> shifts(2 * reach_steps + 1);
    for (std::size_t i = 0; i < shifts.size(); ++i) {
      HingeRun& w = shifts[i];
      w.s_h = s_center + (static_cast<int>(i) - reach_steps) * 0.02;
      w.d_h = d_h, w.e0 = e0, w.m = m, w.start = start, w.step = step, w.count = 11;
    }
    // Support first. A hypothesis replaces the best only when it scores
    // more, and it scores no more than its support (bound): rays are tested
    // only where the bound beats the global search's best, and at angles
    // within [0, 170] deg (the others are never taken).
    // Few hinges (a paired doorway): each on its own costs less.
    if (reach_steps > 3) {
      scoreShifts(shifts, reach_steps, s_center, nullptr);
    } else {
      forEachTask(shifts.size(), [&](std::size_t i) { scorePoints(shifts[i]); });
    }
    std::vector<std::vector<char>> need(shifts.size(), std::vector<char>(11, 0));
    for (std::size_t i = 0; i < shifts.size(); ++i)
      for (int ai = 0; ai < 11; ++ai) {
        const double deg = start + ai * step;
        need[i][ai] = deg >= 0 && deg <= 170 && bound(shifts[i], ai) > best.score;
      }
    if (reach_steps > 3) {
      scoreShifts(shifts, reach_steps, s_center, &need);
    } else {
      forEachTask(shifts.size(), [&](std::size_t i) {
        if (std::find(need[i].begin(), need[i].end(), 1) != need[i].end()) {
          scoreRays(shifts[i], &need[i]);
        } else {
          shifts[i].con.assign(static_cast<std::size_t>(shifts[i].count) * na_max, 0);
        }
      });
    }
    for (std::size_t i = 0; i < shifts.size(); ++i) finishScores(shifts[i], &need[i]);
    for (int ds = -reach_steps; ds <= reach_steps; ++ds) {
      const double s_h = s_center + ds * 0.02;
      for (int ai = 0; ai < 11; ++ai) {
        const double deg = start + ai * step;
        if (deg < 0 || deg > 170) continue;
        const Score& sc = shifts[ds + reach_steps].scores[ai];
        if (sc.score > best.score) best = sc, best_deg = deg, best_s = s_h;
      }
    }
  }
  const int best_support = best.cells, best_contra = best.contra, best_bins = best.bins;

  double band_angle = 0;
  if (band_xy.size() >= 10) {
    // Only the points at the leaf's own depth: not jambs, trim or what lies beyond.
    std::vector<double> dv;
    for (const auto& q : band_xy) dv.push_back(q.y());
    std::nth_element(dv.begin(), dv.begin() + dv.size() / 2, dv.end());
    const double dmed = dv[dv.size() / 2];
    std::vector<Eigen::Vector2d> leaf_xy;
    for (const auto& q : band_xy)
      if (std::abs(q.y() - dmed) < std::max(0.03, lt)) leaf_xy.push_back(q);
    const Line2 l = fitLine(leaf_xy.size() >= 10 ? leaf_xy : band_xy);
    band_angle = std::acos(std::min(1.0, std::abs(l.direction.x()))) * 180 / M_PI;
  }

  const double best_expected = static_cast<double>(best_bins) * nz;
  const double gen_cov = best_support / best_expected;
  const double gen_contra = best_contra / best_expected;
  // A leaf closed in the wall band fills its doorway either way round: its
  // hinge side is told by its handle, at the latch edge, standing 3-10 cm
  // off the visible face about 0.9-1.1 m above the floor. Points there
  // within 30 cm of one jamb, at least three and three times those at the
  // other, put the latch at that jamb (else the search's side stands: a
  // closed leaf's hinge side is a guess without a handle).
  const bool closed_band = band_cov >= 0.55 && (best_deg < p.closed_below_deg + 3 || gen_cov < band_cov);
  // Its visible face: the median depth of the band's points.
  double band_face = 0;
  if (closed_band) {
    std::vector<double> dv;
    for (const Local& q : band) dv.push_back(q.d);
    std::nth_element(dv.begin(), dv.begin() + dv.size() / 2, dv.end());
    band_face = dv[dv.size() / 2];
  }
  if (closed_band && band.size() >= 10) {
    // A leaf ajar in its band slants across the doorway, and its points near
    // the hinge stand 3-10 cm before the median depth as a handle would
    // (rgbd 3027: 13 deg, recessed). Where the band's least-squares line
    // slants by 2 cm or more over the doorway, the face is that line.
    double face = band_face, slope = 0;
    const double s_mid = 0.5 * (door.s0 + door.s1);
    {
      double ms = 0, md = 0;
      for (const Local& q : band) ms += q.s, md += q.d;
      ms /= band.size(), md /= band.size();
      double ss = 0, sd = 0;
      for (const Local& q : band) ss += (q.s - ms) * (q.s - ms), sd += (q.s - ms) * (q.d - md);
      const double b = ss > 0 ? sd / ss : 0;
      if (std::abs(b) * (door.s1 - door.s0) >= 0.02) slope = b, face = md + b * (s_mid - ms);
    }
    int near0 = 0, near1 = 0;
    for (const Local& q : pts) {
      const double z = points[q.index].z() - floor_z, off = q.d - (face + slope * (q.s - s_mid));
      if (z < 0.9 || z > 1.1 || off < 0.03 || off > 0.1) continue;
      if (q.s > door.s0 + 0.02 && q.s < door.s0 + 0.3) ++near0;
      if (q.s < door.s1 - 0.02 && q.s > door.s1 - 0.3) ++near1;
    }
    fit.handle_points = std::max(near0, near1);
    if (near0 >= 3 && near0 >= 3 * near1) best_h = 1;       // latch at s0
    else if (near1 >= 3 && near1 >= 3 * near0) best_h = 0;  // latch at s1
    best_s = best_h == 0 ? door.s0 : door.s1;
  }
  fit.best_angle_deg = best_deg;
  fit.best_coverage = gen_cov;
  fit.best_contradiction = gen_contra;
  fit.candidate_points = static_cast<int>(pts.size());
  fit.candidate_rays = static_cast<int>(rays.size());
  fit.length = L;
  fit.hinge_at_s0 = best_h == 0;
  fit.toward_viewer = best_sw == 0;
  double s_h = best_s;
  const double s_other = best_h == 0 ? door.s1 : door.s0, e0 = best_h == 0 ? 1.0 : -1.0;
  const double m = best_sw == 0 ? 1.0 : -1.0, d_h = best_sw == 0 ? -best_recess : -t + best_recess;
  auto toXY = [&](double s, double d) { return wall.point + s * wall.direction + d * wall.normal; };
  // Support of one hypothesis (cells holding points), with its inliers.
  auto support = [&](double sh, double th_deg, double len, double band_lo, double band_hi, std::vector<int>* inl,
                     std::vector<Eigen::Vector2d>* xy) {
    const double th = th_deg * M_PI / 180;
    const Eigen::Vector2d e(std::cos(th) * e0, std::sin(th) * m), k(std::sin(th) * e0, -std::cos(th) * m);
    const int nl = std::max(1, static_cast<int>(std::ceil(len / abin)));
    std::vector<char> hit(static_cast<std::size_t>(nl) * nz, 0);
    int cells = 0;
    for (const Local& q : pts) {
      const Eigen::Vector2d r(q.s - sh, q.d - d_h);
      const double a = r.dot(e), b = r.dot(k);
      if (a < 0.02 || a > len || b < band_lo || b > band_hi) continue;
      char& f = hit[static_cast<std::size_t>(std::min(nl - 1, static_cast<int>(a / abin))) * nz + q.zbin];
      if (!f) f = 1, ++cells;
      if (inl) inl->push_back(q.index);
      if (xy) xy->emplace_back(q.s, q.d);
    }
    return static_cast<double>(cells) / (static_cast<double>(nl) * nz);
  };

  if (closed_band) {
    fit.found = true;
    fit.closed_in_band = true;
    fit.angle_deg = band_angle;
    // A closed leaf sits flush with (or set back from) the face of the wall
    // on its swing side: its visible face near the near face says "towards
    // the viewer", near the far face (less a leaf thickness) "away".
    fit.face_d = band_face;
    fit.toward_viewer = -fit.face_d < (t - lt) / 2;
    fit.coverage = band_cov;
    for (const Local& q : band) fit.inliers.push_back(q.index);
    s_h = best_h == 0 ? door.s0 : door.s1;  // a closed leaf fills its doorway from jamb to jamb
  } else if ((gen_cov >= 0.1 || (view && gen_cov >= 0.05)) && gen_contra < 0.1) {
    // Refine: a TLS line through the inliers gives the angle; where it meets
    // the wall face on the swing side is the hinge (the doorway's edge seen
    // from the wall can be off where the leaf shadows the wall).
    double angle = best_deg;
    const double len = best_bins * abin;
    for (int iter = 0; iter < 3; ++iter) {
      std::vector<Eigen::Vector2d> xy;
      support(s_h, angle, len + 0.1, -0.05, lt + 0.05, nullptr, &xy);
      if (xy.size() < 10) break;
      Line2 l = fitLine(xy);
      const double th = angle * M_PI / 180;
      const Eigen::Vector2d e(std::cos(th) * e0, std::sin(th) * m);
      if (l.direction.dot(e) < 0) l.direction = -l.direction;
      const double refined = std::atan2(l.direction.y() * m, l.direction.x() * e0) * 180 / M_PI;
      if (std::abs(refined - angle) > 8) break;  // the fit wandered off: keep the search's answer
      angle = std::clamp(refined, 0.0, 180.0);
      if (angle > 25 && angle < 155) {
        // The visible face is the one towards the sensor; the hinge line is
        // the swing face: shift the fitted line by the thickness if needed.
        const Eigen::Vector2d kk(std::sin(angle * M_PI / 180) * e0, -std::cos(angle * M_PI / 180) * m);
        Eigen::Vector2d on = l.point;
        if ((vsd - l.point).dot(kk) > 0) on -= kk * lt;  // sensor sees the back face: move to the swing face
        const double lam = (d_h - on.y()) / l.direction.y();
        const double s_new = on.x() + lam * l.direction.x();
        if (std::abs(s_new - s_h) < 0.2) s_h = s_new;
      }
    }
    // Keep the refinement only if the leaf it describes is as well supported:
    // the refined hinge and angle, else the refined angle alone, else the search's.
    const double search_s_h = best_s;
    const double cov_search = support(search_s_h, best_deg, len, -tol, lt + tol, nullptr, nullptr);
    if (support(s_h, angle, len, -tol, lt + tol, nullptr, nullptr) < 0.9 * cov_search) {
      s_h = search_s_h;
      if (support(s_h, angle, len, -tol, lt + tol, nullptr, nullptr) < 0.9 * cov_search) angle = best_deg;
    }
    std::vector<int> inl;
    const double cov = support(s_h, angle, len, -tol, lt + tol, &inl, nullptr);
    // A doorway beyond doubt (trim, or the room beyond seen through it) takes
    // a leaf seen only edge-on or in part, as long as no ray contradicts it.
    const bool sure_doorway = door.casing || door.through >= 0.4;
    // A leaf cut by the edge of a camera's view: its share of cells inside
    // the view holding points (as above, relaxed in a doorway beyond doubt),
    // where at least a quarter of it is inside.
    double in_view = 1.0;
    if (view) {
      const double th = angle * M_PI / 180;
      const Eigen::Vector2d e(std::cos(th) * e0, std::sin(th) * m), k(std::sin(th) * e0, -std::cos(th) * m);
      const int nl = std::max(1, static_cast<int>(std::ceil(len / abin)));
      int inside = 0;
      for (int i = 0; i < nl; ++i) {
        const Eigen::Vector2d sd = Eigen::Vector2d(s_h, d_h) + e * ((i + 0.5) * abin) + k * (lt / 2);
        const Eigen::Vector2d xy = toXY(sd.x(), sd.y());
        for (int zb = 0; zb < nz; ++zb)
          inside += view->inView(Eigen::Vector3f(static_cast<float>(xy.x()), static_cast<float>(xy.y()),
                                                 static_cast<float>(z0 + (zb + 0.5) * zbin)));
      }
      in_view = static_cast<double>(inside) / (static_cast<double>(nl) * nz);
    }
    const bool cut_by_view = in_view >= 0.25 && in_view < 0.9 && gen_contra <= 0.05 &&
                             cov >= (sure_doorway ? 0.5 : 1.0) * p.min_leaf_coverage * in_view;
    const double min_cov = p.min_leaf_coverage * fit.sampling;
    if (cov >= min_cov || (sure_doorway && cov >= 0.5 * min_cov && gen_contra <= 0.05) || cut_by_view) {
      fit.found = true;
      fit.coverage = cov;
      fit.angle_deg = angle;
      fit.length = len;
      fit.inliers = std::move(inl);
    }
  }
  fit.s_hinge = s_h;
  fit.s_latch = fit.closed_in_band ? s_other : s_h + e0 * (fit.length + 0.008);
  // An open leaf seen only in part (cut by the edge of a camera's view, or
  // hidden in part) is shorter than any door; a doorway seen through from
  // jamb to jamb gives the door's width instead.
  if (fit.found && !fit.closed_in_band && fit.length < p.door_min_width && door.through >= 0.4) {
    const double span = std::abs(s_other - s_h);
    if (span >= p.door_min_width && span <= p.door_max_width) fit.s_latch = s_other;
  }
  if (!fit.found && (door.casing || door.through >= 0.4) && band_cov < 0.3) {
    // No leaf seen in a doorway beyond doubt, and none closed in it: where
    // could a leaf of the doorway's width stand without blocking a ray that
    // went through (free space)? For each hinge and swing side, the least
    // angle a leaf there is not contradicted at (more than 3% of its cells
    // crossed by rays); the least over all four bounds the opening angle
    // from below. A leaf swung behind its wall, out of sight, leaves a high bound.
    const int nl = std::max(1, static_cast<int>(std::ceil(L / abin)));
    std::vector<char> crossed(static_cast<std::size_t>(nl) * nz);
    double bound = 180;
    // Every return near the doorway (the rays above may be thinned).
    const Eigen::Vector2d dcv = dc - vsd;
    RangeImage image(vsd, viewpoint.z(), std::atan2(dcv.y(), dcv.x()));
    for (const auto& q : points) {
      Eigen::Vector2d qsd;
      double len2;
      if (nearDoorway(q, qsd, len2)) image.add(qsd, q.z());
    }
    // Every hinge at a jamb, swing side and recess the search tried (the
    // bound is that of a leaf spanning the doorway seen, so only at its
    // jambs, not at the hinges moved off them): a leaf hinged deeper in its
    // doorway than the hypothesis would rule it out wrongly.
    for (int h = 0; h < 2; ++h)
      for (int sw = 0; sw < 2; ++sw)
        for (double rec : recess_steps) {
          if (rec > 0 && rec + lt > (sw == 0 ? t_toward : t)) continue;
          const double sh = h == 0 ? door.s0 : door.s1, ee = h == 0 ? 1.0 : -1.0, mm = sw == 0 ? 1.0 : -1.0;
          const Eigen::Vector2d H(sh, sw == 0 ? -rec : -t + rec);
          for (int deg = 0; deg < bound && deg <= 170; deg += 2) {
            const double th = deg * M_PI / 180;
            const Eigen::Vector2d e(std::cos(th) * ee, std::sin(th) * mm), k(std::sin(th) * ee, -std::cos(th) * mm);
            const Eigen::Vector2d P = H + k * (lt / 2);
            std::fill(crossed.begin(), crossed.end(), 0);
            // Cells whose centre the range image shows free first (cheap),
            // then cells rays cross, until the leaf is ruled out.
            const double most = 0.03 * nl * nz;
            int n = 0;
            for (int i = 0; i < nl && n <= most; ++i)
              for (int zb = 0; zb < nz; ++zb)
                if (image.free(P + e * ((i + 0.5) * abin), z0 + (zb + 0.5) * zbin))
                  crossed[static_cast<std::size_t>(i) * nz + zb] = 1, ++n;
            for (std::size_t ri = 0; ri < rays.size() && n <= most; ++ri) {
              const Ray& ray = rays[ri];
              double a, z;
              if (!crossLeaf(vsd, ray.q - vsd, vsz, ray.qz - vsz, 1 - 0.06 / ray.len, P, e, a, z) || a < 0.05 ||
                  a >= L || z < z0 || z >= z1)
                continue;
              char& f = crossed[static_cast<std::size_t>(std::min(nl - 1, static_cast<int>(a / abin))) * nz +
                                std::min(nz - 1, static_cast<int>((z - z0) / zbin))];
              if (!f) f = 1, ++n;
            }
            if (n <= 0.03 * nl * nz) {
              if (deg < bound) {
                bound = deg;
                fit.hinge_at_s0 = h == 0;
                fit.toward_viewer = sw == 0;
              }
              break;
            }
          }
        }
    fit.free_from_deg = bound;
  }
  if (!fit.found) return fit;
  if (!fit.closed_in_band && vsd.y() > 0.1) {
    // What hides the doorway from the sensor, near it: points in front of the
    // wall whose sight lines, carried on, meet the wall inside the doorway.
    // A leaf swung towards the sensor is all of it; a cupboard's side taken
    // for a leaf leaves its front unexplained.
    // On the leaf: within its thickness either side of the hinge line (the
    // face seen may be either, and a recess the search missed shifts it).
    const double th = fit.angle_deg * M_PI / 180;
    const Eigen::Vector2d e(std::cos(th) * e0, std::sin(th) * m), k(std::sin(th) * e0, -std::cos(th) * m);
    int occluders = 0, explained = 0;
    for (const Local& q : pts) {
      if (q.d <= p.face_tolerance + 0.02 || q.d >= vsd.y()) continue;
      const double lam = vsd.y() / (vsd.y() - q.d);
      const double s_wall = vsd.x() + lam * (q.s - vsd.x());
      if (s_wall <= door.s0 + 0.05 || s_wall >= door.s1 - 0.05) continue;
      ++occluders;
      const Eigen::Vector2d r(q.s - s_h, q.d - d_h);
      const double a = r.dot(e), b = r.dot(k);
      explained += a >= 0.02 && a <= fit.length && b >= -lt - tol && b <= lt + tol;
    }
    fit.occluders_explained = occluders > 0 ? static_cast<double>(explained) / occluders : 0.0;
  }
  const double th = fit.angle_deg * M_PI / 180;
  const Eigen::Vector2d dir_sd(std::cos(th) * e0, std::sin(th) * m);
  const double hinge_d = !fit.closed_in_band ? d_h : fit.toward_viewer ? fit.face_d : fit.face_d - lt;
  const Eigen::Vector2d hinge_xy = toXY(s_h, hinge_d);
  fit.hinge = hinge_xy;
  fit.direction = (dir_sd.x() * wall.direction + dir_sd.y() * wall.normal).normalized();
  // The leaf's top: highest of its points over its whole height.
  double top = z1;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto& q = points[i];
    if (q.z() < z1) continue;
    const double s = wall.along(q), d = wall.signedDistance(q);
    const Eigen::Vector2d r(s - s_h, d - (fit.closed_in_band ? -t / 2 : d_h));
    const double a = r.dot(dir_sd), b = std::abs(r.x() * dir_sd.y() - r.y() * dir_sd.x());
    if (a > 0.05 && a < fit.length && b < (fit.closed_in_band ? t / 2 + 0.03 : lt + tol)) top = std::max<double>(top, q.z());
  }
  fit.top_z = top;
  return fit;
}

}  // namespace state
}  // namespace dsr
