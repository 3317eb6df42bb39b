#include "door_state_recognition/baseline/stock_pcl.hpp"
#include "door_state_recognition/pipeline/stopwatch.hpp"

#include <pcl/common/transforms.h>
#include <pcl/features/boundary.h>
#include <pcl/features/moment_of_inertia_estimation.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/filters/extract_indices.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/region_growing.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "door_state_recognition/preprocess/preprocess.hpp"
#include "door_state_recognition/recognition/recognition.hpp"
#include "door_state_recognition/segmentation/segmentation.hpp"
#include "door_state_recognition/state/door_state.hpp"
#include "door_state_recognition/state/doors.hpp"

namespace dsr {
namespace baseline {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

Cloud::Ptr voxelGrid(const Cloud::ConstPtr& in, double leaf) {
  Cloud::Ptr out(new Cloud);
  if (leaf <= 0) {
    *out = *in;
    return out;
  }
  pcl::VoxelGrid<pcl::PointXYZ> vg;
  vg.setInputCloud(in);
  vg.setLeafSize(static_cast<float>(leaf), static_cast<float>(leaf), static_cast<float>(leaf));
  vg.filter(*out);
  return out;
}

// The paper's corners (3.2.1) from pcl::MomentOfInertiaEstimation: AABB
// when the major axis is parallel to x or y (within 2 deg), else the OBB.
struct Box {
  std::array<Eigen::Vector3d, 8> corners;
  double height = 0, volume = 0;
  bool oriented = false;
};

Box boxOf(const Cloud::ConstPtr& cloud, const pcl::IndicesPtr& indices) {
  pcl::MomentOfInertiaEstimation<pcl::PointXYZ> moi;
  moi.setInputCloud(cloud);
  moi.setIndices(indices);
  moi.compute();
  Eigen::Vector3f major, middle, minor;
  moi.getEigenVectors(major, middle, minor);
  Box b;
  const Eigen::Vector2f h(major.x(), major.y());
  const float c = h.norm() > 1e-6f ? std::max(std::abs(h.x()), std::abs(h.y())) / h.norm() : 1.0f;
  b.oriented = c < std::cos(2.0f * static_cast<float>(M_PI) / 180.0f);
  if (!b.oriented) {
    pcl::PointXYZ lo, hi;
    moi.getAABB(lo, hi);
    int k = 0;
    for (double z : {lo.z, hi.z})
      for (const auto& xy : {Eigen::Vector2d(lo.x, lo.y), Eigen::Vector2d(hi.x, lo.y), Eigen::Vector2d(hi.x, hi.y),
                             Eigen::Vector2d(lo.x, hi.y)})
        b.corners[k++] = Eigen::Vector3d(xy.x(), xy.y(), z);
    b.height = hi.z - lo.z;
    b.volume = double(hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z);
  } else {
    pcl::PointXYZ lo, hi, pos;
    Eigen::Matrix3f rot;
    moi.getOBB(lo, hi, pos, rot);
    const Eigen::Vector3f p0(pos.x, pos.y, pos.z);
    int k = 0;
    for (float a : {lo.x, hi.x})
      for (float bb : {lo.y, hi.y})
        for (float cc : {lo.z, hi.z}) b.corners[k++] = (p0 + rot * Eigen::Vector3f(a, bb, cc)).cast<double>();
    std::sort(b.corners.begin(), b.corners.end(), [](const Eigen::Vector3d& u, const Eigen::Vector3d& v) { return u.z() < v.z(); });
    double zmin = 1e300, zmax = -1e300;
    for (const auto& q : b.corners) zmin = std::min(zmin, q.z()), zmax = std::max(zmax, q.z());
    b.height = zmax - zmin;
    b.volume = double(hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z);
  }
  return b;
}

}  // namespace

PipelineResult runStockPcl(const Cloud& cloud_in, const Parameters& p, const StockOptions& o,
                           const Eigen::Vector3d& viewpoint_in) {
  PipelineResult res;
  Stopwatch watch(&res.timing_ms);
  res.points_in = cloud_in.size();
  const bool organized = cloud_in.height > 1;
  const std::optional<Eigen::Vector3d> axis = preprocess::parseUpAxis(p.up_axis);
  if (!axis) throw std::invalid_argument("stock-PCL baseline: up_axis must be one of +x -x +y -y +z -z, not 'auto'");
  const Eigen::Vector3d given_up = *axis;

  // --- preprocess: drop garbage, level to the given axis refined by the
  // largest horizontal plane (SAC), voxel grid ---------------------------------
  Cloud::Ptr raw(new Cloud);
  raw->reserve(cloud_in.size());
  const float lim = static_cast<float>(p.max_abs_coordinate);
  for (const auto& q : cloud_in)
    if (std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::abs(q.x) <= lim && std::abs(q.y) <= lim &&
        std::abs(q.z) <= lim)
      raw->push_back(q);
  if (raw->size() < cloud_in.size())
    res.warnings.push_back(std::to_string(cloud_in.size() - raw->size()) + " non-finite or out-of-range points dropped");
  Eigen::Matrix3d R = Eigen::Quaterniond::FromTwoVectors(given_up, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  {
    const Cloud::Ptr coarse = voxelGrid(raw, 0.05);
    Cloud::Ptr lev(new Cloud);
    Eigen::Affine3f T = Eigen::Affine3f::Identity();
    T.linear() = R.cast<float>();
    pcl::transformPointCloud(*coarse, *lev, T);
    if (lev->size() >= 200 && o.up_refine_deg > 0) {
      pcl::SACSegmentation<pcl::PointXYZ> seg;
      seg.setOptimizeCoefficients(true);
      seg.setModelType(pcl::SACMODEL_PERPENDICULAR_PLANE);
      seg.setMethodType(pcl::SAC_RANSAC);
      seg.setAxis(Eigen::Vector3f::UnitZ());
      seg.setEpsAngle(o.up_refine_deg * M_PI / 180.0);
      seg.setDistanceThreshold(0.03);
      seg.setMaxIterations(o.sac_max_iterations);
      seg.setInputCloud(lev);
      pcl::PointIndices inl;
      pcl::ModelCoefficients coef;
      seg.segment(inl, coef);
      if (inl.indices.size() >= 200 && coef.values.size() == 4) {
        Eigen::Vector3d n(coef.values[0], coef.values[1], coef.values[2]);
        n.normalize();
        if (n.z() < 0) n = -n;
        if (n.z() > std::cos(o.up_refine_deg * M_PI / 180.0))
          R = Eigen::Quaterniond::FromTwoVectors(n, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R;
      }
    }
  }
  res.up = R.transpose() * Eigen::Vector3d::UnitZ();
  Cloud::Ptr levelled(new Cloud);
  {
    Eigen::Affine3f T = Eigen::Affine3f::Identity();
    T.linear() = R.cast<float>();
    pcl::transformPointCloud(*raw, *levelled, T);
    raw.reset();
  }
  const Cloud::Ptr cloud = voxelGrid(levelled, p.voxel_size);
  levelled.reset();
  res.points_used = cloud->size();
  watch.mark("preprocess");
  if (cloud->size() < 20) {
    res.warnings.push_back("too few points to find walls");
    watch.total();
    return res;
  }

  // --- normals: NormalEstimationOMP, k nearest ----------------------------------
  const Eigen::Vector3f viewpoint = (R * viewpoint_in).cast<float>();
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  {
    pcl::NormalEstimationOMP<pcl::PointXYZ, pcl::Normal> ne(o.normal_threads);
    ne.setInputCloud(cloud);
    ne.setSearchMethod(tree);
    ne.setKSearch(p.normal_k);
    ne.setViewPoint(viewpoint.x(), viewpoint.y(), viewpoint.z());
    ne.compute(*normals);
  }
  watch.mark("normals");

  // --- floor and ceiling: z histogram of horizontal-surface points (paper 3.1) --
  const std::size_t n = cloud->size();
  segmentation::Points pts(n);
  for (std::size_t i = 0; i < n; ++i) pts[i] = (*cloud)[i].getVector3fMap();
  auto nz = [&](std::size_t i) { return std::isfinite((*normals)[i].normal_z) ? (*normals)[i].normal_z : 0.0f; };
  auto finiteNormal = [&](std::size_t i) { return std::isfinite((*normals)[i].normal_z); };
  {
    float zmin = 1e30f, zmax = -1e30f;
    for (std::size_t i = 0; i < n; ++i)
      if (finiteNormal(i) && std::abs(nz(i)) > p.horizontal_normal_z) zmin = std::min(zmin, pts[i].z()), zmax = std::max(zmax, pts[i].z());
    if (zmax >= zmin) {
      const double bin = p.histogram_bin;
      std::vector<int> h(static_cast<std::size_t>((zmax - zmin) / bin) + 1, 0);
      for (std::size_t i = 0; i < n; ++i)
        if (finiteNormal(i) && std::abs(nz(i)) > p.horizontal_normal_z) ++h[static_cast<std::size_t>((pts[i].z() - zmin) / bin)];
      const int top = *std::max_element(h.begin(), h.end());
      std::vector<double> peaks;  // local maxima holding >= 10 % of the highest bin
      for (std::size_t b = 0; b < h.size(); ++b)
        if (h[b] >= std::max(20, top / 10) && (b == 0 || h[b] >= h[b - 1]) && (b + 1 == h.size() || h[b] >= h[b + 1]))
          peaks.push_back(zmin + (b + 0.5) * bin);
      if (!peaks.empty() && peaks.front() < viewpoint.z()) res.floor = peaks.front();
      if (!peaks.empty() && peaks.back() > viewpoint.z() && (!res.floor || peaks.back() - *res.floor >= p.min_room_height))
        res.ceiling = peaks.back();
    }
  }
  std::vector<float> vertical_z;
  for (std::size_t i = 0; i < n; ++i)
    if (finiteNormal(i) && std::abs(nz(i)) < p.vertical_normal_z) vertical_z.push_back(pts[i].z());
  if (vertical_z.size() < 20) {
    res.warnings.push_back("no vertical structure: no walls");
    watch.total();
    return res;
  }
  std::sort(vertical_z.begin(), vertical_z.end());
  const double floor_z = res.floor ? *res.floor : vertical_z[vertical_z.size() / 200];
  const double top_z = res.ceiling ? *res.ceiling : vertical_z[vertical_z.size() - 1 - vertical_z.size() / 200];
  if (!res.floor) res.warnings.push_back("no floor in view: floor taken at the foot of the vertical structure");
  if (!res.ceiling) res.warnings.push_back("no ceiling in view: wall height taken from the top of the vertical structure");
  watch.mark("floor_ceiling");
  if (top_z - floor_z < 0.5) {
    res.warnings.push_back("scene lower than 0.5 m: no walls");
    watch.total();
    return res;
  }

  // --- walls: iterative SACSegmentation of planes parallel to up -----------------
  std::vector<segmentation::WallPlane> walls;
  {
    Cloud::Ptr pool(new Cloud);
    std::vector<int> orig;  // pool point -> cloud index
    for (std::size_t i = 0; i < n; ++i)
      if (finiteNormal(i) && std::abs(nz(i)) < p.vertical_normal_z && pts[i].z() > floor_z + 0.05) {
        pool->push_back((*cloud)[i]);
        orig.push_back(static_cast<int>(i));
      }
    const Eigen::Vector2d vp2 = viewpoint.head<2>().cast<double>();
    pcl::SACSegmentation<pcl::PointXYZ> seg;
    seg.setOptimizeCoefficients(true);
    seg.setModelType(pcl::SACMODEL_PARALLEL_PLANE);
    seg.setMethodType(pcl::SAC_RANSAC);
    seg.setAxis(Eigen::Vector3f::UnitZ());
    seg.setEpsAngle(o.sac_axis_eps_deg * M_PI / 180.0);
    seg.setDistanceThreshold(p.wall_distance);
    seg.setMaxIterations(o.sac_max_iterations);
    for (int round = 0; round < 4 * p.max_walls && static_cast<int>(walls.size()) < p.max_walls; ++round) {
      if (static_cast<int>(pool->size()) < p.min_wall_points) break;
      seg.setInputCloud(pool);
      pcl::PointIndices::Ptr inl(new pcl::PointIndices);
      pcl::ModelCoefficients coef;
      seg.segment(*inl, coef);
      if (static_cast<int>(inl->indices.size()) < p.min_wall_points || coef.values.size() != 4) break;
      Eigen::Vector2d nrm(coef.values[0], coef.values[1]);
      const double nn = nrm.norm();
      if (nn < 1e-6) break;
      nrm /= nn;
      const double d = coef.values[3] / nn;
      std::vector<int> members;
      members.reserve(inl->indices.size());
      Eigen::Vector2d c = Eigen::Vector2d::Zero();
      for (int k : inl->indices) {
        members.push_back(orig[k]);
        c += pts[orig[k]].head<2>().cast<double>();
      }
      c /= static_cast<double>(members.size());
      // Extract the inliers and go on with the rest.
      {
        pcl::ExtractIndices<pcl::PointXYZ> ex;
        ex.setInputCloud(pool);
        ex.setIndices(inl);
        ex.setNegative(true);
        Cloud::Ptr rest(new Cloud);
        ex.filter(*rest);
        std::vector<char> used(pool->size(), 0);
        for (int k : inl->indices) used[k] = 1;
        std::vector<int> rest_orig;
        rest_orig.reserve(rest->size());
        for (std::size_t k = 0; k < orig.size(); ++k)
          if (!used[k]) rest_orig.push_back(orig[k]);
        pool = rest;
        orig.swap(rest_orig);
      }
      const Eigen::Vector2d point = c - (nrm.dot(c) + d) * nrm;
      if ((vp2 - point).dot(nrm) < 0) nrm = -nrm;
      const Eigen::Vector2d dir(nrm.y(), -nrm.x());
      // The paper's height rule, and the rules of ours that a user would add
      // once the paper's rule took cupboard fronts and leaves for walls.
      segmentation::addWallSegments(pts, members, point, dir, nrm, floor_z, top_z, res.ceiling.has_value(), p, walls);
    }
  }
  watch.mark("walls");

  // --- doors: our doorway evidence and leaf fit on the SAC walls -----------------
  const Eigen::Matrix3d Rt = R.transpose();
  auto toInput = [&](const Eigen::Vector3d& v) -> Eigen::Vector3d { return Rt * v; };
  auto onFloor = [&](const Eigen::Vector2d& xy) { return Eigen::Vector3d(xy.x(), xy.y(), floor_z); };
  state::DoorStage door_stage = state::findDoors(pts, walls, floor_z, top_z, res.ceiling.has_value(), viewpoint, Rt, organized, p);
  res.doors = std::move(door_stage.doors);
  const std::vector<char>& is_leaf = door_stage.is_leaf;
  std::vector<char> is_wall(n, 0);
  for (const segmentation::WallPlane& wall : walls)
    for (int i : wall.inliers) is_wall[i] = 1;
  watch.mark("doors");

  // --- segments: RegionGrowing, MomentOfInertiaEstimation boxes ---------------
  {
    pcl::IndicesPtr rest(new std::vector<int>);
    for (std::size_t i = 0; i < n; ++i) {
      const bool horizontal_slab = std::abs(nz(i)) > p.horizontal_normal_z &&
                                   (std::abs(pts[i].z() - floor_z) < 0.05 || (res.ceiling && std::abs(pts[i].z() - top_z) < 0.05));
      if (finiteNormal(i) && !horizontal_slab && !is_wall[i] && !is_leaf[i]) rest->push_back(static_cast<int>(i));
    }
    std::vector<pcl::PointIndices> clusters;
    if (!rest->empty()) {
      pcl::RegionGrowing<pcl::PointXYZ, pcl::Normal> rg;
      rg.setMinClusterSize(p.min_region_points);
      rg.setMaxClusterSize(std::numeric_limits<int>::max());
      rg.setSearchMethod(tree);
      rg.setNumberOfNeighbours(p.normal_k);
      rg.setInputCloud(cloud);
      rg.setIndices(rest);
      rg.setInputNormals(normals);
      rg.setSmoothnessThreshold(static_cast<float>(p.region_angle_deg * M_PI / 180.0));
      rg.setCurvatureThreshold(static_cast<float>(p.region_curvature));
      rg.extract(clusters);
    }
    for (const auto& cl : clusters) {
      const Box b = boxOf(cloud, pcl::IndicesPtr(new std::vector<int>(cl.indices.begin(), cl.indices.end())));
      SegmentResult s;
      s.id = static_cast<int>(res.others.size());
      for (int k = 0; k < 8; ++k) s.corners[k] = toInput(b.corners[k]);
      s.height = b.height;
      s.volume = b.volume;
      s.oriented_box = b.oriented;
      res.others.push_back(s);
    }
    for (std::size_t wi = 0; wi < walls.size(); ++wi) {
      const auto& w = walls[wi];
      const Box b = boxOf(cloud, pcl::IndicesPtr(new std::vector<int>(w.inliers.begin(), w.inliers.end())));
      WallResult r;
      r.id = static_cast<int>(wi);
      for (int k = 0; k < 8; ++k) r.corners[k] = toInput(b.corners[k]);
      r.height = w.z_max - floor_z;
      r.length = w.s_max - w.s_min;
      r.line_point = toInput(onFloor(w.point + w.s_min * w.direction));
      r.line_direction = toInput(Eigen::Vector3d(w.direction.x(), w.direction.y(), 0));
      r.normal = toInput(Eigen::Vector3d(w.normal.x(), w.normal.y(), 0));
      r.points = w.inliers.size();
      res.walls.push_back(r);
    }
  }
  watch.mark("segments");

  // --- boundary points of walls and leaves (paper 3.3.1) ------------------------
  {
    pcl::IndicesPtr idx(new std::vector<int>);
    for (std::size_t i = 0; i < n; ++i)
      if ((is_wall[i] || is_leaf[i]) && finiteNormal(i)) idx->push_back(static_cast<int>(i));
    if (!idx->empty()) {
      pcl::BoundaryEstimation<pcl::PointXYZ, pcl::Normal, pcl::Boundary> be;
      be.setInputCloud(cloud);
      be.setInputNormals(normals);
      be.setIndices(idx);
      be.setSearchMethod(tree);
      be.setKSearch(p.boundary_k);
      be.setAngleThreshold(static_cast<float>(p.boundary_angle_deg * M_PI / 180.0));
      pcl::PointCloud<pcl::Boundary> flags;
      be.compute(flags);
      std::size_t count = 0;
      for (const auto& f : flags) count += f.boundary_point != 0;
      res.trace.push_back("boundary points of walls and leaves: " + std::to_string(count) + " of " + std::to_string(idx->size()));
    }
  }
  watch.mark("boundary");
  watch.total();
  return res;
}

}  // namespace baseline
}  // namespace dsr
