#include "door_state_recognition/pipeline/pipeline.hpp"
#include "door_state_recognition/pipeline/stopwatch.hpp"
#include "door_state_recognition/pipeline/input_checks.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <memory>
#include <cmath>
#include <stdexcept>

#include "door_state_recognition/preprocess/preprocess.hpp"
#include "door_state_recognition/reconstruction/reconstruction.hpp"
#include "door_state_recognition/recognition/recognition.hpp"
#include "door_state_recognition/segmentation/segmentation.hpp"
#include "door_state_recognition/state/doors.hpp"
#include "door_state_recognition/util/first_error.hpp"

namespace dsr {

namespace {

// recognition::findDoorways on one wall as an OpenMP task, into *out; the
// first exception thrown is kept in *error.
struct DoorwayJob {
  std::shared_ptr<const segmentation::WallPlane> wall;
  std::shared_ptr<std::vector<recognition::Doorway>> out;
  const preprocess::Points* pts;
  double floor_z, top_z;
  Eigen::Vector3f viewpoint;
  const Parameters* p;
  bool organized;
  const segmentation::ViewTop* view;  // a camera frame's, or null
  util::FirstError* error;
};
void startDoorwayTask(const DoorwayJob& job_in) {
  const DoorwayJob job = job_in;
#pragma omp task firstprivate(job)
  job.error->run([&] {
    *job.out = recognition::findDoorways(*job.pts, *job.wall, job.floor_z, job.top_z, job.viewpoint, *job.p, job.organized,
                                         job.view);
  });
}

}  // namespace

const char* toString(DoorStateKind s) {
  switch (s) {
    case DoorStateKind::Closed: return "closed";
    case DoorStateKind::SemiOpen: return "semi_open";
    case DoorStateKind::Open: return "open";
    case DoorStateKind::NotClosed: return "not_closed";
  }
  return "closed";
}

bool sameLeaf(const DoorResult& a, const DoorResult& b) {
  return (a.hinge - b.hinge).norm() < 0.2 && std::abs(a.leaf_line_direction.dot(b.leaf_line_direction)) > 0.95;
}

bool leavesOverlap(const DoorResult& a, const DoorResult& b) {
  constexpr double kParallelCos = 0.94, kOffLine = 0.15, kOverlapShare = 0.4;  // cos 20 deg
  const Eigen::Vector3d &a0 = a.leaf_corners[0], &a1 = a.leaf_corners[1], &b0 = b.leaf_corners[0], &b1 = b.leaf_corners[1];
  const double la = (a1 - a0).norm(), lb = (b1 - b0).norm();
  if (!(la > 1e-6) || !(lb > 1e-6)) return false;  // also false for NaN
  const Eigen::Vector3d ua = (a1 - a0) / la, ub = (b1 - b0) / lb;
  if (std::abs(ua.dot(ub)) < kParallelCos) return false;
  const Eigen::Vector3d m = 0.5 * (b0 + b1) - a0;
  if ((m - m.dot(ua) * ua).norm() > kOffLine) return false;
  const double t0 = (b0 - a0).dot(ua), t1 = (b1 - a0).dot(ua);
  const double overlap = std::min(la, std::max(t0, t1)) - std::max(0.0, std::min(t0, t1));
  return overlap >= kOverlapShare * std::min(la, lb);
}

bool surerReport(const DoorResult& a, const DoorResult& b) {
  if (a.angle_is_lower_bound != b.angle_is_lower_bound) return !a.angle_is_lower_bound;
  if (a.angle_is_lower_bound) return a.opening_angle_deg > b.opening_angle_deg;
  if (a.casing != b.casing && (a.opening_center - b.opening_center).norm() > 0.4 && sameLeaf(a, b)) return a.casing;
  return a.confidence > b.confidence;
}

double clearWidth(double width, double angle_deg, double leaf_thickness, double closed_below_deg) {
  if (!std::isfinite(width) || !std::isfinite(angle_deg) || !std::isfinite(leaf_thickness) || width <= 0 ||
      angle_deg < closed_below_deg)
    return 0.0;
  const double th = std::min(180.0, std::max(0.0, angle_deg)) * M_PI / 180.0;
  const double taken = width * std::max(0.0, std::cos(th)) + std::max(0.0, leaf_thickness) * std::sin(th);
  return std::max(0.0, width - taken);
}

DoorStateKind stateOfBound(double bound_deg, const Parameters& p) {
  return bound_deg >= p.open_from_deg ? DoorStateKind::Open : DoorStateKind::NotClosed;
}

void combineBounds(DoorResult& d, const std::vector<const DoorResult*>& others, const Parameters& p) {
  constexpr double kSameHinge = 0.3, kSameSwingCos = 0.7;  // m; cos 45 deg
  if (!d.angle_is_lower_bound || d.side_bounds.empty()) return;
  const DoorResult::SideBound* least = nullptr;
  double least_deg = 181;
  for (const DoorResult::SideBound& side : d.side_bounds) {
    double deg = side.bound_deg;
    for (const DoorResult* o : others) {
      if (!o->angle_is_lower_bound) continue;
      for (const DoorResult::SideBound& os : o->side_bounds)
        if ((os.hinge - side.hinge).norm() < kSameHinge && os.swing.dot(side.swing) > kSameSwingCos)
          deg = std::max(deg, os.bound_deg);
    }
    if (deg < least_deg) least_deg = deg, least = &side;
  }
  if (!least || !(least_deg > d.opening_angle_deg) || least_deg > 170) return;
  const double th = least_deg * M_PI / 180;
  const Eigen::Vector3d dir = (std::cos(th) * least->along + std::sin(th) * least->swing).normalized();
  const double length = (d.leaf_corners[1] - d.leaf_corners[0]).norm();
  const Eigen::Vector3d up_bottom = d.leaf_corners[0] - d.hinge, up_top = d.leaf_corners[3] - d.hinge;
  d.opening_angle_deg = least_deg;
  d.state = stateOfBound(least_deg, p);
  d.hinge = least->hinge;
  d.wall_normal = least->swing;
  d.leaf_corners = {d.hinge + up_bottom, d.hinge + up_bottom + length * dir, d.hinge + up_top + length * dir,
                    d.hinge + up_top};
  d.leaf_line_point = d.hinge;
  d.leaf_line_direction = dir;
  d.clear_width = clearWidth(d.width, least_deg, p.leaf_thickness, p.closed_below_deg);
}

const char* toString(Swing s) {
  switch (s) {
    case Swing::TowardViewer: return "toward_viewer";
    case Swing::AwayFromViewer: return "away_from_viewer";
    case Swing::Unknown: return "unknown";
  }
  return "unknown";
}

void translate(PipelineResult& r, const Eigen::Vector3d& o) {
  for (WallResult& w : r.walls) {
    for (Eigen::Vector3d& c : w.corners) c += o;
    w.line_point += o;
  }
  for (DoorResult& d : r.doors) {
    for (Eigen::Vector3d& c : d.leaf_corners) c += o;
    d.hinge += o, d.opening_center += o, d.wall_line_point += o, d.leaf_line_point += o;
  }
  for (SegmentResult& g : r.others)
    for (Eigen::Vector3d& c : g.corners) c += o;
  if (r.viewpoint) *r.viewpoint += o;
  for (Eigen::Vector3d& st : r.stations) st += o;
  const double along = o.dot(r.up);
  if (r.floor) *r.floor += along;
  if (r.ceiling) *r.ceiling += along;
}

Pipeline::Pipeline(const Parameters& parameters) : params_(parameters) { params_.validate(); }

namespace {

// A cloud no denser than the voxel grid (a mesh's vertices, an occupancy
// map's voxel centres): its median nearest-neighbour spacing, from up to
// kSpacingSamples of its points (searched within kSpacingReach; farther
// counts as kSpacingReach). Only where the voxel grid kept nearly every point.
constexpr std::size_t kSpacingSamples = 1000;
constexpr float kSpacingReach = 0.2f;
// Neighbourhoods (normals, region growing, the evidence grids) are sized in
// voxels; a cloud whose points lie more than kSparseVoxels voxels apart has
// too few in them: its voxel size is then taken as half its spacing (a mesh
// export's 4 cm vertices work at 2 cm voxels), at most kMaxSparseVoxel.
constexpr double kSparseVoxels = 2.4, kMaxSparseVoxel = 0.1;
// The voxel grid kept this share of the points or more: maybe no denser than it.
constexpr double kSparseKept = 0.8;
// A given up axis this close to a camera frame's optical axis (deg) is
// warned of: the camera would be pitched beyond 60 deg, looking at the
// floor or the ceiling rather than across the room at its doors.
constexpr double kAlongOpticalDeg = 30.0;

double medianSpacing(const preprocess::Points& pts) {
  const segmentation::NeighbourGrid grid(pts, kSpacingReach / 2);
  const std::size_t step = std::max<std::size_t>(1, pts.size() / kSpacingSamples);
  std::vector<float> nn;
  std::vector<int> idx;
  std::vector<float> d2;
  for (std::size_t i = 0; i < pts.size(); i += step) {
    grid.within(static_cast<int>(i), kSpacingReach, idx, d2);
    nn.push_back(d2.empty() ? kSpacingReach : std::sqrt(*std::min_element(d2.begin(), d2.end())));
  }
  std::nth_element(nn.begin(), nn.begin() + nn.size() / 2, nn.end());
  return nn[nn.size() / 2];
}

}  // namespace

PipelineResult Pipeline::run(const pcl::PointCloud<pcl::PointXYZ>& cloud, bool with_reconstruction,
                             const Eigen::Vector3d& viewpoint_in) const {
  Parameters local = params_;  // voxel_size may follow a sparse cloud's spacing
  const Parameters& p = local;
  if (cloud.size() > static_cast<std::size_t>(p.max_points))
    throw std::invalid_argument("cloud of " + std::to_string(cloud.size()) + " points exceeds max_points (" +
                                std::to_string(p.max_points) + ")");
  if (!viewpoint_in.allFinite() || viewpoint_in.cwiseAbs().maxCoeff() > p.max_abs_coordinate)
    throw std::invalid_argument("viewpoint is not finite or lies beyond max_abs_coordinate");
  PipelineResult res;
  Stopwatch watch(&res.timing_ms);
  res.points_in = cloud.size();
  res.viewpoint = viewpoint_in;
  // The axis given, until levelling has found the one it used (a report
  // ending before levelling says the axis it was told, not +z).
  if (const std::optional<Eigen::Vector3d> given = preprocess::parseUpAxis(p.up_axis)) res.up = given->normalized();
  const bool organized = cloud.height > 1;  // a camera frame: no return means nothing in range
  if (const std::optional<std::string> why = implausibleInput(cloud, viewpoint_in)) {
    res.warnings.push_back(*why);
    watch.total();
    return res;
  }

  // --- preprocess: sanitise, downsample ---------------------------------------
  preprocess::Points thinned;
  {
    std::size_t kept = 0;
    thinned = preprocess::sanitizeAndDownsample(cloud, p.max_abs_coordinate, p.voxel_size, &kept);
    if (kept < cloud.size())
      res.warnings.push_back(std::to_string(cloud.size() - kept) + " non-finite or out-of-range points dropped");
    if (p.voxel_size > 0 && thinned.size() >= 100 && thinned.size() >= kSparseKept * kept) {
      const double spacing = medianSpacing(thinned);
      if (spacing > kSparseVoxels * p.voxel_size) {
        local.voxel_size = std::min(kMaxSparseVoxel, spacing / 2);
        thinned = preprocess::sanitizeAndDownsample(cloud, p.max_abs_coordinate, p.voxel_size, &kept);
        char buf[200];
        std::snprintf(buf, sizeof buf,
                      "sparse cloud (points %.1f cm apart, a mesh or an occupancy map): voxel_size taken as %.1f cm",
                      100 * spacing, 100 * p.voxel_size);
        res.warnings.push_back(buf);
      }
    }
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
  segmentation::NeighbourGrid grid(thinned, static_cast<float>(1.5 * std::max(p.voxel_size, 0.01)));
  segmentation::Normals normals = segmentation::estimateNormals(thinned, grid, p.normal_k, viewpoint_in.cast<float>());
  watch.mark("normals");

  // --- levelling: the up axis given (and refined) or estimated ---------------
  // Levelling and the floor and ceiling on this core, and on the other:
  // a camera frame's pixels without a return (rays along which nothing was
  // in range), which depend on the input alone (where the grid was built
  // they took the core its halves would use), then the heights of the
  // vertical structure with its foot and top: two ranks (a rank's value is
  // the same whether the whole is sorted or only selected, and whatever was
  // selected before), used where no floor or no ceiling is found.
  preprocess::Points no_return;
  Eigen::Matrix3f R;
  preprocess::Points pts;
  Eigen::Vector3f viewpoint;
  segmentation::FloorCeiling fc;
  std::vector<float> vertical_z;
  float foot_z = 0, head_z = 0;
  bool levelled = false;
  // A camera frame's pinhole camera (none for other clouds, organized LiDAR
  // rings included): its rays without a return and its image's up.
  const std::optional<preprocess::Pinhole> camera =
      organized ? preprocess::fitPinhole(cloud, viewpoint_in.cast<float>()) : std::nullopt;
  {
    util::FirstError error;
#pragma omp parallel
#pragma omp single
    {
      if (camera) {
#pragma omp task shared(no_return, error)
        error.run([&] { no_return = preprocess::noReturnRays(cloud, *camera); });
      }
      error.run([&] {
        // One levelling path: an axis given and one estimated seed the same
        // refinement, so that both give the same doors when they agree.
        // Sensors are mounted upright or on a side (a camera's -y, a
        // scanner's +z): an estimate within the refinement's reach of one of
        // the frame's axes is refined from that axis, as if it were given.
        std::optional<Eigen::Vector3d> up = preprocess::parseUpAxis(p.up_axis);
        const bool given = up.has_value();
        const double reach = p.refine_up_deg > 0 ? p.refine_up_deg : 10.0;
        if (!given) {
          up = preprocess::estimateUp(thinned, normals.n, static_cast<unsigned>(p.random_seed),
                                      camera ? std::optional<Eigen::Vector3d>(camera->imageUp()) : std::nullopt);
          if (up) up = preprocess::nearestFrameAxis(*up, reach);
        }
        if (up && (!given || p.refine_up_deg > 0)) up = preprocess::refineUp(*up, normals.n, reach);
        if (!up) {
          res.warnings.push_back("up axis could not be estimated; using +z");
          up = Eigen::Vector3d::UnitZ();
        }
        res.up = up->normalized();
        R = preprocess::levellingRotation(res.up).cast<float>();
        pts.resize(thinned.size());
        for (std::size_t i = 0; i < pts.size(); ++i) {
          pts[i] = R * thinned[i];
          normals.n[i] = R * normals.n[i];
        }
        viewpoint = R * viewpoint_in.cast<float>();
        watch.mark("level");
        levelled = true;
      });
      // --- segmentation -----------------------------------------------------------
      if (levelled) {
#pragma omp task shared(vertical_z, foot_z, head_z, error)
        error.run([&] {
          std::vector<float> vz;
          vz.reserve(pts.size());
          for (std::size_t i = 0; i < pts.size(); ++i)
            if (std::abs(normals.n[i].z()) < p.vertical_normal_z) vz.push_back(pts[i].z());
          if (vz.size() >= 20) {
            auto rank = [&](std::size_t k) {
              std::nth_element(vz.begin(), vz.begin() + k, vz.end());
              return vz[k];
            };
            foot_z = rank(vz.size() / 200);
            head_z = rank(vz.size() - 1 - vz.size() / 200);
          }
          vertical_z.swap(vz);
        });
        error.run([&] { fc = segmentation::findFloorCeiling(pts, normals, p, viewpoint.z()); });
      }
    }
    error.rethrow();
  }
  res.floor = fc.floor;
  res.ceiling = fc.ceiling;
  // A given axis the surfaces contradict (levelled: the given axis turned
  // by R, the used one +z) is warned of: a camera pitched beyond the
  // refinement's reach.
  if (const std::optional<Eigen::Vector3d> given = preprocess::parseUpAxis(p.up_axis)) {
    const double reach = p.refine_up_deg > 0 ? p.refine_up_deg : 10.0;
    const std::optional<double> off = preprocess::givenUpContradicted(
        pts, normals.n, R.cast<double>() * *given, Eigen::Vector3d::UnitZ(), reach, fc.floor.has_value(),
        static_cast<unsigned>(p.random_seed),
        camera ? std::optional<Eigen::Vector3d>(R.cast<double>() * camera->imageUp()) : std::nullopt);
    if (off) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "the surfaces show an up %.0f deg from the given axis %s (refined within %.0f deg): "
                    "a sensor pitched or rolled further? try up axis auto",
                    *off, p.up_axis.c_str(), reach);
      res.warnings.push_back(buf);
    } else if (camera) {
      // A camera looks across a room, not straight up or down: a given up
      // within kAlongOpticalDeg of its optical axis is the default +z on
      // a frame in its optical frame (z forward, y down), whose room's
      // axes the check above cannot tell apart (each is square to the others).
      const Eigen::Vector3d optical = camera->ray(camera->cu, camera->cv);
      const double deg = std::acos(std::min(1.0, std::abs(optical.dot(given->normalized())))) * 180.0 / M_PI;
      if (deg < kAlongOpticalDeg) {
        char buf[240];
        std::snprintf(buf, sizeof buf,
                      "the given up axis %s lies %.0f deg from this camera frame's optical axis (a camera looking "
                      "straight up or down?): in a camera's optical frame (z forward, y down) up is -y; try up "
                      "axis -y or auto",
                      p.up_axis.c_str(), deg);
        res.warnings.push_back(buf);
      }
    }
  }
  if (const std::optional<std::string> why = singleSurface(pts, normals.n, viewpoint, p.up_axis != "auto"))
    res.warnings.push_back(*why);
  if (vertical_z.size() < 20) {
    res.warnings.push_back("no vertical structure: no walls");
    watch.total();
    return res;
  }
  double floor_z = fc.floor ? *fc.floor : foot_z;
  double top_z = fc.ceiling ? *fc.ceiling : head_z;
  if (!fc.floor) res.warnings.push_back("no floor in view: floor taken at the foot of the vertical structure");
  if (!fc.ceiling) res.warnings.push_back("no ceiling in view: wall height taken from the top of the vertical structure");
  watch.mark("floor_ceiling");
  if (top_z - floor_z < 0.5) {
    res.warnings.push_back("scene lower than 0.5 m: no walls");
    watch.total();
    return res;
  }
  // A camera frame's view ends above and below: a near wall is cut by it.
  segmentation::ViewTop view = organized ? segmentation::viewTop(pts, viewpoint) : segmentation::ViewTop{};
  // Its pixels without a return: rays along which nothing was in range.
  if (organized) {
    view.ray_spacing = static_cast<float>(preprocess::raySpacing(cloud, viewpoint_in.cast<float>()));
    view.no_return = std::move(no_return);
    for (auto& d : view.no_return) d = R * d;
  }
  // Each wall's doorways are sought (as findDoors would) as soon as
  // findWalls takes the wall, as a task beside its rounds still to come.
  std::vector<std::shared_ptr<std::vector<recognition::Doorway>>> found;  // per wall, filled by its task
  util::FirstError doorway_error;
  auto onWall = [&](std::size_t wi, const segmentation::WallPlane& wall) {
    if (found.size() <= wi) found.resize(wi + 1);
    found[wi] = std::make_shared<std::vector<recognition::Doorway>>();
    startDoorwayTask({std::make_shared<const segmentation::WallPlane>(wall), found[wi], &pts, floor_z, top_z, viewpoint,
                      &p, organized, organized ? &view : nullptr, &doorway_error});
  };
  std::vector<segmentation::WallPlane> walls = segmentation::findWalls(
      pts, normals, floor_z, top_z, fc.ceiling.has_value(), viewpoint.head<2>().cast<double>(), p, &view, onWall);
  doorway_error.rethrow();
  std::vector<std::vector<recognition::Doorway>> doorways(walls.size());
  for (std::size_t wi = 0; wi < walls.size(); ++wi)
    doorways[wi] = wi < found.size() && found[wi]
                       ? std::move(*found[wi])
                       : recognition::findDoorways(pts, walls[wi], floor_z, top_z, viewpoint, p, organized,
                                                   organized ? &view : nullptr);
  {
    // The fronts of furniture against a wall are no walls, nor the gaps between them doorways.
    const std::vector<char> front = segmentation::furnitureFronts(walls, viewpoint.head<2>().cast<double>());
    std::size_t kept = 0;
    for (std::size_t wi = 0; wi < walls.size(); ++wi) {
      if (front[wi]) {
        char buf[120];
        std::snprintf(buf, sizeof buf, "wall at (%.2f, %.2f): the front of furniture against a wall", walls[wi].point.x(),
                      walls[wi].point.y());
        res.trace.push_back(buf);
        continue;
      }
      if (kept != wi) walls[kept] = std::move(walls[wi]), doorways[kept] = std::move(doorways[wi]);
      ++kept;
    }
    walls.resize(kept);
    doorways.resize(kept);
  }
  watch.mark("walls");
  for (std::size_t wi = 0; wi < walls.size(); ++wi) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "wall %zu: point (%.2f, %.2f) dir (%.2f, %.2f) s=[%.2f, %.2f] z=[%.2f, %.2f] %zu pts", wi,
                  walls[wi].point.x(), walls[wi].point.y(), walls[wi].direction.x(), walls[wi].direction.y(),
                  walls[wi].s_min, walls[wi].s_max, walls[wi].z_min, walls[wi].z_max, walls[wi].inliers.size());
    res.trace.push_back(buf);
  }

  // --- recognition and state: doorways on every wall, the leaf in each ------
  auto onFloor = [&](const Eigen::Vector2d& xy) { return Eigen::Vector3d(xy.x(), xy.y(), floor_z); };
  const Eigen::Matrix3d Rt = R.cast<double>().transpose();
  auto toInput = [&](const Eigen::Vector3d& v) -> Eigen::Vector3d { return Rt * v; };
  state::DoorStage door_stage =
      state::findDoors(pts, walls, floor_z, top_z, fc.ceiling.has_value(), viewpoint, Rt, organized, p, &view, &doorways);
  res.doors = std::move(door_stage.doors);
  res.trace.insert(res.trace.end(), door_stage.trace.begin(), door_stage.trace.end());
  const std::vector<char>& is_leaf = door_stage.is_leaf;
  std::vector<char> is_wall(pts.size(), 0);
  for (const segmentation::WallPlane& wall : walls)
    for (int i : wall.inliers) is_wall[i] = 1;
  watch.mark("doors");

  // --- paper 3.1-3.2: region growing, and corners of every segment ------------
  std::vector<char> mask(pts.size(), 0);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const bool horizontal_slab = std::abs(normals.n[i].z()) > p.horizontal_normal_z &&
                                 (std::abs(pts[i].z() - floor_z) < 0.05 || (fc.ceiling && std::abs(pts[i].z() - top_z) < 0.05));
    mask[i] = !horizontal_slab && !is_wall[i] && !is_leaf[i];
  }
  // The walls' boxes on the other core while this one grows the regions;
  // then the regions' boxes, shared out.
  std::vector<std::vector<int>> regions;
  std::vector<recognition::BoxCorners> wall_boxes(walls.size()), region_boxes;
  {
    util::FirstError error;
#pragma omp parallel
#pragma omp single
    {
#pragma omp task shared(wall_boxes, error)
      error.run([&] {
        for (std::size_t wi = 0; wi < walls.size(); ++wi) wall_boxes[wi] = recognition::boundingBox(pts, walls[wi].inliers);
      });
      error.run([&] {
        regions = segmentation::growRegions(pts, normals, grid, mask, p);
        region_boxes.resize(regions.size());
      });
#pragma omp taskloop grainsize(1) shared(region_boxes, regions, error)
      for (std::size_t r = 0; r < region_boxes.size(); ++r)
        error.run([&] { region_boxes[r] = recognition::boundingBox(pts, regions[r]); });
    }
    error.rethrow();
  }
  for (std::size_t r = 0; r < regions.size(); ++r) {
    const recognition::BoxCorners& box = region_boxes[r];
    SegmentResult seg;
    seg.id = static_cast<int>(res.others.size());
    for (int k = 0; k < 8; ++k) seg.corners[k] = toInput(box.corners[k]);
    seg.height = box.height;
    seg.volume = box.volume;
    seg.oriented_box = box.oriented;
    res.others.push_back(seg);
  }
  for (std::size_t wi = 0; wi < walls.size(); ++wi) {
    const recognition::BoxCorners& box = wall_boxes[wi];
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
    res.reconstruction =
        reconstruction::reconstruct(patches, door_stage.openings, p.reconstruction_spacing, R.transpose());
    watch.mark("reconstruction");
  }
  watch.total();
  return res;
}

}  // namespace dsr
