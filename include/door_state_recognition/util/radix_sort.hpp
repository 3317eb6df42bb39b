// Sorts that put pairs in exactly the order std::sort puts them (ascending
// first, then second), in linear time: by buckets of equal width over the
// values, or a stable LSD byte sort of order-preserving unsigned keys,
// skipping the bytes all keys share. ROS-free.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

namespace dsr {
namespace util {

// Stable: items with equal key(item) keep their order. One pass counts
// every byte of every key; each byte that varies then takes one pass that
// moves the items (keys worked out again: cheaper than moving them too).
template <class T, class Key>
void radixSortBy(std::vector<T>& v, const Key& key) {
  const std::size_t n = v.size();
  if (n < 2) return;
  std::array<std::array<std::size_t, 257>, 8> at{};
  std::uint64_t all_or = 0, all_and = ~std::uint64_t(0);
  for (const T& x : v) {
    const std::uint64_t k = key(x);
    all_or |= k, all_and &= k;
    for (int byte = 0; byte < 8; ++byte) ++at[byte][((k >> (8 * byte)) & 0xFF) + 1];
  }
  std::vector<T> tmp(n);
  for (int byte = 0; byte < 8; ++byte) {
    const int shift = 8 * byte;
    if ((((all_or ^ all_and) >> shift) & 0xFF) == 0) continue;  // every key has the same byte here
    std::array<std::size_t, 257>& pos = at[byte];
    for (int b = 0; b < 256; ++b) pos[b + 1] += pos[b];
    for (const T& x : v) tmp[pos[(key(x) >> shift) & 0xFF]++] = x;
    v.swap(tmp);
  }
}

// Order-preserving unsigned images of floating-point values (-0 taken as +0; no NaN).
inline std::uint64_t orderedBits(double d) {
  d += 0.0;  // -0 -> +0: they compare equal
  std::uint64_t u;
  std::memcpy(&u, &d, sizeof u);
  return (u >> 63) ? ~u : (u | (std::uint64_t(1) << 63));
}
inline std::uint32_t orderedBits(float f) {
  f += 0.0f;
  std::uint32_t u;
  std::memcpy(&u, &f, sizeof u);
  return (u >> 31) ? ~u : (u | (std::uint32_t(1) << 31));
}

// std::sort(v) for (value, int) pairs, by buckets of the values: the pairs
// dealt (stably) into n buckets of equal width over the values' range, then
// one insertion pass that only moves pairs within their bucket. A bucket
// never falls as the value rises (subtraction and product round
// monotonically) and equal values share one, so the buckets in turn, each
// sorted, give std::sort's order; with ints_ascend (the ints ascend as
// given) a stable order by value alone is that order. False, v untouched:
// a value not finite, no spread, or a bucket of more than 64 pairs (values
// too clustered for the insertion pass to stay short).
template <class F>
bool bucketSortPairs(std::vector<std::pair<F, int>>& v, bool ints_ascend) {
  const std::size_t n = v.size();
  if (n < 2) return true;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& x : v) {
    const double d = static_cast<double>(x.first);
    if (!std::isfinite(d)) return false;
    lo = std::min(lo, d), hi = std::max(hi, d);
  }
  const double scale = static_cast<double>(n) / (hi - lo);
  if (!(hi > lo) || !std::isfinite(hi - lo) || !std::isfinite(scale) || !(scale > 0)) return false;
  const double top = static_cast<double>(n - 1);
  std::vector<std::uint32_t> bucket(n), start(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = (static_cast<double>(v[i].first) - lo) * scale;  // in [0, n] give or take rounding
    bucket[i] = static_cast<std::uint32_t>(t < top ? t : top);
    ++start[bucket[i] + 1];
  }
  // Bucket starts by a running sum held in a register (not reloaded from
  // the entry just stored), any bucket over 64 noted on the way.
  {
    std::uint32_t acc = 0, over = 0;
    for (std::size_t b = 1; b <= n; ++b) {
      const std::uint32_t c = start[b];
      over |= static_cast<std::uint32_t>(c > 64);
      acc += c;
      start[b] = acc;
    }
    if (over) return false;
  }
  std::vector<std::pair<F, int>> out(n);
  for (std::size_t i = 0; i < n; ++i) out[start[bucket[i]]++] = v[i];
  std::pair<F, int>* a = out.data();
  auto before = [ints_ascend](const std::pair<F, int>& x, const std::pair<F, int>& y) {
    return ints_ascend ? x.first < y.first : x < y;
  };
  for (std::size_t i = 1; i < n; ++i) {
    if (!before(a[i], a[i - 1])) continue;
    const std::pair<F, int> x = a[i];
    std::size_t j = i;
    for (; j > 0 && before(x, a[j - 1]); --j) a[j] = a[j - 1];
    a[j] = x;
  }
  v.swap(out);
  return true;
}

// std::sort(v) for (double, int) pairs: by buckets (bucketSortPairs) where
// they serve; else for pairs whose ints ascend as given (then a stable sort
// by the double alone breaks ties as std::sort does) by radix; otherwise std::sort.
inline void sortPairs(std::vector<std::pair<double, int>>& v) {
  const bool ascending = std::is_sorted(v.begin(), v.end(),
                                        [](const std::pair<double, int>& a, const std::pair<double, int>& b) { return a.second < b.second; });
  if (v.size() >= 64 && bucketSortPairs(v, ascending)) return;
  if (!ascending || v.size() < 64) {
    std::sort(v.begin(), v.end());
    return;
  }
  radixSortBy(v, [](const std::pair<double, int>& x) { return orderedBits(x.first); });
}

// std::sort(v) for (float, int) pairs: by buckets (bucketSortPairs) where
// they serve; else with non-negative ints by radix; otherwise std::sort.
inline void sortPairs(std::vector<std::pair<float, int>>& v) {
  if (v.size() >= 64 && bucketSortPairs(v, false)) return;
  if (v.size() < 64 || std::any_of(v.begin(), v.end(), [](const std::pair<float, int>& x) { return x.second < 0; })) {
    std::sort(v.begin(), v.end());
    return;
  }
  radixSortBy(v, [](const std::pair<float, int>& x) {
    return (static_cast<std::uint64_t>(orderedBits(x.first)) << 32) | static_cast<std::uint32_t>(x.second);
  });
}

}  // namespace util
}  // namespace dsr
