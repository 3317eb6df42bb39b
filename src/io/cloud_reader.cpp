#include "door_state_recognition/io/cloud_reader.hpp"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <new>
#include <optional>
#include <streambuf>
#include <string_view>
#include <system_error>
#include <vector>

#include <pcl/io/lzf.h>

namespace dsr { namespace io {
namespace {

namespace fs = std::filesystem;
using u64 = std::uint64_t;

std::atomic<std::size_t> g_max_points{50000000};

constexpr std::size_t kMaxLine = 1 << 20;        // longest header / ascii line accepted
constexpr std::size_t kMaxToken = 256;           // longest ascii number accepted
constexpr std::size_t kChunkBytes = 1 << 20;     // binary data is read in chunks of this size
constexpr u64 kLzfMaxRatio = 88;                 // LZF: 3 input bytes expand to at most 264

// Checked a*b; false on 64-bit overflow.
bool mulOk(u64 a, u64 b, u64& out) { return !__builtin_mul_overflow(a, b, &out); }

// Printable, short, one-line rendering of text taken from the file.
std::string quote(std::string_view s) {
  std::string out = "'";
  for (std::size_t i = 0; i < s.size() && i < 40; ++i) {
    unsigned char c = static_cast<unsigned char>(s[i]);
    out += (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '?';
  }
  return out + (s.size() > 40 ? "...'" : "'");
}

std::vector<std::string_view> split(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r')) ++i;
    std::size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t' && s[j] != '\r') ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

bool parseDouble(std::string_view s, double& v) {
  if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

bool parseU64(std::string_view s, u64& v) {
  auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return !s.empty() && r.ec == std::errc() && r.ptr == s.data() + s.size();
}

// A read-only streambuf over bytes in memory that can seek (skipBytes needs it).
class MemoryBuf : public std::streambuf {
 public:
  MemoryBuf(const char* data, std::size_t size) {
    char* p = const_cast<char*>(data);  // never written through: no overflow/pbackfail
    setg(p, p, p + size);
  }

 protected:
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override {
    const off_type fail = -1, size = egptr() - eback();
    if (!(which & std::ios_base::in)) return pos_type(fail);
    off_type base = dir == std::ios_base::beg ? 0 : dir == std::ios_base::cur ? gptr() - eback() : size;
    if (off > size - base || off < -base) return pos_type(fail);
    setg(eback(), eback() + (base + off), egptr());
    return pos_type(base + off);
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
    return seekoff(off_type(pos), std::ios_base::beg, which);
  }
};

// Sequential reader over a regular file (or bytes in memory) that knows how many bytes are left.
class Input {
 public:
  explicit Input(const std::string& path) : path_(path) {
    std::error_code ec;
    auto st = fs::status(path, ec);
    if (ec || !fs::exists(st)) fail("file does not exist");
    if (!fs::is_regular_file(st)) fail("not a regular file");
    size_ = fs::file_size(path, ec);
    if (ec) fail("cannot get file size (" + ec.message() + ")");
    auto file = std::make_unique<std::filebuf>();
    if (!file->open(path, std::ios::in | std::ios::binary))
      fail(std::string("cannot open file (") + std::strerror(errno) + ")");
    buf_ = std::move(file);
    if (size_ == 0) fail("file is empty");
  }

  Input(const char* data, std::size_t size, const std::string& name)
      : path_(name), buf_(std::make_unique<MemoryBuf>(data, size)), size_(size) {
    if (size_ == 0) fail("input is empty");
  }

  [[noreturn]] void fail(const std::string& msg) const { throw CloudReadError(path_ + ": " + msg); }
  u64 remaining() const { return pos_ < size_ ? size_ - pos_ : 0; }

  // Reads one line (without "\n" / "\r\n"); false at end of file.
  bool readLine(std::string& line) {
    line.clear();
    int c = buf_->sbumpc();
    if (c == EOF) return false;
    while (c != EOF && c != '\n') {
      ++pos_;
      if (line.size() >= kMaxLine) fail("line longer than " + std::to_string(kMaxLine) + " bytes");
      line += static_cast<char>(c);
      c = buf_->sbumpc();
    }
    if (c == '\n') ++pos_;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  }

  // Reads one whitespace-separated token; false at end of file.
  bool readToken(std::string& tok) {
    tok.clear();
    int c = buf_->sbumpc();
    while (c != EOF && std::isspace(c)) { ++pos_; c = buf_->sbumpc(); }
    while (c != EOF && !std::isspace(c)) {
      ++pos_;
      if (tok.size() >= kMaxToken) fail("value longer than " + std::to_string(kMaxToken) + " characters");
      tok += static_cast<char>(c);
      c = buf_->sbumpc();
    }
    if (c != EOF) ++pos_;
    return !tok.empty();
  }

  void readBytes(char* dst, u64 n, const char* what) {
    if (n > remaining() || static_cast<u64>(buf_->sgetn(dst, static_cast<std::streamsize>(n))) != n)
      fail(std::string("file ends inside ") + what);
    pos_ += n;
  }

  void skipBytes(u64 n, const char* what) {
    if (n > remaining()) fail(std::string("file ends inside ") + what);
    auto p = buf_->pubseekoff(static_cast<std::streamoff>(n), std::ios::cur, std::ios::in);
    if (p == std::streampos(std::streamoff(-1))) fail(std::string("cannot seek past ") + what);
    pos_ += n;
  }

 private:
  std::string path_;
  std::unique_ptr<std::streambuf> buf_;
  u64 size_ = 0, pos_ = 0;
};

// Reads `count` fixed-size records in chunks and hands each to fn(const char* record).
template <typename Fn>
void forEachRecord(Input& in, u64 count, u64 record_size, Fn fn) {
  std::vector<char> buf;
  u64 per_chunk = std::max<u64>(1, kChunkBytes / std::max<u64>(1, record_size));
  for (u64 done = 0; done < count;) {
    u64 n = std::min(per_chunk, count - done);
    buf.resize(n * record_size);
    in.readBytes(buf.data(), buf.size(), "the point data");
    for (u64 i = 0; i < n; ++i) fn(buf.data() + i * record_size);
    done += n;
  }
}

// Scalar float32/float64 at p, optionally byte-swapped.
double loadDouble(const char* p, int size, bool swap) {
  char b[8];
  std::memcpy(b, p, size);
  if (swap) std::reverse(b, b + size);
  if (size == 4) { float f; std::memcpy(&f, b, 4); return f; }
  double d; std::memcpy(&d, b, 8); return d;
}

// Points as float, moved by the cloud's shift (CloudFrame): decided on the
// first finite point unless given, and applied in double before the cast.
struct Localizer {
  CloudFrame* frame;
  bool decided;
  explicit Localizer(CloudFrame* f) : frame(f), decided(f && f->shift_given) {}
  pcl::PointXYZ operator()(double x, double y, double z) {
    if (!frame) return pcl::PointXYZ(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
    if (!decided && std::isfinite(x) && std::isfinite(y) && std::isfinite(z)) {
      decided = true;
      if (std::max({std::abs(x), std::abs(y), std::abs(z)}) > kShiftBeyond)
        frame->shift = Eigen::Vector3d(std::round(x), std::round(y), std::round(z));
    }
    const Eigen::Vector3d& o = frame->shift;
    return pcl::PointXYZ(static_cast<float>(x - o.x()), static_cast<float>(y - o.y()), static_cast<float>(z - o.z()));
  }
};

u64 loadUInt(const char* p, int size, bool swap) {
  unsigned char b[8];
  std::memcpy(b, p, size);
  if (swap) std::reverse(b, b + size);
  u64 v = 0;
  for (int i = size - 1; i >= 0; --i) v = (v << 8) | b[i];  // little-endian after swap
  return v;
}

bool hostLittleEndian() { const std::uint16_t one = 1; char c; std::memcpy(&c, &one, 1); return c == 1; }

// Where x, y and z live in a record: byte offset (binary) / token index (ascii), and byte size.
struct XyzLayout { u64 offset[3]; u64 token[3]; int size[3]; };

void finish(pcl::PointCloud<pcl::PointXYZ>& cloud) {
  cloud.is_dense = std::all_of(cloud.points.begin(), cloud.points.end(), [](const pcl::PointXYZ& p) {
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  });
}

// Allocates the output only after the caller has checked the data can hold `points`.
void allocate(pcl::PointCloud<pcl::PointXYZ>& cloud, u64 points, u64 width, u64 height) {
  cloud.points.resize(static_cast<std::size_t>(points));
  cloud.width = static_cast<std::uint32_t>(width);
  cloud.height = static_cast<std::uint32_t>(height);
}

void checkPointLimit(Input& in, u64 points) {
  if (points > g_max_points.load())
    in.fail("header asks for " + std::to_string(points) + " points, more than the limit of " +
            std::to_string(g_max_points.load()) + " (parameter max_points)");
}

// ---------------------------------------------------------------- point by point

// Text clouds and OBJ meshes hold no count to check first: each point is
// appended within max_points, and the cloud is unorganized.
void appendPoint(Input& in, pcl::PointCloud<pcl::PointXYZ>& cloud, const pcl::PointXYZ& q) {
  if (cloud.points.size() >= g_max_points.load())
    in.fail("holds more than the limit of " + std::to_string(g_max_points.load()) + " points (parameter max_points)");
  cloud.points.push_back(q);
  cloud.width = static_cast<std::uint32_t>(cloud.points.size());
  cloud.height = 1;
}

// ---------------------------------------------------------------- OBJ

bool isObjKeyword(std::string_view k) {
  for (const char* w : {"v", "vn", "vt", "vp", "f", "l", "p", "o", "g", "s", "mtllib", "usemtl"})
    if (k == w) return true;
  return false;
}

// A Wavefront OBJ mesh (photogrammetry and phone-scanner exports): its
// vertices ("v x y z [w | r g b]") as the cloud, in file order; faces,
// normals, texture coordinates, groups and materials skipped. `line` holds
// the first line that is not a # comment, already read.
pcl::PointCloud<pcl::PointXYZ> readObj(Input& in, std::string line, Localizer& loc) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.height = 1;
  for (bool have = true; have; have = in.readLine(line)) {
    const std::vector<std::string_view> tok = split(line);
    if (tok.empty() || tok[0] != "v") continue;
    double v[3];
    if (tok.size() < 4 || !parseDouble(tok[1], v[0]) || !parseDouble(tok[2], v[1]) || !parseDouble(tok[3], v[2]))
      in.fail("vertex " + std::to_string(cloud.points.size()) + ": " + quote(line.substr(0, 80)) +
              " is not 'v x y z'");
    appendPoint(in, cloud, loc(v[0], v[1], v[2]));
  }
  return cloud;
}

// ---------------------------------------------------------------- PCD

bool isPcdKeyword(std::string_view k) {
  for (const char* w : {"VERSION", "FIELDS", "COLUMNS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT",
                        "VIEWPOINT", "POINTS", "DATA"})
    if (k == w) return true;
  return false;
}


// `line` holds the file's first line, already read (an OBJ's first
// keyword after its comments hands it to readObj).
// Text clouds (below): a PCD's first lines may turn out to be a text cloud's comments.
bool looksLikeText(const std::string& first);
pcl::PointCloud<pcl::PointXYZ> readText(Input& in, const std::string& first, Localizer& loc, u64 first_line_no = 1);

pcl::PointCloud<pcl::PointXYZ> readPcd(Input& in, std::string line, Localizer& loc) {
  std::vector<std::string> names, sizes, types, counts;
  std::string width_s, height_s, points_s, data;
  std::vector<double> viewpoint;
  std::vector<std::string> seen;
  bool first = true;
  u64 line_no = 0;  // of `line`
  for (bool have = true; data.empty(); have = false) {
    if (!have && !in.readLine(line))
      in.fail(first ? "not a point cloud file (no PCD or PLY header, nor lines of x y z)" : "PCD header has no DATA line");
    ++line_no;
    auto tok = split(line);
    if (tok.empty() || tok[0][0] == '#') continue;
    std::string key(tok[0]);
    if (first && isObjKeyword(key)) return readObj(in, line, loc);
    // A text cloud after # comment lines ("# exported by ...").
    if (first && looksLikeText(line)) return readText(in, line, loc, line_no);
    if (!isPcdKeyword(key))
      in.fail(first ? "not a point cloud file (no PCD or PLY header, nor lines of x y z)"
                    : "unknown PCD header line " + quote(line));
    first = false;
    if (key == "COLUMNS") key = "FIELDS";
    if (std::find(seen.begin(), seen.end(), key) != seen.end()) in.fail("PCD header repeats " + key);
    seen.push_back(key);
    std::vector<std::string> vals(tok.begin() + 1, tok.end());
    auto one = [&]() -> std::string {
      if (vals.size() != 1) in.fail(key + " needs exactly one value, got " + quote(line));
      return vals[0];
    };
    if (key == "VERSION") one();
    else if (key == "FIELDS") names = vals;
    else if (key == "SIZE") sizes = vals;
    else if (key == "TYPE") types = vals;
    else if (key == "COUNT") counts = vals;
    else if (key == "WIDTH") width_s = one();
    else if (key == "HEIGHT") height_s = one();
    else if (key == "POINTS") points_s = one();
    else if (key == "DATA") data = one();
    else if (key == "VIEWPOINT") {
      viewpoint.resize(vals.size());
      for (std::size_t i = 0; i < vals.size(); ++i)
        if (!parseDouble(vals[i], viewpoint[i])) in.fail("VIEWPOINT value " + quote(vals[i]) + " is not a number");
      if (viewpoint.size() != 7) in.fail("VIEWPOINT needs 7 values (tx ty tz qw qx qy qz)");
    }
  }

  // Fields: names, sizes, types, counts must agree.
  if (names.empty()) in.fail("PCD header has no FIELDS line");
  if (sizes.size() != names.size())
    in.fail("SIZE has " + std::to_string(sizes.size()) + " entries but FIELDS has " + std::to_string(names.size()));
  if (types.size() != names.size())
    in.fail("TYPE has " + std::to_string(types.size()) + " entries but FIELDS has " + std::to_string(names.size()));
  if (counts.empty()) counts.assign(names.size(), "1");
  if (counts.size() != names.size())
    in.fail("COUNT has " + std::to_string(counts.size()) + " entries but FIELDS has " + std::to_string(names.size()));

  XyzLayout xyz{};
  bool found[3] = {false, false, false};
  u64 point_size = 0, tokens = 0;
  for (std::size_t i = 0; i < names.size(); ++i) {
    u64 size = 0, count = 0;
    const std::string& t = types[i];
    if (!parseU64(sizes[i], size)) in.fail("SIZE of field " + quote(names[i]) + " is not a number: " + quote(sizes[i]));
    if (!parseU64(counts[i], count) || count == 0 || count > (1u << 24))
      in.fail("COUNT of field " + quote(names[i]) + " is invalid: " + quote(counts[i]));
    bool ok = (t == "F" && (size == 4 || size == 8)) ||
              ((t == "I" || t == "U") && (size == 1 || size == 2 || size == 4 || size == 8));
    if (!ok) in.fail("field " + quote(names[i]) + " has unsupported TYPE/SIZE " + quote(t) + "/" + sizes[i]);
    for (int a = 0; a < 3; ++a) {
      if (names[i] != std::string(1, "xyz"[a])) continue;
      if (found[a]) in.fail("field " + names[i] + " appears twice");
      if (t != "F" || count != 1)
        in.fail("field " + names[i] + " must be float32 or float64 (TYPE F, SIZE 4 or 8, COUNT 1), got TYPE " +
                t + " SIZE " + sizes[i] + " COUNT " + counts[i]);
      found[a] = true;
      xyz.offset[a] = point_size;
      xyz.token[a] = tokens;
      xyz.size[a] = static_cast<int>(size);
    }
    point_size += size * count;  // < 2^20 fields * 8 * 2^24: cannot overflow
    tokens += count;
  }
  for (int a = 0; a < 3; ++a)
    if (!found[a]) in.fail(std::string("PCD has no '") + "xyz"[a] + "' field");

  // Dimensions.
  u64 width = 0, height = 1, points = 0;
  if (!width_s.empty() && !parseU64(width_s, width)) in.fail("WIDTH is not a non-negative integer: " + quote(width_s));
  if (!height_s.empty() && !parseU64(height_s, height)) in.fail("HEIGHT is not a non-negative integer: " + quote(height_s));
  if (!points_s.empty() && !parseU64(points_s, points)) in.fail("POINTS is not a non-negative integer: " + quote(points_s));
  if (width_s.empty() && points_s.empty()) in.fail("PCD header has neither WIDTH nor POINTS");
  if (width_s.empty()) { width = points; height = 1; }
  u64 wh = 0;
  if (!mulOk(width, height, wh)) in.fail("WIDTH*HEIGHT (" + width_s + "*" + height_s + ") overflows");
  if (points_s.empty()) points = wh;
  if (wh != points)
    in.fail("WIDTH*HEIGHT = " + std::to_string(width) + "*" + std::to_string(height) + " = " + std::to_string(wh) +
            " but POINTS is " + std::to_string(points));
  checkPointLimit(in, points);
  if (width > UINT32_MAX || height > UINT32_MAX) in.fail("WIDTH or HEIGHT does not fit in 32 bits");

  pcl::PointCloud<pcl::PointXYZ> cloud;
  if (loc.frame) loc.frame->viewpoint_given = viewpoint.size() == 7 && (viewpoint[0] != 0 || viewpoint[1] != 0 || viewpoint[2] != 0);
  if (viewpoint.size() == 7) {
    if (loc.frame) loc.frame->viewpoint = Eigen::Vector3d(viewpoint[0], viewpoint[1], viewpoint[2]);
    cloud.sensor_origin_ = Eigen::Vector4d(viewpoint[0], viewpoint[1], viewpoint[2], 0.0).cast<float>();
    cloud.sensor_orientation_ =
        Eigen::Quaterniond(viewpoint[3], viewpoint[4], viewpoint[5], viewpoint[6]).cast<float>();
  }
  const std::string promised = "header promises " + std::to_string(points) + " points";

  if (data == "ascii") {
    // Every row needs at least one character per value plus separators.
    u64 min_bytes = 0;
    if (points > 0 && (!mulOk(points, 2 * tokens, min_bytes) || min_bytes - 1 > in.remaining()))
      in.fail(promised + " of " + std::to_string(tokens) + " values but only " + std::to_string(in.remaining()) +
              " bytes of DATA follow");
    allocate(cloud, points, width, height);
    u64 row = 0;
    while (row < points) {
      if (!in.readLine(line))
        in.fail(promised + " but DATA holds " + std::to_string(row));
      auto tok = split(line);
      if (tok.empty()) continue;
      if (tok.size() != tokens)
        in.fail("DATA row " + std::to_string(row + 1) + " has " + std::to_string(tok.size()) + " values, expected " +
                std::to_string(tokens));
      double v[3] = {0, 0, 0};
      for (std::size_t k = 0; k < tok.size(); ++k) {
        double d;
        if (!parseDouble(tok[k], d))
          in.fail("DATA row " + std::to_string(row + 1) + ": " + quote(tok[k]) + " is not a number");
        for (int a = 0; a < 3; ++a)
          if (xyz.token[a] == k) v[a] = d;
      }
      cloud.points[row] = loc(v[0], v[1], v[2]);
      ++row;
    }
  } else if (data == "binary") {
    u64 need = 0;
    if (!mulOk(points, point_size, need) || need > in.remaining())
      in.fail(promised + " but DATA holds " + std::to_string(in.remaining() / point_size) + " (" +
              std::to_string(in.remaining()) + " bytes of " + std::to_string(point_size) + "-byte points)");
    allocate(cloud, points, width, height);
    std::size_t i = 0;
    forEachRecord(in, points, point_size, [&](const char* r) {
      cloud.points[i++] = loc(loadDouble(r + xyz.offset[0], xyz.size[0], false),
                              loadDouble(r + xyz.offset[1], xyz.size[1], false),
                              loadDouble(r + xyz.offset[2], xyz.size[2], false));
    });
  } else if (data == "binary_compressed") {
    if (points == 0 && in.remaining() == 0) { allocate(cloud, 0, width, height); return cloud; }
    char hdr[8];
    in.readBytes(hdr, 8, "the compressed-data header (8 bytes)");
    u64 csize = loadUInt(hdr, 4, false), usize = loadUInt(hdr + 4, 4, false), need = 0;
    if (!mulOk(points, point_size, need) || usize != need)
      in.fail("compressed header says " + std::to_string(usize) + " bytes uncompressed but " + promised + " of " +
              std::to_string(point_size) + " bytes");
    if (csize > in.remaining())
      in.fail("compressed header says " + std::to_string(csize) + " compressed bytes but only " +
              std::to_string(in.remaining()) + " follow (file truncated?)");
    if (usize > csize * kLzfMaxRatio)
      in.fail(std::to_string(csize) + " compressed bytes cannot expand to the " + std::to_string(usize) +
              " bytes the header claims");
    allocate(cloud, points, width, height);
    if (points == 0) return cloud;
    std::vector<char> packed(csize), raw(usize);
    in.readBytes(packed.data(), csize, "the compressed data");
    unsigned got = pcl::lzfDecompress(packed.data(), static_cast<unsigned>(csize), raw.data(),
                                      static_cast<unsigned>(usize));
    if (got != usize)
      in.fail("compressed data is corrupt (decompressed " + std::to_string(got) + " of " + std::to_string(usize) +
              " bytes)");
    // Column-major: all values of field 0 for every point, then field 1, ...
    const char* col[3];
    for (int a = 0; a < 3; ++a) col[a] = raw.data() + xyz.offset[a] * points;
    for (u64 i = 0; i < points; ++i)
      cloud.points[i] = loc(loadDouble(col[0] + i * xyz.size[0], xyz.size[0], false),
                            loadDouble(col[1] + i * xyz.size[1], xyz.size[1], false),
                            loadDouble(col[2] + i * xyz.size[2], xyz.size[2], false));
  } else {
    in.fail("unknown DATA kind " + quote(data) + " (expected ascii, binary or binary_compressed)");
  }
  return cloud;
}

// ---------------------------------------------------------------- plain text

// The fields of a text line, split at spaces, tabs, commas and semicolons.
std::vector<std::string_view> textFields(const std::string& line) {
  std::vector<std::string_view> out;
  auto sep = [](char c) { return c == ' ' || c == '\t' || c == ',' || c == ';'; };
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && sep(line[i])) ++i;
    std::size_t j = i;
    while (j < line.size() && !sep(line[j])) ++j;
    if (j > i) out.emplace_back(line.data() + i, j - i);
    i = j;
  }
  return out;
}

// The fields of a line written with decimal commas (a European locale's
// export: "-0,39;0,84;-1,59", or the same tab-separated): split at spaces,
// tabs and semicolons, each comma taken as the decimal point.
std::vector<std::string> decimalCommaFields(const std::string& line) {
  std::vector<std::string> out;
  auto sep = [](char c) { return c == ' ' || c == '\t' || c == ';'; };
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && sep(line[i])) ++i;
    std::size_t j = i;
    while (j < line.size() && !sep(line[j])) ++j;
    if (j > i) {
      std::string f = line.substr(i, j - i);
      std::replace(f.begin(), f.end(), ',', '.');
      out.push_back(std::move(f));
    }
    i = j;
  }
  return out;
}

// Whether a data line is written with decimal commas: no '.', some ',', and
// split at spaces, tabs and semicolons only, three numbers or more once each
// comma is a point, one of them with a comma ("1,5 2 3" too; "1, 2, 3" is
// commas between integers: "1," is no number).
bool decimalCommas(const std::string& line) {
  if (line.find('.') != std::string::npos || line.find(',') == std::string::npos) return false;
  const std::vector<std::string> f = decimalCommaFields(line);
  double d;
  return f.size() >= 3 && std::all_of(f.begin(), f.end(), [&](const std::string& v) { return parseDouble(v, d); });
}

bool skippedText(const std::string& line) {
  const std::size_t i = line.find_first_not_of(" \t");
  return i == std::string::npos || line[i] == '#' || line.compare(i, 2, "//") == 0;
}

// A first line of numbers only: three or more (a point), or one whole count
// (Leica .pts); or a column header after // (CloudCompare's "//X,Y,Z"). A
// PCD header's first line is a # comment or a keyword.
bool looksLikeText(const std::string& first) {
  if (first.compare(0, 2, "//") == 0) return true;
  const std::vector<std::string_view> f = textFields(first);
  double d;
  u64 n;
  if (f.size() == 1) return parseU64(f[0], n);
  return f.size() >= 3 && std::all_of(f.begin(), f.end(), [&](std::string_view v) { return parseDouble(v, d); });
}

// A line of column names before the points ("x y z", "X,Y,Z,R,G,B",
// "X;Y;Z;Intensity"): three or more fields, each a name (a letter first;
// letters, digits, '_', '-', '(' and ')'), the first no PCD or OBJ keyword.
bool looksLikeColumnHeader(const std::string& line) {
  const std::vector<std::string_view> f = textFields(line);
  if (f.size() < 3 || f.size() > 64 || isPcdKeyword(f[0]) || isObjKeyword(f[0])) return false;
  return std::all_of(f.begin(), f.end(), [](std::string_view v) {
    return std::isalpha(static_cast<unsigned char>(v[0])) &&
           std::all_of(v.begin(), v.end(), [](char c) {
             return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '(' || c == ')';
           });
  });
}

// x y z and any further columns per line (S3DIS rooms' .txt, .xyz,
// CloudCompare's ASCII export), optionally after a line holding the point
// count alone (.pts); blank lines and lines starting with # or // (a column
// header) are skipped. One cloud of the points in file order, unorganized.
pcl::PointCloud<pcl::PointXYZ> readText(Input& in, const std::string& first, Localizer& loc, u64 first_line_no) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.height = 1;
  std::optional<u64> promised;
  std::string line = first;
  u64 line_no = first_line_no;
  bool have = true;
  {
    const std::vector<std::string_view> f = textFields(first);
    u64 n;
    if (!skippedText(first) && f.size() == 1 && parseU64(f[0], n)) {
      checkPointLimit(in, n);
      promised = n;
      have = in.readLine(line), ++line_no;
    }
  }
  // Decimal commas or not: decided on the first line of data, for the file.
  std::optional<bool> comma;
  for (; have; have = in.readLine(line), ++line_no) {
    if (skippedText(line)) continue;
    if (!comma) comma = decimalCommas(line);
    double v[3];
    bool ok;
    if (*comma) {
      const std::vector<std::string> f = decimalCommaFields(line);
      ok = f.size() >= 3 && parseDouble(f[0], v[0]) && parseDouble(f[1], v[1]) && parseDouble(f[2], v[2]);
    } else {
      const std::vector<std::string_view> f = textFields(line);
      ok = f.size() >= 3 && parseDouble(f[0], v[0]) && parseDouble(f[1], v[1]) && parseDouble(f[2], v[2]);
    }
    if (!ok)
      in.fail("line " + std::to_string(line_no) + ": " + quote(line.substr(0, 80)) + " does not begin with three numbers x y z" +
              (*comma ? " (read with decimal commas, as the first line of points is written)" : ""));
    appendPoint(in, cloud, loc(v[0], v[1], v[2]));
  }
  if (promised && *promised != cloud.points.size())
    in.fail("the first line promises " + std::to_string(*promised) + " points but " +
            std::to_string(cloud.points.size()) + " follow");
  return cloud;
}

// ---------------------------------------------------------------- PLY

struct PlyProp { std::string name; int size = 0; bool is_float = false; bool list = false; int count_size = 0; };
struct PlyElement { std::string name; u64 count = 0; std::vector<PlyProp> props; };

// Byte size of a PLY scalar type (0 = unknown); is_float set for float/double.
int plyTypeSize(std::string_view t, bool& is_float) {
  is_float = (t == "float" || t == "float32" || t == "double" || t == "float64");
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

void skipPlyElement(Input& in, const PlyElement& e, bool ascii, bool swap) {
  std::string tok;
  bool has_list = std::any_of(e.props.begin(), e.props.end(), [](const PlyProp& p) { return p.list; });
  if (!ascii && !has_list) {
    u64 rec = 0, total = 0;
    for (const auto& p : e.props) rec += p.size;
    if (!mulOk(rec, e.count, total)) in.fail("element '" + e.name + "' is too large");
    in.skipBytes(total, "a PLY element before the vertices");
    return;
  }
  if (e.props.empty()) return;
  for (u64 i = 0; i < e.count; ++i) {  // every instance consumes >= 1 byte, so this ends with the file
    for (const auto& p : e.props) {
      u64 n = 1;
      if (p.list) {
        if (ascii) {
          if (!in.readToken(tok) || !parseU64(tok, n)) in.fail("bad list length in element '" + e.name + "'");
        } else {
          char b[4];
          in.readBytes(b, p.count_size, "a PLY element before the vertices");
          n = loadUInt(b, p.count_size, swap);
        }
      }
      if (ascii) {
        for (u64 k = 0; k < n; ++k)
          if (!in.readToken(tok)) in.fail("file ends inside element '" + e.name + "'");
      } else {
        in.skipBytes(n * p.size, "a PLY element before the vertices");  // n < 2^32, size <= 8
      }
    }
  }
}

pcl::PointCloud<pcl::PointXYZ> readPly(Input& in, Localizer& loc) {
  std::string line, format;  // the "ply" line has been read
  std::vector<PlyElement> elems;
  bool ended = false;
  while (!ended) {
    if (!in.readLine(line)) in.fail("PLY header has no end_header line");
    auto tok = split(line);
    if (tok.empty()) continue;
    if (tok[0] == "comment" || tok[0] == "obj_info") continue;
    if (tok[0] == "end_header") { ended = true; continue; }
    if (tok[0] == "format") {
      if (tok.size() != 3 || !format.empty()) in.fail("bad PLY format line " + quote(line));
      format = tok[1];
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
        in.fail("unknown PLY format " + quote(format));
    } else if (tok[0] == "element") {
      PlyElement e;
      if (tok.size() != 3 || !parseU64(tok[2], e.count)) in.fail("bad PLY element line " + quote(line));
      e.name = tok[1];
      elems.push_back(e);
    } else if (tok[0] == "property") {
      if (elems.empty()) in.fail("PLY property before any element: " + quote(line));
      PlyProp p;
      std::string_view type;
      if (tok.size() == 5 && tok[1] == "list") {
        bool f;
        p.list = true;
        p.count_size = plyTypeSize(tok[2], f);
        if (p.count_size == 0 || f) in.fail("bad PLY list count type " + quote(tok[2]));
        type = tok[3];
        p.name = tok[4];
      } else if (tok.size() == 3) {
        type = tok[1];
        p.name = tok[2];
      } else {
        in.fail("bad PLY property line " + quote(line));
      }
      p.size = plyTypeSize(type, p.is_float);
      if (p.size == 0) in.fail("unknown PLY property type " + quote(type));
      elems.back().props.push_back(p);
    } else {
      in.fail("unknown PLY header line " + quote(line));
    }
  }
  if (format.empty()) in.fail("PLY header has no format line");
  const bool ascii = format == "ascii";
  const bool swap = !ascii && ((format == "binary_little_endian") != hostLittleEndian());

  auto isVertex = [](const PlyElement& e) { return e.name == "vertex"; };
  auto vit = std::find_if(elems.begin(), elems.end(), isVertex);
  if (vit == elems.end()) in.fail("PLY has no vertex element");
  if (std::count_if(elems.begin(), elems.end(), isVertex) > 1) in.fail("PLY has more than one vertex element");
  const PlyElement& v = *vit;
  XyzLayout xyz{};
  bool found[3] = {false, false, false};
  u64 rec = 0;
  for (std::size_t k = 0; k < v.props.size(); ++k) {
    const PlyProp& p = v.props[k];
    if (p.list) in.fail("vertex property '" + p.name + "' is a list; lists are not supported in vertices");
    for (int a = 0; a < 3; ++a) {
      if (p.name != std::string(1, "xyz"[a])) continue;
      if (found[a]) in.fail("vertex property " + p.name + " appears twice");
      if (!p.is_float) in.fail("vertex property " + p.name + " must be float or double");
      found[a] = true;
      xyz.offset[a] = rec;
      xyz.token[a] = k;
      xyz.size[a] = p.size;
    }
    rec += p.size;
  }
  for (int a = 0; a < 3; ++a)
    if (!found[a]) in.fail(std::string("PLY vertex has no '") + "xyz"[a] + "' property");
  checkPointLimit(in, v.count);

  for (auto it = elems.begin(); it != vit; ++it) skipPlyElement(in, *it, ascii, swap);

  const u64 n = v.count, nprops = v.props.size();
  const std::string promised = "header promises " + std::to_string(n) + " vertices";
  pcl::PointCloud<pcl::PointXYZ> cloud;
  if (ascii) {
    u64 min_bytes = 0;
    if (n > 0 && (!mulOk(n, 2 * nprops, min_bytes) || min_bytes - 1 > in.remaining()))
      in.fail(promised + " but only " + std::to_string(in.remaining()) + " bytes of data follow");
    allocate(cloud, n, n, 1);
    std::string tok;
    for (u64 i = 0; i < n; ++i) {
      double val[3] = {0, 0, 0};
      for (u64 k = 0; k < nprops; ++k) {
        double d;
        if (!in.readToken(tok)) in.fail(promised + " but data holds " + std::to_string(i));
        if (!parseDouble(tok, d)) in.fail("vertex " + std::to_string(i) + ": " + quote(tok) + " is not a number");
        for (int a = 0; a < 3; ++a)
          if (xyz.token[a] == k) val[a] = d;
      }
      cloud.points[i] = loc(val[0], val[1], val[2]);
    }
  } else {
    u64 need = 0;
    if (!mulOk(n, rec, need) || need > in.remaining())
      in.fail(promised + " but data holds " + std::to_string(in.remaining() / rec) + " (" +
              std::to_string(in.remaining()) + " bytes)");
    allocate(cloud, n, n, 1);
    std::size_t i = 0;
    forEachRecord(in, n, rec, [&](const char* r) {
      cloud.points[i++] = loc(loadDouble(r + xyz.offset[0], xyz.size[0], swap),
                              loadDouble(r + xyz.offset[1], xyz.size[1], swap),
                              loadDouble(r + xyz.offset[2], xyz.size[2], swap));
    });
  }
  return cloud;
}

}  // namespace

void setMaxPoints(std::size_t n) { g_max_points = n; }

namespace {

// Reads a cloud from `in`; every error becomes a CloudReadError naming `name`.
template <typename MakeInput>
pcl::PointCloud<pcl::PointXYZ> readFrom(const std::string& name, MakeInput make, CloudFrame* frame) {
  try {
    Input in = make();
    // PLY files start with the line "ply", text clouds with numbers;
    // anything else is tried as PCD.
    std::string first;
    in.readLine(first);
    if (first.compare(0, 3, "\xEF\xBB\xBF") == 0) first.erase(0, 3);  // a UTF-8 byte order mark
    Localizer loc(frame);
    pcl::PointCloud<pcl::PointXYZ> cloud;
    if (first == "ply") {
      cloud = readPly(in, loc);
    } else if (looksLikeText(first)) {
      cloud = readText(in, first, loc);
    } else if (looksLikeColumnHeader(first)) {  // names of columns, then the points
      std::string second;
      in.readLine(second);
      if (!looksLikeText(second))
        in.fail("line 1 " + quote(first.substr(0, 80)) + " names columns, but line 2 " + quote(second.substr(0, 80)) +
                " is not x y z");
      cloud = readText(in, second, loc, 2);
    } else {
      cloud = readPcd(in, first, loc);
    }
    // The VIEWPOINT in the frame the points were moved into, from its value
    // as read (in double: a float holds a georeferenced coordinate to a
    // decimetre, the point's shifted coordinates to a millimetre).
    if (frame && !frame->shift.isZero())
      cloud.sensor_origin_.head<3>() = (frame->viewpoint - frame->shift).cast<float>();
    finish(cloud);
    return cloud;
  } catch (const CloudReadError&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw CloudReadError(name + ": out of memory while reading");
  } catch (const std::exception& e) {
    throw CloudReadError(name + ": " + e.what());
  }
}

}  // namespace

pcl::PointCloud<pcl::PointXYZ> readCloud(const std::string& path, CloudFrame* frame) {
  return readFrom(path, [&] { return Input(path); }, frame);
}

pcl::PointCloud<pcl::PointXYZ> readCloudFromMemory(const void* data, std::size_t size, const std::string& name) {
  return readFrom(name, [&] { return Input(static_cast<const char*>(data), size, name); }, nullptr);
}

}}  // namespace dsr::io
