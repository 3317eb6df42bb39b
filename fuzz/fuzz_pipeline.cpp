// libFuzzer target: small arbitrary clouds (up to 4096 points) through
// dsr::Pipeline::run with the default parameters and the up axis, viewpoint
// and organisation taken from the input. The pipeline promises never to throw
// for a cloud's content (degenerate clouds give zero doors and a warning), so
// any exception, crash or sanitizer report is a bug.
//
// Encoding (little-endian, see fuzz_input.hpp): up u8 % 7 (+z -z +y -y +x -x
// auto); mode u8; width - 1 of an organized cloud u8 % 64; if mode & 2 the
// viewpoint as 3 int8 decimetres; then points, 3 int16 times 1e-3 * (1 +
// mode >> 4) m each if mode & 1 (room-sized structure is easy to reach), else
// 3 raw float32 (NaN, Inf, huge, denormal). mode & 4: organized (whole rows of
// width points); mode & 8: with the reconstruction.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "door_state_recognition/pipeline/pipeline.hpp"
#include "fuzz_input.hpp"

namespace {
const char* kUp[] = {"+z", "-z", "+y", "-y", "+x", "-x", "auto"};

const dsr::Pipeline& pipeline(int up) {
  static dsr::Pipeline* p[7] = {};  // built once per axis, kept for the process
  if (!p[up]) {
    dsr::Parameters params;
    params.up_axis = kUp[up];
    p[up] = new dsr::Pipeline(params);
  }
  return *p[up];
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  fuzz::Input in(bytes, size);
  const int up = in.u8() % 7;
  const std::uint8_t mode = in.u8();
  const std::uint32_t width = 1 + in.u8() % 64;
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();
  if (mode & 2)
    for (int a = 0; a < 3; ++a) viewpoint[a] = static_cast<std::int8_t>(in.u8()) * 0.1;
  const bool ints = mode & 1;
  const float scale = 1e-3f * float(1 + (mode >> 4));
  pcl::PointCloud<pcl::PointXYZ> cloud;
  while (cloud.size() < 4096 && in.left() >= (ints ? 6u : 12u)) {
    float v[3];
    for (float& c : v) {
      if (ints) {
        c = float(static_cast<std::int16_t>(in.u16())) * scale;
      } else {
        const std::uint32_t raw = in.u32();
        std::memcpy(&c, &raw, 4);
      }
    }
    cloud.push_back(pcl::PointXYZ(v[0], v[1], v[2]));
  }
  if ((mode & 4) && cloud.size() >= 2 * width) {
    cloud.resize((cloud.size() / width) * width);
    cloud.width = width;
    cloud.height = static_cast<std::uint32_t>(cloud.size() / width);
  }
  cloud.is_dense = false;
  const dsr::PipelineResult r = pipeline(up).run(cloud, /*with_reconstruction=*/mode & 8, viewpoint);
  if (r.points_in != cloud.size() || r.points_used > r.points_in) std::abort();
  for (const auto& d : r.doors)
    if (!std::isfinite(d.opening_angle_deg) || d.opening_angle_deg < 0 || d.opening_angle_deg > 180) std::abort();
  return 0;
}
