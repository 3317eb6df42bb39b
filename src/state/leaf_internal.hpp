// Internal to the state stage: fitLeaf's search for a doorway's leaf, its
// steps in the files named below, and what they share (the points and rays
// near the doorway, the hypotheses' scores, the best leaf found).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <vector>

#include "door_state_recognition/pipeline/parameters.hpp"
#include "door_state_recognition/recognition/recognition.hpp"
#include "door_state_recognition/segmentation/segmentation.hpp"
#include "door_state_recognition/state/door_state.hpp"
#include "door_state_recognition/util/first_error.hpp"

namespace dsr {
namespace state {
namespace detail {

// f(0) ... f(n - 1) as OpenMP tasks: run by the threads of the enclosing
// parallel region as they come free (findDoors runs doorways over the cores,
// so one doorway's search is shared by a core left idle), or in turn outside
// one. The first exception thrown is rethrown here.
template <class F>
void forEachTask(std::size_t n, const F& f) {
  util::FirstError error;
#pragma omp taskloop grainsize(1) shared(error, f)
  for (long long i = 0; i < static_cast<long long>(n); ++i) error.run([&] { f(static_cast<std::size_t>(i)); });
  error.rethrow();
}

// A leaf's axes in wall coordinates (s along, d towards the viewer), swung
// by th (rad) from closed, its latch towards e0 (+1: +s) and opening to the
// side m (+1: the viewer's): e from the hinge to the latch, k square to it,
// away from the side the leaf opens to.
struct LeafAxes {
  Eigen::Vector2d e, k;
  LeafAxes(double th, double e0, double m)
      : e(std::cos(th) * e0, std::sin(th) * m), k(std::sin(th) * e0, -std::cos(th) * m) {}
};

// Where a sensor ray from v (height vz) along r (rising dz over its length)
// crosses the line P + a e of a leaf's mid-plane: a along the leaf and the
// height z; false when it does not, or only past lam_max of its length.
inline bool crossLeaf(const Eigen::Vector2d& v, const Eigen::Vector2d& r, double vz, double dz, double lam_max,
                      const Eigen::Vector2d& P, const Eigen::Vector2d& e, double& a, double& z) {
  const double denom = r.x() * e.y() - r.y() * e.x();
  if (std::abs(denom) < 1e-9) return false;
  const Eigen::Vector2d w = P - v;
  const double lam = (w.x() * e.y() - w.y() * e.x()) / denom;
  a = (w.x() * r.y() - w.y() * r.x()) / denom;
  if (lam <= 0 || lam > lam_max) return false;
  z = vz + lam * dz;
  return true;
}

struct Local {  // a point in wall coordinates: s along, d towards the viewer
  double s, d;
  int zbin, index;
};

struct LeafSearch {
  LeafSearch(const segmentation::Points& points, const segmentation::WallPlane& wall,
             const recognition::Doorway& door, double floor_z, double t, const Eigen::Vector3f& viewpoint,
             const Parameters& p, double closed_band_only_above, const segmentation::ViewTop* view)
      : points(points), wall(wall), door(door), floor_z(floor_z), t(t), viewpoint(viewpoint), p(p),
        closed_band_only_above(closed_band_only_above), view(view) {}

  // The steps of fitLeaf, in this order.
  void gather();          // leaf_gather.cpp: the doorway's frame, the points and rays near it
  bool bandEvidence();    // closed_leaf.cpp: a closed leaf's cells in the wall band, sampling (false: done)
  void searchHinges();    // leaf_search.cpp: the global and the local search of hinge, swing and angle
  void closedInBand();    // closed_leaf.cpp: a leaf closed in the wall band, its face and handle
  void measureLeaf();     // leaf_measure.cpp: the leaf's angle, hinge and coverage refined and judged
  void freeSpaceBound();  // leaf_free_space.cpp: no leaf seen, the least angle free space allows
  void placeLeaf();       // leaf_measure.cpp: occluders explained, hinge, direction and top

  // fitLeaf's arguments.
  const segmentation::Points& points;
  const segmentation::WallPlane& wall;
  const recognition::Doorway& door;
  double floor_z, t;
  const Eigen::Vector3f& viewpoint;
  const Parameters& p;
  double closed_band_only_above;
  const segmentation::ViewTop* view;
  LeafFit fit;

  // The doorway's frame and what lies near it (leaf_gather.cpp).
  double w = 0, L = 0, lt = 0, tol = 0, z0 = 0, z1 = 0, zbin = 0, abin = 0;
  int nz = 0;
  double s_mid = 0, reach = 0, Lmax = 0, reach_h = 0, reach_h2 = 0;
  bool withinReach(double x, double y) const;
  bool nearJamb(double s, double d) const;
  std::vector<Local> pts, band;
  static constexpr double kSideFrom = 0.15, kSideTo = 0.6;  // the wall's face beside the doorway (m beyond a jamb)
  int side_cols = 0;
  std::vector<char> side_cells;
  void gatherPoints();
  // Rays from the sensor that pass near the doorway: a leaf cannot stand
  // where a ray went through to something farther away (free space).
  // Every ray starts at the sensor, (s, d) = vsd at height vsz: a ray holds
  // only its end (the searches read every ray at every hinge; a compact ray
  // spares the memory traffic).
  struct Ray {
    Eigen::Vector2d q;  // (s, d) of the point
    double qz, len;
  };
  std::vector<Ray> rays;
  Eigen::Vector2d vsd = Eigen::Vector2d::Zero(), dc = Eigen::Vector2d::Zero();
  double vsz = 0;
  bool nearDoorway(const Eigen::Vector3f& q, Eigen::Vector2d& qsd, double& len2) const;
  static constexpr int kRayParts = 5;
  std::vector<std::vector<Ray>> ray_parts;
  void gatherRayPart(int k);
  void joinRays();
  bool rays_needed = false;

