// The search structures the speed of the pipeline rests on, checked against
// brute force on random points (seeds printed): the flat cell hash, the voxel
// grid, the neighbour grid and the normals from cell moments.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "door_state_recognition/preprocess/cell_map.hpp"
#include "door_state_recognition/preprocess/preprocess.hpp"
#include "door_state_recognition/segmentation/neighbour_grid.hpp"
#include "door_state_recognition/segmentation/segmentation.hpp"
#include "door_state_recognition/util/radix_sort.hpp"

using namespace dsr;

namespace {

std::vector<Eigen::Vector3f> randomPoints(unsigned seed, std::size_t n, float half, const Eigen::Vector3f& centre) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-half, half);
  std::vector<Eigen::Vector3f> pts(n);
  for (auto& p : pts) p = centre + Eigen::Vector3f(u(rng), u(rng), u(rng));
  return pts;
}

// The voxel grid done the obvious way: each voxel's centroid, in the order
// its first point came.
std::vector<Eigen::Vector3f> naiveCentroids(const std::vector<Eigen::Vector3f>& pts, double leaf) {
  std::map<std::tuple<long, long, long>, std::pair<Eigen::Vector3d, int>> cells;
  std::vector<std::tuple<long, long, long>> order;
  for (const auto& p : pts) {
    const auto k = std::make_tuple(static_cast<long>(std::floor(p.x() * (1 / leaf))), static_cast<long>(std::floor(p.y() * (1 / leaf))),
                                   static_cast<long>(std::floor(p.z() * (1 / leaf))));
    auto it = cells.find(k);
    if (it == cells.end()) {
      cells[k] = {p.cast<double>(), 1};
      order.push_back(k);
    } else {
      it->second.first += p.cast<double>();
      ++it->second.second;
    }
  }
  std::vector<Eigen::Vector3f> out;
  for (const auto& k : order) out.push_back((cells[k].first / cells[k].second).cast<float>());
  return out;
}

}  // namespace

TEST(CellMap, NumbersKeysInOrderOfFirstInsertionAndFindsThemAfterGrowing) {
  preprocess::CellMap map(4);
  std::vector<std::uint64_t> keys;
  for (int i = 0; i < 5000; ++i) keys.push_back(preprocess::packCell(i * 7 - 9000, -i, i % 13));
  for (std::size_t i = 0; i < keys.size(); ++i) EXPECT_EQ(map.insert(keys[i]), i);
  for (std::size_t i = 0; i < keys.size(); ++i) EXPECT_EQ(map.insert(keys[i]), i);  // again: same number
  EXPECT_EQ(map.size(), keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) EXPECT_EQ(map.find(keys[i]), i);
  EXPECT_EQ(map.find(preprocess::packCell(1, 1, 1) + 12345), preprocess::CellMap::kNone);
}

TEST(VoxelGrid, EqualsANaiveCentroidPerVoxelInFirstSeenOrder) {
  for (unsigned seed : {1u, 2u, 3u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    // Far from the origin and on both sides of zero (negative cells).
    const auto pts = randomPoints(seed, 20000, 0.5f, seed == 3 ? Eigen::Vector3f(1000, -2000, 5) : Eigen::Vector3f::Zero());
    const double leaf = 0.05;
    const auto naive = naiveCentroids(pts, leaf);
    const auto out = preprocess::voxelDownsample(pts, leaf);
    ASSERT_EQ(out.size(), naive.size());
    for (std::size_t i = 0; i < out.size(); ++i) EXPECT_LT((out[i] - naive[i]).norm(), 1e-3f) << "voxel " << i;
  }
}

TEST(VoxelGrid, LargeCloudsGiveExactlyTheNaiveCentroidsAndSanitizingInThePassChangesNothing) {
  // Enough points for the voxel grid to share its cells among the cores, in
  // runs along a scan line (as a scanner delivers them), with garbage mixed in.
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f), jitter(-0.004f, 0.004f);
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (int line = 0; line < 400; ++line) {
    const Eigen::Vector3f a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
    for (int k = 0; k < 300; ++k) {
      const Eigen::Vector3f p = a + (b - a) * (k / 300.0f) + Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng));
      cloud.push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    }
    cloud.push_back(pcl::PointXYZ(std::nanf(""), 0, 0));
    cloud.push_back(pcl::PointXYZ(0, 2e4f, 0));
  }
  const double leaf = 0.02, max_abs = 1e4;
  const auto pts = preprocess::sanitize(cloud, max_abs);
  ASSERT_EQ(pts.size(), 400u * 300u);
  const auto naive = naiveCentroids(pts, leaf);
  const auto out = preprocess::voxelDownsample(pts, leaf);
  ASSERT_EQ(out.size(), naive.size());
  for (std::size_t i = 0; i < out.size(); ++i) ASSERT_EQ(out[i], naive[i]) << "voxel " << i;
  std::size_t kept = 0;
  const auto fused = preprocess::sanitizeAndDownsample(cloud, max_abs, leaf, &kept);
  EXPECT_EQ(kept, pts.size());
  EXPECT_EQ(fused, out);
  // Spread too wide for the dense index, the hash map (shared among the cores) serves: the same result.
  auto wide = pts;
  wide.push_back(Eigen::Vector3f(9000, -9000, 9000));
  wide.push_back(Eigen::Vector3f(-9000, 9000, -9000));
  const auto naive_wide = naiveCentroids(wide, leaf);
  const auto out_wide = preprocess::voxelDownsample(wide, leaf);
  ASSERT_EQ(out_wide.size(), naive_wide.size());
  for (std::size_t i = 0; i < out_wide.size(); ++i) ASSERT_EQ(out_wide[i], naive_wide[i]) << "voxel " << i;
}

