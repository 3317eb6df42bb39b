// Segmentation: walls as vertical planes by iterative 1-point RANSAC,
// refined by total least squares (findWalls); each plane's segments go
// through the wall rules (wall_acceptance.cpp).
#include "door_state_recognition/segmentation/segmentation.hpp"

#include "door_state_recognition/util/first_error.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <exception>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#endif

#ifdef _OPENMP
#include <omp.h>
#endif

namespace dsr {
namespace segmentation {

namespace {

// Total least squares line of 2-D points: centroid and unit direction.
void fitLine(const std::vector<Eigen::Vector2d>& pts, Eigen::Vector2d& c, Eigen::Vector2d& dir) {
  c.setZero();
  for (const auto& q : pts) c += q;
  c /= static_cast<double>(pts.size());
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  for (const auto& q : pts) C += (q - c) * (q - c).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  dir = es.eigenvectors().col(1);
}

}  // namespace

namespace {

// Passes of inliers and TLS refit after RANSAC, at most. The inlier band
// (wall_distance, 3 cm) cuts the wall's own noise where a depth camera's
// reaches 1.5-2 cm (3-4 m off): the refit is then drawn to the line whose
// band it was cut with, and from the RANSAC hypothesis (a point's own
// normal, off by a degree or more in such noise) it closes in on the wall
// by about a third per pass (a robot camera 3 m from a wall with a closed
// door, seed 1018: 1.2 deg off after the 3 passes, 0.2 deg after 10). A
// pass beyond the third is kept only while its line holds more inliers
// than the last (RANSAC's own measure): where other surfaces lie within
// the band (a leaf set back, trim, furniture against the wall) the refit
// could otherwise walk off the wall (lidar64 1016: 1.7 deg).
constexpr int kRefinePasses = 10;
// ... and the converged line replaces the third pass's only where it turns
// the wall by this much or more (degrees). Where the noise lies well inside
// the band (a LiDAR's walls) the three passes have converged already: the
// further passes turn 99 % of them by under 0.7 deg, most by hundredths,
// and such a turn decides nothing but which noise points sit at the
// band's edge, which the trim and recess tests downstream read (lidar64
// drive 1018: a wall turned 0.04 deg lost a door's trim leg and paired
// another at the corner, a false door). A camera's biased third pass is
// off by a degree or more. Measured in doc/results.md ("Walls fitted to
// convergence").
constexpr double kConvergedTurnDeg = 0.5;

// A wall's noise (sigma) is read off its inliers, from the share of them
// within a third of wall_distance of its line, in each kNoiseStretch (m)
// along it holding kNoiseStretchPoints of them; a wall whose three refits
// in wall_distance left kNoiseBandLeft of a tilt or more (passesLeft: sigma
// above 0.6 wall_distance, 1.8 cm; a LiDAR's 1.5 cm range noise leaves
// 1 %) is refit in a band of kNoiseBandSigmas sigma (at most kNoiseBandMax
// wall_distance), passes ending once a pass turns it by less than 0.05 deg
// (kNoiseBandConverged: its cosine).
constexpr double kNoiseStretch = 0.5, kNoiseBandSigmas = 2.5, kNoiseBandMax = 2.0;
constexpr std::size_t kNoiseStretchPoints = 20;
constexpr double kNoiseBandConverged = 0.9999996, kNoiseBandLeft = 0.05;

// The sigma of Gaussian noise about a line that leaves `share` of the points
// within a band of +-wd within +-wd/3 of the line: the share falls from 1
// (no noise) to 1/3 (noise far wider than the band), one sigma for each.
double sigmaOfInnerShare(double share, double wd) {
  auto shareOf = [&](double sigma) {
    return std::erf(wd / 3 / (sigma * std::sqrt(2.0))) / std::erf(wd / (sigma * std::sqrt(2.0)));
  };
  double lo = 1e-4 * wd, hi = 100 * wd;  // shareOf(lo) ~ 1, shareOf(hi) ~ 1/3
  for (int i = 0; i < 60; ++i) {
    const double mid = std::sqrt(lo * hi);
    (shareOf(mid) > share ? lo : hi) = mid;
  }
  return std::sqrt(lo * hi);
}

// The share of a line's tilt off a wall that three refits in a band of
// +-x sigma of Gaussian noise leave: each takes the points within the band
// of the line it was cut with, whose slope then holds 1 - r of the tilt,
// r = 2 x phi(x) / (2 Phi(x) - 1) (x = 3: 0.03; 2: 0.23; 1.5: 0.45).
double passesLeft(double x) {
  const double phi = std::exp(-0.5 * x * x) / std::sqrt(2 * M_PI);
  const double r = 2 * x * phi / std::erf(x / std::sqrt(2.0));
  return r * r * r;
}

// RANSAC never stops before this many draws.
constexpr int kMinRansacIterations = 20;
// Below these (sample points scored, a plane's inliers) the work of a RANSAC
// round is too small to hand to the other thread: waiting for it could cost
// more (a thread of a loaded machine waits for its turn on a core).
constexpr std::size_t kTaskSample = 4000, kTaskInliers = 1000;
// A pool of this many points or more has its inliers found in two halves at once.
constexpr std::size_t kTaskPool = 20000;

// Of the n sample points (x, y, normal nx_i, ny_i), those within wd of the
// line through (qx, qy) with normal (nx, ny) whose normal agrees (|n . n_i|
// > agree), without branches.
std::size_t countInliersScalar(const float* x, const float* y, const float* nxs, const float* nys, std::size_t n,
                               double qx, double qy, double nx, double ny, double wd, double agree) {
  std::size_t count = 0, j = 0;
#if defined(__SSE2__)
  {  // two at a time: the same double operations, in the same order
    const __m128d vqx = _mm_set1_pd(qx), vqy = _mm_set1_pd(qy), vnx = _mm_set1_pd(nx), vny = _mm_set1_pd(ny);
    const __m128d vwd = _mm_set1_pd(wd), vag = _mm_set1_pd(agree);
    const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
    auto load2 = [](const float* f) { return _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(f)))); };
    for (; j + 2 <= n; j += 2) {
      const __m128d dist = _mm_add_pd(_mm_mul_pd(_mm_sub_pd(load2(&x[j]), vqx), vnx),
                                      _mm_mul_pd(_mm_sub_pd(load2(&y[j]), vqy), vny));
      const __m128d dot = _mm_add_pd(_mm_mul_pd(vnx, load2(&nxs[j])), _mm_mul_pd(vny, load2(&nys[j])));
      const __m128d in = _mm_and_pd(_mm_cmplt_pd(_mm_and_pd(dist, abs_mask), vwd),
                                    _mm_cmpgt_pd(_mm_and_pd(dot, abs_mask), vag));
      const int bits = _mm_movemask_pd(in);
      count += static_cast<std::size_t>((bits & 1) + (bits >> 1));
    }
  }
#endif
  for (; j < n; ++j) {
    const double dist = (static_cast<double>(x[j]) - qx) * nx + (static_cast<double>(y[j]) - qy) * ny;
    const double dot = nx * static_cast<double>(nxs[j]) + ny * static_cast<double>(nys[j]);
    count += static_cast<std::size_t>((std::abs(dist) < wd) & (std::abs(dot) > agree));
  }
  return count;
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DSR_COUNT_INLIERS_AVX2 1
// countInliersScalar four at a time on a CPU with AVX2: the same double
// operations in each lane (AVX2 alone, no FMA: no multiply-add is fused),
// the same count. The rest as countInliersScalar counts it.
// The inlier test of countInliersScalar on points [j, j + 4), for every
// whole block of four of the n: on(j, bits), bit k set when point j + k is
// an inlier. Returns where the blocks end (the rest is the scalar code's).
template <class F>
__attribute__((target("avx2"))) inline std::size_t inlierBlocksAvx2(const float* x, const float* y, const float* nxs,
                                                                    const float* nys, std::size_t n, double qx,
                                                                    double qy, double nx, double ny, double wd,
                                                                    double agree, const F& on) {
  std::size_t j = 0;
  const __m256d vqx = _mm256_set1_pd(qx), vqy = _mm256_set1_pd(qy), vnx = _mm256_set1_pd(nx), vny = _mm256_set1_pd(ny);
  const __m256d vwd = _mm256_set1_pd(wd), vag = _mm256_set1_pd(agree);
  const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL));
  for (; j + 4 <= n; j += 4) {
    const __m256d px = _mm256_cvtps_pd(_mm_loadu_ps(&x[j])), py = _mm256_cvtps_pd(_mm_loadu_ps(&y[j]));
    const __m256d pnx = _mm256_cvtps_pd(_mm_loadu_ps(&nxs[j])), pny = _mm256_cvtps_pd(_mm_loadu_ps(&nys[j]));
    const __m256d dist = _mm256_add_pd(_mm256_mul_pd(_mm256_sub_pd(px, vqx), vnx), _mm256_mul_pd(_mm256_sub_pd(py, vqy), vny));
    const __m256d dot = _mm256_add_pd(_mm256_mul_pd(vnx, pnx), _mm256_mul_pd(vny, pny));
    const __m256d in = _mm256_and_pd(_mm256_cmp_pd(_mm256_and_pd(dist, abs_mask), vwd, _CMP_LT_OQ),
                                     _mm256_cmp_pd(_mm256_and_pd(dot, abs_mask), vag, _CMP_GT_OQ));
    on(j, static_cast<unsigned>(_mm256_movemask_pd(in)));
  }
  // Upper halves of the vector registers cleared before returning to SSE
  // code: left dirty, every SSE instruction after would wait on them.
  _mm256_zeroupper();
  return j;
}

