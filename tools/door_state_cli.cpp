// door_state_cli: runs the door-state pipeline on a PCD, PLY, OBJ or text file and
// writes the report JSON.
#include <pcl/io/ply_io.h>

#include <algorithm>
#include <cctype>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "cli_args.hpp"
#include "door_state_recognition/io/cloud_reader.hpp"
#include "door_state_recognition/io/report.hpp"
#include "door_state_recognition/io/svg.hpp"
#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/pipeline/viewpoint_choice.hpp"
#include "door_state_recognition/util/keep_freed_memory.hpp"
#include "door_state_recognition/util/omp_spin.hpp"

namespace {

const char* kUsage = R"(usage: door_state_cli [--config FILE.yaml] [--up +z|-z|+y|-y|+x|-x|auto]
                      [--viewpoint auto|header|none|X,Y,Z] [--json OUT.json]
                      [--reconstruction OUT.ply] [--svg OUT.svg] [--quiet] [--verbose]
                      INPUT [INPUT...]

Finds the walls and doors in a point cloud and tells every door's state
(closed, semi_open, open; not_closed where the doorway is seen through but
its leaf is not) and opening angle. INPUT is a PCD (ascii, binary,
binary_compressed) or PLY (ascii, binary) file with at least x, y, z, an
OBJ mesh (its vertices), or a text file with x y z first on each line
(S3DIS, .xyz, .pts). The
report (JSON, input frame, metres and degrees) goes to stdout, or to --json.

Free space is told by rays from where the sensor stood (--viewpoint). By
default (auto) that is the PCD header's VIEWPOINT (the origin where there is
none, and for a PLY) when it is credible for the cloud: an organized cloud
whose pixels' rays meet there (one moved out of its sensor's frame is seen
from where they do meet), or one in which almost no point lies behind
another surface seen from there, as for one sensor's scan. A registered
room, stations merged into one cloud, a map or a mesh export is not: its
stations are then inferred from the cloud's own surfaces (positions from
which they are seen) and run as a survey. The report's "viewpoint" says which was used ([x, y, z], or null
with the inferred "stations"), and "warnings" why.

Several INPUTs are the stations of one survey: scans from several scanner
positions, registered into one frame, each a PCD whose VIEWPOINT header says
where its scanner stood in that frame (a PLY has none: its station is taken
at the origin). Each station is run alone, with rays from its own position,
and the results merged: walls on one line joined, each door reported once,
from the station that saw its leaf best. "input" in the report lists them
joined by commas. With auto, a station whose VIEWPOINT is not credible makes
the inputs one cloud without a viewpoint.

  --config FILE.yaml       parameters over the defaults (config/default.yaml lists them)
  --up AXIS                the cloud's up axis, or auto to estimate it (default +z;
                           -y for a camera optical frame)
  --viewpoint WHERE        auto (default): the header's VIEWPOINT when credible, else none;
                           header: each INPUT's VIEWPOINT as given; none: no viewpoint
                           (stations inferred from the surfaces); X,Y,Z: the sensor's
                           position in the cloud's frame (metres, one INPUT only)
  --json OUT.json          write the report there instead of stdout
  --reconstruction OUT.ply walls rebuilt with their doorways and leaves (label 1 wall, 2 leaf);
                           with no wall found, a valid PLY of 0 points
  --svg OUT.svg            a plan (top view, metres, scale bar): points as grey density,
                           walls, doorways, each leaf at its angle with its swing arc,
                           coloured by state (a lower bound dashed), labelled
  --quiet                  no progress or timings on stderr
  --verbose                also every wall and doorway candidate with the decision on it
  -h, --help               this text

Every output is opened before any INPUT is read: one that cannot be written
is refused at once, as is one that names an INPUT or another output, and a
--json or --svg path ending in .pcd or .ply (a file name forgotten before a
glob). INPUT must be a file ('-', stdin, is refused).

exit status: 0 report written (zero doors included; the reconstruction, if
asked, is written before it); 2 bad arguments (the message and this usage on
stderr), or an output that cannot be opened, or an unreadable or malformed
input (one line on stderr); 1 anything else (no report written).
)";

using dsr::tools::UsageError;

