#pragma once
#include <Eigen/Core>
#include <stdexcept>
#include <string>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
namespace dsr { namespace io {
// Thrown with a one-line, human-readable message saying what is wrong
// (e.g. "office.pcd: header promises 307200 points but DATA holds 1200").
class CloudReadError : public std::runtime_error { using std::runtime_error::runtime_error; };
// Reads x,y,z of a PCD (ascii, binary, binary_compressed) or PLY (ascii,
// binary_little_endian, binary_big_endian) file, or of a text file with x y
// z first on each line (S3DIS's .txt, .xyz, .pts with its count line;
// spaces, tabs, commas or semicolons between; # and // lines skipped), or
// the vertices of a Wavefront OBJ mesh. The format is chosen by the file's
// content (magic "ply" / PCD header keywords / a first line of numbers / OBJ
// keywords), not its extension.
// Keeps width/height (organized clouds stay organized) and keeps NaN/Inf
// points as they are (callers filter). Extra fields (rgb, label, normals...)
// are skipped. x,y,z may be float32 or float64 (converted to float); any
// other type for x/y/z is an error. Throws CloudReadError on anything wrong.
// Georeferenced clouds (UTM eastings of 1e5-1e6 m) hold coordinates that
// float32 cannot keep to a millimetre. Given a CloudFrame, a cloud whose
// first finite point lies beyond kShiftBeyond from the origin is moved by
// `shift` (that point, to the metre; or the one given, shift_given: the
// stations of one survey share it), subtracted in double before the cast;
// its VIEWPOINT is moved too. Add `shift` back to what is found.
constexpr double kShiftBeyond = 1000.0;
struct CloudFrame {
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  bool shift_given = false;
  bool viewpoint_given = false;  // the header's VIEWPOINT is present and not the origin
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();  // the header's VIEWPOINT as read (double), before the shift
};
pcl::PointCloud<pcl::PointXYZ> readCloud(const std::string& path, CloudFrame* frame = nullptr);
// The same from `size` bytes in memory (a file's content); `name` stands for
// the path in error messages. Used by the fuzz target; nothing is copied.
pcl::PointCloud<pcl::PointXYZ> readCloudFromMemory(const void* data, std::size_t size,
                                                   const std::string& name = "<memory>");
// Upper bound on points accepted (default 50,000,000, the default of the
// parameter max_points; door_state_cli sets it from its parameters); a header
// asking more is refused, the message naming max_points.
void setMaxPoints(std::size_t n);
}}