TEST(NeighbourGrid, FindsExactlyThePointsWithinTheRadius) {
  for (unsigned seed : {11u, 12u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const auto pts = randomPoints(seed, 3000, 0.4f, Eigen::Vector3f(-3, 2, 0));
    const float cell = 0.05f;
    const segmentation::NeighbourGrid grid(pts, cell);
    ASSERT_EQ(grid.size(), pts.size());
    std::vector<int> idx;
    std::vector<float> d2;
    for (float r : {0.03f, 0.05f, 0.09f}) {  // within one cell, and up to two
      for (int i = 0; i < 300; ++i) {
        grid.within(i, r, idx, d2);
        std::vector<int> expect;
        for (int j = 0; j < static_cast<int>(pts.size()); ++j)
          if (j != i && (pts[j] - pts[i]).squaredNorm() <= r * r) expect.push_back(j);
        std::sort(idx.begin(), idx.end());
        EXPECT_EQ(idx, expect) << "point " << i << " radius " << r;
      }
    }
    // Every point sits in exactly one cell, and the cell's neighbours include it.
    std::vector<int> seen(pts.size(), 0);
    std::vector<std::uint32_t> nbs;
    for (std::size_t c = 0; c < grid.cells(); ++c) {
      for (const int* it = grid.cellBegin(c); it != grid.cellEnd(c); ++it) ++seen[*it];
      grid.neighbourCells(c, 1, nbs);
      EXPECT_NE(std::find(nbs.begin(), nbs.end(), c), nbs.end());
    }
    EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int s) { return s == 1; }));
  }
}

// A small box is indexed densely, a huge one by the hash map: the same
// cells, numbered alike, the same neighbours, and the same normals.
TEST(NeighbourGrid, DenseAndHashedIndexesAgree) {
  const auto pts = randomPoints(13, 3000, 0.4f, Eigen::Vector3f(-3, 2, 0));
  auto far = pts;
  far.push_back(Eigen::Vector3f(5000, -4000, 300));  // a bounding box far too large for the dense index
  const segmentation::NeighbourGrid dense(pts, 0.05f), hashed(far, 0.05f);
  ASSERT_GT(dense.coarseCells(), 0u);
  ASSERT_EQ(hashed.coarseCells(), 0u);
  ASSERT_EQ(hashed.cells(), dense.cells() + 1);
  std::vector<std::uint32_t> a, b;
  for (std::size_t c = 0; c < dense.cells(); ++c) {
    ASSERT_EQ(dense.coord(c), hashed.coord(c));
    ASSERT_EQ(std::vector<int>(dense.cellBegin(c), dense.cellEnd(c)), std::vector<int>(hashed.cellBegin(c), hashed.cellEnd(c)));
    for (int ring : {1, 2}) {
      dense.neighbourCells(c, ring, a);
      hashed.neighbourCells(c, ring, b);
      ASSERT_EQ(a, b) << "cell " << c << " ring " << ring;
    }
  }
  const auto na = segmentation::estimateNormals(pts, dense, 16, Eigen::Vector3f::Zero());
  const auto nb = segmentation::estimateNormals(far, hashed, 16, Eigen::Vector3f::Zero());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ASSERT_EQ(na.n[i], nb.n[i]) << "point " << i;
    ASSERT_EQ(na.curvature[i], nb.curvature[i]) << "point " << i;
  }
}

