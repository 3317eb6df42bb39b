// State: where no leaf is seen in a doorway beyond doubt, the least opening
// angle at which a leaf blocks no ray that went through (free space).
#include "leaf_internal.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace dsr {
namespace state {
namespace detail {

namespace {

// Free space as a range image: the nearest return in each bin of bearing and
// elevation seen from the sensor (in wall coordinates: s along, d towards
// the viewer). A surface at a point nearer than the nearest return of the
// point's bin (by more than kFreeMargin) would have been seen there instead:
// the point is free. Unlike counting the rays that cross a leaf, this rules
// out a leaf seen edge-on, which few rays cross though every bin it would
// fill shows the wall or the room beyond it.
constexpr double kRangeBinDeg = 0.5, kFreeMargin = 0.06;
class RangeImage {
 public:
  RangeImage(const Eigen::Vector2d& v, double vz, double az0) : v_(v), vz_(vz), az0_(az0) {
    near_.assign(static_cast<std::size_t>(kAz) * kEl, std::numeric_limits<float>::infinity());
  }
  void add(const Eigen::Vector2d& q, double qz) {
    double r;
    const int b = bin(q, qz, r);
    if (b >= 0) near_[b] = std::min(near_[b], static_cast<float>(r));
  }
  // The point is free: its bin holds a return farther than it by kFreeMargin.
  bool free(const Eigen::Vector2d& q, double qz) const {
    double r;
    const int b = bin(q, qz, r);
    return b >= 0 && std::isfinite(near_[b]) && near_[b] > r + kFreeMargin;
  }

 private:
  static constexpr int kAz = static_cast<int>(360 / kRangeBinDeg), kEl = static_cast<int>(180 / kRangeBinDeg);
  int bin(const Eigen::Vector2d& q, double qz, double& range) const {
    const Eigen::Vector2d r = q - v_;
    const double h = r.norm(), dz = qz - vz_;
    range = std::hypot(h, dz);
    if (range < 1e-6) return -1;
    double az = std::atan2(r.y(), r.x()) - az0_;  // relative to the doorway's bearing: no wrap near it
    if (az < -M_PI) az += 2 * M_PI;
    if (az >= M_PI) az -= 2 * M_PI;
    const double el = std::atan2(dz, h);
    const int a = std::clamp(static_cast<int>((az + M_PI) * 180 / M_PI / kRangeBinDeg), 0, kAz - 1);
    const int e = std::clamp(static_cast<int>((el + M_PI / 2) * 180 / M_PI / kRangeBinDeg), 0, kEl - 1);
    return e * kAz + a;
  }
  Eigen::Vector2d v_;
  double vz_, az0_;
  std::vector<float> near_;
};

}  // namespace

void LeafSearch::freeSpaceBound() {
  if (!fit.found && door.sure() && band_cov < 0.3) {
    // No leaf seen in a doorway beyond doubt, and none closed in it: where
    // could a leaf of the doorway's width stand without blocking a ray that
    // went through (free space)? For each hinge and swing side, the least
    // angle a leaf there is not contradicted at (more than 3% of its cells
    // crossed by rays); the least over all four bounds the opening angle
    // from below. A leaf swung behind its wall, out of sight, leaves a high bound.
    const int nl = std::max(1, static_cast<int>(std::ceil(L / abin)));
    std::vector<char> crossed(static_cast<std::size_t>(nl) * nz);
    double bound = 180;
    // Every return near the doorway (the rays above may be thinned).
    const Eigen::Vector2d dcv = dc - vsd;
    RangeImage image(vsd, viewpoint.z(), std::atan2(dcv.y(), dcv.x()));
    for (const auto& q : points) {
      Eigen::Vector2d qsd;
      double len2;
      if (nearDoorway(q, qsd, len2)) image.add(qsd, q.z());
    }
    // Every hinge at a jamb, swing side and recess the search tried (the
    // bound is that of a leaf spanning the doorway seen, so only at its
    // jambs, not at the hinges moved off them): a leaf hinged deeper in its
    // doorway than the hypothesis would rule it out wrongly.
    // Each hinge and swing side on its own (free_from_each: several
    // stations' bounds combine per side, runStations), the least of them
    // the bound (the first side reaching it says where).
    for (int h = 0; h < 2; ++h)
      for (int sw = 0; sw < 2; ++sw) {
        double side = 180;
        for (double rec : recess_steps) {
          if (rec > 0 && rec + lt > (sw == 0 ? t_toward : t)) continue;
          const double sh = h == 0 ? door.s0 : door.s1, ee = h == 0 ? 1.0 : -1.0, mm = sw == 0 ? 1.0 : -1.0;
          const Eigen::Vector2d H(sh, sw == 0 ? -rec : -t + rec);
          for (int deg = 0; deg < side && deg <= 170; deg += 2) {
            const double th = deg * M_PI / 180;
            const LeafAxes axes(th, ee, mm);
            const Eigen::Vector2d &e = axes.e, &k = axes.k;
            const Eigen::Vector2d P = H + k * (lt / 2);
            std::fill(crossed.begin(), crossed.end(), 0);
            // Cells whose centre the range image shows free first (cheap),
            // then cells rays cross, until the leaf is ruled out.
            const double most = 0.03 * nl * nz;
            int n = 0;
            for (int i = 0; i < nl && n <= most; ++i)
              for (int zb = 0; zb < nz; ++zb)
                if (image.free(P + e * ((i + 0.5) * abin), z0 + (zb + 0.5) * zbin))
                  crossed[static_cast<std::size_t>(i) * nz + zb] = 1, ++n;
            for (std::size_t ri = 0; ri < rays.size() && n <= most; ++ri) {
              const Ray& ray = rays[ri];
              double a, z;
              if (!crossLeaf(vsd, ray.q - vsd, vsz, ray.qz - vsz, 1 - 0.06 / ray.len, P, e, a, z) || a < 0.05 ||
                  a >= L || z < z0 || z >= z1)
                continue;
              char& f = crossed[static_cast<std::size_t>(std::min(nl - 1, static_cast<int>(a / abin))) * nz +
                                std::min(nz - 1, static_cast<int>((z - z0) / zbin))];
              if (!f) f = 1, ++n;
            }
            if (n <= 0.03 * nl * nz) {
              side = deg;
              break;
            }
          }
        }
        fit.free_from_each[h * 2 + sw] = side;
        if (side < bound) {
          bound = side;
          fit.hinge_at_s0 = h == 0;
          fit.toward_viewer = sw == 0;
        }
      }
    fit.free_from_deg = bound;
  }
}

}  // namespace detail
}  // namespace state
}  // namespace dsr
