#include "door_state_recognition/io/cloud_reader.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <pcl/io/lzf.h>
#include <pcl/io/pcd_io.h>

namespace {

namespace fs = std::filesystem;
using dsr::io::CloudReadError;
using dsr::io::readCloud;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

const float kNaN = std::numeric_limits<float>::quiet_NaN();

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// Message of the CloudReadError thrown by readCloud, or "<no error>".
std::string errorOf(const std::string& path) {
  try {
    readCloud(path);
  } catch (const CloudReadError& e) {
    return e.what();
  }
  return "<no error>";
}

// Must throw CloudReadError with a non-empty one-line message mentioning `what`.
#define EXPECT_READ_ERROR(path, what)                              \
  do {                                                             \
    EXPECT_THROW(readCloud(path), CloudReadError);                 \
    const std::string msg_ = errorOf(path);                        \
    EXPECT_FALSE(msg_.empty());                                    \
    EXPECT_EQ(msg_.find('\n'), std::string::npos) << msg_;         \
    EXPECT_NE(msg_.find(what), std::string::npos) << msg_;         \
  } while (0)

// Little/big-endian byte writers for hand-made binary files.
template <typename T>
void put(std::string& out, T v, bool big_endian = false) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big_endian) std::reverse(b, b + sizeof(T));
  out.append(b, sizeof(T));
}

void expectSamePoint(const pcl::PointXYZ& got, const pcl::PointXYZ& want) {
  for (int a = 0; a < 3; ++a) {
    if (std::isnan(want.data[a]))
      EXPECT_TRUE(std::isnan(got.data[a]));
    else
      EXPECT_EQ(got.data[a], want.data[a]);
  }
}

void expectSameCloud(const Cloud& got, const Cloud& want) {
  ASSERT_EQ(got.width, want.width);
  ASSERT_EQ(got.height, want.height);
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    SCOPED_TRACE("point " + std::to_string(i));
    expectSamePoint(got[i], want[i]);
  }
}

// Restores the default point limit when a test changes it.
struct MaxPointsGuard {
  explicit MaxPointsGuard(std::size_t n) { dsr::io::setMaxPoints(n); }
  ~MaxPointsGuard() { dsr::io::setMaxPoints(50000000); }
};

class CloudReader : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    dir_ = fs::temp_directory_path() /
           ("dsr_cloud_reader_" + std::to_string(::getpid()) + "_" + std::to_string(rd()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  std::string write(const std::string& name, const std::string& bytes) const {
    std::ofstream(file(name), std::ios::binary) << bytes;
    return file(name);
  }
  // Organized 4x3 cloud with dyadic values (exact in ascii) and NaN points.
  static Cloud organized() {
    Cloud c(4, 3);
    for (std::size_t i = 0; i < c.size(); ++i)
      c[i] = pcl::PointXYZ(0.25f * i - 1.5f, -0.125f * i, 1000.5f + i);
    c[1] = pcl::PointXYZ(kNaN, kNaN, kNaN);
    c[6].z = kNaN;
    c.is_dense = false;
    return c;
  }
  fs::path dir_;
};

// PCD text header for x y z with the given types/sizes and trailing DATA line.
std::string pcdHeader(const std::string& fields, const std::string& size, const std::string& type,
                      const std::string& count, const std::string& width, const std::string& height,
                      const std::string& points, const std::string& data) {
  return "# .PCD v0.7\nVERSION 0.7\nFIELDS " + fields + "\nSIZE " + size + "\nTYPE " + type + "\nCOUNT " + count +
         "\nWIDTH " + width + "\nHEIGHT " + height + "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + points + "\nDATA " +
         data + "\n";
}

std::string xyzHeader(const std::string& points, const std::string& data) {
  return pcdHeader("x y z", "4 4 4", "F F F", "1 1 1", points, "1", points, data);
}

// Offset of the first byte after the "DATA ...\n" line.
std::size_t dataOffset(const std::string& pcd) { return pcd.find('\n', pcd.find("\nDATA ") + 1) + 1; }

// ------------------------------------------------------------------ good PCD files

TEST_F(CloudReader, PcdRoundTripOrganizedWithNaNAllEncodings) {
  const Cloud want = organized();
  pcl::io::savePCDFileASCII(file("a.pcd"), want);
  pcl::io::savePCDFileBinary(file("b.pcd"), want);
  pcl::io::savePCDFileBinaryCompressed(file("c.pcd"), want);
  for (const char* name : {"a.pcd", "b.pcd", "c.pcd"}) {
    SCOPED_TRACE(name);
    Cloud got = readCloud(file(name));
    expectSameCloud(got, want);
    EXPECT_FALSE(got.is_dense);
    EXPECT_TRUE(got.isOrganized());
  }
}

TEST_F(CloudReader, PcdRoundTripRandomBinaryAndCompressed) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> d(-50.f, 50.f);
  Cloud want;
  for (int i = 0; i < 5000; ++i) want.push_back(pcl::PointXYZ(d(rng), d(rng), d(rng)));
  want[17].x = std::numeric_limits<float>::infinity();
  pcl::io::savePCDFileBinary(file("b.pcd"), want);
  pcl::io::savePCDFileBinaryCompressed(file("c.pcd"), want);
  expectSameCloud(readCloud(file("b.pcd")), want);
  expectSameCloud(readCloud(file("c.pcd")), want);
}

