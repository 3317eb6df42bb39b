#include "door_state_recognition/preprocess/preprocess.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <exception>
#include <random>
#include <stdexcept>
#include <limits>
#include <unordered_map>

#ifdef _OPENMP
#include <omp.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#endif

#include "door_state_recognition/preprocess/cell_map.hpp"
#include "door_state_recognition/util/first_error.hpp"

namespace dsr {
namespace preprocess {

Points sanitize(const pcl::PointCloud<pcl::PointXYZ>& cloud, double max_abs) {
  Points out;
  out.reserve(cloud.size());
  const float lim = static_cast<float>(max_abs);
  for (const auto& p : cloud.points)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::abs(p.x) <= lim &&
        std::abs(p.y) <= lim && std::abs(p.z) <= lim)
      out.emplace_back(p.x, p.y, p.z);
  return out;
}

namespace {

constexpr std::uint64_t kNoKey = ~std::uint64_t(0);  // packed keys use 63 bits
// downsampleDense's room made at once in each half: cells, and bricks of 64 cells.
constexpr std::size_t kReserveCells = std::size_t(1) << 20, kReserveBricks = std::size_t(1) << 18;

// The voxel grid of the points point(i), i < n, whose key(i) is not kNoKey.
// Cells are numbered in order of first occurrence: the output keeps the input's order.
// A packed key's cell coordinates (21-bit two's complement an axis): one to
// one with keys, so cells told apart by coordinates are those told apart by keys.
inline Eigen::Vector3i unpackCell(std::uint64_t k) {
  auto axis = [](std::uint64_t v) { return static_cast<int>(static_cast<std::int32_t>(static_cast<std::uint32_t>(v << 11)) >> 11); };
  return Eigen::Vector3i(axis(k & 0x1FFFFF), axis((k >> 21) & 0x1FFFFF), axis((k >> 42) & 0x1FFFFF));
}

// downsample() through a dense index instead of a hash map, when the cells'
// bounding box is small: bricks of 4 x 4 x 4 cells over the box (at most 2
// entries a point plus 1M), each brick's 64 cells numbered as first met. A
// scan meets cells brick by brick, so the lookups stay in cache. Cells are
// numbered and summed exactly as downsample() does. False: box too large.
// The cells' bounding box (of their keys' coordinates) and whether any key
// is valid, when the caller found them already.
struct KeyBox {
  Eigen::Vector3i lo, hi;
  bool any;
};

template <class PointAt>
bool downsampleDense(long long n, const PointAt& point, const std::vector<std::uint64_t>& key, Points& out,
                     const KeyBox* box = nullptr) {
  Eigen::Vector3i lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max()), hi = -lo;
  long long valid = 0;
  std::uint64_t last_key = kNoKey;
  if (box) {
    lo = box->lo, hi = box->hi, valid = box->any;
  } else {
    for (long long i = 0; i < n; ++i) {
      if (key[i] == kNoKey || key[i] == last_key) continue;
      last_key = key[i];
      const Eigen::Vector3i c = unpackCell(key[i]);
      lo = lo.cwiseMin(c), hi = hi.cwiseMax(c);
      ++valid;
    }
  }
  if (valid == 0) return false;
  auto brickOf = [](int v) { return v >> 2; };  // floor(v / 4): an arithmetic shift (as g++ shifts, and C++20 requires)
  const Eigen::Vector3i blo(brickOf(lo.x()), brickOf(lo.y()), brickOf(lo.z()));
  const Eigen::Vector3i dims = Eigen::Vector3i(brickOf(hi.x()), brickOf(hi.y()), brickOf(hi.z())) - blo + Eigen::Vector3i::Ones();
  const double volume = static_cast<double>(dims.x()) * dims.y() * dims.z();
  if (volume > 2.0 * static_cast<double>(n) + (1 << 20)) return false;
  // The cell entry of key k in a dense index (brick -> its 64 cells), the
  // brick made when missing. The box is held by value: a copy of it in a
  // loop keeps it in registers.
  auto entry = [blo, dims, brickOf](std::vector<std::uint32_t>& brick, std::vector<std::uint32_t>& cell,
                                    std::uint64_t k) -> std::uint32_t& {
    const Eigen::Vector3i c = unpackCell(k);
    const Eigen::Vector3i b(brickOf(c.x()), brickOf(c.y()), brickOf(c.z()));
    std::uint32_t& kb = brick[(static_cast<std::size_t>(b.z() - blo.z()) * dims.y() + (b.y() - blo.y())) * dims.x() +
                              (b.x() - blo.x())];
    if (kb == CellMap::kNone) {
      kb = static_cast<std::uint32_t>(cell.size() / 64);
      cell.resize(cell.size() + 64, CellMap::kNone);
    }
    return cell[64 * static_cast<std::size_t>(kb) + (c.x() & 3) + 4 * (c.y() & 3) + 16 * (c.z() & 3)];
  };
  // A large cloud in two halves at once, each numbering and summing the
  // cells it meets as below, in an index of its own. A cell of the second
  // half not met in the first comes after every cell of the first (in order
  // of first point) with the sums of all its points in order; a cell met in
  // both takes the first's number, and the second's points are added to the
  // first's sums after it, in point order: the numbers and sums of one pass.
  // Each on cache lines of its own: the ends of its lists, written as a
  // half grows them, stay off the lines the other half reads and writes.
  struct alignas(64) Half {
    std::vector<std::uint32_t> brick, cell;  // brick -> its 64 cells -> cell number
    std::vector<Eigen::Vector3d> sum;
    std::vector<int> count;
    std::vector<std::uint64_t> keys;  // each cell's key
  };
  auto fill = [&](Half& h, long long i0, long long i1) {
    h.brick.assign(static_cast<std::size_t>(volume), CellMap::kNone);
    // Room for a cell (and a brick) per point, up to kReserveCells cells and
    // kReserveBricks bricks (only what is used is touched): the lists of a
    // camera frame or a laser scan of a few 100k points never move as they
    // grow; a larger cloud's grow past that. Room for all of a cloud of
    // max_points would be gigabytes of address space (64 entries a brick),
    // refused under ulimit -v or strict overcommit.
    const std::size_t most = static_cast<std::size_t>(i1 - i0);
    const std::size_t cells = std::min(most, kReserveCells);
    h.sum.reserve(cells);
    h.count.reserve(cells);
    h.keys.reserve(cells);
    h.cell.reserve(64 * std::min({cells, static_cast<std::size_t>(volume), kReserveBricks}));
    std::uint64_t last_key = kNoKey;
    std::uint32_t last_id = 0;
    // A scan visits a voxel in runs of points: the run's cell is known, and
    // its sum and count are kept here while the run lasts (the same
    // additions in the same order as into the lists), written back when it
    // ends. The keys and points through local copies: nothing in the loop
    // can move them.
    const std::uint64_t* const keys = key.data();
    const PointAt at = point;
    const auto cellEntry = entry;
    Eigen::Vector3d run_sum = Eigen::Vector3d::Zero();
    int run_count = 0;  // 0: no run yet
    for (long long i = i0; i < i1; ++i) {
      const std::uint64_t k = keys[i];
      if (k == kNoKey) continue;
      if (k == last_key) {
        run_sum += at(i).template cast<double>();
        ++run_count;
        continue;
      }
      if (run_count > 0) h.sum[last_id] = run_sum, h.count[last_id] = run_count;
      std::uint32_t& id = cellEntry(h.brick, h.cell, k);
      if (id == CellMap::kNone) {
        id = static_cast<std::uint32_t>(h.sum.size());
        h.sum.push_back(at(i).template cast<double>());
        h.count.push_back(1);
        h.keys.push_back(k);
        run_sum = h.sum.back();
        run_count = 1;
      } else {
        run_sum = h.sum[id] + at(i).template cast<double>();
        run_count = h.count[id] + 1;
      }
      last_key = k;
      last_id = id;
    }
    if (run_count > 0) h.sum[last_id] = run_sum, h.count[last_id] = run_count;
  };
  long long mid = n;
#ifdef _OPENMP
  if (n >= 50000 && omp_get_max_threads() >= 2) mid = n / 2;
#endif
  Half first, second;
  if (mid == n) {
    fill(first, 0, n);
  } else {
    util::FirstError error;
#pragma omp parallel for schedule(static, 1) num_threads(2)
    for (int t = 0; t < 2; ++t) error.run([&] { t == 0 ? fill(first, 0, mid) : fill(second, mid, n); });
    error.rethrow();
  }
  // The second half's cells: the first's number when met there (shared), else kNone.
  std::vector<std::uint32_t> shared(second.sum.size());
  auto find = [&](const Half& h, std::uint64_t k) {
    const Eigen::Vector3i c = unpackCell(k);
    const Eigen::Vector3i b(brickOf(c.x()), brickOf(c.y()), brickOf(c.z()));
    const std::uint32_t kb = h.brick[(static_cast<std::size_t>(b.z() - blo.z()) * dims.y() + (b.y() - blo.y())) * dims.x() +
                                     (b.x() - blo.x())];
    return kb == CellMap::kNone ? kb : h.cell[64 * static_cast<std::size_t>(kb) + (c.x() & 3) + 4 * (c.y() & 3) + 16 * (c.z() & 3)];
  };
  long long remaining = 0;  // points of the second half in shared cells
  for (std::size_t l = 0; l < shared.size(); ++l) {
    shared[l] = find(first, second.keys[l]);
    if (shared[l] != CellMap::kNone) remaining += second.count[l];
  }
  // Their points added to the first's sums in point order (a scan stopping
  // after the last: shared cells lie near where the halves meet).
  {
    std::uint64_t last_key = kNoKey;
    std::uint32_t last_shared = CellMap::kNone;
    for (long long i = mid; i < n && remaining > 0; ++i) {
      if (key[i] == kNoKey) continue;
      if (key[i] != last_key) {
        last_key = key[i];
        last_shared = shared[find(second, key[i])];
      }
      if (last_shared == CellMap::kNone) continue;
      first.sum[last_shared] += point(i).template cast<double>();
      ++first.count[last_shared];
      --remaining;
    }
  }
  std::size_t total = first.sum.size();
  for (std::uint32_t id : shared) total += id == CellMap::kNone;
  out.resize(total);
  for (std::size_t k = 0; k < first.sum.size(); ++k) out[k] = (first.sum[k] / first.count[k]).template cast<float>();
  std::size_t k = first.sum.size();
  for (std::size_t l = 0; l < second.sum.size(); ++l)
    if (shared[l] == CellMap::kNone) out[k++] = (second.sum[l] / second.count[l]).template cast<float>();
  return true;
}

template <class PointAt>
Points downsample(long long n, const PointAt& point, const std::vector<std::uint64_t>& key, const KeyBox* box = nullptr) {
  {
    Points out;
    if (downsampleDense(n, point, key, out, box)) return out;
  }
  // The cells are shared out among the cores by a hash of their key: each
  // numbers and sums its own over all points in input order (the same sums,
  // in the same order, as one core makes); then they are merged by first point.
  int parts = 1;
#ifdef _OPENMP
  if (n >= 50000) parts = std::clamp(omp_get_max_threads(), 1, 8);
#endif
  struct Part {
    std::vector<Eigen::Vector3d> sum;
    std::vector<int> count;
    std::vector<long long> first;  // the cell's first point
  };
  std::vector<Part> part(parts);
  const std::size_t expected = std::min<std::size_t>(static_cast<std::size_t>(n) / (2 * parts) + 1, 1 << 17);
  auto partOf = [parts](std::uint64_t k) { return static_cast<int>(((k * 0x9E3779B97F4A7C15ull) >> 40) % parts); };
  auto fill = [&](int t) {
    Part& pt = part[t];
    CellMap cells(expected);
    pt.sum.reserve(expected);
    pt.count.reserve(expected);
    pt.first.reserve(expected);
    std::uint64_t last_key = kNoKey;
    std::uint32_t last_id = 0;
    for (long long i = 0; i < n; ++i) {
      if (key[i] == kNoKey || (parts > 1 && partOf(key[i]) != t)) continue;
      // A scan visits a voxel in runs of points: the run's cell is known.
      const std::uint32_t id = key[i] == last_key ? last_id : cells.insert(key[i]);
      last_key = key[i];
      last_id = id;
      const Eigen::Vector3f p = point(i);
      if (id == pt.sum.size()) {
        pt.sum.push_back(p.template cast<double>());
        pt.count.push_back(1);
        pt.first.push_back(i);
      } else {
        pt.sum[id] += p.template cast<double>();
        ++pt.count[id];
      }
    }
  };
#pragma omp parallel for schedule(static, 1) num_threads(parts) if (parts > 1)
  for (int t = 0; t < parts; ++t) fill(t);
  std::size_t total = 0;
  for (const Part& pt : part) total += pt.sum.size();
  Points out(total);
  std::vector<std::size_t> next(parts, 0);
  for (std::size_t k = 0; k < total; ++k) {
    int best = -1;
    for (int t = 0; t < parts; ++t)
      if (next[t] < part[t].first.size() && (best < 0 || part[t].first[next[t]] < part[best].first[next[best]])) best = t;
    const std::size_t id = next[best]++;
    out[k] = (part[best].sum[id] / part[best].count[id]).template cast<float>();
  }
  return out;
}

// The bounds of the valid points' cells (unpacked from their keys).
struct KeyBounds {
  int lo[3] = {std::numeric_limits<int>::max(), std::numeric_limits<int>::max(), std::numeric_limits<int>::max()};
  int hi[3] = {-std::numeric_limits<int>::max(), -std::numeric_limits<int>::max(), -std::numeric_limits<int>::max()};
};

// The voxel key of each of the n points (kNoKey where sanitize would drop
// the point), their cells' bounds into b; returns how many are valid.
long long keysScalar(const pcl::PointXYZ* pts, long long n, double inv, float lim, std::uint64_t* key, KeyBounds& b) {
  long long valid = 0;
  for (long long i = 0; i < n; ++i) {
    const pcl::PointXYZ& p = pts[i];
    // The test of sanitize.
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::abs(p.x) <= lim &&
        std::abs(p.y) <= lim && std::abs(p.z) <= lim) {
      const Eigen::Vector3i c = cellOf(Eigen::Vector3f(p.x, p.y, p.z), inv);
      key[i] = packCell(c.x(), c.y(), c.z());
      const Eigen::Vector3i u = unpackCell(key[i]);
      for (int a = 0; a < 3; ++a) b.lo[a] = std::min(b.lo[a], u[a]), b.hi[a] = std::max(b.hi[a], u[a]);
      ++valid;
    } else {
      key[i] = kNoKey;
    }
  }
  return valid;
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DSR_KEYS_AVX2 1
// keysScalar four points at a time on a CPU with AVX2 (AVX2 alone, no FMA):
// in each lane the same float tests (|v| < inf is isfinite, NaN failing
// both), the same double product, truncation and floorToInt's correction
// (cvttpd gives INT_MIN out of range, as cvttsd2si does), the same 21-bit
// fields packed and sign-extended back; the same keys, bounds and count.
__attribute__((target("avx2"))) long long keysAvx2(const pcl::PointXYZ* pts, long long n, double inv, float lim,
                                                   std::uint64_t* key, KeyBounds& b) {
  static_assert(sizeof(pcl::PointXYZ) == 16, "x, y, z and a pad float");
  long long valid = 0, i = 0;
  const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  const __m128 vinf = _mm_set1_ps(std::numeric_limits<float>::infinity()), vlim = _mm_set1_ps(lim);
  const __m256d vinv = _mm256_set1_pd(inv);
  const __m128i int_min = _mm_set1_epi32(std::numeric_limits<int>::min()), m21 = _mm_set1_epi32(0x1FFFFF);
  const __m256i even = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6), no_key = _mm256_set1_epi64x(static_cast<long long>(kNoKey));
  __m128i lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = _mm_set1_epi32(b.lo[a]), hi[a] = _mm_set1_epi32(b.hi[a]);
  for (; i + 4 <= n; i += 4) {
    __m128 r0 = _mm_loadu_ps(&pts[i].x), r1 = _mm_loadu_ps(&pts[i + 1].x), r2 = _mm_loadu_ps(&pts[i + 2].x),
           r3 = _mm_loadu_ps(&pts[i + 3].x);
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);  // r0: the x of the four, r1: y, r2: z
    const __m128 v[3] = {r0, r1, r2};
    __m128 ok = _mm_castsi128_ps(_mm_set1_epi32(-1));
    __m128i c[3];
    for (int a = 0; a < 3; ++a) {
      const __m128 av = _mm_and_ps(v[a], abs_mask);
      ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmplt_ps(av, vinf), _mm_cmple_ps(av, vlim)));
      const __m256d d = _mm256_mul_pd(_mm256_cvtps_pd(v[a]), vinv);
      const __m128i t = _mm256_cvttpd_epi32(d);
      const __m256d below = _mm256_cmp_pd(d, _mm256_cvtepi32_pd(t), _CMP_LT_OQ);
      const __m128i below32 = _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(_mm256_castpd_si256(below), even));
      c[a] = _mm_add_epi32(t, _mm_andnot_si128(_mm_cmpeq_epi32(t, int_min), below32));  // t - 1 where below
    }
    const __m128i ok32 = _mm_castps_si128(ok);
    const int bits = _mm_movemask_ps(ok);
    if (bits == 0) {
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(key + i), no_key);
      continue;
    }
    valid += __builtin_popcount(static_cast<unsigned>(bits));
    const __m256i k = _mm256_or_si256(
        _mm256_or_si256(_mm256_cvtepu32_epi64(_mm_and_si128(c[0], m21)),
                        _mm256_slli_epi64(_mm256_cvtepu32_epi64(_mm_and_si128(c[1], m21)), 21)),
        _mm256_slli_epi64(_mm256_cvtepu32_epi64(_mm_and_si128(c[2], m21)), 42));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(key + i), _mm256_blendv_epi8(no_key, k, _mm256_cvtepi32_epi64(ok32)));
    for (int a = 0; a < 3; ++a) {
      const __m128i u = _mm_srai_epi32(_mm_slli_epi32(c[a], 11), 11);  // unpackCell's axis
      lo[a] = _mm_blendv_epi8(lo[a], _mm_min_epi32(lo[a], u), ok32);
      hi[a] = _mm_blendv_epi8(hi[a], _mm_max_epi32(hi[a], u), ok32);
    }
  }
  for (int a = 0; a < 3; ++a) {
    alignas(16) int l[4], h[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(l), lo[a]);
    _mm_store_si128(reinterpret_cast<__m128i*>(h), hi[a]);
    for (int j = 0; j < 4; ++j) b.lo[a] = std::min(b.lo[a], l[j]), b.hi[a] = std::max(b.hi[a], h[j]);
  }
  // Upper halves of the vector registers cleared before returning to SSE code.
  _mm256_zeroupper();
  return valid + keysScalar(pts + i, n - i, inv, lim, key + i, b);
}
#endif

