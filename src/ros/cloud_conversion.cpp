#include "door_state_recognition/ros/cloud_conversion.hpp"

#include <cstring>
#include <limits>

namespace dsr {
namespace ros_io {
namespace {

struct Field {
  std::uint32_t offset = 0;
  std::uint8_t type = 0;
  bool found = false;
};

Field find(const sensor_msgs::PointCloud2& msg, const char* name) {
  Field f;
  for (const auto& pf : msg.fields)
    if (pf.name == name) {
      if (f.found) return Field{0, 0, false};  // duplicated: refuse
      f = {pf.offset, pf.datatype, pf.count == 1};
      if (!f.found) return f;
    }
  return f;
}

std::uint32_t size(std::uint8_t type) {
  return type == sensor_msgs::PointField::FLOAT32 ? 4 : type == sensor_msgs::PointField::FLOAT64 ? 8 : 0;
}

}  // namespace

std::string validate(const sensor_msgs::PointCloud2& msg, std::size_t max_points) {
  if (msg.is_bigendian) return "big-endian clouds are not supported";
  const std::uint64_t n = static_cast<std::uint64_t>(msg.width) * msg.height;
  if (n > max_points) return "cloud of " + std::to_string(n) + " points exceeds max_points";
  if (msg.point_step == 0 && n > 0) return "point_step is 0";
  // width * height * point_step in 64 bits: at most 2^32 * 2^32 * 2^32 would
  // overflow, so check the product of the first two against the third.
  if (msg.point_step > 0 && n > std::numeric_limits<std::uint64_t>::max() / msg.point_step)
    return "width * height * point_step overflows";
  // Rows may be padded (row_step > width * point_step); the data holds
  // exactly row_step * height bytes. Both products fit in 64 bits (2^32 * 2^32).
  const std::uint64_t row_bytes = static_cast<std::uint64_t>(msg.width) * msg.point_step;
  if (msg.height > 0 && row_bytes > msg.row_step)
    return "row_step " + std::to_string(msg.row_step) + " is shorter than width*point_step " + std::to_string(row_bytes);
  const std::uint64_t expected = static_cast<std::uint64_t>(msg.row_step) * msg.height;
  if (expected != msg.data.size())
    return "data holds " + std::to_string(msg.data.size()) + " bytes but row_step*height is " + std::to_string(expected);
  for (const char* name : {"x", "y", "z"}) {
    const Field f = find(msg, name);
    if (!f.found) return std::string("field ") + name + " is missing, duplicated or has count != 1";
    const std::uint32_t s = size(f.type);
    if (s == 0) return std::string("field ") + name + " is not FLOAT32 or FLOAT64";
    if (static_cast<std::uint64_t>(f.offset) + s > msg.point_step)
      return std::string("field ") + name + " lies outside point_step";
  }
  // x, y and z must not overlap (e.g. x declared FLOAT64 over a FLOAT32 y).
  const Field f[3] = {find(msg, "x"), find(msg, "y"), find(msg, "z")};
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
      if (f[a].offset < f[b].offset + size(f[b].type) && f[b].offset < f[a].offset + size(f[a].type))
        return std::string("fields ") + "xyz"[a] + " and " + "xyz"[b] + " overlap";
  return "";
}

void toPcl(const sensor_msgs::PointCloud2& msg, pcl::PointCloud<pcl::PointXYZ>& out) {
  const Field fx = find(msg, "x"), fy = find(msg, "y"), fz = find(msg, "z");
  const std::size_t n = static_cast<std::size_t>(msg.width) * msg.height;
  out.points.resize(n);
  out.width = msg.width;
  out.height = msg.height;
  out.is_dense = false;
  auto read = [&](const std::uint8_t* p, const Field& f) -> float {
    if (f.type == sensor_msgs::PointField::FLOAT32) {
      float v;
      std::memcpy(&v, p + f.offset, 4);
      return v;
    }
    double v;
    std::memcpy(&v, p + f.offset, 8);
    return static_cast<float>(v);
  };
  for (std::size_t r = 0, i = 0; r < msg.height; ++r) {
    const std::uint8_t* row = msg.data.data() + r * static_cast<std::size_t>(msg.row_step);
    for (std::size_t c = 0; c < msg.width; ++c, ++i) {
      const std::uint8_t* p = row + c * msg.point_step;
      out.points[i] = pcl::PointXYZ(read(p, fx), read(p, fy), read(p, fz));
    }
  }
}

}  // namespace ros_io
}  // namespace dsr
