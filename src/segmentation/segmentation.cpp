#include "door_state_recognition/segmentation/segmentation.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>

namespace dsr {
namespace segmentation {

Normals estimateNormals(const Points& points, const Tree& tree, int k, const Eigen::Vector3f& viewpoint) {
  Normals out;
  out.n.assign(points.size(), Eigen::Vector3f::UnitZ());
  out.curvature.assign(points.size(), 1.0f);
  const int kk = std::min<int>(k, static_cast<int>(points.size()));
  if (kk < 3) return out;
#pragma omp parallel
  {
    std::vector<int> idx(kk);
    std::vector<float> dist(kk);
#pragma omp for schedule(static, 1024)
    for (long long i = 0; i < static_cast<long long>(points.size()); ++i) {
      pcl::PointXYZ q(points[i].x(), points[i].y(), points[i].z());
      const int found = tree.nearestKSearch(q, kk, idx, dist);
      if (found < 3) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int j = 0; j < found; ++j) mean += points[idx[j]].cast<double>();
      mean /= found;
      Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
      for (int j = 0; j < found; ++j) {
        const Eigen::Vector3d d = points[idx[j]].cast<double>() - mean;
        C += d * d.transpose();
      }
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
      Eigen::Vector3f n = es.eigenvectors().col(0).cast<float>();
      if (n.dot(viewpoint - points[i]) < 0) n = -n;
      out.n[i] = n;
      const double sum = es.eigenvalues().sum();
      out.curvature[i] = sum > 0 ? static_cast<float>(es.eigenvalues()(0) / sum) : 0.0f;
    }
  }
  return out;
}

FloorCeiling findFloorCeiling(const Points& points, const Normals& normals, const Parameters& p, double viewpoint_z) {
  FloorCeiling fc;
  std::vector<float> z;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (std::abs(normals.n[i].z()) > p.horizontal_normal_z) z.push_back(points[i].z());
  if (z.size() < 50) return fc;
  const auto [mn, mx] = std::minmax_element(z.begin(), z.end());
  const double z0 = *mn, bin = std::max(p.histogram_bin, (*mx - z0) / 100000.0);
  const std::size_t bins = static_cast<std::size_t>((*mx - z0) / bin) + 1;
  std::vector<int> hist(bins, 0);
  for (float v : z) ++hist[std::min(bins - 1, static_cast<std::size_t>((v - z0) / bin))];
  const int peak = *std::max_element(hist.begin(), hist.end());
  const int threshold = std::max(30, peak / 8);
  // Significant local maxima, low to high.
  std::vector<std::size_t> peaks;
  for (std::size_t b = 0; b < bins; ++b) {
    const int left = b > 0 ? hist[b - 1] : 0, right = b + 1 < bins ? hist[b + 1] : 0;
    if (hist[b] >= threshold && hist[b] >= left && hist[b] >= right) peaks.push_back(b);
  }
  if (peaks.empty()) return fc;
  auto refine = [&](std::size_t b) {  // mean z of the points in the peak's neighbourhood
    double s = 0;
    int n = 0;
    for (float v : z)
      if (std::abs(v - (z0 + (b + 0.5) * bin)) <= 1.5 * bin) s += v, ++n;
    return n ? s / n : z0 + (b + 0.5) * bin;
  };
  const double lo = refine(peaks.front()), hi = refine(peaks.back());
  if (hi - lo >= p.min_room_height) {
    fc.floor = lo;
    fc.ceiling = hi;
  } else if (lo < viewpoint_z) {
    fc.floor = lo;  // one horizontal level below the sensor: the floor
  } else {
    fc.ceiling = hi;
  }
  return fc;
}

namespace {

// Total least squares line of 2-D points: centroid and unit direction.
void fitLine(const std::vector<Eigen::Vector2d>& pts, Eigen::Vector2d& c, Eigen::Vector2d& dir) {
  c.setZero();
  for (const auto& q : pts) c += q;
  c /= static_cast<double>(pts.size());
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  for (const auto& q : pts) C += (q - c) * (q - c).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  dir = es.eigenvectors().col(1);
}

}  // namespace

std::vector<WallPlane> findWalls(const Points& points, const Normals& normals, double floor_z, double height_top,
                                 bool ceiling_known, const Eigen::Vector2d& viewpoint, const Parameters& p) {
  std::vector<int> pool;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (std::abs(normals.n[i].z()) < p.vertical_normal_z && points[i].z() > floor_z + 0.05) pool.push_back(static_cast<int>(i));
  std::vector<WallPlane> walls;
  std::mt19937 rng(static_cast<unsigned>(p.random_seed));
  const double room_h = height_top - floor_z;
  for (int round = 0; round < 4 * p.max_walls && static_cast<int>(walls.size()) < p.max_walls; ++round) {
    if (static_cast<int>(pool.size()) < p.min_wall_points) break;
    // 1-point RANSAC: a point with its (horizontal) normal proposes a plane.
    std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
    std::size_t best_count = 0;
    Eigen::Vector2d best_pt, best_n;
    const std::size_t stride = std::max<std::size_t>(1, pool.size() / 20000);
    for (int it = 0; it < p.ransac_iterations; ++it) {
      const int s = pool[pick(rng)];
      Eigen::Vector2d n(normals.n[s].x(), normals.n[s].y());
      if (n.norm() < 0.5) continue;
      n.normalize();
      const Eigen::Vector2d q(points[s].x(), points[s].y());
      std::size_t count = 0;
      for (std::size_t j = 0; j < pool.size(); j += stride) {
        const int i = pool[j];
        const Eigen::Vector2d r(points[i].x(), points[i].y());
        if (std::abs((r - q).dot(n)) < p.wall_distance &&
            std::abs(n.x() * normals.n[i].x() + n.y() * normals.n[i].y()) > p.wall_normal_agreement)
          ++count;
      }
      if (count > best_count) best_count = count, best_pt = q, best_n = n;
    }
    if (best_count * stride < static_cast<std::size_t>(p.min_wall_points)) break;
    // Refine twice by TLS on the inliers.
    std::vector<int> inl;
    for (int pass = 0; pass < 3; ++pass) {
      inl.clear();
      std::vector<Eigen::Vector2d> q2;
      for (int i : pool) {
        const Eigen::Vector2d r(points[i].x(), points[i].y());
        if (std::abs((r - best_pt).dot(best_n)) < p.wall_distance &&
            std::abs(best_n.x() * normals.n[i].x() + best_n.y() * normals.n[i].y()) > p.wall_normal_agreement) {
          inl.push_back(i);
          q2.push_back(r);
        }
      }
      if (q2.size() < 3 || pass == 2) break;
      Eigen::Vector2d c, dir;
      fitLine(q2, c, dir);
      best_pt = c;
      best_n = Eigen::Vector2d(-dir.y(), dir.x());
    }
    // Remove the inliers from the pool whatever becomes of them.
    {
      std::vector<char> used(points.size(), 0);
      for (int i : inl) used[i] = 1;
      std::vector<int> rest;
      for (int i : pool)
        if (!used[i]) rest.push_back(i);
      pool.swap(rest);
    }
    const Eigen::Vector2d dir(best_n.y(), -best_n.x());
    if ((viewpoint - best_pt).dot(best_n) < 0) best_n = -best_n;
    // Split along the wall at gaps wider than wall_gap.
    std::vector<std::pair<double, int>> along;
    for (int i : inl) along.push_back({(Eigen::Vector2d(points[i].x(), points[i].y()) - best_pt).dot(dir), i});
    std::sort(along.begin(), along.end());
    std::size_t start = 0;
    for (std::size_t k = 1; k <= along.size(); ++k) {
      if (k < along.size() && along[k].first - along[k - 1].first <= p.wall_gap) continue;
      WallPlane w;
      w.point = best_pt;
      w.direction = dir;
      w.normal = best_n;
      w.s_min = along[start].first;
      w.s_max = along[k - 1].first;
      w.z_min = 1e9;
      w.z_max = -1e9;
      for (std::size_t j = start; j < k; ++j) {
        w.inliers.push_back(along[j].second);
        w.z_min = std::min<double>(w.z_min, points[along[j].second].z());
        w.z_max = std::max<double>(w.z_max, points[along[j].second].z());
      }
      start = k;
      const double h = w.z_max - floor_z;
      const bool tall = h >= p.wall_height_ratio * room_h && w.z_min < floor_z + 0.5;
      const bool reaches_top = !ceiling_known || w.z_max > height_top - 0.25;
      // A plane parallel to a stronger wall and close behind or before it
      // (a recessed leaf, trim, a cupboard front) is not another wall.
      bool shadowed = false;
      for (const WallPlane& o : walls) {
        if (std::abs(o.normal.dot(w.normal)) < 0.995) continue;
        const Eigen::Vector2d a = w.point + w.s_min * w.direction, b = w.point + w.s_max * w.direction;
        const double off = std::abs((0.5 * (a + b) - o.point).dot(o.normal));
        const double s0 = std::min((a - o.point).dot(o.direction), (b - o.point).dot(o.direction));
        const double s1 = std::max((a - o.point).dot(o.direction), (b - o.point).dot(o.direction));
        shadowed |= off < 0.3 && s0 < o.s_max && s1 > o.s_min;
      }
      // Without a ceiling to reach, a door leaf is as tall as a wall: then a
      // wall must also be longer than any door.
      const double min_length = ceiling_known ? p.min_wall_length : std::max(p.min_wall_length, p.door_max_width + 0.1);
      if (static_cast<int>(w.inliers.size()) >= p.min_wall_points && w.s_max - w.s_min >= min_length && tall &&
          reaches_top && !shadowed)
        walls.push_back(std::move(w));
    }
  }
  return walls;
}

std::vector<std::vector<int>> growRegions(const Points& points, const Normals& normals, const Tree& tree,
                                         const std::vector<char>& mask, const Parameters& p) {
  const float cos_thr = static_cast<float>(std::cos(p.region_angle_deg * M_PI / 180.0));
  std::vector<int> order;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (mask[i]) order.push_back(static_cast<int>(i));
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return normals.curvature[a] < normals.curvature[b]; });
  std::vector<int> label(points.size(), -1);
  std::vector<std::vector<int>> regions;
  const int k = std::min<int>(p.normal_k, static_cast<int>(points.size()));
  std::vector<int> idx(k);
  std::vector<float> dist(k);
  for (int seed : order) {
    if (label[seed] >= 0 || normals.curvature[seed] > p.region_curvature) continue;
    std::vector<int> region{seed}, stack{seed};
    label[seed] = static_cast<int>(regions.size());
    while (!stack.empty()) {
      const int cur = stack.back();
      stack.pop_back();
      pcl::PointXYZ q(points[cur].x(), points[cur].y(), points[cur].z());
      const int found = tree.nearestKSearch(q, k, idx, dist);
      for (int j = 0; j < found; ++j) {
        const int nb = idx[j];
        if (!mask[nb] || label[nb] >= 0) continue;
        if (std::abs(normals.n[cur].dot(normals.n[nb])) < cos_thr) continue;
        label[nb] = label[seed];
        region.push_back(nb);
        if (normals.curvature[nb] <= p.region_curvature) stack.push_back(nb);
      }
    }
    if (static_cast<int>(region.size()) >= p.min_region_points) {
      regions.push_back(std::move(region));
    } else {
      for (int i : region) label[i] = -2;  // too small: never reused as a seed
    }
  }
  return regions;
}

}  // namespace segmentation
}  // namespace dsr