  // A closed leaf's evidence in the wall band (closed_leaf.cpp).
  std::vector<Eigen::Vector2d> band_xy;
  double band_cov = 0;

  // The hypotheses and their scores (leaf_scoring.cpp).
  int na = 0, na_max = 0, na_min = 0;
  struct Score {
    double score = -1e9;
    int cells = 0, contra = 0, bins = 0;
  };
  double band_hw = 0, r_pts = 0, r_rays = 0;
  std::size_t cells = 0;
  // One hinge over the angles start + i step (i < count): points first
  // (support), then rays (contradiction) at the angles still needed, then
  // the scores (an angle not needed scores -infinity).
  struct HingeRun {
    double s_h = 0, d_h = 0, e0 = 1, m = 1, start = 0, step = 1;
    int count = 0;
    std::vector<int> sup, con;  // per angle: leaf bin
    std::vector<Score> scores;
  };
  int bound(const HingeRun& w, int ai) const;
  void axes(const HingeRun& w, std::vector<Eigen::Vector2d>& E, std::vector<Eigen::Vector2d>& K,
            std::vector<Eigen::Vector2d>& P) const;
  template <class F>
  void forArc(const HingeRun& w, double inv_step, double lo, double hi, F&& f, int first = 0, int last = -1) const;
  void scorePoints(HingeRun& w) const;
  void markRays(const HingeRun& w, const std::vector<char>* need, std::size_t r0, std::size_t r1,
                std::vector<char>& blocked) const;
  void tallyRays(HingeRun& w, const std::vector<char>* need, const std::vector<char>& blocked) const;
  void scoreRays(HingeRun& w, const std::vector<char>* need) const;
  void finishScores(HingeRun& w, const std::vector<char>* need) const;
  void scoreShifts(std::vector<HingeRun>& ws, int reach, double s_center,
                   const std::vector<std::vector<char>>* need) const;

  // The search (leaf_search.cpp).
  double t_toward = 0;
  std::vector<double> recess_steps;
  struct Hinge {
    int h, sw;
    double rec;
    double out = 0;  // the hinge this far outwards of its jamb (away from the doorway)
  };
  int shadow_h = 0;
  std::vector<Hinge> hingesAt(double out) const;
  Score best;
  int best_h = 0, best_sw = 0;
  double best_deg = 0, best_recess = 0, best_s = 0;
  void globalSearch(const std::vector<Hinge>& hinges, double lower);
  int best_support = 0, best_contra = 0, best_bins = 0;

  // A leaf closed in the band (closed_leaf.cpp).
  double band_angle = 0, gen_cov = 0, gen_contra = 0;
  bool closed_band = false;
  double band_face = 0;

  // The leaf measured (leaf_measure.cpp).
  // A leaf seen by the sensor has free space before it, on the sensor's
  // side: a plane fitted through a volume (a bookcase's or an open
  // cupboard's contents, a shelf unit) has as many points just before it as
  // in it. crowdBefore: the points within kCrowdSlab (m) past the leaf's
  // band on the sensor's side, over its length less kCrowdFromHinge at the
  // hinge and kCrowdToTip at the tip, per point in its band. A leaf above
  // kCrowdFromDeg at kCrowdShare or more is no leaf; below, the jamb
  // and the trim at the latch stand before a leaf ajar.
  static constexpr double kCrowdSlab = 0.1, kCrowdFromHinge = 0.1, kCrowdToTip = 0.05;
  static constexpr double kCrowdFromDeg = 30, kCrowdShare = 0.5;
  double crowdBefore(double angle_deg, double len) const;
  // A leaf is as wide as its doorway. An open leaf measured shorter than
  // kRestFromShare of a doorway framed by trim, whose rest (from
  // kRestMargin past its measured tip to the doorway's width, at the same
  // hinge and angle) rays went through in kRestSeenThrough of its cells or
  // more, is no leaf but something shorter standing at the jamb: a
  // cupboard's side, seen past (LeafFit::rest_seen_through). A leaf seen in
  // part is hidden in the rest (behind its jamb, furniture, the view's edge).
  // Over the tuning sweeps (merged, mesh-like, single laser scans) such
  // "leaves" had 0.40-0.99 of their rest seen through, true leaves at most 0.10.
  static constexpr double kRestFromShare = 0.65, kRestMargin = 0.1, kRestSeenThrough = 0.3;
  double restSeenThrough(double angle_deg, double len, double span) const;
  // An open leaf stands clear of its doorway's passage: before its tip, on
  // the side it opens to, the way through runs. A cupboard's or wardrobe's
  // side taken for a leaf at about 90 deg, the wall hidden behind the
  // cupboard taken for its doorway, has the cupboard's front there. A leaf
  // between kTipFrontFromDeg and kTipFrontToDeg is no leaf where kTipFront
  // or more of the cells of a strip 5-45 cm long from its tip, across that
  // side, hold points (LeafFit::front_at_tip; lidar64 drives 1040 and 1077:
  // 0.17-0.26 at the wardrobes).
  static constexpr double kTipFront = 0.1, kTipFrontFromDeg = 60, kTipFrontToDeg = 120;
  double frontAtTip(double angle_deg, double len) const;
  double s_h = 0, s_other = 0, e0 = 0, m = 0, d_h = 0;
  Eigen::Vector2d toXY(double s, double d) const;
};

}  // namespace detail
}  // namespace state
}  // namespace dsr