// Clouds large enough to be gridded in two halves at once: the dense and
// hashed indexes still agree cell by cell, point by point.
TEST(NeighbourGrid, DenseAndHashedIndexesAgreeWhenBuiltInHalves) {
  const auto pts = randomPoints(17, 60000, 0.4f, Eigen::Vector3f(1, -2, 0.5f));
  auto far = pts;
  far.push_back(Eigen::Vector3f(-5000, 4000, 300));
  const segmentation::NeighbourGrid dense(pts, 0.05f), hashed(far, 0.05f);
  ASSERT_GT(dense.coarseCells(), 0u);
  ASSERT_EQ(hashed.coarseCells(), 0u);
  ASSERT_EQ(hashed.cells(), dense.cells() + 1);
  std::size_t points = 0;
  for (std::size_t c = 0; c < dense.cells(); ++c) {
    ASSERT_EQ(dense.coord(c), hashed.coord(c));
    const std::vector<int> in(dense.cellBegin(c), dense.cellEnd(c));
    ASSERT_EQ(in, std::vector<int>(hashed.cellBegin(c), hashed.cellEnd(c)));
    ASSERT_TRUE(std::is_sorted(in.begin(), in.end())) << "cell " << c;
    for (std::size_t k = 0; k < in.size(); ++k) {
      ASSERT_EQ(dense.cellPoints(c)[k], pts[in[k]]);
      ASSERT_EQ(dense.point(in[k]), pts[in[k]]);
    }
    points += in.size();
  }
  EXPECT_EQ(points, pts.size());
}

// The radix sorts put pairs in std::sort's order, ties, -0 and negatives included.
// util::sortPairs puts both lists in std::sort's order (pairs compared
// whole: equal values in the order of their ints).
static void expectSortedAsStdSortDoes(std::vector<std::pair<double, int>> a, std::vector<std::pair<float, int>> b, int round) {
  auto ea = a;
  auto eb = b;
  std::sort(ea.begin(), ea.end());
  std::sort(eb.begin(), eb.end());
  util::sortPairs(a);
  util::sortPairs(b);
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].second, ea[i].second) << "round " << round << " at " << i;
    ASSERT_EQ(a[i].first, ea[i].first);
  }
  for (std::size_t i = 0; i < b.size(); ++i) {
    ASSERT_EQ(b[i].second, eb[i].second) << "round " << round << " at " << i;
    ASSERT_EQ(b[i].first, eb[i].first);
  }
}

TEST(RadixSort, PairsInStdSortOrder) {
  std::mt19937 rng(21);
  std::uniform_int_distribution<int> small(-20, 20);
  for (int round = 0; round < 20; ++round) {
    const std::size_t n = 50 + 300 * round;
    std::vector<std::pair<double, int>> a;
    std::vector<std::pair<float, int>> b;
    for (std::size_t i = 0; i < n; ++i) {
      // Few distinct values (ties), both zeros, large and tiny magnitudes.
      const int k = small(rng);
      const double d = k == 0 ? (i % 2 ? -0.0 : 0.0) : k * (k % 3 == 0 ? 1e-300 : k % 3 == 1 ? 0.37 : 1e12);
      a.push_back({d, static_cast<int>(i)});  // ascending ints: the radix path
      b.push_back({std::abs(static_cast<float>(d)), std::abs(small(rng)) * 1000 + small(rng) + 20});
    }
    ASSERT_NO_FATAL_FAILURE(expectSortedAsStdSortDoes(a, b, round));
  }
}

