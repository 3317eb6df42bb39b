// sensor_msgs/PointCloud2 validation and conversion (src/ros/cloud_conversion.cpp),
// called directly: no ROS master, no node. Malformed messages must be refused by
// validate() with a reason, and anything validate() accepts must convert exactly.
#include "door_state_recognition/ros/cloud_conversion.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace {

using dsr::ros_io::toPcl;
using dsr::ros_io::validate;
using sensor_msgs::PointField;
using Msg = sensor_msgs::PointCloud2;

PointField field(const std::string& name, std::uint32_t offset, std::uint8_t type, std::uint32_t count = 1) {
  PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = type;
  f.count = count;
  return f;
}

template <typename T>
void put(std::vector<std::uint8_t>& data, std::size_t at, T v) {
  std::memcpy(data.data() + at, &v, sizeof v);
}

// width x height points of x,y,z FLOAT32 at 0,4,8 plus an rgb float at 16, point_step 20;
// point i is (i, -i, 0.5 i).
Msg xyzCloud(std::uint32_t width, std::uint32_t height) {
  Msg m;
  m.width = width;
  m.height = height;
  m.point_step = 20;
  m.row_step = width * m.point_step;
  m.fields = {field("x", 0, PointField::FLOAT32), field("y", 4, PointField::FLOAT32),
              field("z", 8, PointField::FLOAT32), field("rgb", 16, PointField::FLOAT32)};
  m.data.assign(std::size_t(width) * height * m.point_step, 0xAB);
  for (std::size_t i = 0; i < std::size_t(width) * height; ++i) {
    put<float>(m.data, i * 20 + 0, float(i));
    put<float>(m.data, i * 20 + 4, -float(i));
    put<float>(m.data, i * 20 + 8, 0.5f * float(i));
  }
  return m;
}

constexpr std::size_t kMax = 1000000;

TEST(CloudConversion, Float32OrganizedCloudConvertsExactly) {
  const Msg m = xyzCloud(4, 3);
  ASSERT_EQ(validate(m, kMax), "");
  pcl::PointCloud<pcl::PointXYZ> c;
  toPcl(m, c);
  EXPECT_EQ(c.width, 4u);
  EXPECT_EQ(c.height, 3u);
  ASSERT_EQ(c.size(), 12u);
  for (std::size_t i = 0; i < 12; ++i) {
    EXPECT_EQ(c[i].x, float(i));
    EXPECT_EQ(c[i].y, -float(i));
    EXPECT_EQ(c[i].z, 0.5f * float(i));
  }
}

TEST(CloudConversion, Float64FieldsInAnyOrderAndNaNKept) {
  Msg m;
  m.width = 2;
  m.height = 1;
  m.point_step = 32;
  m.row_step = 64;
  m.fields = {field("z", 0, PointField::FLOAT64), field("intensity", 8, PointField::UINT16),
              field("x", 16, PointField::FLOAT64), field("y", 24, PointField::FLOAT64)};
  m.data.assign(64, 0);
  put<double>(m.data, 16, 1.25);
  put<double>(m.data, 24, -2.5);
  put<double>(m.data, 0, 3.0);
  put<double>(m.data, 32 + 24, std::numeric_limits<double>::quiet_NaN());  // y of point 1
  ASSERT_EQ(validate(m, kMax), "");
  pcl::PointCloud<pcl::PointXYZ> c;
  toPcl(m, c);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].x, 1.25f);
  EXPECT_EQ(c[0].y, -2.5f);
  EXPECT_EQ(c[0].z, 3.0f);
  EXPECT_EQ(c[1].x, 0.0f);
  EXPECT_TRUE(std::isnan(c[1].y));
  EXPECT_FALSE(c.is_dense);
}

TEST(CloudConversion, EmptyCloudIsValidAndConvertsToNothing) {
  Msg m = xyzCloud(0, 0);
  ASSERT_EQ(validate(m, kMax), "");
  pcl::PointCloud<pcl::PointXYZ> c;
  c.push_back(pcl::PointXYZ(1, 2, 3));
  toPcl(m, c);
  EXPECT_EQ(c.size(), 0u);
}

