#include "door_state_recognition/preprocess/camera.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <vector>

namespace dsr {
namespace preprocess {

std::optional<Pinhole> fitPinhole(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3f& viewpoint) {
  const int w = static_cast<int>(cloud.width), h = static_cast<int>(cloud.height);
  if (h < 2 || w < 2 || cloud.size() != static_cast<std::size_t>(w) * h) return std::nullopt;
  auto finite = [](const pcl::PointXYZ& q) { return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z); };
  // Pixel coordinates scaled to about [-1, 1].
  const double cu = 0.5 * w, cv = 0.5 * h, sc = 0.5 * w;
  // u = (m1 . X) / (m3 . X), v = (m2 . X) / (m3 . X), X from the viewpoint:
  // two linear equations in m = (m1, m2, m3) per pixel, solved by the
  // eigenvector of the smallest eigenvalue of A^T A.
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector3d>> sample;
  // About 60 samples across the image's short side, and no more than about
  // 5000 in all: a 64-beam LiDAR's 64 x 1024 sweep, no pinhole camera, had
  // every one of its 65k pixels taken to reject it.
  const int grid = std::max({1, std::min(w, h) / 60, static_cast<int>(std::ceil(std::sqrt(w * static_cast<double>(h) / 5000.0)))});
  for (int r = 0; r < h; r += grid)
    for (int c = 0; c < w; c += grid) {
      const pcl::PointXYZ& q = cloud.points[static_cast<std::size_t>(r) * w + c];
      if (!finite(q)) continue;
      const Eigen::Vector3d X = Eigen::Vector3d(q.x, q.y, q.z) - viewpoint.cast<double>();
      if (X.norm() < 1e-3) continue;
      sample.push_back({Eigen::Vector2d((c - cu) / sc, (r - cv) / sc), X});
    }
  if (sample.size() < 100) return std::nullopt;
  // A^T A as the sum over the samples of a a^T + b b^T, a = (X, 0, -u X)
  // and b = (0, X, -v X): only the terms of its nonzero blocks are added
  // (a term of zeros adds +-0, which leaves every sum as it is: a sum
  // starting at +0 is never -0), and only on and above the diagonal, the
  // rest mirrored (the same terms in the same order): the same sums.
  Eigen::Matrix<double, 9, 9> ata = Eigen::Matrix<double, 9, 9>::Zero();
  for (const auto& [uv, X] : sample) {
    const Eigen::Vector3d au = -uv.x() * X, bv = -uv.y() * X;  // the last three of a and of b
    for (int i = 0; i < 3; ++i) {
      for (int j = i; j < 3; ++j) {
        ata(i, j) += X(i) * X(j);
        ata(3 + i, 3 + j) += X(i) * X(j);
        ata(6 + i, 6 + j) += au(i) * au(j) + bv(i) * bv(j);
      }
      for (int j = 0; j < 3; ++j) {
        ata(i, 6 + j) += X(i) * au(j);
        ata(3 + i, 6 + j) += X(i) * bv(j);
      }
    }
  }
  for (int i = 0; i < 9; ++i)
    for (int j = i + 1; j < 9; ++j) ata(j, i) = ata(i, j);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> es(ata);
  const Eigen::Matrix<double, 9, 1> m = es.eigenvectors().col(0);
  Eigen::Matrix3d M;
  M.row(0) = m.segment<3>(0).transpose();
  M.row(1) = m.segment<3>(3).transpose();
  M.row(2) = m.segment<3>(6).transpose();
  if (!M.allFinite() || std::abs(M.determinant()) < 1e-12) return std::nullopt;
  // Within a pixel at nine in ten of the sampled pixels.
  std::vector<double> err;
  int ahead = 0;
  for (const auto& [uv, X] : sample) {
    const Eigen::Vector3d y = M * X;
    ahead += y.z() > 0;
    err.push_back(std::abs(y.z()) > 1e-12 ? (y.head<2>() / y.z() - uv).norm() * sc : 1e9);
  }
  std::nth_element(err.begin(), err.begin() + err.size() * 9 / 10, err.end());
  if (!(err[err.size() * 9 / 10] <= 1.0)) return std::nullopt;
  if (2 * ahead < static_cast<int>(sample.size())) M = -M;  // m3 . X > 0 in front of the camera
  Pinhole cam;
  cam.Mi = M.inverse();
  cam.cu = cu, cam.cv = cv, cam.sc = sc;
  cam.width = w, cam.height = h;
  return cam;
}

Eigen::Vector3d Pinhole::ray(double col, double row) const {
  // M d = (u, v, 1): m3 . d = 1, in front.
  return (Mi * Eigen::Vector3d((col - cu) / sc, (row - cv) / sc, 1.0)).normalized();
}

Eigen::Vector3d Pinhole::imageUp() const {
  // A ray moves by Mi's second column per unit of (scaled) row, downwards:
  // Mi = R^T K^-1 up to scale, whose second column is the camera's y axis
  // (rows square to columns, as in every camera's sensor).
  return -Mi.col(1).normalized();
}

Points noReturnRays(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Pinhole& cam, int step) {
  Points out;
  const int w = static_cast<int>(cloud.width), h = static_cast<int>(cloud.height);
  if (w != cam.width || h != cam.height || cloud.size() != static_cast<std::size_t>(w) * h || step < 1) return out;
  auto finite = [](const pcl::PointXYZ& q) { return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z); };
  for (int r = 0; r < h; r += step)
    for (int c = 0; c < w; c += step)
      if (!finite(cloud.points[static_cast<std::size_t>(r) * w + c])) out.push_back(cam.ray(c, r).cast<float>());
  return out;
}

Points noReturnRays(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3f& viewpoint, int step) {
  const std::optional<Pinhole> cam = fitPinhole(cloud, viewpoint);
  return cam ? noReturnRays(cloud, *cam, step) : Points();
}

double raySpacing(const pcl::PointCloud<pcl::PointXYZ>& cloud, const Eigen::Vector3f& viewpoint) {
  const int w = static_cast<int>(cloud.width), h = static_cast<int>(cloud.height);
  if (h < 2 || w < 2 || cloud.size() != static_cast<std::size_t>(w) * h) return 0;
  // About kSpacingPixels pixels looked at, spread over the image.
  constexpr double kSpacingPixels = 4000;
  const int step = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(w) * h / kSpacingPixels))));
  auto dir = [&](int r, int c, Eigen::Vector3f* out) {
    const auto& q = cloud.points[static_cast<std::size_t>(r) * w + c];
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) return false;
    const Eigen::Vector3f d = q.getVector3fMap() - viewpoint;
    const float n = d.norm();
    if (n < 1e-3f) return false;  // (0, 0, 0) for no return
    *out = d / n;
    return true;
  };
  // Chords between unit directions, the median turned into an angle once.
  std::vector<float> along_row, along_column;
  for (int r = 0; r + 1 < h; r += step)
    for (int c = 0; c + 1 < w; c += step) {
      Eigen::Vector3f a, b;
      if (!dir(r, c, &a)) continue;
      if (dir(r, c + 1, &b)) along_row.push_back((a - b).norm());
      if (dir(r + 1, c, &b)) along_column.push_back((a - b).norm());
    }
  auto median = [](std::vector<float>& v) {
    if (v.size() < 20) return 0.0;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return 2 * std::asin(std::min(1.0, v[v.size() / 2] / 2.0));
  };
  return std::max(median(along_row), median(along_column));
}

}  // namespace preprocess
}  // namespace dsr
