// door_state_fusion_bench: time of DoorFusion::update over a long drive: 60
// doors tracked, 6 doors per cloud, 20000 clouds (figures on stdout).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>
#include "door_state_recognition/tracking/door_fusion.hpp"
int main() {
  dsr::DoorFusion f;
  std::vector<double> ms;
  for (int k = 0; k < 20000; ++k) {
    std::vector<dsr::DoorResult> doors;
    for (int i = 0; i < 6; ++i) {
      dsr::DoorResult d;
      const int door = (k / 50 + i) % 60;
      d.opening_center = Eigen::Vector3d(door * 2.0 + 0.05 * ((k * 7 + i) % 5), (door % 2) * 5.0, 0);
      d.wall_line_direction = Eigen::Vector3d::UnitX();
      d.opening_angle_deg = (k % 13 == 0) ? 80 : 30;
      d.confidence = 0.6;
      d.width = 0.9;
      doors.push_back(d);
    }
    const auto t0 = std::chrono::steady_clock::now();
    f.update(doors, 0.1 * k);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  std::printf("tracks %zu; update ms: median %.4f p99 %.4f max %.4f\n", f.tracks().size(), ms[ms.size() / 2], ms[ms.size() * 99 / 100], ms.back());
}