// Values spread as positions along a wall or deviations from it (the
// bucket path): std::sort's order, with repeated values, both zeros, ints
// ascending or not, a cluster too dense for the buckets (the other paths),
// and an extreme value that leaves most buckets empty.
TEST(RadixSort, SpreadValuesInStdSortOrder) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> along(-2.0, 2.5);
  std::normal_distribution<float> dev(0.0f, 0.01f);
  std::uniform_int_distribution<int> ints(-50, 5000), pick(0, 9);
  for (int round = 0; round < 16; ++round) {
    const std::size_t n = 64 + 997 * round;
    std::vector<std::pair<double, int>> a;
    std::vector<std::pair<float, int>> b;
    for (std::size_t i = 0; i < n; ++i) {
      double d = along(rng);
      if (pick(rng) == 0) d = std::round(d * 100) / 100;  // repeated values
      if (pick(rng) == 1) d = i % 2 ? -0.0 : 0.0;
      if (round % 4 == 3 && i == n / 2) d = 1e9;
      if (round % 4 == 2 && i < n / 3) d = 1.0 + 1e-12 * static_cast<double>(i % 7);
      a.push_back({d, round % 2 ? ints(rng) : static_cast<int>(i)});
      float f = std::abs(dev(rng));
      if (pick(rng) == 0) f = std::round(f * 1000) / 1000;
      if (pick(rng) == 1) f = i % 2 ? -0.0f : 0.0f;
      b.push_back({f, round % 2 ? static_cast<int>(i) : ints(rng) % 200});
    }
    ASSERT_NO_FATAL_FAILURE(expectSortedAsStdSortDoes(a, b, round));
  }
}

TEST(Normals, PlanesGetTheirNormalTowardsTheViewpointAndEdgesACurvature) {
  // Two perpendicular planes sampled at 2 cm with 2 mm noise: a floor z = 0
  // and a tilted wall through x = 1.
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.0f, 0.002f);
  const Eigen::Vector3f wall_n = Eigen::Vector3f(-1, 0.2f, 0).normalized();
  const Eigen::Vector3f wall_u = Eigen::Vector3f(0.2f, 1, 0).normalized();
  std::vector<Eigen::Vector3f> pts;
  std::vector<int> kind;  // 0 floor, 1 wall
  for (float a = -1.0f; a <= 1.4f; a += 0.02f)
    for (float b = -1.0f; b <= 1.0f; b += 0.02f) {
      const Eigen::Vector3f p(a, b, noise(rng));
      if ((p - Eigen::Vector3f(1, 0, 0)).dot(wall_n) < 0.01f) continue;  // the floor ends at the wall
      pts.push_back(p);
      kind.push_back(0);
    }
  for (float a = -1.0f; a <= 1.0f; a += 0.02f)
    for (float z = 0.02f; z <= 1.5f; z += 0.02f) {
      pts.push_back(Eigen::Vector3f(1, 0, 0) + a * wall_u + Eigen::Vector3f(0, 0, z) + noise(rng) * wall_n);
      kind.push_back(1);
    }
  const segmentation::NeighbourGrid grid(pts, 0.03f);
  const Eigen::Vector3f viewpoint(0, 0, 1);
  const segmentation::Normals n = segmentation::estimateNormals(pts, grid, 16, viewpoint);
  int far_checked = 0, wall_checked = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const float to_wall = std::abs((pts[i] - Eigen::Vector3f(1, 0, 0)).dot(wall_n));
    const bool far = kind[i] == 0 ? to_wall > 0.25f : pts[i].z() > 0.25f;
    const bool near_edge = kind[i] == 0 ? to_wall < 0.02f : pts[i].z() < 0.03f;
    ASSERT_GT(n.n[i].norm(), 0.99f) << "point " << i;
    EXPECT_GT(n.n[i].dot(viewpoint - pts[i]), 0.0f) << "point " << i << " faces away from the viewpoint";
    // Away from the patches' own borders too.
    const bool inside = kind[i] == 0 ? std::abs(pts[i].x()) < 0.9f && std::abs(pts[i].y()) < 0.9f
                                     : std::abs((pts[i] - Eigen::Vector3f(1, 0, 0)).dot(wall_u)) < 0.9f && pts[i].z() < 1.35f;
    if (far && inside) {
      const Eigen::Vector3f truth = kind[i] == 0 ? Eigen::Vector3f::UnitZ() : Eigen::Vector3f(wall_n);
      EXPECT_GT(std::abs(n.n[i].dot(truth)), std::cos(2.0f * static_cast<float>(M_PI) / 180)) << "point " << i;
      EXPECT_LT(n.curvature[i], 0.005f) << "point " << i;
      ++far_checked;
      wall_checked += kind[i];
    }
    if (near_edge && std::abs(pts[i].y()) < 0.8f) {
      EXPECT_GT(n.curvature[i], 0.01f) << "edge point " << i;
    }
  }
  EXPECT_GT(far_checked, 3000);
  EXPECT_GT(wall_checked, 2000);
}
