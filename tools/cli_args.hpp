// Command-line parsing shared by the tools: a usage error, the value after a
// flag, and strict number parsing (the whole string, finite).
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>

namespace dsr {
namespace tools {

// Wrong arguments: the tool prints the message and its usage, and exits 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The value after the flag argv[i]; advances i past it.
inline std::string nextValue(int argc, char** argv, int& i) {
  const std::string flag = argv[i];
  if (i + 1 >= argc) throw UsageError(flag + " needs a value");
  return argv[++i];
}

inline double toDouble(const std::string& flag, const std::string& v) {
  std::size_t n = 0;
  double x = 0;
  try {
    x = std::stod(v, &n);
  } catch (...) {
    n = 0;
  }
  if (v.empty() || n != v.size() || !std::isfinite(x)) throw UsageError(flag + " needs a number, got '" + v + "'");
  return x;
}

inline long long toInt(const std::string& flag, const std::string& v) {
  std::size_t n = 0;
  long long x = 0;
  try {
    x = std::stoll(v, &n);
  } catch (...) {
    n = 0;
  }
  if (v.empty() || n != v.size()) throw UsageError(flag + " needs an integer, got '" + v + "'");
  return x;
}

}  // namespace tools
}  // namespace dsr
