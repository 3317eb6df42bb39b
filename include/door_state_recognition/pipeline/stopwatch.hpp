// Stage timings: mark(stage) records the time since the previous mark,
// total() the time since construction, as (name, ms) pairs in order.
#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace dsr {

class Stopwatch {
 public:
  explicit Stopwatch(std::vector<std::pair<std::string, double>>* out) : out_(out) {}
  void mark(const std::string& stage) {
    const auto now = Clock::now();
    out_->push_back({stage, std::chrono::duration<double, std::milli>(now - lap_).count()});
    lap_ = now;
  }
  void total() { out_->push_back({"total", std::chrono::duration<double, std::milli>(Clock::now() - start_).count()}); }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_ = Clock::now(), lap_ = start_;
  std::vector<std::pair<std::string, double>>* out_;
};

}  // namespace dsr