TEST_F(CloudReader, PcdCompressedWithExtraFieldsIsColumnMajor) {
  pcl::PointCloud<pcl::PointXYZRGBNormal> src(3, 2);
  Cloud want(3, 2);
  for (std::size_t i = 0; i < src.size(); ++i) {
    src[i].x = i + 0.5f; src[i].y = -2.f * i; src[i].z = 7.f - i;
    src[i].r = 10 * i; src[i].normal_x = 99.f; src[i].curvature = -1.f;
    want[i] = pcl::PointXYZ(src[i].x, src[i].y, src[i].z);
  }
  pcl::io::savePCDFileBinaryCompressed(file("c.pcd"), src);
  pcl::io::savePCDFileBinary(file("b.pcd"), src);
  pcl::io::savePCDFileASCII(file("a.pcd"), src);
  for (const char* name : {"a.pcd", "b.pcd", "c.pcd"}) {
    SCOPED_TRACE(name);
    expectSameCloud(readCloud(file(name)), want);
  }
}

TEST_F(CloudReader, PcdEmptyCloud) {
  pcl::io::savePCDFileBinaryCompressed(file("c.pcd"), Cloud());  // PCL writes WIDTH 0 HEIGHT 0
  EXPECT_EQ(readCloud(file("c.pcd")).size(), 0u);
  write("a.pcd", xyzHeader("0", "ascii"));
  EXPECT_EQ(readCloud(file("a.pcd")).size(), 0u);
}

TEST_F(CloudReader, PcdAsciiWithRgbCrlfCommentsAndNaNSpellings) {
  std::string s = pcdHeader("x y z rgb", "4 4 4 4", "F F F U", "1 1 1 1", "4", "1", "4", "ascii");
  s += "1.5 -2 3e2 4278190335\r\n\r\n";
  s += "nan NaN -nan 0\n";
  s += "+0.25 inf -inf 16777215\n";
  s += "  7\t8 9 1  \n";
  Cloud c = readCloud(write("rgb.pcd", s));
  ASSERT_EQ(c.size(), 4u);
  expectSamePoint(c[0], pcl::PointXYZ(1.5f, -2.f, 300.f));
  expectSamePoint(c[1], pcl::PointXYZ(kNaN, kNaN, kNaN));
  EXPECT_EQ(c[2].x, 0.25f);
  EXPECT_EQ(c[2].y, std::numeric_limits<float>::infinity());
  EXPECT_EQ(c[2].z, -std::numeric_limits<float>::infinity());
  expectSamePoint(c[3], pcl::PointXYZ(7.f, 8.f, 9.f));
  EXPECT_FALSE(c.is_dense);
}

TEST_F(CloudReader, PcdBinaryWithRgbPaddingAndCountGreaterThanOne) {
  // x, 2 padding bytes, y, 3-float histogram, z, rgb
  std::string s = pcdHeader("x _ y hist z rgb", "4 1 4 4 4 4", "F U F F F U", "1 2 1 3 1 1", "2", "1", "2", "binary");
  for (int i = 0; i < 2; ++i) {
    put<float>(s, 1.f + i); s += "\xAA\xBB";
    put<float>(s, 2.f + i); put<float>(s, 9.f); put<float>(s, 9.f); put<float>(s, 9.f);
    put<float>(s, 3.f + i); put<std::uint32_t>(s, 0xFF00FF);
  }
  s += "trailing bytes are tolerated";
  Cloud c = readCloud(write("pad.pcd", s));
  ASSERT_EQ(c.size(), 2u);
  expectSamePoint(c[0], pcl::PointXYZ(1, 2, 3));
  expectSamePoint(c[1], pcl::PointXYZ(2, 3, 4));
}

TEST_F(CloudReader, PcdFloat64XyzAllEncodings) {
  const double v[2][3] = {{0.1, -1e10, 3.25}, {1.0 / 3.0, 2.5, -7.0}};
  const std::string fields = "x y z intensity", size = "8 8 8 2", type = "F F F U", count = "1 1 1 1";
  // binary, row-major
  std::string b = pcdHeader(fields, size, type, count, "2", "1", "2", "binary");
  for (auto& p : v) { put(b, p[0]); put(b, p[1]); put(b, p[2]); put<std::uint16_t>(b, 7); }
  // ascii
  std::string a = pcdHeader(fields, size, type, count, "2", "1", "2", "ascii");
  a += "0.1 -1e10 3.25 7\n0.33333333333333331 2.5 -7 7\n";
  // binary_compressed, column-major, built with pcl::lzfCompress
  std::string raw;
  for (int f = 0; f < 3; ++f) for (auto& p : v) put(raw, p[f]);
  for (int i = 0; i < 2; ++i) put<std::uint16_t>(raw, 7);
  std::vector<char> packed(raw.size() * 2 + 16);
  unsigned n = pcl::lzfCompress(raw.data(), raw.size(), packed.data(), packed.size());
  ASSERT_GT(n, 0u);
  std::string c = pcdHeader(fields, size, type, count, "2", "1", "2", "binary_compressed");
  put<std::uint32_t>(c, n); put<std::uint32_t>(c, raw.size()); c.append(packed.data(), n);

  for (const auto& [name, bytes] : {std::pair{"b.pcd", b}, {"a.pcd", a}, {"c.pcd", c}}) {
    SCOPED_TRACE(name);
    Cloud got = readCloud(write(name, bytes));
    ASSERT_EQ(got.size(), 2u);
    for (int i = 0; i < 2; ++i)
      expectSamePoint(got[i], pcl::PointXYZ(float(v[i][0]), float(v[i][1]), float(v[i][2])));
  }
}

