// libFuzzer target: a sensor_msgs/PointCloud2 whose every member comes from
// the input (fields with names, offsets, types and counts; width, height,
// point_step, row_step, is_bigendian; the data bytes), through
// dsr::ros_io::validate and, when it accepts the message, dsr::ros_io::toPcl.
// toPcl must then read only inside data (ASan) and give width*height points.
//
// Encoding (little-endian, see fuzz_input.hpp): mode u8; point_step (u8 % 49
// if mode & 2, else u32); field count u8 % 7; per field: name pick u8 (x y z
// rgb intensity "" by pick % 6 when pick < 240, else a string of u8 % 9
// bytes), offset (u8 % 49 if mode & 4, else u32), datatype u8, count (u8 % 4
// if mode & 8, else u32). With mode & 16 the sizes are consistent: height u8
// % 5, the rest is data, width = data / (height * point_step) and row_step
// matches. Otherwise width, height (u8 % 65, u8 % 5 if mode & 32, else u32),
// row_step (width * point_step if mode & 64, else u32), the rest is data.
// mode & 1: big-endian; mode & 128: max_points 1e6, else unlimited.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "door_state_recognition/ros/cloud_conversion.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* bytes, std::size_t size) {
  fuzz::Input in(bytes, size);
  sensor_msgs::PointCloud2 m;
  const std::uint8_t mode = in.u8();
  m.is_bigendian = mode & 1;
  m.point_step = (mode & 2) ? in.u8() % 49 : in.u32();
  const int nfields = in.u8() % 7;
  static const char* kNames[] = {"x", "y", "z", "rgb", "intensity", ""};
  for (int i = 0; i < nfields; ++i) {
    sensor_msgs::PointField f;
    const std::uint8_t pick = in.u8();
    if (pick < 240) {
      f.name = kNames[pick % 6];
    } else {
      for (int k = in.u8() % 9; k > 0; --k) f.name += static_cast<char>(in.u8());
    }
    f.offset = (mode & 4) ? in.u8() % 49 : in.u32();
    f.datatype = in.u8();
    f.count = (mode & 8) ? in.u8() % 4 : in.u32();
    m.fields.push_back(f);
  }
  if (mode & 16) {
    m.height = in.u8() % 5;
    m.data = in.rest();
    const std::uint64_t per_row = static_cast<std::uint64_t>(m.height) * m.point_step;
    m.width = per_row ? static_cast<std::uint32_t>(m.data.size() / per_row) : static_cast<std::uint32_t>(m.data.size());
    if (per_row) m.data.resize(static_cast<std::size_t>(m.width * per_row));
    m.row_step = m.width * m.point_step;
  } else {
    m.width = (mode & 32) ? in.u8() % 65 : in.u32();
    m.height = (mode & 32) ? in.u8() % 5 : in.u32();
    m.row_step = (mode & 64) ? m.width * m.point_step : in.u32();
    m.data = in.rest();
  }
  const std::size_t max_points = (mode & 128) ? 1000000 : static_cast<std::size_t>(-1);
  if (!dsr::ros_io::validate(m, max_points).empty()) return 0;
  pcl::PointCloud<pcl::PointXYZ> out;
  dsr::ros_io::toPcl(m, out);
  if (out.size() != static_cast<std::uint64_t>(m.width) * m.height || out.width != m.width ||
      out.height != m.height)
    std::abort();
  return 0;
}