long long keysOf(const pcl::PointXYZ* pts, long long n, double inv, float lim, std::uint64_t* key, KeyBounds& b) {
#ifdef DSR_KEYS_AVX2
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return keysAvx2(pts, n, inv, lim, key, b);
#endif
  return keysScalar(pts, n, inv, lim, key, b);
}

}  // namespace

Points voxelDownsample(const Points& points, double leaf) {
  if (leaf <= 0 || points.empty()) return points;
  const double inv = 1.0 / leaf;
  const long long n = static_cast<long long>(points.size());
  std::vector<std::uint64_t> key(points.size());
#pragma omp parallel for schedule(dynamic, 16384) if (n >= 50000)
  for (long long i = 0; i < n; ++i) {
    const Eigen::Vector3i c = cellOf(points[i], inv);
    key[i] = packCell(c.x(), c.y(), c.z());
  }
  return downsample(n, [pts = points.data()](long long i) { return pts[i]; }, key);
}

Points sanitizeAndDownsample(const pcl::PointCloud<pcl::PointXYZ>& cloud, double max_abs, double leaf,
                             std::size_t* kept) {
  if (leaf <= 0 || cloud.empty()) {
    Points out = sanitize(cloud, max_abs);
    if (kept) *kept = out.size();
    return out;
  }
  const double inv = 1.0 / leaf;
  const float lim = static_cast<float>(max_abs);
  const long long n = static_cast<long long>(cloud.size());
  std::vector<std::uint64_t> key(cloud.size());
  long long valid = 0;
  // The keys' bounding box too (for the dense index), in the same pass.
  int lx = std::numeric_limits<int>::max(), ly = lx, lz = lx, hx = -lx, hy = -lx, hz = -lx;
  constexpr long long kBlock = 16384;
  const long long blocks = (n + kBlock - 1) / kBlock;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : valid) reduction(min : lx, ly, lz) \
    reduction(max : hx, hy, hz) if (n >= 50000)
  for (long long b = 0; b < blocks; ++b) {
    KeyBounds kb;
    const long long i0 = b * kBlock, i1 = std::min(n, i0 + kBlock);
    valid += keysOf(cloud.points.data() + i0, i1 - i0, inv, lim, key.data() + i0, kb);
    lx = std::min(lx, kb.lo[0]), ly = std::min(ly, kb.lo[1]), lz = std::min(lz, kb.lo[2]);
    hx = std::max(hx, kb.hi[0]), hy = std::max(hy, kb.hi[1]), hz = std::max(hz, kb.hi[2]);
  }
  if (kept) *kept = static_cast<std::size_t>(valid);
  const KeyBox box{Eigen::Vector3i(lx, ly, lz), Eigen::Vector3i(hx, hy, hz), valid > 0};
  return downsample(
      n, [pts = cloud.points.data()](long long i) { return Eigen::Vector3f(pts[i].x, pts[i].y, pts[i].z); }, key,
      &box);
}

}  // namespace preprocess
}  // namespace dsr
