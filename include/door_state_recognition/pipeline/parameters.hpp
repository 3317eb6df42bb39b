// Every parameter of the pipeline, with its default. The same defaults are
// written, with unit and range, in config/default.yaml. ROS-free.
#pragma once

#include <string>
#include <vector>

namespace dsr {

struct Parameters {
  // --- levelling ---------------------------------------------------------
  std::string up_axis = "+z";        // +x -x +y -y +z -z or auto
  double refine_up_deg = 25.0;       // deg, a given axis is refined from the floor or walls within this (a robot camera pitched to 20 deg, rolled 5); 0: taken as exact
  // --- preprocessing -----------------------------------------------------
  double voxel_size = 0.02;          // m, 0 disables downsampling
  double max_abs_coordinate = 1e4;   // m, points farther out are dropped as garbage
  int max_points = 50000000;         // clouds larger than this are refused
  // --- floor and ceiling (height histogram) -------------------------------
  double histogram_bin = 0.02;       // m
  double horizontal_normal_z = 0.9;  // |n_z| above which a point is on a horizontal surface
  double min_room_height = 1.8;      // m, floor-to-ceiling below this is not a room
  // --- normals -------------------------------------------------------------
  int normal_k = 16;                 // neighbours for PCA normals and curvature
  // --- walls (RANSAC of vertical planes) -------------------------------------
  double vertical_normal_z = 0.25;   // |n_z| below which a point is on a vertical surface
  double wall_distance = 0.03;       // m, RANSAC inlier distance
  double wall_normal_agreement = 0.9;// |n_i . n_wall| for an inlier
  int ransac_iterations = 300;
  int min_wall_points = 300;
  double min_wall_length = 0.8;      // m
  double wall_height_ratio = 0.75;   // walls span at least this share of the room height
  double wall_gap = 1.6;             // m, a wall's inliers split at gaps wider than this
  int max_walls = 16;
  // --- region growing -------------------------------------------------------
  double region_angle_deg = 8.0;     // normal angle between neighbours of a region
  double region_curvature = 0.05;    // seeds and growth stop at higher curvature
  int min_region_points = 50;
  // --- doors ----------------------------------------------------------------
  double door_min_width = 0.6;       // m
  double door_max_width = 1.4;       // m
  double door_min_height = 1.7;      // m
  double door_height_ratio = 0.75;   // the paper's rule: door height >= ratio * wall height - phi
  double door_height_phi = 0.5;      // m, the paper allows 0..0.5
  double grid_cell = 0.04;           // m, cell of a wall's evidence grid (along the wall); trim is sought at half of it
  double face_tolerance = 0.03;      // m, a point this close to a wall plane lies on its face
  double casing_min_offset = 0.008;  // m, trim stands at least this far out of the wall face
  double default_wall_thickness = 0.15;  // m, when the jambs are not seen
  double leaf_thickness = 0.04;      // m
  double leaf_tolerance = 0.025;     // m, inlier band around a leaf hypothesis
  double min_leaf_coverage = 0.35;   // share of a leaf's cells that must hold points
  double boundary_angle_deg = 90.0;  // angular gap that makes a boundary point
  int boundary_k = 16;
  // --- states -----------------------------------------------------------------
  double closed_below_deg = 5.0;     // closed: angle < this
  double open_from_deg = 90.0;       // open: angle >= this; semi-open in between
  // A doorway seen through whose leaf is out of sight is a door when free
  // space bounds its opening angle from below at this or more (reported with
  // the bound as its angle, angle_is_lower_bound; state NOT_CLOSED below
  // open_from_deg, OPEN from it). Taken as at least closed_below_deg.
  // 5 (closed_below_deg, the default): every such door, which is surely not
  // closed (issue 20's decision); 90: only doors sure to be open.
  double unseen_leaf_min_bound_deg = 5.0;
  // --- reconstruction ---------------------------------------------------------
  double reconstruction_spacing = 0.02;  // m between up-sampled points
  // --- misc -------------------------------------------------------------------
  int random_seed = 1;               // RANSAC seed (results are deterministic)

  // Throws std::invalid_argument naming the first parameter out of range.
  void validate() const;
};

// Reads a YAML file of `name: value` pairs (unknown names are an error) over
// the defaults. Throws std::invalid_argument with the file and the key.
Parameters loadParameters(const std::string& yaml_path, Parameters base = Parameters());

// The same from YAML text (`source` names it in errors), e.g. built from ROS
// parameters or a dynamic_reconfigure request.
Parameters parseParameters(const std::string& yaml_text, Parameters base, const std::string& source);

// Every parameter as YAML `name: value`, sorted by name.
std::string dumpParameters(const Parameters& p);

// The names of every parameter, sorted.
std::vector<std::string> parameterNames();

}  // namespace dsr
