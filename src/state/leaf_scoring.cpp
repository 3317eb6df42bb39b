// State: the scores of leaf hypotheses in fitLeaf's search: support (cells
// of the leaf holding points) against contradiction (cells rays went
// through), each point and ray tested only at the angles (and hinges)
// where its test can pass.
#include "leaf_internal.hpp"

#include "door_state_recognition/util/floor.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#endif

namespace dsr {
namespace state {
namespace detail {

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

// An upper bound of asin(x), x in [0, 1], within 2% for x <= 0.5: asin's
// series x + x^3/6 + 3x^5/40 + ... has no coefficient above 1/6 after the
// first, so it is at most x + x^3 / (6 (1 - x^2)); capped at pi / 2. An arc
// widened by it holds every angle asin's would (the tests decide).
inline double asinAbove(double x) {
  if (x >= 1) return M_PI / 2;
  return std::min(M_PI / 2, x + x * x * x / (6 * (1 - x * x)));
}

}  // namespace

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

int LeafSearch::bound(const HingeRun& w, int ai) const {  // no length of the leaf at angle ai scores more
  int total = 0;
  for (int i = 0; i < na_max; ++i) total += w.sup[static_cast<std::size_t>(ai) * na_max + i];
  return total;
}

void LeafSearch::axes(const HingeRun& w, std::vector<Eigen::Vector2d>& E, std::vector<Eigen::Vector2d>& K,
                      std::vector<Eigen::Vector2d>& P) const {
  E.resize(w.count);
  K.resize(w.count);
  P.resize(w.count);
  const Eigen::Vector2d H(w.s_h, w.d_h);
  for (int ai = 0; ai < w.count; ++ai) {
    const double th = (w.start + ai * w.step) * M_PI / 180;
    const LeafAxes axes(th, w.e0, w.m);
    E[ai] = axes.e;
    K[ai] = axes.k;
    P[ai] = H + K[ai] * (lt / 2);  // the leaf's mid-plane
  }
}

// f(i) for every angle start + i step of w within [lo, hi] degrees, modulo
// 360, and with i in [first, last] (f is not called outside it). inv_step:
// 1 / w.step (the steps searched, 2 and 0.5 deg, are powers of two: their
// inverse multiplies exactly as they divide; any other would move an index
// by a rounding, far inside its 1e-9 of slack).
template <class F>
void LeafSearch::forArc(const HingeRun& w, double inv_step, double lo, double hi, F&& f, int first, int last) const {
  if (last < 0) last = w.count - 1;
  const double end = w.start + (w.count - 1) * w.step;
  for (double shift = -360; shift <= 360; shift += 360) {
    const double a = lo + shift, b = hi + shift;
    if (b < w.start - w.step || a > end + w.step) continue;  // no angle of the run
    const int i0 = std::max(first, util::ceilToInt((a - w.start) * inv_step - 1e-9));
    const int i1 = std::min(last, util::floorToInt((b - w.start) * inv_step + 1e-9));
    for (int i = i0; i <= i1; ++i) f(i);
  }
}

namespace {

// A point's distance from the hinge and the arc of angles (deg) at which
// it can lie in the leaf's band (see scorePoints), for points of a chunk:
// rho; the arc's ends without asin (slo, shi: the short-run test) and with
// it, widened by kBearingSlackDeg (lo, hi). Whether and how they are used
// is decided by rho. Four points at a time with AVX2 (no FMA: the same
// operations in the same order as arcsScalar, lane by lane the same bits).
struct Arcs {
  static constexpr std::size_t kChunk = 256;
  double rho[kChunk], slo[kChunk], shi[kChunk], lo[kChunk], hi[kChunk];
};
struct ArcFrame {  // one hinge's: its position, closed direction and swing side, the band's widths
  double s_h, d_h, e0, m, tol, band_hw;
};
constexpr double kDeg = 180 / M_PI;

inline void arcsScalar(const Local* q, std::size_t k0, std::size_t n, const ArcFrame& f, Arcs& out) {
  for (std::size_t k = k0; k < n; ++k) {
    const Eigen::Vector2d r(q[k].s - f.s_h, q[k].d - f.d_h);
    const double rho = r.norm();
    // b = rho sin(th - c) lies in [-tol, lt + tol] only for th - c within
    // [-asin(tol / rho), asin((lt + tol) / rho)].
    const double c = fastAtan2Deg(f.m * r.y(), f.e0 * r.x());
    // tol / rho and band_hw / rho by one division: each off by a rounding
    // at most, which moves the arc far less than kBearingSlackDeg (and the
    // short-run test only by as little): the same angles pass.
    const double inv_rho = 1 / rho, x_below = f.tol * inv_rho, x_above = f.band_hw * inv_rho;
    out.rho[k] = rho;
    out.slo[k] = c - x_below * kDeg;
    out.shi[k] = c + x_above * kDeg;
    out.lo[k] = c - (asinAbove(x_below) * kDeg + kBearingSlackDeg);
    out.hi[k] = c + (asinAbove(x_above) * kDeg + kBearingSlackDeg);
  }
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DSR_LEAF_ARCS_AVX2 1
__attribute__((target("avx2"))) inline __m256d asinAboveAvx2(__m256d x) {
  // std::min(pi / 2, v): v where v < pi / 2, else pi / 2 (v is no NaN for x < 1); pi / 2 where x >= 1.
  const __m256d one = _mm256_set1_pd(1.0), half_pi = _mm256_set1_pd(M_PI / 2);
  const __m256d x2 = _mm256_mul_pd(x, x);
  const __m256d v = _mm256_add_pd(
      x, _mm256_div_pd(_mm256_mul_pd(x2, x), _mm256_mul_pd(_mm256_set1_pd(6.0), _mm256_sub_pd(one, x2))));
  const __m256d below = _mm256_blendv_pd(half_pi, v, _mm256_cmp_pd(v, half_pi, _CMP_LT_OQ));
  return _mm256_blendv_pd(below, half_pi, _mm256_cmp_pd(x, one, _CMP_GE_OQ));
}
__attribute__((target("avx2"))) void arcsAvx2(const Local* q, std::size_t n, const ArcFrame& f, Arcs& out) {
  const __m256d s_h = _mm256_set1_pd(f.s_h), d_h = _mm256_set1_pd(f.d_h), e0 = _mm256_set1_pd(f.e0),
                m = _mm256_set1_pd(f.m), tol = _mm256_set1_pd(f.tol), band_hw = _mm256_set1_pd(f.band_hw);
  const __m256d sign = _mm256_set1_pd(-0.0), zero = _mm256_setzero_pd(), deg = _mm256_set1_pd(kDeg),
                slack = _mm256_set1_pd(kBearingSlackDeg);
  std::size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    const __m256d rx = _mm256_sub_pd(_mm256_set_pd(q[k + 3].s, q[k + 2].s, q[k + 1].s, q[k].s), s_h);
    const __m256d ry = _mm256_sub_pd(_mm256_set_pd(q[k + 3].d, q[k + 2].d, q[k + 1].d, q[k].d), d_h);
    const __m256d rho = _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(rx, rx), _mm256_mul_pd(ry, ry)));
    // fastAtan2Deg(m ry, e0 rx), step for step.
    const __m256d y = _mm256_mul_pd(m, ry), x = _mm256_mul_pd(e0, rx);
    const __m256d ax = _mm256_andnot_pd(sign, x), ay = _mm256_andnot_pd(sign, y);
    // std::max(ax, ay) and std::min(ax, ay) (no NaN; equal values alike).
    const __m256d ay_gt_ax = _mm256_cmp_pd(ay, ax, _CMP_GT_OQ);
    const __m256d mx = _mm256_blendv_pd(ax, ay, _mm256_cmp_pd(ax, ay, _CMP_LT_OQ));
    const __m256d mn = _mm256_blendv_pd(ax, ay, _mm256_cmp_pd(ay, ax, _CMP_LT_OQ));
    const __m256d t = _mm256_div_pd(mn, mx), t2 = _mm256_mul_pd(t, t);
    __m256d poly = _mm256_add_pd(_mm256_set1_pd(-0.0851330), _mm256_mul_pd(_mm256_set1_pd(0.0208351), t2));
    poly = _mm256_add_pd(_mm256_set1_pd(0.1801410), _mm256_mul_pd(t2, poly));
    poly = _mm256_add_pd(_mm256_set1_pd(-0.3302995), _mm256_mul_pd(t2, poly));
    poly = _mm256_add_pd(_mm256_set1_pd(0.9998660), _mm256_mul_pd(t2, poly));
    __m256d a = _mm256_mul_pd(t, poly);
    a = _mm256_blendv_pd(a, _mm256_sub_pd(_mm256_set1_pd(M_PI / 2), a), ay_gt_ax);
    a = _mm256_blendv_pd(a, _mm256_sub_pd(_mm256_set1_pd(M_PI), a), _mm256_cmp_pd(x, zero, _CMP_LT_OQ));
    a = _mm256_blendv_pd(a, _mm256_xor_pd(a, sign), _mm256_cmp_pd(y, zero, _CMP_LT_OQ));
    a = _mm256_mul_pd(a, deg);
    const __m256d c = _mm256_blendv_pd(a, zero, _mm256_cmp_pd(mx, zero, _CMP_EQ_OQ));
    const __m256d inv_rho = _mm256_div_pd(_mm256_set1_pd(1.0), rho);
    const __m256d x_below = _mm256_mul_pd(tol, inv_rho), x_above = _mm256_mul_pd(band_hw, inv_rho);
    _mm256_storeu_pd(out.rho + k, rho);
    _mm256_storeu_pd(out.slo + k, _mm256_sub_pd(c, _mm256_mul_pd(x_below, deg)));
    _mm256_storeu_pd(out.shi + k, _mm256_add_pd(c, _mm256_mul_pd(x_above, deg)));
    _mm256_storeu_pd(out.lo + k, _mm256_sub_pd(c, _mm256_add_pd(_mm256_mul_pd(asinAboveAvx2(x_below), deg), slack)));
    _mm256_storeu_pd(out.hi + k, _mm256_add_pd(c, _mm256_add_pd(_mm256_mul_pd(asinAboveAvx2(x_above), deg), slack)));
  }
  _mm256_zeroupper();
  arcsScalar(q, k, n, f, out);
}
#endif

void arcsOf(const Local* q, std::size_t n, const ArcFrame& f, Arcs& out) {
#ifdef DSR_LEAF_ARCS_AVX2
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return arcsAvx2(q, n, f, out);
#endif
  arcsScalar(q, 0, n, f, out);
}

}  // namespace