__attribute__((target("avx2"))) std::size_t countInliersAvx2(const float* x, const float* y, const float* nxs,
                                                              const float* nys, std::size_t n, double qx, double qy,
                                                              double nx, double ny, double wd, double agree) {
  std::size_t count = 0;
  const std::size_t j = inlierBlocksAvx2(x, y, nxs, nys, n, qx, qy, nx, ny, wd, agree, [&](std::size_t, unsigned bits) {
    count += static_cast<std::size_t>(__builtin_popcount(bits));
  });
  return count + countInliersScalar(x + j, y + j, nxs + j, nys + j, n - j, qx, qy, nx, ny, wd, agree);
}
#endif

// Of the n pool points (x, y, normal nx_i, ny_i; pool indices idx), those
// countInliersScalar counts, appended in order: index to in, (x, y) in
// double to q.
void collectInliersScalar(const float* x, const float* y, const float* nxs, const float* nys, const int* idx,
                          std::size_t n, double qx, double qy, double nx, double ny, double wd, double agree,
                          std::vector<int>& in, std::vector<Eigen::Vector2d>& q) {
  for (std::size_t j = 0; j < n; ++j) {
    const double rx = x[j], ry = y[j];
    const double dist = (rx - qx) * nx + (ry - qy) * ny;
    const double dot = nx * static_cast<double>(nxs[j]) + ny * static_cast<double>(nys[j]);
    if (std::abs(dist) < wd && std::abs(dot) > agree) {
      in.push_back(idx[j]);
      q.emplace_back(rx, ry);
    }
  }
}

