#include "door_state_recognition/pipeline/parameters.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <type_traits>

namespace dsr {
namespace {

// One table of name -> (reader, range check) so YAML, validation and the
// documentation can't drift apart.
struct Field {
  std::function<void(Parameters&, const YAML::Node&)> read;
  std::function<void(const Parameters&, YAML::Emitter&)> write;
};

// An integer parameter also takes a number written with a fraction or an
// exponent when its value is integral and fits (5e8, 16.0); 1.5 stays a
// wrong type. Other types read as YAML reads them.
template <typename T>
T readValue(const YAML::Node& n) {
  if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    try {
      return n.as<T>();
    } catch (const YAML::Exception&) {
      const double d = n.as<double>();  // throws on a non-number
      if (!std::isfinite(d) || d != std::trunc(d) || d < double(std::numeric_limits<T>::min()) ||
          d > double(std::numeric_limits<T>::max()))
        throw std::invalid_argument("not an integer");
      return static_cast<T>(d);
    }
  } else {
    return n.as<T>();
  }
}

template <typename T>
Field field(T Parameters::*member) {
  return {[member](Parameters& p, const YAML::Node& n) { p.*member = readValue<T>(n); },
          [member](const Parameters& p, YAML::Emitter& e) { e << p.*member; }};
}

const std::map<std::string, Field>& fields() {
  static const std::map<std::string, Field> f = {
      {"up_axis", field(&Parameters::up_axis)},
      {"refine_up_deg", field(&Parameters::refine_up_deg)},
      {"voxel_size", field(&Parameters::voxel_size)},
      {"max_abs_coordinate", field(&Parameters::max_abs_coordinate)},
      {"max_points", field(&Parameters::max_points)},
      {"histogram_bin", field(&Parameters::histogram_bin)},
      {"horizontal_normal_z", field(&Parameters::horizontal_normal_z)},
      {"min_room_height", field(&Parameters::min_room_height)},
      {"normal_k", field(&Parameters::normal_k)},
      {"vertical_normal_z", field(&Parameters::vertical_normal_z)},
      {"wall_distance", field(&Parameters::wall_distance)},
      {"wall_normal_agreement", field(&Parameters::wall_normal_agreement)},
      {"ransac_iterations", field(&Parameters::ransac_iterations)},
      {"min_wall_points", field(&Parameters::min_wall_points)},
      {"min_wall_length", field(&Parameters::min_wall_length)},
      {"wall_height_ratio", field(&Parameters::wall_height_ratio)},
      {"wall_gap", field(&Parameters::wall_gap)},
      {"max_walls", field(&Parameters::max_walls)},
      {"region_angle_deg", field(&Parameters::region_angle_deg)},
      {"region_curvature", field(&Parameters::region_curvature)},
      {"min_region_points", field(&Parameters::min_region_points)},
      {"door_min_width", field(&Parameters::door_min_width)},
      {"door_max_width", field(&Parameters::door_max_width)},
      {"door_min_height", field(&Parameters::door_min_height)},
      {"door_height_ratio", field(&Parameters::door_height_ratio)},
      {"door_height_phi", field(&Parameters::door_height_phi)},
      {"grid_cell", field(&Parameters::grid_cell)},
      {"face_tolerance", field(&Parameters::face_tolerance)},
      {"casing_min_offset", field(&Parameters::casing_min_offset)},
      {"default_wall_thickness", field(&Parameters::default_wall_thickness)},
      {"leaf_thickness", field(&Parameters::leaf_thickness)},
      {"leaf_tolerance", field(&Parameters::leaf_tolerance)},
      {"min_leaf_coverage", field(&Parameters::min_leaf_coverage)},
      {"boundary_angle_deg", field(&Parameters::boundary_angle_deg)},
      {"boundary_k", field(&Parameters::boundary_k)},
      {"closed_below_deg", field(&Parameters::closed_below_deg)},
      {"open_from_deg", field(&Parameters::open_from_deg)},
      {"unseen_leaf_min_bound_deg", field(&Parameters::unseen_leaf_min_bound_deg)},
      {"reconstruction_spacing", field(&Parameters::reconstruction_spacing)},
      {"random_seed", field(&Parameters::random_seed)},
  };
  return f;
}

void check(bool ok, const std::string& name, const std::string& range) {
  if (!ok) throw std::invalid_argument("parameter " + name + " out of range: must be " + range);
}

bool in(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

// Parameters from a parsed YAML map over `p`; `path` names the source in errors.
Parameters fromNode(const YAML::Node& root, Parameters p, const std::string& path);

}  // namespace

void Parameters::validate() const {
  static const char* axes[] = {"+x", "-x", "+y", "-y", "+z", "-z", "auto"};
  bool axis_ok = false;
  for (const char* a : axes) axis_ok |= up_axis == a;
  check(axis_ok, "up_axis", "one of +x -x +y -y +z -z auto");
  check(in(refine_up_deg, 0, 45), "refine_up_deg", "in [0, 45] deg");
  check(voxel_size == 0 || in(voxel_size, 0.001, 1.0), "voxel_size", "0 or in [0.001, 1] m");
  check(in(max_abs_coordinate, 1, 1e7), "max_abs_coordinate", "in [1, 1e7] m");
  check(max_points >= 10 && max_points <= 500000000, "max_points", "in [10, 5e8]");
  check(in(histogram_bin, 0.001, 0.5), "histogram_bin", "in [0.001, 0.5] m");
  check(in(horizontal_normal_z, 0.5, 1.0), "horizontal_normal_z", "in [0.5, 1]");
  check(in(min_room_height, 0.5, 20), "min_room_height", "in [0.5, 20] m");
  check(normal_k >= 5 && normal_k <= 200, "normal_k", "in [5, 200]");
  check(in(vertical_normal_z, 0.0, 0.7), "vertical_normal_z", "in [0, 0.7]");
  check(in(wall_distance, 0.002, 0.5), "wall_distance", "in [0.002, 0.5] m");
  check(in(wall_normal_agreement, 0.0, 1.0), "wall_normal_agreement", "in [0, 1]");
  check(ransac_iterations >= 1 && ransac_iterations <= 100000, "ransac_iterations", "in [1, 100000]");
  check(min_wall_points >= 3 && min_wall_points <= 10000000, "min_wall_points", "in [3, 1e7]");
  check(in(min_wall_length, 0.05, 100), "min_wall_length", "in [0.05, 100] m");
  check(in(wall_height_ratio, 0.0, 1.0), "wall_height_ratio", "in [0, 1]");
  check(in(wall_gap, 0.05, 100), "wall_gap", "in [0.05, 100] m");
  check(max_walls >= 1 && max_walls <= 1000, "max_walls", "in [1, 1000]");
  check(in(region_angle_deg, 0.1, 90), "region_angle_deg", "in [0.1, 90] deg");
  check(in(region_curvature, 0.0, 1.0), "region_curvature", "in [0, 1]");
  check(min_region_points >= 3 && min_region_points <= 1000000, "min_region_points", "in [3, 1000000]");
  check(in(door_min_width, 0.1, 5) && in(door_max_width, door_min_width, 10), "door_min_width/door_max_width",
        "0.1 <= min <= max <= 10 m");
  check(in(door_min_height, 0.5, 5), "door_min_height", "in [0.5, 5] m");
  check(in(door_height_ratio, 0.0, 1.0), "door_height_ratio", "in [0, 1]");
  check(in(door_height_phi, 0.0, 0.5), "door_height_phi", "in [0, 0.5] m (the paper's phi)");
  check(in(grid_cell, 0.005, 0.5), "grid_cell", "in [0.005, 0.5] m");
  check(in(face_tolerance, 0.002, 0.3), "face_tolerance", "in [0.002, 0.3] m");
  check(in(casing_min_offset, 0.0, 0.2), "casing_min_offset", "in [0, 0.2] m");
  check(in(default_wall_thickness, 0.02, 1.0), "default_wall_thickness", "in [0.02, 1] m");
  check(in(leaf_thickness, 0.005, 0.3), "leaf_thickness", "in [0.005, 0.3] m");
  check(in(leaf_tolerance, 0.002, 0.3), "leaf_tolerance", "in [0.002, 0.3] m");
  check(in(min_leaf_coverage, 0.0, 1.0), "min_leaf_coverage", "in [0, 1]");
  check(in(boundary_angle_deg, 10, 350), "boundary_angle_deg", "in [10, 350] deg");
  check(boundary_k >= 4 && boundary_k <= 200, "boundary_k", "in [4, 200]");
  check(in(closed_below_deg, 0, 90) && in(open_from_deg, closed_below_deg, 180), "closed_below_deg/open_from_deg",
        "0 <= closed_below <= open_from <= 180 deg");
  check(in(unseen_leaf_min_bound_deg, 0, 180), "unseen_leaf_min_bound_deg", "in [0, 180] deg");
  check(in(reconstruction_spacing, 0.002, 1.0), "reconstruction_spacing", "in [0.002, 1] m");
  check(random_seed >= 0 && random_seed <= 1000000, "random_seed", "in [0, 1000000]");
}

std::string dumpParameters(const Parameters& p) {
  YAML::Emitter e;
  e.SetDoublePrecision(10);
  e << YAML::BeginMap;
  for (const auto& kv : fields()) {
    e << YAML::Key << kv.first << YAML::Value;
    kv.second.write(p, e);
  }
  e << YAML::EndMap;
  return e.c_str();
}

std::vector<std::string> parameterNames() {
  std::vector<std::string> names;
  for (const auto& kv : fields()) names.push_back(kv.first);
  return names;
}

Parameters parseParameters(const std::string& yaml_text, Parameters base, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const std::exception& e) {
    throw std::invalid_argument(source + ": cannot read YAML: " + e.what());
  }
  return fromNode(root, base, source);
}

Parameters loadParameters(const std::string& path, Parameters p) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const std::exception& e) {
    throw std::invalid_argument(path + ": cannot read YAML: " + e.what());
  }
  return fromNode(root, p, path);
}

namespace {

Parameters fromNode(const YAML::Node& root, Parameters p, const std::string& path) {
  if (!root || root.IsNull()) return p;
  if (!root.IsMap()) throw std::invalid_argument(path + ": expected a map of parameter: value");
  std::set<std::string> given;
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    const auto it = fields().find(key);
    if (it == fields().end()) throw std::invalid_argument(path + ": unknown parameter '" + key + "'");
    // Two values for one parameter: which was meant is not for us to guess.
    if (!given.insert(key).second) throw std::invalid_argument(path + ": parameter '" + key + "' is given twice");
    try {
      it->second.read(p, kv.second);
    } catch (const std::exception&) {
      throw std::invalid_argument(path + ": parameter '" + key + "' has a value of the wrong type");
    }
  }
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  return p;
}

}  // namespace

}  // namespace dsr