void LeafSearch::scorePoints(HingeRun& w) const {
  std::vector<char> seen(w.count * cells, 0);  // per angle: leaf bin x z bin
  w.sup.assign(static_cast<std::size_t>(w.count) * na_max, 0);
  std::vector<Eigen::Vector2d> E, K, P;
  axes(w, E, K, P);
  const double end = w.start + (w.count - 1) * w.step, inv_step = 1 / w.step;
  const ArcFrame frame{w.s_h, w.d_h, w.e0, w.m, tol, band_hw};
  Arcs arcs;
  for (std::size_t k0 = 0; k0 < pts.size(); k0 += Arcs::kChunk) {
    const std::size_t n = std::min(Arcs::kChunk, pts.size() - k0);
    arcsOf(pts.data() + k0, n, frame, arcs);
    for (std::size_t k = 0; k < n; ++k) {
      const Local& q = pts[k0 + k];
      const double rho = arcs.rho[k];
      if (rho > r_pts) continue;
      const Eigen::Vector2d r(q.s - w.s_h, q.d - w.d_h);
      auto test = [&](int ai) {
        const double a = r.dot(E[ai]), b = r.dot(K[ai]);
        if (a < 0.02 || a >= Lmax || b < -tol || b > lt + tol) return;
        const int ab = std::min(na_max - 1, static_cast<int>(a / abin));
        char& f = seen[ai * cells + static_cast<std::size_t>(ab) * nz + q.zbin];
        if (!f) f = 1, ++w.sup[static_cast<std::size_t>(ai) * na_max + ab];
      };
      // Near the hinge, and where a short run of angles (the local search)
      // lies wholly inside the arc (x <= asin(x) tells so without asin),
      // every angle is tested (testing more angles than the arc holds is
      // always safe; the test decides).
      if (rho <= band_hw || (arcs.slo[k] <= w.start && arcs.shi[k] >= end)) {
        for (int ai = 0; ai < w.count; ++ai) test(ai);
        continue;
      }
      forArc(w, inv_step, arcs.lo[k], arcs.hi[k], test);
    }
  }
}