TEST_F(CloudReader, FormatChosenByContentNotExtension) {
  pcl::io::savePCDFileBinary(file("cloud.ply"), organized());
  expectSameCloud(readCloud(file("cloud.ply")), organized());
  write("cloud.pcd", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                     "property float z\nend_header\n1 2 3\n");
  expectSamePoint(readCloud(file("cloud.pcd"))[0], pcl::PointXYZ(1, 2, 3));
}

// ------------------------------------------------------------------ good PLY files

TEST_F(CloudReader, PlyAscii) {
  const std::string ply =
      "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nobj_info test\r\nelement vertex 3\r\n"
      "property float x\r\nproperty float y\r\nproperty double z\r\nproperty uchar red\r\n"
      "element face 1\r\nproperty list uchar int vertex_indices\r\nend_header\r\n"
      "1.5 2.5 -3.5 255\r\nnan 0 1e-3 0\r\n-0 7 8 1\r\n3 0 1 2\r\n";
  Cloud c = readCloud(write("a.ply", ply));
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.width, 3u);
  EXPECT_EQ(c.height, 1u);
  expectSamePoint(c[0], pcl::PointXYZ(1.5f, 2.5f, -3.5f));
  expectSamePoint(c[1], pcl::PointXYZ(kNaN, 0.f, float(1e-3)));
  expectSamePoint(c[2], pcl::PointXYZ(-0.f, 7.f, 8.f));
  EXPECT_FALSE(c.is_dense);
}

TEST_F(CloudReader, PlyBinaryLittleEndian) {
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement camera 1\nproperty list uchar float k\nproperty int id\n"
      "element vertex 2\nproperty uint8 intensity\nproperty float32 x\nproperty float32 y\nproperty float32 z\n"
      "property int16 label\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  put<std::uint8_t>(s, 2); put<float>(s, 1.f); put<float>(s, 2.f); put<std::int32_t>(s, 5);  // camera
  put<std::uint8_t>(s, 9); put<float>(s, 1.25f); put<float>(s, -2.f); put<float>(s, 1e-7f); put<std::int16_t>(s, -1);
  put<std::uint8_t>(s, 9); put<float>(s, kNaN); put<float>(s, 3.f); put<float>(s, 4.f); put<std::int16_t>(s, 2);
  put<std::uint8_t>(s, 3); put<std::int32_t>(s, 0); put<std::int32_t>(s, 1); put<std::int32_t>(s, 0);  // face
  Cloud c = readCloud(write("le.ply", s));
  ASSERT_EQ(c.size(), 2u);
  expectSamePoint(c[0], pcl::PointXYZ(1.25f, -2.f, 1e-7f));
  expectSamePoint(c[1], pcl::PointXYZ(kNaN, 3.f, 4.f));
}

TEST_F(CloudReader, PlyBinaryBigEndian) {
  std::string s =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty ushort u\n"
      "property double y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const double xy[3][2] = {{1.0 / 3.0, -1e30}, {42.0, 0.5}, {-1e-3, 1e3}};
  const float z[3] = {1.5f, -0.f, 3.0e38f};
  for (int i = 0; i < 3; ++i) {
    put(s, xy[i][0], true); put<std::uint16_t>(s, 0xABCD, true); put(s, xy[i][1], true); put(s, z[i], true);
  }
  put<std::uint8_t>(s, 3, true); put<std::int32_t>(s, 0, true); put<std::int32_t>(s, 1, true);
  put<std::int32_t>(s, 2, true);
  Cloud c = readCloud(write("be.ply", s));
  ASSERT_EQ(c.size(), 3u);
  for (int i = 0; i < 3; ++i)
    expectSamePoint(c[i], pcl::PointXYZ(float(xy[i][0]), float(xy[i][1]), z[i]));
}

TEST_F(CloudReader, PlyElementsBeforeVertexAreSkipped) {
  const std::string a =
      "ply\nformat ascii 1.0\nelement camera 2\nproperty list uchar float k\nproperty int id\n"
      "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
      "3 1 2 3 7\n0 8\n-1 -2 -3\n";
  expectSamePoint(readCloud(write("a.ply", a))[0], pcl::PointXYZ(-1, -2, -3));
  std::string b =
      "ply\nformat binary_little_endian 1.0\nelement camera 2\nproperty double k\nproperty uchar id\n"
      "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (int i = 0; i < 2; ++i) { put<double>(b, 1e9); put<std::uint8_t>(b, 1); }
  put<float>(b, 4.f); put<float>(b, 5.f); put<float>(b, 6.f);
  expectSamePoint(readCloud(write("b.ply", b))[0], pcl::PointXYZ(4, 5, 6));
  EXPECT_READ_ERROR(write("short.ply", b.substr(0, b.size() - 13)), "file ends inside a PLY element");
}

