// Radix sorts that put pairs in exactly the order std::sort puts them
// (ascending first, then second), in linear time: a stable LSD byte sort of
// order-preserving unsigned keys, skipping the bytes all keys share. ROS-free.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
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

// std::sort(v) for (double, int) pairs whose ints ascend as given (then a
// stable sort by the double alone breaks ties as std::sort does); otherwise std::sort.
inline void sortPairs(std::vector<std::pair<double, int>>& v) {
  const bool ascending = std::is_sorted(v.begin(), v.end(),
                                        [](const std::pair<double, int>& a, const std::pair<double, int>& b) { return a.second < b.second; });
  if (!ascending || v.size() < 64) {
    std::sort(v.begin(), v.end());
    return;
  }
  radixSortBy(v, [](const std::pair<double, int>& x) { return orderedBits(x.first); });
}

// std::sort(v) for (float, int) pairs with non-negative ints.
inline void sortPairs(std::vector<std::pair<float, int>>& v) {
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
