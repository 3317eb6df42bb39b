// Internal to recognition: findDoorways's search on one wall, its steps in
// the files named below, and what they share (the wall's evidence grid, the
// trim legs, the candidates found so far).
#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "door_state_recognition/pipeline/parameters.hpp"
#include "door_state_recognition/recognition/recognition.hpp"
#include "door_state_recognition/segmentation/segmentation.hpp"

namespace dsr {
namespace recognition {
namespace detail {

// Evidence counts of one cell of a wall's grid.
struct Cell {
  int face = 0, out = 0, through = 0, front = 0, recess = 0;  // out: face points standing out (trim)
  bool empty_in_view = false;  // no return at all, inside a camera frame's view: nothing there in range
};

struct DoorwaySearch {
  DoorwaySearch(const Points& points, const segmentation::WallPlane& wall, double floor_z, double top_z,
                const Eigen::Vector3f& viewpoint, const Parameters& p, bool no_return_is_free,
                const segmentation::ViewTop* view)
      : points(points), wall(wall), floor_z(floor_z), top_z(top_z), viewpoint(viewpoint), p(p),
        no_return_is_free(no_return_is_free), view(view) {}

  // The steps of findDoorways, in this order.
  bool buildGrid();              // doorway_grid.cpp: the evidence grid (false: no doorway on this wall)
  void findTrimLegs();           // doorway_trim.cpp: (1) trim legs paired under a head
  void findOpenings();           // doorway_openings.cpp: (2) openings
  void findSetBackLeaves();      // doorway_set_back.cpp: (3), (4), (4b) set-back panels and leaves
  void pairLegsUnderMeanHead();  // doorway_trim.cpp: (5) trim legs under a head seen in the mean
  void measureCandidates();      // doorway_candidates.cpp: shares, head and thickness of every candidate

  // findDoorways's arguments.
  const Points& points;
  const segmentation::WallPlane& wall;
  double floor_z, top_z;
  const Eigen::Vector3f& viewpoint;
  const Parameters& p;
  bool no_return_is_free;
  const segmentation::ViewTop* view;

  // The evidence grid (doorway_grid.cpp): cols x rows cells of cell x row_h
  // from s_lo along the wall and floor_z up, trim sought on sub sub-columns.
  double cell = 0, row_h = 0, s_lo = 0, s_hi = 0;
  int cols = 0, rows = 0, sub = 0;
  std::vector<Cell> grid;
  std::vector<int> face_d_out, face_d_n;
  std::vector<double> face_d_sum;
  double d_view = 0;
  int body0 = 0, body1 = 0, low1 = 0;
  static constexpr int kFine = 5;  // fine rows (1 cm) to a row of the grid, above the body
  int fine0 = 0, fine_n = 0;
  std::vector<std::pair<int, int>> head_fine;  // face, out
  std::vector<double> head_fine_d;
  std::vector<double> col_tol, col_sigma;
  std::vector<double> face_along;
  std::vector<std::pair<double, double>> behind_face;
  std::vector<double> face, expl, casing_share;
  // Per column over the body rows: cells seen (face or explained), and of
  // them seen through (no face; a ray past the plane, a reveal, or no return
  // inside a camera's view).
  std::vector<int> col_seen, col_through;
  double tolAt(double s) const;
  bool sampled(const Eigen::Vector3f& q, int c, int r) const;
  Eigen::Vector3f cellCentre(int c, int r) const;

  // Trim (doorway_trim.cpp).
  std::vector<double> quiet_sigma;
  bool significant(int c, double offset, int n) const;
  double half = 0;
  std::vector<std::pair<int, int>> legs;
  // The fine head cells of columns c0..c1 summed over the row of kFine fine
  // rows from w0: face points, those standing out, columns holding face
  // points, and (camera frames) the face points' summed offsets.
  struct HeadRow {
    int face = 0, out = 0, columns = 0;
    double offset = 0;
  };
  HeadRow headRow(int c0, int c1, int w0) const;
  int headState(double a, double b) const;
  bool hasHead(double a, double b) const;

  // The candidates (doorway_candidates.cpp).
  double colS(int c) const;
  double subS(int c) const;
  std::vector<Doorway> out;
  void addCandidate(double s0, double s1, bool casing);
};

}  // namespace detail
}  // namespace recognition
}  // namespace dsr