// ------------------------------------------------------------------ malformed catalogue

TEST_F(CloudReader, TruncatedBinaryData) {
  pcl::io::savePCDFileBinary(file("b.pcd"), organized());
  std::string s = slurp(file("b.pcd"));
  EXPECT_READ_ERROR(write("t.pcd", s.substr(0, s.size() - 5)), "header promises 12 points");
  EXPECT_READ_ERROR(write("t0.pcd", s.substr(0, dataOffset(s))), "but DATA holds 0");
}

TEST_F(CloudReader, TruncatedCompressedData) {
  pcl::io::savePCDFileBinaryCompressed(file("c.pcd"), organized());
  std::string s = slurp(file("c.pcd"));
  EXPECT_READ_ERROR(write("t1.pcd", s.substr(0, s.size() - 3)), "compressed bytes but only");
  EXPECT_READ_ERROR(write("t2.pcd", s.substr(0, dataOffset(s) + 5)), "compressed-data header");
  EXPECT_READ_ERROR(write("t3.pcd", s.substr(0, dataOffset(s))), "compressed-data header");
}

TEST_F(CloudReader, CorruptCompressedStream) {
  pcl::io::savePCDFileBinaryCompressed(file("c.pcd"), organized());
  std::string s = slurp(file("c.pcd"));
  std::string bad = s;
  bad[dataOffset(s) + 8] = '\xE0';  // back-reference before the start of the output
  EXPECT_READ_ERROR(write("bad.pcd", bad), "corrupt");
  std::string zero = s.substr(0, dataOffset(s));
  put<std::uint32_t>(zero, 0); put<std::uint32_t>(zero, 144);  // 0 compressed bytes for 144 raw
  EXPECT_READ_ERROR(write("zero.pcd", zero), "cannot expand");
}

TEST_F(CloudReader, CompressedHeaderClaims4GB) {
  pcl::io::savePCDFileBinaryCompressed(file("c.pcd"), organized());
  std::string s = slurp(file("c.pcd"));
  std::string lie = s;
  const std::uint32_t big = 0xFFFFFFFFu;
  std::memcpy(&lie[dataOffset(s) + 4], &big, 4);
  EXPECT_READ_ERROR(write("lie.pcd", lie), "4294967295 bytes uncompressed");
  // A self-consistent lie: 357913941 points * 12 bytes = 4294967292 uncompressed, from ~150 bytes.
  MaxPointsGuard guard(std::numeric_limits<std::size_t>::max());
  std::string h = xyzHeader("357913941", "binary_compressed");
  put<std::uint32_t>(h, 4); put<std::uint32_t>(h, 4294967292u); h += "\x01\x02\x03\x04";
  EXPECT_READ_ERROR(write("lie2.pcd", h), "cannot expand");
}

TEST_F(CloudReader, PointsLargerThanData) {
  std::string a = xyzHeader("10", "ascii") + "1 2 3\n4 5 6\n7 8 9\n";
  EXPECT_READ_ERROR(write("a.pcd", a), "only");
  std::string a2 = xyzHeader("3", "ascii") + "1 2 3\n4 5 6\n      \n\n";
  EXPECT_READ_ERROR(write("a2.pcd", a2), "header promises 3 points but DATA holds 2");
  std::string b = xyzHeader("10", "binary");
  for (int i = 0; i < 9; ++i) put<float>(b, i);
  EXPECT_READ_ERROR(write("b.pcd", b), "header promises 10 points");
}

TEST_F(CloudReader, WidthTimesHeightNotPoints) {
  std::string s = pcdHeader("x y z", "4 4 4", "F F F", "1 1 1", "4", "3", "11", "ascii");
  for (int i = 0; i < 12; ++i) s += "1 2 3\n";
  EXPECT_READ_ERROR(write("wh.pcd", s), "but POINTS is 11");
}

TEST_F(CloudReader, WidthTimesHeightOverflows64Bits) {
  // 2^33 * 2^31 = 2^64 wraps to 0 == POINTS in unchecked 64-bit arithmetic.
  std::string s = pcdHeader("x y z", "4 4 4", "F F F", "1 1 1", "8589934592", "2147483648", "0", "binary");
  EXPECT_READ_ERROR(write("ovf.pcd", s), "overflows");
  std::string s2 = pcdHeader("x y z", "4 4 4", "F F F", "1 1 1", "99999999999999999999", "1", "1", "binary");
  EXPECT_READ_ERROR(write("ovf2.pcd", s2), "WIDTH is not");
}