namespace {

// The part of a ray that counts, from the sensor (vsd) to 6 cm before its
// point, as A + t u (t in [0, 1]), and the chord [t0, t1] of it within the
// disc (radius r_rays) about the hinge the leaf's mid-line can reach (w0 =
// A - hinge, cq = |w0|^2 - r_rays^2), for rays of a chunk: ok where that
// chord is not empty and the ray's height on it reaches the leaf's heights
// [zlo, zhi) (1 mm spared: zlo = z0 - 1e-3, zhi = z1 + 1e-3). Four rays at
// a time with AVX2 (no FMA: the same operations in the same order as
// chordsScalar, lane by lane the same bits).
struct Chords {
  static constexpr std::size_t kChunk = 256;
  double t0[kChunk], t1[kChunk];
  char ok[kChunk];
};
struct ChordFrame {
  double vx, vy, w0x, w0y, cq, vsz, zlo, zhi;
};

inline void chordsScalar(const LeafSearch::Ray* rays, std::size_t k0, std::size_t n, const ChordFrame& f, Chords& out) {
  const Eigen::Vector2d vsd(f.vx, f.vy), w0(f.w0x, f.w0y);
  for (std::size_t k = k0; k < n; ++k) {
    const LeafSearch::Ray& ray = rays[k];
    out.ok[k] = 0;
    const Eigen::Vector2d A = vsd, B = ray.q - (0.06 / ray.len) * (ray.q - vsd);
    const Eigen::Vector2d u = B - A;
    const double uu = u.squaredNorm();
    if (uu < 1e-12) continue;
    // Chord within the disc the leaf's mid-line can reach.
    const double bq = w0.dot(u), disc = bq * bq - uu * f.cq;
    if (disc <= 0) continue;
    const double sq = std::sqrt(disc);
    const double t0 = std::max(0.0, (-bq - sq) / uu), t1 = std::min(1.0, (-bq + sq) / uu);
    if (t0 >= t1) continue;
    // Every crossing with a leaf lies on that chord: a ray passing above or
    // below the leaf's heights there crosses none.
    const double lam_max = 1 - 0.06 / ray.len, dz = ray.qz - f.vsz;
    const double za = f.vsz + t0 * lam_max * dz, zb = f.vsz + t1 * lam_max * dz;
    if (std::max(za, zb) < f.zlo || std::min(za, zb) >= f.zhi) continue;
    out.t0[k] = t0, out.t1[k] = t1, out.ok[k] = 1;
  }
}

#ifdef DSR_LEAF_ARCS_AVX2
__attribute__((target("avx2"))) void chordsAvx2(const LeafSearch::Ray* rays, std::size_t n, const ChordFrame& f,
                                                 Chords& out) {
  const __m256d vx = _mm256_set1_pd(f.vx), vy = _mm256_set1_pd(f.vy), w0x = _mm256_set1_pd(f.w0x),
                w0y = _mm256_set1_pd(f.w0y), cq = _mm256_set1_pd(f.cq), vsz = _mm256_set1_pd(f.vsz),
                zlo = _mm256_set1_pd(f.zlo), zhi = _mm256_set1_pd(f.zhi);
  const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0), sign = _mm256_set1_pd(-0.0),
                six_cm = _mm256_set1_pd(0.06), tiny = _mm256_set1_pd(1e-12);
  std::size_t k = 0;
  for (; k + 4 <= n; k += 4) {
    const LeafSearch::Ray* q = rays + k;
    const __m256d qx = _mm256_set_pd(q[3].q.x(), q[2].q.x(), q[1].q.x(), q[0].q.x());
    const __m256d qy = _mm256_set_pd(q[3].q.y(), q[2].q.y(), q[1].q.y(), q[0].q.y());
    const __m256d qz = _mm256_set_pd(q[3].qz, q[2].qz, q[1].qz, q[0].qz);
    const __m256d len = _mm256_set_pd(q[3].len, q[2].len, q[1].len, q[0].len);
    const __m256d kk = _mm256_div_pd(six_cm, len);
    // B = q - k (q - vsd), u = B - vsd.
    const __m256d ux = _mm256_sub_pd(_mm256_sub_pd(qx, _mm256_mul_pd(kk, _mm256_sub_pd(qx, vx))), vx);
    const __m256d uy = _mm256_sub_pd(_mm256_sub_pd(qy, _mm256_mul_pd(kk, _mm256_sub_pd(qy, vy))), vy);
    const __m256d uu = _mm256_add_pd(_mm256_mul_pd(ux, ux), _mm256_mul_pd(uy, uy));
    const __m256d bq = _mm256_add_pd(_mm256_mul_pd(w0x, ux), _mm256_mul_pd(w0y, uy));
    const __m256d disc = _mm256_sub_pd(_mm256_mul_pd(bq, bq), _mm256_mul_pd(uu, cq));
    // Not (uu < 1e-12), not (disc <= 0): as the scalar tests go on past a NaN.
    __m256d ok = _mm256_and_pd(_mm256_cmp_pd(uu, tiny, _CMP_NLT_UQ), _mm256_cmp_pd(disc, zero, _CMP_NLE_UQ));
    const __m256d sq = _mm256_sqrt_pd(disc), nb = _mm256_xor_pd(bq, sign);
    const __m256d v0 = _mm256_div_pd(_mm256_sub_pd(nb, sq), uu), v1 = _mm256_div_pd(_mm256_add_pd(nb, sq), uu);
    // std::max(0.0, v0): v0 where 0 < v0, else 0; std::min(1.0, v1): v1 where v1 < 1, else 1.
    const __m256d t0 = _mm256_blendv_pd(zero, v0, _mm256_cmp_pd(zero, v0, _CMP_LT_OQ));
    const __m256d t1 = _mm256_blendv_pd(one, v1, _mm256_cmp_pd(v1, one, _CMP_LT_OQ));
    ok = _mm256_and_pd(ok, _mm256_cmp_pd(t0, t1, _CMP_NGE_UQ));
    const __m256d lam_max = _mm256_sub_pd(one, kk), dz = _mm256_sub_pd(qz, vsz);
    const __m256d za = _mm256_add_pd(vsz, _mm256_mul_pd(_mm256_mul_pd(t0, lam_max), dz));
    const __m256d zb = _mm256_add_pd(vsz, _mm256_mul_pd(_mm256_mul_pd(t1, lam_max), dz));
    // std::max(za, zb): zb where za < zb, else za; std::min(za, zb): zb where zb < za, else za.
    const __m256d zmax = _mm256_blendv_pd(za, zb, _mm256_cmp_pd(za, zb, _CMP_LT_OQ));
    const __m256d zmin = _mm256_blendv_pd(za, zb, _mm256_cmp_pd(zb, za, _CMP_LT_OQ));
    ok = _mm256_andnot_pd(_mm256_or_pd(_mm256_cmp_pd(zmax, zlo, _CMP_LT_OQ), _mm256_cmp_pd(zmin, zhi, _CMP_GE_OQ)), ok);
    _mm256_storeu_pd(out.t0 + k, t0);
    _mm256_storeu_pd(out.t1 + k, t1);
    const int mask = _mm256_movemask_pd(ok);
    for (int j = 0; j < 4; ++j) out.ok[k + j] = static_cast<char>((mask >> j) & 1);
  }
  _mm256_zeroupper();
  chordsScalar(rays, k, n, f, out);
}
#endif