#ifdef DSR_COUNT_INLIERS_AVX2
// collectInliersScalar four at a time with AVX2 (no FMA): the same double
// operations in each lane, the same inliers in the same order.
__attribute__((target("avx2"))) void collectInliersAvx2(const float* x, const float* y, const float* nxs,
                                                         const float* nys, const int* idx, std::size_t n, double qx,
                                                         double qy, double nx, double ny, double wd, double agree,
                                                         std::vector<int>& in, std::vector<Eigen::Vector2d>& q) {
  const std::size_t j = inlierBlocksAvx2(x, y, nxs, nys, n, qx, qy, nx, ny, wd, agree, [&](std::size_t b, unsigned bits) {
    while (bits) {
      const int k = __builtin_ctz(bits);
      bits &= bits - 1;
      in.push_back(idx[b + k]);
      q.emplace_back(static_cast<double>(x[b + k]), static_cast<double>(y[b + k]));
    }
  });
  collectInliersScalar(x + j, y + j, nxs + j, nys + j, idx + j, n - j, qx, qy, nx, ny, wd, agree, in, q);
}
#endif

void collectInliers(const float* x, const float* y, const float* nxs, const float* nys, const int* idx, std::size_t n,
                    double qx, double qy, double nx, double ny, double wd, double agree, std::vector<int>& in,
                    std::vector<Eigen::Vector2d>& q) {
#ifdef DSR_COUNT_INLIERS_AVX2
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return collectInliersAvx2(x, y, nxs, nys, idx, n, qx, qy, nx, ny, wd, agree, in, q);
#endif
  collectInliersScalar(x, y, nxs, nys, idx, n, qx, qy, nx, ny, wd, agree, in, q);
}