TEST_F(CloudReader, SizeTypeCountMismatch) {
  const std::string tail = "1 2 3\n";
  EXPECT_READ_ERROR(write("s.pcd", pcdHeader("x y z", "4 4", "F F F", "1 1 1", "1", "1", "1", "ascii") + tail),
                    "SIZE has 2 entries but FIELDS has 3");
  EXPECT_READ_ERROR(write("t.pcd", pcdHeader("x y z", "4 4 4", "F F F F", "1 1 1", "1", "1", "1", "ascii") + tail),
                    "TYPE has 4 entries");
  EXPECT_READ_ERROR(write("c.pcd", pcdHeader("x y z", "4 4 4", "F F F", "1 1", "1", "1", "1", "ascii") + tail),
                    "COUNT has 2 entries");
  EXPECT_READ_ERROR(write("c0.pcd", pcdHeader("x y z", "4 4 4", "F F F", "1 0 1", "1", "1", "1", "ascii") + tail),
                    "COUNT of field");
  EXPECT_READ_ERROR(write("f3.pcd", pcdHeader("x y z", "4 3 4", "F F F", "1 1 1", "1", "1", "1", "ascii") + tail),
                    "unsupported TYPE/SIZE");
  EXPECT_READ_ERROR(write("q.pcd", pcdHeader("x y z", "4 4 4", "F Q F", "1 1 1", "1", "1", "1", "ascii") + tail),
                    "unsupported TYPE/SIZE");
}

TEST_F(CloudReader, XyzWithWrongType) {
  std::string s = pcdHeader("x y z", "1 4 4", "U F F", "1 1 1", "1", "1", "1", "binary");
  s += "\x01"; put<float>(s, 2.f); put<float>(s, 3.f);
  EXPECT_READ_ERROR(write("u8.pcd", s), "field x must be float32 or float64");
  std::string c = pcdHeader("x y z", "4 4 4", "F F F", "1 2 1", "1", "1", "1", "ascii") + "1 2 2 3\n";
  EXPECT_READ_ERROR(write("cnt.pcd", c), "field y must be");
  std::string ply = "ply\nformat ascii 1.0\nelement vertex 1\nproperty int x\nproperty float y\n"
                    "property float z\nend_header\n1 2 3\n";
  EXPECT_READ_ERROR(write("int.ply", ply), "vertex property x must be float or double");
}

TEST_F(CloudReader, MissingZField) {
  std::string s = pcdHeader("x y rgb", "4 4 4", "F F F", "1 1 1", "1", "1", "1", "ascii") + "1 2 3\n";
  EXPECT_READ_ERROR(write("noz.pcd", s), "no 'z' field");
  std::string ply = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n";
  EXPECT_READ_ERROR(write("noz.ply", ply), "no 'z' property");
}

TEST_F(CloudReader, UnknownDataKind) {
  EXPECT_READ_ERROR(write("d.pcd", xyzHeader("1", "binary_lzma") + "xxxxxxxxxxxx"), "unknown DATA kind");
  EXPECT_READ_ERROR(write("n.pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\n"),
                    "no DATA line");
}

TEST_F(CloudReader, BadHeaderAndDataValues) {
  EXPECT_READ_ERROR(write("neg.pcd", xyzHeader("-5", "ascii")), "not a non-negative integer");
  EXPECT_READ_ERROR(write("num.pcd", xyzHeader("2", "ascii") + "1 2 3\n4 five 6\n"), "'five' is not a number");
  EXPECT_READ_ERROR(write("few.pcd", xyzHeader("2", "ascii") + "1 2 3\n4 5\n\n\n\n"), "has 2 values, expected 3");
  EXPECT_READ_ERROR(write("dup.pcd", "VERSION 0.7\nVERSION 0.7\n"), "repeats VERSION");
  EXPECT_READ_ERROR(write("key.pcd", "VERSION 0.7\nFIELDS x y z\nBOGUS 1\n"), "unknown PCD header line");
  EXPECT_READ_ERROR(write("vp.pcd", "VERSION 0.7\nVIEWPOINT 0 0 0 1\n"), "VIEWPOINT needs 7 values");
  EXPECT_READ_ERROR(write("nowp.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nDATA ascii\n1 2 3\n"),
                    "neither WIDTH nor POINTS");
  std::string dupx = pcdHeader("x y x z", "4 4 4 4", "F F F F", "1 1 1 1", "1", "1", "1", "ascii") + "1 2 3 4\n";
  EXPECT_READ_ERROR(write("dupx.pcd", dupx), "appears twice");
}

TEST_F(CloudReader, PlyVertexCountLargerThanData) {
  std::string b = "ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
                  "property float z\nend_header\n";
  for (int i = 0; i < 14; ++i) put<float>(b, i);
  EXPECT_READ_ERROR(write("b.ply", b), "header promises 5 vertices but data holds 4");
  std::string a = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                  "property float z\nend_header\n1 2 3\n4 5 6\n7 8\n\n\n\n";
  EXPECT_READ_ERROR(write("a.ply", a), "header promises 3 vertices but data holds 2");
  EXPECT_READ_ERROR(write("a2.ply", a.substr(0, a.size() - 3)), "but only 16 bytes of data follow");
}

TEST_F(CloudReader, PlyListPropertyInVertex) {
  std::string s = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                  "property float z\nproperty list uchar int idx\nend_header\n1 2 3 1 0\n";
  EXPECT_READ_ERROR(write("l.ply", s), "is a list");
}