// An output file that cannot be opened for writing: exit 2, before any input is read.
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// An output path checked before the pipeline runs: opened for writing
// (created if missing, not truncated, so a refused run leaves an existing file
// as it was); a file this run created is removed again if no report is written.
struct Output {
  std::string path;
  bool created = false;
  bool done = false;
  Output(const std::string& flag, const std::string& p) : path(p) {
    if (p.empty()) return;
    const int fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      created = true;
    } else if (errno == EEXIST) {
      const int fd2 = ::open(p.c_str(), O_WRONLY | O_CLOEXEC);
      if (fd2 < 0) throw OutputError(flag + " " + p + ": cannot write: " + std::strerror(errno));
      ::close(fd2);
      return;
    } else {
      throw OutputError(flag + " " + p + ": cannot write: " + std::strerror(errno));
    }
    ::close(fd);
  }
  ~Output() {
    if (created && !done) std::remove(path.c_str());
  }
};

// Two paths naming one file: the same inode where both exist, else the same text.
bool samePath(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  if (::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  return a == b;
}

// The reconstruction, or with nothing reconstructed a valid PLY of 0 points
// (PCL refuses to write an empty cloud) so no earlier file is left behind.
void writeReconstruction(const std::string& path, const pcl::PointCloud<pcl::PointXYZL>& cloud) {
  if (!cloud.empty()) {
    if (pcl::io::savePLYFileBinary(path, cloud) != 0) throw std::runtime_error("cannot write " + path);
    return;
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << "ply\nformat binary_little_endian 1.0\ncomment door_state_cli: no wall found, nothing reconstructed\n"
         "element vertex 0\nproperty float x\nproperty float y\nproperty float z\nproperty uint label\nend_header\n";
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
}

}  // namespace

int main(int argc, char** argv) {
  dsr::util::shortOmpSpin(argv);  // before anything else: the program may be run again
  dsr::util::keepFreedMemory();   // the stations of a survey, one after another
  std::string config, up, json_out, recon_out, svg_out, viewpoint_arg = "auto";
  std::optional<Eigen::Vector3d> viewpoint_xyz;
  std::vector<std::string> inputs;
  bool quiet = false, verbose = false;
  // An option given twice: which one was meant? (the last silently won)
  auto once = [](const std::string& flag, const std::string& before, const std::string& now) {
    if (!before.empty()) throw UsageError(flag + " given twice ('" + before + "', '" + now + "')");
    return now;
  };
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&] { return dsr::tools::nextValue(argc, argv, i); };
      if (a == "-h" || a == "--help") {
        std::cout << kUsage;
        return 0;
      } else if (a == "--config") config = once(a, config, value());
      else if (a == "--up") {
        up = once(a, up, value());
        static const char* kAxes[] = {"+z", "-z", "+y", "-y", "+x", "-x", "auto"};
        if (std::none_of(std::begin(kAxes), std::end(kAxes), [&](const char* x) { return up == x; }))
          throw UsageError("--up needs an axis (+z, -z, +y, -y, +x, -x or auto), got '" + up + "'");
      }
      else if (a == "--viewpoint") {
        viewpoint_arg = value();
        if (viewpoint_arg != "auto" && viewpoint_arg != "header" && viewpoint_arg != "none") {
          double xyz[3];
          dsr::tools::toXYZ("--viewpoint", viewpoint_arg, "auto, header, none or X,Y,Z (three numbers)", xyz);
          viewpoint_xyz = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
        }
      }
      else if (a == "--json") json_out = once(a, json_out, value());
      else if (a == "--reconstruction") recon_out = once(a, recon_out, value());
      else if (a == "--svg") svg_out = once(a, svg_out, value());
      else if (a == "--quiet") quiet = true;
      else if (a == "--verbose") verbose = true;
      else if (a == "-") throw UsageError("INPUT '-': reading a cloud from stdin is not supported; give a file");
      else if (!a.empty() && a[0] == '-') throw UsageError("unknown option '" + a + "'");
      else inputs.push_back(a);
    }
    if (inputs.empty()) throw UsageError("INPUT is missing");
    // One file given twice is no survey of two stations (a shell glob and a name).
    for (std::size_t k = 0; k < inputs.size(); ++k)
      for (std::size_t j = 0; j < k; ++j)
        if (samePath(inputs[k], inputs[j])) throw UsageError("INPUT " + inputs[k] + " is given twice");
    if (viewpoint_xyz && inputs.size() > 1)
      throw UsageError("--viewpoint X,Y,Z is one position: with several INPUTs give auto, header or none");
    // An output that is an INPUT or another output would destroy the scan
    // (`--svg` with its name forgotten takes the first INPUT) or one report.
    const std::vector<std::pair<std::string, std::string>> outputs = {
        {"--json", json_out}, {"--reconstruction", recon_out}, {"--svg", svg_out}};
    for (std::size_t k = 0; k < outputs.size(); ++k) {
      const auto& [flag, path] = outputs[k];
      if (path.empty()) continue;
      // A report or a plan never goes to a cloud's name: a shell glob after
      // a flag whose file name was forgotten hands it the first scan.
      std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
      for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      if (flag != "--reconstruction" && (ext == ".pcd" || ext == ".ply"))
        throw UsageError(flag + " " + path + " names a point cloud: it would be overwritten (did " + flag +
                         " lose its file name?)");
      for (const std::string& input : inputs)
        if (samePath(path, input))
          throw UsageError(flag + " " + path + " is also an INPUT: it would be overwritten (did " + flag +
                           " lose its file name?)");
      for (std::size_t j = 0; j < k; ++j)
        if (!outputs[j].second.empty() && samePath(path, outputs[j].second))
          throw UsageError(flag + " and " + outputs[j].first + " name the same file " + path);
    }
  } catch (const UsageError& e) {
    std::cerr << "door_state_cli: " << e.what() << "\n\n" << kUsage;
    return 2;
  }

  try {
    dsr::Parameters params = config.empty() ? dsr::Parameters() : dsr::loadParameters(config);
    if (!up.empty()) params.up_axis = up;
    const dsr::Pipeline pipeline(params);  // validates
    // The configured limit applies to reading too: a header asking more is refused unread.
    dsr::io::setMaxPoints(static_cast<std::size_t>(params.max_points));
    // Both outputs opened before anything is read: a bad path costs no pipeline run.
    Output json_file("--json", json_out), recon_file("--reconstruction", recon_out), svg_file("--svg", svg_out);
    const auto t0 = std::chrono::steady_clock::now();
    // Every input read before anything is said: a bad one is one line on stderr.
    std::vector<pcl::PointCloud<pcl::PointXYZ>> clouds;
    std::vector<double> read_each_ms;
    std::size_t total = 0;
    // A georeferenced cloud is read moved near its points (CloudFrame); the
    // stations of a survey share the first one's shift.
    std::vector<dsr::io::CloudFrame> frames;
    for (const std::string& input : inputs) {
      const auto t_read = std::chrono::steady_clock::now();
      frames.emplace_back();
      if (frames.size() > 1) frames.back().shift = frames.front().shift, frames.back().shift_given = true;
      clouds.push_back(dsr::io::readCloud(input, &frames.back()));
      // Stations above max_points in all are refused before the next is read.
      total += clouds.back().size();
      if (total > static_cast<std::size_t>(params.max_points))
        throw std::invalid_argument("inputs up to " + input + " hold " + std::to_string(total) +
                                    " points, above max_points (" + std::to_string(params.max_points) + ")");
      read_each_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_read).count());
    }
    const double read_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    // Each INPUT seen from its VIEWPOINT, from --viewpoint X,Y,Z, or from
    // no known position (dsr::sight::chooseViewpoints says which and why).
    std::string input = inputs[0];
    for (std::size_t k = 1; k < inputs.size(); ++k) input += "," + inputs[k];
    const Eigen::Vector3d shift = frames.front().shift;
    std::vector<std::string> sight_notes;
    if (!shift.isZero()) {
      char at[160];
      std::snprintf(at, sizeof at, "(%.0f, %.0f, %.0f)", shift.x(), shift.y(), shift.z());
      sight_notes.push_back(std::string("coordinates lie far from their origin: read moved by -") + at +
                            " (in double, kept to the millimetre); the report is in the input's frame, " +
                            "the --reconstruction and --svg in that moved frame");
    }
    std::vector<dsr::sight::InputCloud> input_clouds;
    for (std::size_t k = 0; k < clouds.size(); ++k) input_clouds.push_back({&clouds[k], inputs[k], frames[k].viewpoint_given});
    const dsr::sight::ViewpointMode mode = viewpoint_xyz             ? dsr::sight::ViewpointMode::Given
                                           : viewpoint_arg == "none"   ? dsr::sight::ViewpointMode::None
                                           : viewpoint_arg == "header" ? dsr::sight::ViewpointMode::Header
                                                                       : dsr::sight::ViewpointMode::Auto;
    dsr::sight::ViewpointChoice choice;
    dsr::sight::chooseViewpoints(input_clouds, mode, viewpoint_xyz, shift, params, choice);
    sight_notes.insert(sight_notes.end(), choice.notes.begin(), choice.notes.end());
    const std::vector<dsr::Station>& stations = choice.stations;
    const bool without_viewpoint = choice.without_viewpoint;
    if (!quiet) {
      for (std::size_t k = 0; k < clouds.size(); ++k)
        std::cerr << "door_state_cli: read " << clouds[k].size() << " points from " << inputs[k] << " in "
                  << read_each_ms[k] << " ms\n";
      for (std::size_t k = 0; k < stations.size() && !without_viewpoint; ++k) {
        const Eigen::Vector3d& vp = stations[k].viewpoint;
        if (stations.size() > 1 || !vp.isZero())
          std::cerr << "door_state_cli: station " << k << " at (" << vp.x() << ", " << vp.y() << ", " << vp.z() << ")\n";
      }
      for (const std::string& t : choice.taken) std::cerr << "door_state_cli: " << t << "\n";
    }
    dsr::PipelineResult result = without_viewpoint ? pipeline.runWithoutViewpoint(*stations[0].cloud, !recon_out.empty())
                                                   : pipeline.runStations(stations, !recon_out.empty());
    result.warnings.insert(result.warnings.begin(), sight_notes.begin(), sight_notes.end());
    nlohmann::json report;
    if (shift.isZero()) {
      report = dsr::io::reportJson(result, input);
    } else {  // in the input's frame; the plan and the reconstruction stay in the moved one
      dsr::PipelineResult shown = result;
      dsr::translate(shown, shift);
      report = dsr::io::reportJson(shown, input);
    }
    report["timing_ms"]["read"] = read_ms;
    // The reconstruction before the report: exit 0 always means both were written.
    if (!recon_out.empty()) {
      if (result.reconstruction.empty() && !quiet)
        std::cerr << "door_state_cli: no wall to reconstruct, " << recon_out << " holds 0 points\n";
      writeReconstruction(recon_out, result.reconstruction);
      recon_file.done = true;
    }
    if (!svg_out.empty()) {  // the plan, before the report too
      dsr::io::PlanOptions plan;
      plan.title = input;
      std::vector<const pcl::PointCloud<pcl::PointXYZ>*> plan_clouds;
      for (const dsr::Station& st : stations) plan_clouds.push_back(st.cloud), plan.viewpoints.push_back(st.viewpoint);
      dsr::io::writePlanSvg(svg_out, result, plan_clouds, plan);
      svg_file.done = true;
    }
    if (json_out.empty()) {
      std::cout << report.dump(2) << "\n";
    } else {
      std::ofstream out(json_out, std::ios::trunc);
      out << report.dump(2) << "\n";
      out.close();
      if (!out) throw std::runtime_error("cannot write " + json_out + ": " + std::strerror(errno));
      json_file.done = true;
    }
    if (!quiet) {
      for (const auto& w : result.warnings) std::cerr << "door_state_cli: warning: " << w << "\n";
      if (verbose)
        for (const auto& t : result.trace) std::cerr << "door_state_cli: " << t << "\n";
      std::cerr << "door_state_cli: " << result.walls.size() << " wall(s), " << result.doors.size() << " door(s)";
      for (const auto& d : result.doors)
      {  // a tenth of a degree: rounding to whole ones put 89.8 (semi-open) at open's 90
        char angle[32];
        std::snprintf(angle, sizeof angle, "%.1f", d.opening_angle_deg);
        std::cerr << "; door " << d.id << " " << dsr::toString(d.state) << " " << angle << " deg";
      }
      std::cerr << "\ndoor_state_cli: timings (ms):";
      for (const auto& kv : result.timing_ms) std::cerr << " " << kv.first << " " << static_cast<int>(kv.second + 0.5);
      std::cerr << "\n";
    }
  } catch (const OutputError& e) {
    std::cerr << "door_state_cli: " << e.what() << "\n";
    return 2;
  } catch (const dsr::io::CloudReadError& e) {
    std::cerr << "door_state_cli: " << e.what() << "\n";
    return 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << "door_state_cli: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "door_state_cli: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
