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

// Three comma-separated numbers X,Y,Z (each as toDouble); `what` names them
// in the error ("X,Y,Z (three numbers)").
inline void toXYZ(const std::string& flag, const std::string& v, const std::string& what, double out[3]) {
  int k = 0;
  std::size_t from = 0;
  for (std::size_t comma;; from = comma + 1) {
    comma = v.find(',', from);
    if (k == 3) throw UsageError(flag + " needs " + what + ", got '" + v + "'");
    out[k++] = toDouble(flag, v.substr(from, comma == std::string::npos ? std::string::npos : comma - from));
    if (comma == std::string::npos) break;
  }
  if (k != 3) throw UsageError(flag + " needs " + what + ", got '" + v + "'");
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

// --toggle-door K:ANGLE@T (door_scene_sim, door_state_drive_eval): door K
// is at ANGLE deg from T s after the start on.
struct Toggle {
  int door = 0;
  double angle_deg = 0, t = 0;
};
inline Toggle toToggle(const std::string& flag, const std::string& v) {
  const auto colon = v.find(':'), at = v.find('@');
  if (colon == std::string::npos || at == std::string::npos || at < colon) throw UsageError(flag + " needs K:ANGLE@T");
  Toggle c;
  c.door = static_cast<int>(toInt(flag, v.substr(0, colon)));
  c.angle_deg = toDouble(flag, v.substr(colon + 1, at - colon - 1));
  c.t = toDouble(flag, v.substr(at + 1));
  if (c.door < 0 || c.angle_deg < 0 || c.angle_deg > 180 || c.t < 0)
    throw UsageError(flag + " needs K >= 0, ANGLE in [0, 180] and T >= 0");
  return c;
}

}  // namespace tools
}  // namespace dsr
