// Stations inferred from a cloud's own surfaces (sight.hpp): positions
// inside the scanned space from which the cloud's surfaces are seen, each
// with the points it sees unoccluded (range_sphere.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "door_state_recognition/pipeline/sight.hpp"
#include "door_state_recognition/preprocess/preprocess.hpp"
#include "door_state_recognition/segmentation/neighbour_grid.hpp"
#include "door_state_recognition/segmentation/segmentation.hpp"
#include "range_sphere.hpp"

namespace dsr {
namespace sight {

using namespace detail;

InferredStations inferStations(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Parameters& p) {
  InferredStations out;
  auto t_last = std::chrono::steady_clock::now();
  auto mark = [&](const char* stage) {
    const auto now = std::chrono::steady_clock::now();
    out.timing_ms.emplace_back(stage, std::chrono::duration<double, std::milli>(now - t_last).count());
    t_last = now;
  };
  const Occluders occ = occluders(cloud, p);
  mark("sight_disks");
  if (occ.p.size() < 50) return out;

  // Up: given, or estimated as the pipeline does; positions are placed in
  // the levelled frame.
  std::optional<Eigen::Vector3d> up = preprocess::parseUpAxis(p.up_axis);
  if (!up) up = preprocess::estimateUp(occ.p, occ.n, static_cast<unsigned>(p.random_seed));
  if (!up) up = Eigen::Vector3d::UnitZ();
  out.up = up->normalized();
  const Eigen::Matrix3f R = preprocess::levellingRotation(out.up).cast<float>();
  Occluders lev = occ;
  for (std::size_t i = 0; i < lev.p.size(); ++i) {
    lev.p[i] = R * lev.p[i];
    lev.n[i] = R * lev.n[i];
  }

  // Extent: robust percentiles (a few stray points do not stretch it).
  auto percentile = [&](int axis, double q) {
    std::vector<float> v;
    v.reserve(lev.p.size());
    for (const auto& x : lev.p) v.push_back(x(axis));
    const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())));
    std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
    return v[k];
  };
  const float x0 = percentile(0, 0.005), x1 = percentile(0, 0.995);
  const float y0 = percentile(1, 0.005), y1 = percentile(1, 0.995);
  const float z0 = percentile(2, 0.01), z1 = percentile(2, 0.99);
  // A scanner's height: 1.3 m above the floor, or half the room where lower.
  const float zs = z0 + std::min(1.3f, 0.5f * (z1 - z0));
  // A horizontal grid of about 1 m, at most ~100 positions.
  const double area = std::max(1e-3, static_cast<double>(x1 - x0) * (y1 - y0));
  const float g = static_cast<float>(std::max(1.0, std::sqrt(area / 100)));
  std::vector<Eigen::Vector3f> cand;
  for (float x = x0 + g / 2; x < x1; x += g)
    for (float y = y0 + g / 2; y < y1; y += g) cand.emplace_back(x, y, zs);

  // Positions a scanner could stand at: free (nothing of the cloud within
  // kClearance) and enclosed (walls all around: of 36 horizontal rays,
  // kMinEnclosed meet the cloud's structure at the scanner's height within
  // the extent; a position outside a room, or in a corridor's open end,
  // sees its walls on one side only). On a 2D occupancy grid of the band
  // +-0.6 m around that height.
  {
    constexpr float kCell = 0.1f, kClearance = 0.3f;
    constexpr int kRays = 36, kMinEnclosed = 31;
    constexpr float kFloorBand = 0.1f, kFloorFrom = 0.6f, kFloorTo = 2.0f, kMinFloorSeen = 0.8f, kFloorExtent = 0.1f;
    const int nx = static_cast<int>(std::ceil((x1 - x0) / kCell)) + 1, ny = static_cast<int>(std::ceil((y1 - y0) / kCell)) + 1;
    std::vector<char> occupied(static_cast<std::size_t>(nx) * ny, 0);
    auto cellOf = [&](float x, float y, int& i, int& j) {
      i = static_cast<int>(std::floor((x - x0) / kCell));
      j = static_cast<int>(std::floor((y - y0) / kCell));
      return i >= 0 && j >= 0 && i < nx && j < ny;
    };
    // Floor seen (below): the cells holding a point within kFloorBand of the floor.
    std::vector<char> floor_seen(occupied.size(), 0);
    std::size_t floor_cells = 0;
    for (const auto& x : lev.p) {
      int i, j;
      if (!cellOf(x.x(), x.y(), i, j)) continue;
      const std::size_t k = static_cast<std::size_t>(j) * nx + i;
      if (std::abs(x.z() - zs) <= 0.6f) occupied[k] = 1;
      if (std::abs(x.z() - z0) <= kFloorBand) floor_cells += !floor_seen[k], floor_seen[k] = 1;
    }
    // Free: only points in a band a little wider than kClearance around
    // the height can be that close; they are bucketed in columns of that
    // width, and a candidate tests the 3x3 columns around it.
    constexpr float kReach = kClearance + 0.01f;
    std::vector<Eigen::Vector3f> band;
    Eigen::Vector2f blo = Eigen::Vector2f::Constant(std::numeric_limits<float>::max()), bhi = -blo;
    for (const auto& x : lev.p)
      if (std::abs(x.z() - zs) <= kReach) {
        band.push_back(x);
        blo = blo.cwiseMin(x.head<2>());
        bhi = bhi.cwiseMax(x.head<2>());
      }
    const int bx = band.empty() ? 1 : static_cast<int>((bhi.x() - blo.x()) / kReach) + 1;
    const int by = band.empty() ? 1 : static_cast<int>((bhi.y() - blo.y()) / kReach) + 1;
    auto column = [&](const Eigen::Vector3f& x, int& i, int& j) {
      i = static_cast<int>(std::floor((x.x() - blo.x()) / kReach));
      j = static_cast<int>(std::floor((x.y() - blo.y()) / kReach));
    };
    std::vector<std::size_t> start(static_cast<std::size_t>(bx) * by + 1, 0);
    std::vector<Eigen::Vector3f> bucketed(band.size());
    {
      std::vector<std::size_t> col(band.size());
      for (std::size_t k = 0; k < band.size(); ++k) {
        int i, j;
        column(band[k], i, j);
        col[k] = static_cast<std::size_t>(std::clamp(j, 0, by - 1)) * bx + std::clamp(i, 0, bx - 1);
        ++start[col[k] + 1];
      }
      for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
      std::vector<std::size_t> fill(start.begin(), start.end() - 1);
      for (std::size_t k = 0; k < band.size(); ++k) bucketed[fill[col[k]]++] = band[k];
    }
    auto clearAt = [&](const Eigen::Vector3f& c) {
      int ci, cj;
      column(c, ci, cj);
      for (int j = std::max(0, cj - 1); j <= std::min(by - 1, cj + 1); ++j)
        for (int i = std::max(0, ci - 1); i <= std::min(bx - 1, ci + 1); ++i) {
          const std::size_t b = static_cast<std::size_t>(j) * bx + i;
          for (std::size_t k = start[b]; k < start[b + 1]; ++k)
            if (!((bucketed[k] - c).squaredNorm() > kClearance * kClearance)) return false;
        }
      return true;
    };
    // Floor seen: a scanner sees the floor around where it stands, out to
    // the first wall or furniture; a position in a room seen only through
    // its doorways (the floor there seen in a few wedges) is no station's.
    // (Where the cloud holds no floor to speak of, cut away or never
    // scanned, over less than kFloorExtent of its extent: not asked.)
    const bool ask_floor = static_cast<double>(floor_cells) >= kFloorExtent * static_cast<double>(floor_seen.size());
    std::vector<Eigen::Vector3f> kept;
    for (const auto& c : cand) {
      if (!clearAt(c)) continue;
      // Rays free for kFloorFrom or more: on each, floor seen between
      // kFloorFrom and kFloorTo or the first structure.
      int enclosed = 0, free_rays = 0, floor_hits = 0;
      for (int r = 0; r < kRays; ++r) {
        const float a = static_cast<float>(2 * kPi * r / kRays), dx = std::cos(a) * kCell / 2, dy = std::sin(a) * kCell / 2;
        int i, j, step = 0;
        bool hit = false, floor_on_ray = false;
        float reach = 0;
        for (float x = c.x(), y = c.y(); cellOf(x, y, i, j); x += dx, y += dy, ++step) {
          reach = step * kCell / 2;
          if (occupied[static_cast<std::size_t>(j) * nx + i]) {
            hit = true;
            break;
          }
          if (reach >= kFloorFrom && reach <= kFloorTo && floor_seen[static_cast<std::size_t>(j) * nx + i]) floor_on_ray = true;
        }
        enclosed += hit;
        if (reach >= kFloorFrom + kCell) ++free_rays, floor_hits += floor_on_ray;
      }
      if (enclosed >= kMinEnclosed && (!ask_floor || floor_hits >= kMinFloorSeen * free_rays)) kept.push_back(c);
    }
    cand.swap(kept);
  }
  mark("sight_candidates");
  if (cand.empty()) return out;

  // Score on a sample of the thinned points: which each position sees,
  // against coarser disks (kScoreVoxel) in coarser bins.
  constexpr double kScoreVoxel = 0.1;
  const Occluders coarse = disks(preprocess::voxelDownsample(lev.p, kScoreVoxel), kScoreVoxel, p);
  const std::size_t stride = std::max<std::size_t>(1, lev.p.size() / 20000);
  std::vector<int> sample;
  for (std::size_t i = 0; i < lev.p.size(); i += stride) sample.push_back(static_cast<int>(i));
  std::vector<std::vector<char>> sees(cand.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (long c = 0; c < static_cast<long>(cand.size()); ++c) {
    RangeSphere sphere(cand[c], 4 * kBin);
    sphere.cast(coarse);
    sees[c].resize(sample.size());
    for (std::size_t k = 0; k < sample.size(); ++k) sees[c][k] = !sphere.hidden(lev.p[sample[k]]);
  }

  mark("sight_score");
  // Greedy cover: the position seeing most of what no chosen one sees, while
  // it adds a station's worth (kMinGain of the sample: main stations), then
  // while it adds kMinGainMinor (minor stations, whose doors only refine).
  constexpr double kMinGain = 0.08, kMinGainMinor = 0.03;
  constexpr int kMaxStations = 6;
  std::vector<char> covered(sample.size(), 0);
  std::vector<std::size_t> chosen;
  std::size_t main_count = 0;
  while (static_cast<int>(chosen.size()) < kMaxStations) {
    std::size_t best = cand.size(), best_gain = 0;
    for (std::size_t c = 0; c < cand.size(); ++c) {
      std::size_t gain = 0;
      for (std::size_t k = 0; k < sample.size(); ++k) gain += sees[c][k] && !covered[k];
      if (gain > best_gain) best_gain = gain, best = c;
    }
    if (best == cand.size() || static_cast<double>(best_gain) < kMinGainMinor * static_cast<double>(sample.size())) break;
    if (static_cast<double>(best_gain) >= kMinGain * static_cast<double>(sample.size()) && main_count == chosen.size())
      ++main_count;
    chosen.push_back(best);
    for (std::size_t k = 0; k < sample.size(); ++k) covered[k] |= sees[best][k];
  }
  if (main_count == 0) return out;
  out.main = main_count;

  // Every input point to each chosen station that sees it (a point seen from
  // two stations is in both scans, as in a survey).
  const Eigen::Matrix3f Rt = R.transpose();
  std::vector<RangeSphere> spheres;
  for (std::size_t c : chosen) {
    spheres.emplace_back(cand[c], kBin);
    out.viewpoints.push_back((Rt * cand[c]).cast<double>());
  }
#pragma omp parallel for schedule(dynamic, 1)
  for (long k = 0; k < static_cast<long>(spheres.size()); ++k) spheres[static_cast<std::size_t>(k)].cast(lev);
  out.clouds.resize(chosen.size());
  const float lim = static_cast<float>(p.max_abs_coordinate);
  const long n = static_cast<long>(cloud.size());
  // Bit s of seen_by[i]: station s sees point i (0: none, or not a point).
  std::vector<std::uint8_t> seen_by(cloud.size(), 0);
#pragma omp parallel for schedule(static, 4096)
  for (long i = 0; i < n; ++i) {
    const Eigen::Vector3f x = cloud.points[static_cast<std::size_t>(i)].getVector3fMap();
    if (!x.allFinite() || x.cwiseAbs().maxCoeff() > lim) continue;
    const Eigen::Vector3f xl = R * x;
    std::uint8_t bits = 0;
    for (std::size_t k = 0; k < spheres.size(); ++k)
      if (!spheres[k].hidden(xl)) bits |= static_cast<std::uint8_t>(1u << k);
    seen_by[static_cast<std::size_t>(i)] = bits ? bits : 0x80;
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const std::uint8_t bits = seen_by[i];
    if (bits == 0x80) ++out.unseen;
    if (bits & 0x80) continue;
    for (std::size_t k = 0; k < spheres.size(); ++k)
      if (bits & (1u << k)) out.clouds[k].push_back(cloud.points[i]);
  }
  mark("sight_assign");
  for (auto& c : out.clouds) {
    c.width = static_cast<std::uint32_t>(c.size());
    c.height = 1;
    c.is_dense = true;
  }
  return out;
}

}  // namespace sight
}  // namespace dsr