std::size_t countInliers(const float* x, const float* y, const float* nxs, const float* nys, std::size_t n, double qx,
                         double qy, double nx, double ny, double wd, double agree) {
#ifdef DSR_COUNT_INLIERS_AVX2
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return countInliersAvx2(x, y, nxs, nys, n, qx, qy, nx, ny, wd, agree);
#endif
  return countInliersScalar(x, y, nxs, nys, n, qx, qy, nx, ny, wd, agree);
}

}  // namespace

std::vector<WallPlane> findWalls(const Points& points, const Normals& normals, double floor_z, double height_top,
                                 bool ceiling_known, const Eigen::Vector2d& viewpoint, const Parameters& p,
                                 const ViewTop* view, const OnWall& on_wall) {
  std::vector<int> pool;
  pool.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    if (std::abs(normals.n[i].z()) < p.vertical_normal_z && points[i].z() > floor_z + 0.05) pool.push_back(static_cast<int>(i));
  // The pool's x, y and normal x, y side by side (kept in the pool's order
  // as it shrinks): the sample and the inlier passes read them in turn
  // instead of gathering them.
  std::vector<float> px(pool.size()), py(pool.size()), pnx(pool.size()), pny(pool.size());
  for (std::size_t j = 0; j < pool.size(); ++j) {
    const int i = pool[j];
    px[j] = points[i].x(), py[j] = points[i].y();
    pnx[j] = normals.n[i].x(), pny[j] = normals.n[i].y();
  }
  std::vector<WallPlane> walls;
  std::mt19937 rng(static_cast<unsigned>(p.random_seed));
  std::vector<float> sx, sy, snx, sny;  // the scored sample, side by side
  // A round's wall rules (addWallSegments) run as a task on the other core
  // while this one draws the next rounds' planes, which need only the pool
  // and the generator, not the walls. The rules of consecutive rounds still
  // run in turn (task dependences: the shadow test reads the walls before),
  // and a round is kept only if the walls found before it leave room
  // (max_walls), as in a loop that waited for them: rounds drawn past the
  // last are dropped unused.
  util::FirstError error;
  int threads = 1;
#ifdef _OPENMP
  threads = std::min(2, omp_get_max_threads());
#endif
  // The rounds drawn on the master thread (the other takes the tasks at the
  // region's end): libgomp keeps the dependences of the tasks a thread makes
  // in that thread's implicit task, and a pool thread's (where a single
  // construct may put the rounds) can be set up afresh for the next region
  // before it is freed (LeakSanitizer saw it leak); the master's is freed as
  // its region ends.
#pragma omp parallel num_threads(threads) if (threads > 1)
#pragma omp master
  try {
    for (int round = 0; round < 4 * p.max_walls; ++round) {
      if (static_cast<int>(pool.size()) < p.min_wall_points) break;
      // 1-point RANSAC: a point with its (horizontal) normal proposes a plane.
      std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
      std::size_t best_count = 0;
      Eigen::Vector2d best_pt, best_n;
      const std::size_t stride = std::max<std::size_t>(1, pool.size() / 20000);
      const double sampled = static_cast<double>((pool.size() + stride - 1) / stride);
      // Adaptive: stop once a plane larger than the best would have been drawn
      // with probability 0.999 (capped by ransac_iterations).
      int needed = p.ransac_iterations;
      // The scored sample (every stride-th point of the pool) in arrays of
      // x, y and the normal's x, y, read in turn instead of gathered.
      // Every point of the pool (stride 1): the pool's own arrays.
      const float *sxp = px.data(), *syp = py.data(), *snxp = pnx.data(), *snyp = pny.data();
      if (stride > 1) {
        sx.clear(), sy.clear(), snx.clear(), sny.clear();
        for (std::size_t j = 0; j < pool.size(); j += stride) {
          sx.push_back(px[j]), sy.push_back(py[j]);
          snx.push_back(pnx[j]), sny.push_back(pny[j]);
        }
        sxp = sx.data(), syp = sy.data(), snxp = snx.data(), snyp = sny.data();
      }
      const std::size_t ns = (pool.size() + stride - 1) / stride;
      const double wd = p.wall_distance, agree = p.wall_normal_agreement;
      // The plane of pool point s scored on the sample (0 if s has no normal).
      auto score = [&](int s) -> std::size_t {
        Eigen::Vector2d n(normals.n[s].x(), normals.n[s].y());
        if (n.norm() < 0.5) return 0;
        n.normalize();
        return countInliers(sxp, syp, snxp, snyp, ns, points[s].x(), points[s].y(), n.x(), n.y(), wd, agree);
      };
      // The first kMinRansacIterations draws are scored whatever they score
      // (needed never falls below): drawn in turn as the loop draws them, and
      // scored as tasks, two at once (a small sample here: no tasks, no wait
      // on the other thread).
      const int always = std::min(kMinRansacIterations, p.ransac_iterations);
      std::vector<int> drawn(always);
      std::vector<std::size_t> counts(always, 0);
      for (int it = 0; it < always; ++it) drawn[it] = pool[pick(rng)];
#pragma omp taskloop default(shared) num_tasks(2) if (ns >= kTaskSample)
      for (int it = 0; it < always; ++it) counts[it] = score(drawn[it]);
      for (int it = 0; it < std::min(needed, p.ransac_iterations); ++it) {
        const int s = it < always ? drawn[it] : pool[pick(rng)];
        Eigen::Vector2d n(normals.n[s].x(), normals.n[s].y());
        if (n.norm() < 0.5) continue;
        n.normalize();
        const Eigen::Vector2d q(points[s].x(), points[s].y());
        const std::size_t count = it < always ? counts[it] : score(s);
        if (count > best_count) {
          best_count = count, best_pt = q, best_n = n;
          const double w = std::min(0.999, best_count / sampled);
          needed = std::max(kMinRansacIterations, static_cast<int>(std::ceil(std::log(0.001) / std::log(1.0 - w))));
        }
      }
      if (best_count * stride < static_cast<std::size_t>(p.min_wall_points)) break;
      // Refine twice by TLS on the inliers.
      std::vector<int> inl;
      std::vector<Eigen::Vector2d> q2;
      inl.reserve(pool.size());
      q2.reserve(pool.size());
      // The inliers of pool[j0, j1) in pool order.
      // (Those within wall_distance of the line whose normal agrees: |(r -
      // best_pt) . best_n| and |best_n . n_i| in double, from the pool's arrays.)
      auto inliersOf = [&](std::size_t j0, std::size_t j1, std::vector<int>& in, std::vector<Eigen::Vector2d>& q) {
        collectInliers(px.data() + j0, py.data() + j0, pnx.data() + j0, pny.data() + j0, pool.data() + j0, j1 - j0,
                       best_pt.x(), best_pt.y(), best_n.x(), best_n.y(), p.wall_distance, p.wall_normal_agreement, in,
                       q);
      };
      // The inliers of the whole pool: a large pool in two halves at once,
      // the second as a task into lists of its own (moved out when done: the
      // ends of lists side by side would share cache lines between the
      // cores), appended after the first's: the lists of one pass. A task
      // group waits for that task alone, not for the rounds' rules (tasks).
      std::vector<int> inl_second;
      std::vector<Eigen::Vector2d> q2_second;
      auto allInliers = [&] {
        inl.clear();
        q2.clear();
        if (pool.size() < kTaskPool) {
          inliersOf(0, pool.size(), inl, q2);
          return;
        }
        const std::size_t mid = pool.size() / 2;
        util::FirstError failed;  // an exception must not leave the task
#pragma omp taskgroup
        {
#pragma omp task default(shared)
          failed.run([&] {
            std::vector<int> in;
            std::vector<Eigen::Vector2d> q;
            in.reserve(pool.size() - mid);
            q.reserve(pool.size() - mid);
            inliersOf(mid, pool.size(), in, q);
            inl_second.swap(in);
            q2_second.swap(q);
          });
          failed.run([&] { inliersOf(0, mid, inl, q2); });
        }
        failed.rethrow();
        inl.insert(inl.end(), inl_second.begin(), inl_second.end());
        q2.insert(q2.end(), q2_second.begin(), q2_second.end());
      };
      // Where the wall's own noise fills the inlier band (a depth camera's
      // wall 3-5 m off: sigma 1.5-2.5 cm against wall_distance's 3 cm), a
      // refit on the points within the band is drawn to the line it was cut
      // with (see kRefinePasses), and the tilt left hides trim and recess.
      // The noise is read off the inliers themselves (kNoiseStretch; the
      // median of the stretches', where a leaf or trim fills one or two):
      // where the three refits left 5 % of a tilt or more (passesLeft), the
      // line is refit in a band of kNoiseBandSigmas sigma to convergence,
      // and kept where it holds at least as many inliers (within
      // wall_distance) as the line it started from (a band centred on the
      // wall holds the most of its points); the inliers stay those within
      // wall_distance. A quiet wall is left as it is.
      auto fitInNoiseBand = [&] {
        std::vector<int> wide_in;
        std::vector<Eigen::Vector2d> wide_q;
        auto wideBand = [&](double band) {
          wide_in.clear(), wide_q.clear();
          collectInliers(px.data(), py.data(), pnx.data(), pny.data(), pool.data(), pool.size(), best_pt.x(),
                         best_pt.y(), best_n.x(), best_n.y(), band, p.wall_normal_agreement, wide_in, wide_q);
        };
        // Each kNoiseStretch (m) along the line with kNoiseStretchPoints
        // inliers or more: the share of them within a third of the band.
        const double wd = p.wall_distance;
        const Eigen::Vector2d along(best_n.y(), -best_n.x());
        double s_min = std::numeric_limits<double>::infinity(), s_max = -s_min;
        for (const Eigen::Vector2d& q : q2) {
          const double sq = (q - best_pt).dot(along);
          s_min = std::min(s_min, sq), s_max = std::max(s_max, sq);
        }
        if (!(s_max >= s_min && s_max - s_min < 1e4)) return;  // none, or no room's wall
        const double k0 = std::floor(s_min / kNoiseStretch);
        const std::size_t stretches = static_cast<std::size_t>(std::floor(s_max / kNoiseStretch) - k0) + 1;
        std::vector<std::size_t> all(stretches, 0), inner(stretches, 0);
        for (const Eigen::Vector2d& q : q2) {
          const Eigen::Vector2d r = q - best_pt;
          const double kf = std::floor(r.dot(along) / kNoiseStretch) - k0;
          const std::size_t k = std::min(stretches - 1, static_cast<std::size_t>(std::max(0.0, kf)));
          ++all[k];
          inner[k] += std::abs(r.dot(best_n)) < wd / 3;
        }
        std::vector<double> stretch_sigma;
        for (std::size_t k = 0; k < stretches; ++k)
          if (all[k] >= kNoiseStretchPoints)
            stretch_sigma.push_back(sigmaOfInnerShare(static_cast<double>(inner[k]) / all[k], wd));
        if (stretch_sigma.empty()) return;
        std::nth_element(stretch_sigma.begin(), stretch_sigma.begin() + stretch_sigma.size() / 2, stretch_sigma.end());
        const double sigma = stretch_sigma[stretch_sigma.size() / 2];
        if (passesLeft(wd / sigma) < kNoiseBandLeft) return;
        const double band = std::min(kNoiseBandMax * wd, kNoiseBandSigmas * sigma);
        const Eigen::Vector2d start_pt = best_pt, start_n = best_n;
        const std::size_t start_count = inl.size();
        for (int pass = 0; pass < kRefinePasses; ++pass) {
          wideBand(band);
          if (wide_q.size() < 3) break;
          Eigen::Vector2d c, dir;
          fitLine(wide_q, c, dir);
          Eigen::Vector2d nn(-dir.y(), dir.x());
          if (nn.dot(best_n) < 0) nn = -nn;
          const double cos_turn = nn.dot(best_n);
          best_pt = c, best_n = nn;
          if (cos_turn > kNoiseBandConverged) break;
        }
        allInliers();
        if (inl.size() < start_count) {  // off the wall: back to the line it started from
          best_pt = start_pt, best_n = start_n;
          allInliers();
        }
      };
      for (int pass = 0; pass < 3; ++pass) {
        allInliers();
        if (q2.size() < 3 || pass == 2) break;
        Eigen::Vector2d c, dir;
        fitLine(q2, c, dir);
        best_pt = c;
        best_n = Eigen::Vector2d(-dir.y(), dir.x());
      }
      // A wall noisier than its band: refit in a band scaled to its noise.
      fitInNoiseBand();
      // Then on while the refit line holds more inliers (kRefinePasses),
      // taken if it turned the wall by kConvergedTurnDeg or more. (A pass's
      // lists are swapped aside, not copied: the last pass's come back when
      // a pass holds no more, the third's when the turn is too small.)
      {
        const Eigen::Vector2d third_pt = best_pt, third_n = best_n;
        std::vector<int> third_inl, last_inl;
        std::vector<Eigen::Vector2d> third_q2, last_q2;
        for (int pass = 3; pass < kRefinePasses && q2.size() >= 3; ++pass) {
          const std::size_t count = inl.size();
          const Eigen::Vector2d keep_pt = best_pt, keep_n = best_n;
          Eigen::Vector2d c, dir;
          fitLine(q2, c, dir);
          Eigen::Vector2d nn(-dir.y(), dir.x());
          if (nn.dot(best_n) < 0) nn = -nn;
          best_pt = c, best_n = nn;
          last_inl.swap(inl), last_q2.swap(q2);
          allInliers();
          if (inl.size() <= count) {
            best_pt = keep_pt, best_n = keep_n;
            inl.swap(last_inl), q2.swap(last_q2);
            break;
          }
          if (pass == 3) third_inl.swap(last_inl), third_q2.swap(last_q2);
        }
        const double turn = std::acos(std::min(1.0, std::abs(third_n.dot(best_n)))) * 180.0 / M_PI;
        if (!third_inl.empty() && turn < kConvergedTurnDeg) {
          best_pt = third_pt, best_n = third_n;
          inl.swap(third_inl), q2.swap(third_q2);
        }
      }
      // Remove the inliers from the pool whatever becomes of them (they are
      // a part of it, in its order).
      {
        std::size_t k = 0, kept = 0;
        for (std::size_t j = 0; j < pool.size(); ++j) {
          const int i = pool[j];
          if (k < inl.size() && inl[k] == i) {
            ++k;
            continue;
          }
          pool[kept] = i;
          px[kept] = px[j], py[kept] = py[j], pnx[kept] = pnx[j], pny[kept] = pny[j];
          ++kept;
        }
        pool.resize(kept);
        px.resize(kept), py.resize(kept), pnx.resize(kept), pny.resize(kept);
      }
      const Eigen::Vector2d dir(best_n.y(), -best_n.x());
      if ((viewpoint - best_pt).dot(best_n) < 0) best_n = -best_n;
      // The round's rules after the previous round's (depend), each with its
      // own inliers; skipped once a round failed or max_walls walls are
      // found, where a loop that waited for them would have stopped.
      auto round_inl = std::make_shared<std::vector<int>>(std::move(inl));
      const bool defer = round_inl->size() >= kTaskInliers;
#pragma omp task default(shared) firstprivate(best_pt, best_n, dir, round_inl) depend(inout : walls) if (defer)
      error.run([&] {
        if (!error.failed() && static_cast<int>(walls.size()) < p.max_walls) {
          const std::size_t before = walls.size();
          addWallSegments(points, *round_inl, best_pt, dir, best_n, floor_z, height_top, ceiling_known, p, walls, view,
                          &viewpoint);
          if (on_wall)
            for (std::size_t i = before; i < walls.size(); ++i) on_wall(i, walls[i]);
        }
      });
    }
  } catch (...) {
    // Kept after the rules of the rounds drawn before it, whose exception comes first.
#pragma omp taskwait
    error.keep(std::current_exception());
  }
  error.rethrow();
  return walls;
}

}  // namespace segmentation
}  // namespace dsr
