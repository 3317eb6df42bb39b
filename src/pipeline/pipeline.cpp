#include "door_state_recognition/pipeline/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <cmath>
#include <stdexcept>

#include "door_state_recognition/preprocess/preprocess.hpp"
#include "door_state_recognition/reconstruction/reconstruction.hpp"
#include "door_state_recognition/recognition/recognition.hpp"
#include "door_state_recognition/segmentation/segmentation.hpp"
#include "door_state_recognition/state/door_state.hpp"

namespace dsr {

const char* toString(DoorStateKind s) {
  switch (s) {
    case DoorStateKind::Closed: return "closed";
    case DoorStateKind::SemiOpen: return "semi_open";
    case DoorStateKind::Open: return "open";
  }
  return "closed";
}

const char* toString(Swing s) {
  switch (s) {
    case Swing::TowardViewer: return "toward_viewer";
    case Swing::AwayFromViewer: return "away_from_viewer";
    case Swing::Unknown: return "unknown";
  }
  return "unknown";
}

Pipeline::Pipeline(const Parameters& parameters) : params_(parameters) { params_.validate(); }

namespace {

using Clock = std::chrono::steady_clock;

struct Stopwatch {
  Clock::time_point start = Clock::now(), lap = start;
  std::vector<std::pair<std::string, double>>* out;
  explicit Stopwatch(std::vector<std::pair<std::string, double>>* o) : out(o) {}
  void mark(const std::string& stage) {
    const auto now = Clock::now();
    out->push_back({stage, std::chrono::duration<double, std::milli>(now - lap).count()});
    lap = now;
  }
  void total() { out->push_back({"total", std::chrono::duration<double, std::milli>(Clock::now() - start).count()}); }
};

// A closed leaf is a door's only evidence when it covers more than this
// share of its doorway (no trim, see-through or recess).
constexpr double kClosedBandEvidence = 0.7;

// f(0) ... f(n - 1) over the cores (OpenMP), each at most once; the first
// exception thrown is rethrown here (none may escape an OpenMP region).
template <class F>
void parallelFor(std::size_t n, F f) {
  std::exception_ptr error;
#pragma omp parallel for schedule(dynamic, 1)
  for (long long i = 0; i < static_cast<long long>(n); ++i) {
    try {
      f(static_cast<std::size_t>(i));
    } catch (...) {
#pragma omp critical(dsr_parallel_for_error)
      if (!error) error = std::current_exception();
    }
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace

PipelineResult Pipeline::run(const pcl::PointCloud<pcl::PointXYZ>& cloud, bool with_reconstruction,
                             const Eigen::Vector3d& viewpoint_in) const {
  const Parameters& p = params_;
  if (cloud.size() > static_cast<std::size_t>(p.max_points))
    throw std::invalid_argument("cloud of " + std::to_string(cloud.size()) + " points exceeds max_points (" +
                                std::to_string(p.max_points) + ")");
  PipelineResult res;
  Stopwatch watch(&res.timing_ms);
  res.points_in = cloud.size();
  const bool organized = cloud.height > 1;  // a camera frame: no return means nothing in range

  // --- preprocess: sanitise, downsample ---------------------------------------
  preprocess::Points thinned;
  {
    const preprocess::Points raw = preprocess::sanitize(cloud, p.max_abs_coordinate);
    if (raw.size() < cloud.size())
      res.warnings.push_back(std::to_string(cloud.size() - raw.size()) + " non-finite or out-of-range points dropped");
    thinned = preprocess::voxelDownsample(raw, p.voxel_size);
  }
  res.points_used = thinned.size();
  watch.mark("preprocess");
  if (thinned.size() < 20) {
    res.warnings.push_back("too few points to find walls");
    watch.total();
    return res;
  }

  // --- normals: one neighbour grid serves normals and region growing ---------
  // Cells of 1.5 voxels: a neighbourhood of 3 x 3 x 3 cells, 4.5 voxels wide,
  // holds normal_k points or more of a surface thinned to the voxel size even
  // where the scan is sparser than the voxel grid.
  const segmentation::NeighbourGrid grid(thinned, static_cast<float>(1.5 * std::max(p.voxel_size, 0.01)));
  segmentation::Normals normals = segmentation::estimateNormals(thinned, grid, p.normal_k, viewpoint_in.cast<float>());
  watch.mark("normals");

  // --- levelling: the up axis given (and refined) or estimated ---------------
  std::optional<Eigen::Vector3d> up = preprocess::parseUpAxis(p.up_axis);
  if (!up) {
    up = preprocess::estimateUp(thinned, normals.n, static_cast<unsigned>(p.random_seed));
    if (up) up = preprocess::refineUp(*up, normals.n, 10.0);
  } else if (p.refine_up_deg > 0) {
    up = preprocess::refineUp(*up, normals.n, p.refine_up_deg);
  }
  if (!up) {
    res.warnings.push_back("up axis could not be estimated; using +z");
    up = Eigen::Vector3d::UnitZ();
  }
  res.up = up->normalized();
  const Eigen::Matrix3f R = preprocess::levellingRotation(res.up).cast<float>();
  preprocess::Points pts(thinned.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    pts[i] = R * thinned[i];
    normals.n[i] = R * normals.n[i];
  }
  const Eigen::Vector3f viewpoint = R * viewpoint_in.cast<float>();
  watch.mark("level");

  // --- segmentation -----------------------------------------------------------
  const segmentation::FloorCeiling fc = segmentation::findFloorCeiling(pts, normals, p, viewpoint.z());
  res.floor = fc.floor;
  res.ceiling = fc.ceiling;
  std::vector<float> vertical_z;
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (std::abs(normals.n[i].z()) < p.vertical_normal_z) vertical_z.push_back(pts[i].z());
  if (vertical_z.size() < 20) {
    res.warnings.push_back("no vertical structure: no walls");
    watch.total();
    return res;
  }
  std::sort(vertical_z.begin(), vertical_z.end());
  double floor_z = fc.floor ? *fc.floor : vertical_z[vertical_z.size() / 200];
  double top_z = fc.ceiling ? *fc.ceiling : vertical_z[vertical_z.size() - 1 - vertical_z.size() / 200];
  if (!fc.floor) res.warnings.push_back("no floor in view: floor taken at the foot of the vertical structure");
  if (!fc.ceiling) res.warnings.push_back("no ceiling in view: wall height taken from the top of the vertical structure");
  watch.mark("floor_ceiling");
  if (top_z - floor_z < 0.5) {
    res.warnings.push_back("scene lower than 0.5 m: no walls");
    watch.total();
    return res;
  }
  const std::vector<segmentation::WallPlane> walls =
      segmentation::findWalls(pts, normals, floor_z, top_z, fc.ceiling.has_value(), viewpoint.head<2>().cast<double>(), p);
  watch.mark("walls");
  for (std::size_t wi = 0; wi < walls.size(); ++wi) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "wall %zu: point (%.2f, %.2f) dir (%.2f, %.2f) s=[%.2f, %.2f] z=[%.2f, %.2f] %zu pts", wi,
                  walls[wi].point.x(), walls[wi].point.y(), walls[wi].direction.x(), walls[wi].direction.y(),
                  walls[wi].s_min, walls[wi].s_max, walls[wi].z_min, walls[wi].z_max, walls[wi].inliers.size());
    res.trace.push_back(buf);
  }

  // --- recognition and state: doorways on every wall, the leaf in each ------
  const Eigen::Matrix3d Rt = R.cast<double>().transpose();
  auto toInput = [&](const Eigen::Vector3d& v) -> Eigen::Vector3d { return Rt * v; };
  auto onFloor = [&](const Eigen::Vector2d& xy) { return Eigen::Vector3d(xy.x(), xy.y(), floor_z); };
  std::vector<char> is_leaf(pts.size(), 0), is_wall(pts.size(), 0);
  std::vector<reconstruction::Opening> openings;
  // The doorways of each wall, then the leaf in each doorway: independent
  // searches, run over both cores; decisions follow in wall and doorway order.
  std::vector<std::vector<recognition::Doorway>> doorways(walls.size());
  parallelFor(walls.size(), [&](std::size_t wi) {
    doorways[wi] = recognition::findDoorways(pts, walls[wi], floor_z, top_z, viewpoint, p, organized);
  });
  struct Candidate {
    std::size_t wall;
    recognition::Doorway doorway;
    state::LeafFit leaf;
  };
  std::vector<Candidate> candidates;
  for (std::size_t wi = 0; wi < walls.size(); ++wi)
    for (const recognition::Doorway& d : doorways[wi]) candidates.push_back({wi, d, {}});
  auto thicknessOf = [&](const recognition::Doorway& d) { return d.thickness > 0.04 ? d.thickness : p.default_wall_thickness; };
  parallelFor(candidates.size(), [&](std::size_t i) {
    Candidate& c = candidates[i];
    // Without trim, see-through or a deep recess only a closed leaf filling
    // the doorway makes it a door (the evidence rule below): skip the search
    // when the wall band holds too little for one.
    const recognition::Doorway& d = c.doorway;
    const bool other_evidence = d.casing || d.through >= 0.08 || d.recess > 0.3;
    c.leaf = state::fitLeaf(pts, walls[c.wall], d, floor_z, thicknessOf(d), viewpoint, p,
                            other_evidence ? 0.0 : kClosedBandEvidence);
  });
  for (const segmentation::WallPlane& wall : walls)
    for (int i : wall.inliers) is_wall[i] = 1;
  for (const Candidate& cand : candidates) {
    {
      const std::size_t wi = cand.wall;
      const segmentation::WallPlane& wall = walls[wi];
      const recognition::Doorway& d = cand.doorway;
      const double t = thicknessOf(d);
      const state::LeafFit& leaf = cand.leaf;
      if (!leaf.found) {
        char buf[400];
        std::snprintf(buf, sizeof buf,
                      "wall %zu: doorway s=[%.2f, %.2f] casing=%d through=%.2f front=%.2f recess=%.2f top=%.2f "
                      "thick=%.2f | no leaf (%s: %.0f deg, coverage %.2f, contradicted %.2f; %d points, %d rays)",
                      wi, d.s0, d.s1, d.casing, d.through, d.front, d.recess, d.top - floor_z, d.thickness,
                      leaf.searched ? "best" : "not searched, no evidence and wall band",
                      leaf.best_angle_deg, leaf.best_coverage, leaf.best_contradiction, leaf.candidate_points,
                      leaf.candidate_rays);
        res.trace.push_back(buf);
        continue;
      }
      // What tells a door from a cupboard or a gap: a closed leaf inside the
      // wall, or trim around the doorway, or the room beyond seen through it.
      const bool evidence = leaf.closed_in_band ? (d.casing || d.recess > 0.3 || leaf.coverage > kClosedBandEvidence)
                                                : (d.casing || d.through >= 0.08);
      const double height = (std::isfinite(d.top) ? d.top : leaf.top_z) - floor_z;
      const double wall_h = top_z - floor_z;
      const bool tall = height >= p.door_min_height && height >= p.door_height_ratio * wall_h - p.door_height_phi;
      const double width = std::abs(leaf.s_latch - leaf.s_hinge);
      const bool wide = width >= p.door_min_width && width <= p.door_max_width;
      {
        char buf[400];
        std::snprintf(buf, sizeof buf,
                      "wall %zu: doorway s=[%.2f, %.2f] casing=%d face=%.2f through=%.2f front=%.2f recess=%.2f "
                      "top=%.2f thick=%.2f | leaf found=%d band=%d angle=%.1f cov=%.2f hinge_s0=%d toward=%d | %s",
                      wi, d.s0, d.s1, d.casing, d.face, d.through, d.front, d.recess, d.top - floor_z, d.thickness,
                      leaf.found, leaf.closed_in_band, leaf.angle_deg, leaf.coverage, leaf.hinge_at_s0,
                      leaf.toward_viewer,
                      !evidence ? "rejected: no casing, recess or see-through"
                                : !tall ? "rejected: too low" : !wide ? "rejected: width" : "door");
        res.trace.push_back(buf);
      }
      if (!evidence || !tall || !wide) continue;

      DoorResult door;
      door.wall_id = static_cast<int>(wi);
      door.opening_angle_deg = leaf.angle_deg;
      door.state = state::classify(leaf.angle_deg, p);
      // Confidence: how much of the leaf was seen, and how sure the doorway is.
      door.confidence = std::min(1.0, leaf.coverage) * (d.casing || d.through >= 0.4 ? 1.0 : 0.7);
      door.swing = leaf.toward_viewer ? Swing::TowardViewer : Swing::AwayFromViewer;
      const Eigen::Vector2d n2 = leaf.toward_viewer ? wall.normal : Eigen::Vector2d(-wall.normal);
      door.wall_normal = toInput(Eigen::Vector3d(n2.x(), n2.y(), 0));
      door.hinge = toInput(onFloor(leaf.hinge));
      const Eigen::Vector2d center = wall.point + ((leaf.s_hinge + leaf.s_latch) / 2) * wall.direction - (t / 2) * wall.normal;
      door.opening_center = toInput(onFloor(center));
      door.width = std::abs(leaf.s_latch - leaf.s_hinge);
      door.height = height;
      const double bottom = floor_z + 0.01, top = std::max(leaf.top_z, floor_z + 0.5);
      const Eigen::Vector2d latch = leaf.hinge + leaf.length * leaf.direction;
      door.leaf_corners = {toInput(Eigen::Vector3d(leaf.hinge.x(), leaf.hinge.y(), bottom)),
                           toInput(Eigen::Vector3d(latch.x(), latch.y(), bottom)),
                           toInput(Eigen::Vector3d(latch.x(), latch.y(), top)),
                           toInput(Eigen::Vector3d(leaf.hinge.x(), leaf.hinge.y(), top))};
      door.wall_line_point = toInput(onFloor(wall.point));
      door.wall_line_direction = toInput(Eigen::Vector3d(wall.direction.x(), wall.direction.y(), 0));
      door.leaf_line_point = door.hinge;
      door.leaf_line_direction = toInput(Eigen::Vector3d(leaf.direction.x(), leaf.direction.y(), 0));
      // The same doorway found from two overlapping wall hypotheses, or the
      // same leaf claimed by two doorways (a leaf's shadow beside its own
      // doorway looks like one): keep the surer one.
      bool duplicate = false;
      for (DoorResult& other : res.doors)
        if ((other.opening_center - door.opening_center).norm() < 0.4 ||
            ((other.hinge - door.hinge).norm() < 0.2 &&
             std::abs(other.leaf_line_direction.dot(door.leaf_line_direction)) > 0.95)) {
          duplicate = true;
          if (door.confidence > other.confidence) other = door;
        }
      if (duplicate) continue;
      for (int i : leaf.inliers) is_leaf[i] = 1;
      res.doors.push_back(door);
      openings.push_back({static_cast<int>(wi), std::min(leaf.s_hinge, leaf.s_latch), std::max(leaf.s_hinge, leaf.s_latch), floor_z + height, leaf.hinge, leaf.direction, leaf.length,
                          bottom, top});
    }
  }
  for (std::size_t i = 0; i < res.doors.size(); ++i) res.doors[i].id = static_cast<int>(i);
  watch.mark("doors");

  // --- paper 3.1-3.2: region growing, and corners of every segment ------------
  std::vector<char> mask(pts.size(), 0);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const bool horizontal_slab = std::abs(normals.n[i].z()) > p.horizontal_normal_z &&
                                 (std::abs(pts[i].z() - floor_z) < 0.05 || (fc.ceiling && std::abs(pts[i].z() - top_z) < 0.05));
    mask[i] = !horizontal_slab && !is_wall[i] && !is_leaf[i];
  }
  const auto regions = segmentation::growRegions(pts, normals, grid, mask, p);
  for (const auto& region : regions) {
    const recognition::BoxCorners box = recognition::boundingBox(pts, region);
    SegmentResult seg;
    seg.id = static_cast<int>(res.others.size());
    for (int k = 0; k < 8; ++k) seg.corners[k] = toInput(box.corners[k]);
    seg.height = box.height;
    seg.volume = box.volume;
    seg.oriented_box = box.oriented;
    res.others.push_back(seg);
  }
  for (std::size_t wi = 0; wi < walls.size(); ++wi) {
    const recognition::BoxCorners box = recognition::boundingBox(pts, walls[wi].inliers);
    WallResult w;
    w.id = static_cast<int>(wi);
    for (int k = 0; k < 8; ++k) w.corners[k] = toInput(box.corners[k]);
    w.height = walls[wi].z_max - floor_z;
    w.length = walls[wi].s_max - walls[wi].s_min;
    w.line_point = toInput(onFloor(walls[wi].point + walls[wi].s_min * walls[wi].direction));
    w.line_direction = toInput(Eigen::Vector3d(walls[wi].direction.x(), walls[wi].direction.y(), 0));
    w.normal = toInput(Eigen::Vector3d(walls[wi].normal.x(), walls[wi].normal.y(), 0));
    w.points = walls[wi].inliers.size();
    res.walls.push_back(w);
  }
  watch.mark("segments");

  // --- reconstruction ------------------------------------------------------------
  if (with_reconstruction) {
    std::vector<reconstruction::WallPatch> patches;
    for (const auto& w : walls) patches.push_back({w.point, w.direction, w.s_min, w.s_max, floor_z, top_z});
    res.reconstruction = reconstruction::reconstruct(patches, openings, p.reconstruction_spacing);
    for (auto& q : res.reconstruction.points) {
      const Eigen::Vector3f v = R.transpose() * Eigen::Vector3f(q.x, q.y, q.z);
      q.x = v.x();
      q.y = v.y();
      q.z = v.z();
    }
    watch.mark("reconstruction");
  }
  watch.total();
  return res;
}

}  // namespace dsr