TEST_F(CloudReader, PlyBadHeaders) {
  const std::string v = "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
  EXPECT_READ_ERROR(write("fmt.ply", "ply\nformat binary_middle_endian 1.0\n" + v + "end_header\n"),
                    "unknown PLY format");
  EXPECT_READ_ERROR(write("noend.ply", "ply\nformat ascii 1.0\n" + v + "1 2 3\n"), "unknown PLY header line");
  EXPECT_READ_ERROR(write("eof.ply", "ply\nformat ascii 1.0\n" + v), "no end_header");
  EXPECT_READ_ERROR(write("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n"),
                    "unknown PLY property type");
  EXPECT_READ_ERROR(write("nov.ply", "ply\nformat ascii 1.0\nelement face 0\nend_header\n"), "no vertex element");
  EXPECT_READ_ERROR(write("nofmt.ply", "ply\n" + v + "end_header\n1 2 3\n"), "no format line");
}

// ------------------------------------------------------------------ text clouds

TEST_F(CloudReader, TextCloudsAndMeshesAsDatasetsAndScannersShipThem) {
  // S3DIS's rooms: "x y z r g b" per line; CloudCompare's export with its
  // column header, separators of all kinds, a comment and a blank line; a
  // Leica .pts: the count, then "x y z i r g b".
  const Cloud s3dis = readCloud(write("office_1.txt", "-1.5 0.25 1000.5 120 110 100\n2 -3.125 4 0 0 0\n"));
  ASSERT_EQ(s3dis.size(), 2u);
  EXPECT_EQ(s3dis.width, 2u);
  EXPECT_EQ(s3dis.height, 1u);
  EXPECT_EQ(s3dis[0].x, -1.5f);
  EXPECT_EQ(s3dis[0].z, 1000.5f);
  EXPECT_EQ(s3dis[1].y, -3.125f);
  EXPECT_TRUE(s3dis.sensor_origin_.isZero());
  const Cloud csv = readCloud(write("scan.xyz", "//X,Y,Z\n1,2,3\n\n# station 2\n4;5;6;0.5\r\n7\t8\t9\n"));
  ASSERT_EQ(csv.size(), 3u);
  EXPECT_EQ(csv[1].x, 4.0f);
  EXPECT_EQ(csv[2].z, 9.0f);
  const Cloud pts = readCloud(write("station.pts", "2\n1 2 3 -1200 10 20 30\n4 5 6 -800 10 20 30\n"));
  ASSERT_EQ(pts.size(), 2u);
  EXPECT_EQ(pts[1].z, 6.0f);
  // A phone scanner's or photogrammetry's OBJ mesh: its vertices.
  const Cloud obj = readCloud(write("room.obj", "# Polycam\nmtllib room.mtl\no Mesh\nv 1 2 3\nv 4 5 6 0.5 0.5 0.5\n"
                                                "vn 0 0 1\nvt 0 1\nusemtl m\nf 1/1/1 2/1/1 1/1/1\nv -1 -2 -3\n"));
  ASSERT_EQ(obj.size(), 3u);
  EXPECT_EQ(obj[1].y, 5.0f);
  EXPECT_EQ(obj[2].z, -3.0f);
  EXPECT_READ_ERROR(write("bad.obj", "v 1 2 3\nv 1 2\n"), "vertex 1");
  // What is wrong is said with its line.
  EXPECT_READ_ERROR(write("short.txt", "1 2 3\n4 5\n"), "line 2");
  EXPECT_READ_ERROR(write("word.txt", "1 2 3\n4 five 6\n"), "does not begin with three numbers");
  EXPECT_READ_ERROR(write("cut.pts", "3\n1 2 3\n4 5 6\n"), "promises 3 points but 2 follow");
  {
    MaxPointsGuard guard(1);
    EXPECT_READ_ERROR(write("two.txt", "1 2 3\n4 5 6\n"), "more than the limit of 1");
    EXPECT_READ_ERROR(write("many.pts", "5\n1 2 3\n"), "more than the limit of 1");
  }
}

TEST_F(CloudReader, TextWithDecimalCommasAsEuropeanLocalesExportIt) {
  // CloudCompare in a European locale: ';' between fields, ',' the decimal
  // point; or tab-separated. Read as numbers, not as integers split at the commas.
  const Cloud semi = readCloud(write("eu.txt", "-0,3868;0,8416;-1,5925\n2,5;3;4,25;0,5\n"));
  ASSERT_EQ(semi.size(), 2u);
  EXPECT_FLOAT_EQ(semi[0].x, -0.3868f);
  EXPECT_FLOAT_EQ(semi[0].y, 0.8416f);
  EXPECT_FLOAT_EQ(semi[0].z, -1.5925f);
  EXPECT_EQ(semi[1].x, 2.5f);
  EXPECT_EQ(semi[1].z, 4.25f);
  const Cloud tab = readCloud(write("eu.xyz", "//X\tY\tZ\n1,5\t2,25\t-3,75\r\n"));
  ASSERT_EQ(tab.size(), 1u);
  EXPECT_EQ(tab[0].y, 2.25f);
  EXPECT_EQ(tab[0].z, -3.75f);
  // Commas between integers (or after a point) stay separators.
  const Cloud ints = readCloud(write("ints.txt", "1,2,3\n4,5,6\n"));
  ASSERT_EQ(ints.size(), 2u);
  EXPECT_EQ(ints[1].x, 4.0f);
  EXPECT_EQ(ints[1].z, 6.0f);
  const Cloud dots = readCloud(write("dots.txt", "1.5,2,3\n"));
  ASSERT_EQ(dots.size(), 1u);
  EXPECT_EQ(dots[0].x, 1.5f);
  EXPECT_EQ(dots[0].y, 2.0f);
  // The first line of points decides for the file; a line read the other way is refused with its number.
  EXPECT_READ_ERROR(write("mixed.txt", "1,5;2;3\n1,5,2,3\n"), "line 2");
}