void chordsOf(const LeafSearch::Ray* rays, std::size_t n, const ChordFrame& f, Chords& out) {
#ifdef DSR_LEAF_ARCS_AVX2
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return chordsAvx2(rays, n, f, out);
#endif
  chordsScalar(rays, 0, n, f, out);
}

}  // namespace

// The cells (per angle: leaf bin x z bin) that rays [r0, r1) go through,
// marked in blocked; the count of each leaf bin's is its contradiction.
void LeafSearch::markRays(const HingeRun& w, const std::vector<char>* need, std::size_t r0, std::size_t r1,
                          std::vector<char>& blocked) const {
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
  const double inv_step = 1 / w.step;
  const Eigen::Vector2d w0 = vsd - H;
  const ChordFrame frame{vsd.x(), vsd.y(), w0.x(), w0.y(), w0.squaredNorm() - r_rays * r_rays, vsz, z0 - 1e-3,
                         z1 + 1e-3};
  Chords chords;
  for (std::size_t k0 = r0; k0 < r1; k0 += Chords::kChunk) {
    const std::size_t n = std::min(Chords::kChunk, r1 - k0);
    chordsOf(rays.data() + k0, n, frame, chords);
    for (std::size_t k = 0; k < n; ++k) {
      if (!chords.ok[k]) continue;
      const Ray& ray = rays[k0 + k];
      // The ray's chord [t0, t1] (chordsOf), and again what the tests below read.
      const Eigen::Vector2d A = vsd, B = ray.q - (0.06 / ray.len) * (ray.q - vsd);
      const Eigen::Vector2d u = B - A;
      const double uu = u.squaredNorm(), bq = w0.dot(u), t0 = chords.t0[k], t1 = chords.t1[k];
      const double lam_max = 1 - 0.06 / ray.len, dz = ray.qz - vsz;
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
      forArc(w, inv_step, lo - kBearingSlackDeg, hi + dl, test, first, last);
    }
  }
}

