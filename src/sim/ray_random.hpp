// Counter-based random numbers of the simulator's sensors (internal header):
// the value for (seed, stream, index) does not depend on the order rays are
// processed in, so threads keep results exact.
#pragma once

#include <cmath>
#include <cstdint>

namespace dsr {
namespace sim {

inline std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
struct RayRandom {
  std::uint64_t state;
  RayRandom(std::uint64_t seed, std::uint64_t stream, std::uint64_t index)
      : state(splitmix(seed ^ splitmix(stream * 0x100000001B3ull ^ splitmix(index)))) {}
  double uniform() {
    state = splitmix(state);
    return ((state >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  }
  double gaussian() { return std::sqrt(-2.0 * std::log(uniform())) * std::cos(2 * 3.14159265358979323846 * uniform()); }
};

}  // namespace sim
}  // namespace dsr