TEST_F(CloudReader, TextWithAColumnHeaderLineAsSpreadsheetsWriteIt) {
  const Cloud xyz = readCloud(write("h.xyz", "x y z\n1 2 3\n4 5 6\n"));
  ASSERT_EQ(xyz.size(), 2u);
  EXPECT_EQ(xyz[1].y, 5.0f);
  // A UTF-8 byte order mark, names of more columns, CRLF.
  const Cloud csv = readCloud(write("h.csv", "\xEF\xBB\xBFX,Y,Z,Red,Green,Blue\r\n1.5,2,3,0,0,0\r\n"));
  ASSERT_EQ(csv.size(), 1u);
  EXPECT_EQ(csv[0].x, 1.5f);
  const Cloud semi = readCloud(write("h.txt", "X;Y;Z;Intensity\n-0,5;1,25;2;7\n"));
  ASSERT_EQ(semi.size(), 1u);
  EXPECT_EQ(semi[0].x, -0.5f);
  // # comment lines first (a PCD's header starts so too).
  const Cloud commented = readCloud(write("c.xyz", "# exported by a scanner\n# units: m\n1 2 3\n4 5 6\n"));
  ASSERT_EQ(commented.size(), 2u);
  EXPECT_EQ(commented[1].z, 6.0f);
  EXPECT_READ_ERROR(write("c_bad.xyz", "# exported\n1 2 3\n4 5\n"), "line 3");
  // A header over something else is said so, and a bad line later counted from the file's start.
  EXPECT_READ_ERROR(write("h_bad.txt", "x y z\nnot numbers here\n"), "names columns");
  EXPECT_READ_ERROR(write("h_line.txt", "x y z\n1 2 3\n4 5\n"), "line 3");
}

TEST_F(CloudReader, NotAPointCloud) {
  EXPECT_READ_ERROR(write("text.pcd", "Dear diary,\ntoday I scanned a door.\n"), "not a point cloud file");
  const char png_bytes[] = "\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x10\0\0\0\x10\x08\x06\0\0\0";
  const std::string png(png_bytes, sizeof(png_bytes) - 1);
  EXPECT_READ_ERROR(write("image.pcd", png), "not a point cloud file");
  EXPECT_READ_ERROR(write("junk.ply", std::string(3 << 20, 'A')), "line longer than");
  EXPECT_READ_ERROR(write("nl.pcd", "\n\n\n"), "not a point cloud file");
}

TEST_F(CloudReader, EmptyMissingAndDirectory) {
  EXPECT_READ_ERROR(write("empty.pcd", ""), "file is empty");
  EXPECT_READ_ERROR(file("does_not_exist.pcd"), "does not exist");
  EXPECT_READ_ERROR(dir_.string(), "not a regular file");
  EXPECT_READ_ERROR(std::string(), "does not exist");
}

TEST_F(CloudReader, PointLimitIsEnforced) {
  pcl::io::savePCDFileBinary(file("b.pcd"), organized());
  {
    MaxPointsGuard guard(11);
    EXPECT_READ_ERROR(file("b.pcd"), "more than the limit of 11");
  }
  {
    MaxPointsGuard guard(12);
    EXPECT_EQ(readCloud(file("b.pcd")).size(), 12u);
  }
}

// Headers claiming 2 billion points in a ~200-byte file: refused without a large
// allocation, both by the default limit and (with the limit lifted) by the file-size checks.
TEST_F(CloudReader, TwoBillionPointsIn200Bytes) {
  std::vector<std::string> files;
  auto pad = [](std::string s) { s.resize(200, '1'); return s; };
  files.push_back(write("b.pcd", pad(xyzHeader("2000000000", "binary"))));
  files.push_back(write("a.pcd", pad(xyzHeader("2000000000", "ascii") + "1 2 3\n")));
  std::string c = xyzHeader("2000000000", "binary_compressed");
  put<std::uint32_t>(c, 16); put<std::uint32_t>(c, 4000000000u);
  files.push_back(write("c.pcd", pad(c)));
  files.push_back(write("o.pcd", pad(pcdHeader("x y z", "4 4 4", "F F F", "1 1 1", "50000", "40000",
                                               "2000000000", "binary"))));
  files.push_back(write("b.ply", pad("ply\nformat binary_big_endian 1.0\nelement vertex 2000000000\n"
                                     "property float x\nproperty float y\nproperty float z\nend_header\n")));
  files.push_back(write("a.ply", pad("ply\nformat ascii 1.0\nelement vertex 2000000000\n"
                                     "property float x\nproperty float y\nproperty float z\nend_header\n")));
  for (const auto& f : files) {
    SCOPED_TRACE(f);
    ASSERT_EQ(fs::file_size(f), 200u);
    // Default limit: refused from the header alone.
    EXPECT_READ_ERROR(f, "more than the limit");
    // Limit lifted: the file-size checks must refuse it. Run in a child whose address space is
    // capped at +256 MiB, so any attempt to allocate for 2e9 points fails (exit code != 0).
    EXPECT_EXIT(
        {
          dsr::io::setMaxPoints(std::numeric_limits<std::size_t>::max());
          long kb = 0;
          std::ifstream st("/proc/self/status");
          for (std::string l; std::getline(st, l);)
            if (l.rfind("VmSize:", 0) == 0) kb = std::atol(l.c_str() + 7);
          rlimit r{};
          r.rlim_cur = r.rlim_max = (rlim_t(kb) << 10) + (rlim_t(256) << 20);
          if (kb > 0) setrlimit(RLIMIT_AS, &r);
          try {
            readCloud(f);
          } catch (const CloudReadError& e) {  // a caught bad_alloc would say "out of memory"
            const bool oom = std::string(e.what()).find("out of memory") != std::string::npos;
            std::_Exit(!oom && e.what()[0] != '\0' ? 0 : 4);
          } catch (...) {
            std::_Exit(2);
          }
          std::_Exit(3);
        },
        ::testing::ExitedWithCode(0), "");
  }
}

