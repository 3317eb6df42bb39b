// static_cast<int>(std::floor(v)) and static_cast<int>(std::ceil(v)) in a few
// instructions: without SSE4.1 (the x86-64 baseline) std::floor and
// std::ceil take some twenty. ROS-free.
#pragma once

#include <limits>

namespace dsr {
namespace util {

// static_cast<int>(std::floor(v)) wherever that is defined (floor(v) an
// int): truncated, one less where truncation rounded up (v negative, not
// whole). Out of range both give what x86 converts it to, INT_MIN.
inline int floorToInt(double v) {
  const int t = static_cast<int>(v);
  return t - static_cast<int>(v < static_cast<double>(t) && t != std::numeric_limits<int>::min());
}

// static_cast<int>(std::ceil(v)) for ceil(v) within int range: ceil(v) = -floor(-v).
inline int ceilToInt(double v) { return -floorToInt(-v); }

}  // namespace util
}  // namespace dsr