// Rows padded past width * point_step (allowed by sensor_msgs/PointCloud2):
// each row is read from its own start, the padding skipped.
TEST(CloudConversion, PaddedRowsAreReadRowByRow) {
  Msg m = xyzCloud(4, 3);
  pcl::PointCloud<pcl::PointXYZ> plain;
  toPcl(m, plain);
  const std::uint32_t pad = 12, old_step = m.row_step;
  std::vector<std::uint8_t> data(std::size_t(old_step + pad) * m.height, 0xAB);  // padding bytes are garbage
  for (std::uint32_t r = 0; r < m.height; ++r)
    std::copy(m.data.begin() + std::size_t(r) * old_step, m.data.begin() + std::size_t(r + 1) * old_step,
              data.begin() + std::size_t(r) * (old_step + pad));
  m.row_step = old_step + pad;
  m.data = data;
  ASSERT_EQ(validate(m, kMax), "");
  pcl::PointCloud<pcl::PointXYZ> padded;
  toPcl(m, padded);
  ASSERT_EQ(padded.size(), plain.size());
  EXPECT_EQ(padded.width, 4u);
  EXPECT_EQ(padded.height, 3u);
  for (std::size_t i = 0; i < plain.size(); ++i) {
    EXPECT_EQ(padded[i].x, plain[i].x) << i;
    EXPECT_EQ(padded[i].y, plain[i].y) << i;
    EXPECT_EQ(padded[i].z, plain[i].z) << i;
  }
}

// Each malformed message is refused, with a reason that names the fault.
TEST(CloudConversion, MalformedMessagesAreRefusedWithAReason) {
  struct Case {
    const char* what;
    void (*spoil)(Msg&);
    const char* reason;
  };
  const Case cases[] = {
      {"big endian", [](Msg& m) { m.is_bigendian = true; }, "big-endian"},
      {"data short", [](Msg& m) { m.data.pop_back(); }, "data holds"},
      {"data long", [](Msg& m) { m.data.push_back(0); }, "data holds"},
      {"point_step 0", [](Msg& m) { m.point_step = 0; }, "point_step is 0"},
      {"point_step smaller than the fields", [](Msg& m) {
         m.point_step = 8;
         m.row_step = m.width * 8;
         m.data.resize(std::size_t(m.width) * m.height * 8);
       }, "field z lies outside point_step"},
      {"row_step wrong", [](Msg& m) { m.row_step += 1; }, "row_step"},
      {"row_step shorter than a row", [](Msg& m) {
         m.row_step -= 4;
         m.data.resize(std::size_t(m.row_step) * m.height);
       }, "is shorter than width*point_step"},
      {"no z", [](Msg& m) { m.fields.erase(m.fields.begin() + 2); }, "field z is missing"},
      {"x twice", [](Msg& m) { m.fields.push_back(field("x", 12, PointField::FLOAT32)); }, "field x is missing, duplicated"},
      {"y count 2", [](Msg& m) { m.fields[1].count = 2; }, "field y is missing, duplicated or has count != 1"},
      {"y count 0", [](Msg& m) { m.fields[1].count = 0; }, "field y is missing"},
      {"x as uint8", [](Msg& m) { m.fields[0].datatype = PointField::UINT8; }, "field x is not FLOAT32 or FLOAT64"},
      {"x of unknown type 0", [](Msg& m) { m.fields[0].datatype = 0; }, "field x is not FLOAT32 or FLOAT64"},
      {"z offset past the end", [](Msg& m) { m.fields[2].offset = 17; }, "field z lies outside point_step"},
      {"z offset near 2^32", [](Msg& m) { m.fields[2].offset = 0xFFFFFFFEu; }, "field z lies outside point_step"},
      {"double x past the end", [](Msg& m) { m.fields[0].datatype = PointField::FLOAT64; m.fields[0].offset = 16; },
       "field x lies outside point_step"},
      {"width*height*point_step overflows 64 bits", [](Msg& m) {
         m.width = m.height = 0xFFFFFFFFu;
         m.point_step = 0xFFFFFFFFu;
         m.row_step = 0xFFFFFFFFu;
       }, "overflows"},
      {"height 0 with data", [](Msg& m) { m.height = 0; }, "data holds"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    Msg m = xyzCloud(4, 3);
    ASSERT_EQ(validate(m, kMax), "");
    c.spoil(m);
    const std::string why = validate(m, std::numeric_limits<std::size_t>::max());
    EXPECT_NE(why.find(c.reason), std::string::npos) << "got: '" << why << "'";
  }
}

TEST(CloudConversion, MaxPointsIsEnforcedBeforeAnythingElse) {
  const Msg m = xyzCloud(4, 3);
  EXPECT_EQ(validate(m, 12), "");
  EXPECT_NE(validate(m, 11).find("exceeds max_points"), std::string::npos);
  // A header claiming 2^64 - 2^33 + 1 points in 240 bytes is refused by the limit, not converted.
  Msg big = m;
  big.width = big.height = 0xFFFFFFFFu;
  EXPECT_NE(validate(big, kMax).find("exceeds max_points"), std::string::npos);
}

}  // namespace