// Each leaf bin's contradiction at the angles needed (0 at the others, never read).
void LeafSearch::tallyRays(HingeRun& w, const std::vector<char>* need, const std::vector<char>& blocked) const {
  w.con.assign(static_cast<std::size_t>(w.count) * na_max, 0);
  for (int ai = 0; ai < w.count; ++ai)
    for (int ab = 0; ab < na_max && (!need || (*need)[ai]); ++ab) {
      const char* b = &blocked[ai * cells + static_cast<std::size_t>(ab) * nz];
      int n = 0;
      for (int zb = 0; zb < nz; ++zb) n += b[zb];
      w.con[static_cast<std::size_t>(ai) * na_max + ab] = n;
    }
}

void LeafSearch::scoreRays(HingeRun& w, const std::vector<char>* need) const {
  std::vector<char> blocked(w.count * cells, 0);
  markRays(w, need, 0, rays.size(), blocked);
  tallyRays(w, need, blocked);
}

void LeafSearch::finishScores(HingeRun& w, const std::vector<char>* need) const {
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
}

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
void LeafSearch::scoreShifts(std::vector<HingeRun>& ws, int reach, double s_center,
                             const std::vector<std::vector<char>>* need) const {
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
}

}  // namespace detail
}  // namespace state
}  // namespace dsr