// ------------------------------------------------------------------ from memory

// readCloudFromMemory (the fuzz target's entry) reads what readCloud reads from
// the same bytes, and refuses what it refuses with the same message.
TEST_F(CloudReader, FromMemoryAgreesWithTheFileReader) {
  std::vector<std::string> contents;
  pcl::io::savePCDFileASCII(file("a.pcd"), organized());
  pcl::io::savePCDFileBinary(file("b.pcd"), organized());
  pcl::io::savePCDFileBinaryCompressed(file("c.pcd"), organized());
  for (const char* f : {"a.pcd", "b.pcd", "c.pcd"}) {
    const std::string s = slurp(file(f));
    contents.push_back(s);
    contents.push_back(s.substr(0, s.size() - 3));  // truncated
  }
  // Binary PLY with an element skipped by seeking, then the same cut short inside it.
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement camera 2\nproperty double k\n"
      "element vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  put<double>(ply, 1.0); put<double>(ply, 2.0);
  for (float v : {1.f, 2.f, 3.f, -4.f, -5.f, -6.f}) put<float>(ply, v);
  contents.push_back(ply);
  contents.push_back(ply.substr(0, ply.size() - 30));
  contents.push_back("");
  contents.push_back("not a cloud\n");
  for (std::size_t i = 0; i < contents.size(); ++i) {
    SCOPED_TRACE("content " + std::to_string(i));
    const std::string& s = contents[i];
    const std::string path = write("m" + std::to_string(i), s);
    std::string file_error, memory_error;
    Cloud from_file, from_memory;
    try { from_file = readCloud(path); } catch (const CloudReadError& e) { file_error = e.what(); }
    try {
      from_memory = dsr::io::readCloudFromMemory(s.data(), s.size(), path);
    } catch (const CloudReadError& e) {
      memory_error = e.what();
    }
    if (s.empty()) {  // the only difference: a file says "file is empty"
      EXPECT_NE(file_error.find("file is empty"), std::string::npos) << file_error;
      EXPECT_EQ(memory_error, path + ": input is empty");
      continue;
    }
    EXPECT_EQ(memory_error, file_error);
    if (file_error.empty()) {
      expectSameCloud(from_memory, from_file);
      EXPECT_EQ(from_memory.is_dense, from_file.is_dense);
    }
  }
  // The good ones really were read (the comparison above is not between two errors).
  EXPECT_EQ(dsr::io::readCloudFromMemory(contents[4].data(), contents[4].size()).size(), 12u);
  expectSamePoint(dsr::io::readCloudFromMemory(ply.data(), ply.size())[1], pcl::PointXYZ(-4, -5, -6));
}

// ------------------------------------------------------------------ real data

fs::path sharedDataDir() {
  if (const char* env = std::getenv("DSR_SHARED_DATA")) return env;
#ifdef DSR_SHARED_DATA_DIR
  return DSR_SHARED_DATA_DIR;
#endif
  fs::path repo = fs::path(__FILE__).parent_path().parent_path();  // <repo>/test/this.cpp
  if (repo.empty()) repo = ".";
  return repo / ".." / "shared" / "data" / "real";
}

TEST(CloudReaderReal, Office1BinaryCompressed) {
  const fs::path p = sharedDataDir() / "office1.pcd";
  if (!fs::exists(p)) GTEST_SKIP() << p << " not found (set DSR_SHARED_DATA)";
  Cloud c = readCloud(p.string());
  EXPECT_EQ(c.width, 640u);
  EXPECT_EQ(c.height, 480u);
  ASSERT_EQ(c.size(), 307200u);
  std::size_t finite = 0;
  for (const auto& q : c) finite += std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
  EXPECT_GT(finite, 250000u);
  EXPECT_LT(finite, 258000u);
  EXPECT_FALSE(c.is_dense);
  RecordProperty("finite_points", std::to_string(finite));
  // Cross-check against PCL's own loader on this trusted file.
  Cloud ref;
  ASSERT_EQ(pcl::io::loadPCDFile(p.string(), ref), 0);
  expectSameCloud(c, ref);
}

}  // namespace
