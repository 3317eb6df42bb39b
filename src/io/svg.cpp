#include "door_state_recognition/io/svg.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace dsr {
namespace io {
namespace {

std::string num(double v, int decimals = 3) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string vec3(const Eigen::Vector3d& v) { return num(v.x(), 6) + " " + num(v.y(), 6) + " " + num(v.z(), 6); }

std::string escape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default:
        // Control characters are not allowed in XML 1.0 text.
        if (static_cast<unsigned char>(c) >= 0x20 || c == '\t' || c == '\n') out += c;
    }
  }
  return out;
}

// Plan coordinates (metres) of an input-frame point.
struct Plan {
  Eigen::Vector3d up, u, v;
  Eigen::Vector2d operator()(const Eigen::Vector3d& p) const { return {p.dot(u), p.dot(v)}; }
};

struct Box2 {
  double u0 = std::numeric_limits<double>::infinity(), v0 = u0, u1 = -u0, v1 = -u0;
  void add(const Eigen::Vector2d& p) {
    if (!p.allFinite()) return;
    u0 = std::min(u0, p.x()), u1 = std::max(u1, p.x());
    v0 = std::min(v0, p.y()), v1 = std::max(v1, p.y());
  }
  bool empty() const { return !(u0 <= u1 && v0 <= v1); }
};

// A horizontal unit vector along `d` (zero when d is vertical or not finite).
Eigen::Vector3d horizontal(const Eigen::Vector3d& d, const Eigen::Vector3d& up) {
  const Eigen::Vector3d h = d - d.dot(up) * up;
  const double n = h.norm();
  return (n > 1e-9 && h.allFinite()) ? Eigen::Vector3d(h / n) : Eigen::Vector3d::Zero();
}

double niceLength(double at_most) {
  double best = 0.1;
  for (const double base : {0.1, 1.0, 10.0, 100.0})
    for (const double m : {1.0, 2.0, 5.0})
      if (base * m <= at_most) best = base * m;
  return best;
}

}  // namespace

void planAxes(const Eigen::Vector3d& up_in, Eigen::Vector3d& u, Eigen::Vector3d& v) {
  Eigen::Vector3d up = up_in.allFinite() && up_in.norm() > 1e-9 ? Eigen::Vector3d(up_in.normalized())
                                                                 : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d x = std::abs(up.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  u = horizontal(x, up);
  v = up.cross(u);
}

std::string stateColour(const std::string& name) {
  static const std::unordered_map<std::string, std::string> known = {
      {"closed", "#d62728"}, {"semi_open", "#ff8c00"}, {"open", "#2ca02c"}, {"not_closed", "#8e44ad"}};
  const auto it = known.find(name);
  if (it != known.end()) return it->second;
  // Another state: a hue from its name (FNV-1a), mid saturation and lightness.
  std::uint32_t h = 2166136261u;
  for (const char c : name) h = (h ^ static_cast<unsigned char>(c)) * 16777619u;
  const double hue = (h % 360) / 60.0, c = 0.55, x = c * (1 - std::abs(std::fmod(hue, 2.0) - 1)), m = 0.2;
  double r = 0, g = 0, b = 0;
  if (hue < 1) r = c, g = x;
  else if (hue < 2) r = x, g = c;
  else if (hue < 3) g = c, b = x;
  else if (hue < 4) g = x, b = c;
  else if (hue < 5) r = x, b = c;
  else r = c, b = x;
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", static_cast<int>((r + m) * 255), static_cast<int>((g + m) * 255),
                static_cast<int>((b + m) * 255));
  return buf;
}

std::string planSvg(const PipelineResult& r, const std::vector<const pcl::PointCloud<pcl::PointXYZ>*>& clouds,
                    const PlanOptions& opt) {
  Plan plan;
  plan.up = r.up.allFinite() && r.up.norm() > 1e-9 ? Eigen::Vector3d(r.up.normalized()) : Eigen::Vector3d::UnitZ();
  planAxes(plan.up, plan.u, plan.v);

  // Points between the floor and the ceiling (0.1 m off each), on the plan.
  std::vector<float> pu, pv;
  const double lo = r.floor ? *r.floor + 0.1 : -std::numeric_limits<double>::infinity();
  const double hi = r.ceiling ? *r.ceiling - 0.1 : std::numeric_limits<double>::infinity();
  for (const auto* cloud : clouds) {
    if (!cloud) continue;
    for (const auto& q : cloud->points) {
      const Eigen::Vector3d p(q.x, q.y, q.z);
      if (!p.allFinite()) continue;
      const double h = p.dot(plan.up);
      if (h < lo || h > hi) continue;
      pu.push_back(static_cast<float>(p.dot(plan.u)));
      pv.push_back(static_cast<float>(p.dot(plan.v)));
    }
  }

  // Extent: walls, doors and viewpoints, and the points' 0.5-99.5 % range
  // (a stray return far off does not shrink the room).
  Box2 box;
  for (const WallResult& w : r.walls)
    for (const auto& c : w.corners) box.add(plan(c));
  for (const DoorResult& d : r.doors) {
    for (const auto& c : d.leaf_corners) box.add(plan(c));
    box.add(plan(d.opening_center));
  }
  for (const auto& vp : opt.viewpoints) box.add(plan(vp));
  if (!pu.empty()) {
    auto quantiles = [](std::vector<float> a) {
      const std::size_t k0 = a.size() / 200, k1 = a.size() - 1 - a.size() / 200;
      std::nth_element(a.begin(), a.begin() + k0, a.end());
      const float q0 = a[k0];
      std::nth_element(a.begin(), a.begin() + k1, a.end());
      return std::make_pair(q0, a[k1]);
    };
    const auto qu = quantiles(pu), qv = quantiles(pv);
    box.add({qu.first, qv.first});
    box.add({qu.second, qv.second});
  }
  if (box.empty()) box.add({0, 0});
  const double pad = 0.5;
  box.u0 -= pad, box.v0 -= pad, box.u1 += pad, box.v1 += pad;
  const double wm = std::max(box.u1 - box.u0, 1.0), hm = std::max(box.v1 - box.v0, 1.0);

  // Pixels: s px a metre; px = ox + s u, py = oy - s v.
  const double margin = 20, top = 40, bottom = 70;
  const double s = std::max(
      1.0, std::min((opt.max_width_px - 2 * margin) / wm, (opt.max_height_px - top - bottom) / hm));
  // At least as wide as the legend; the plan centred in the width.
  const double W = std::max(760.0, std::ceil(wm * s + 2 * margin)), H = std::ceil(hm * s + top + bottom);
  const double ox = (W - wm * s) / 2 - s * box.u0, oy = top + s * box.v1;
  auto px = [&](const Eigen::Vector2d& p) { return Eigen::Vector2d(ox + s * p.x(), oy - s * p.y()); };

  std::ostringstream o;
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"" << W << "\" height=\"" << H
    << "\" viewBox=\"0 0 " << W << " " << H << "\" font-family=\"sans-serif\" data-plan-up=\"" << vec3(plan.up)
    << "\" data-plan-u=\"" << vec3(plan.u) << "\" data-plan-v=\"" << vec3(plan.v) << "\" data-pixels-per-metre=\""
    << num(s, 4) << "\">\n";
  o << "<title>" << escape(opt.title.empty() ? "door_state plan" : opt.title) << "</title>\n";
  o << "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n";
  o << "<g id=\"plan\" transform=\"translate(" << num(ox, 4) << "," << num(oy, 4) << ") scale(" << num(s, 4) << ","
    << num(-s, 4) << ")\">\n";

  // Point density: counts per cell, opacity in 8 levels by log count.
  // (A cell asked finer than the extent / 2000 is widened: the grid stays small.)
  const double cell = opt.cell > 0 ? std::max(opt.cell, std::max(wm, hm) / 2000.0)
                                   : std::max(0.04, std::max(wm, hm) / 250.0);
  const int nx = static_cast<int>(std::ceil(wm / cell)), ny = static_cast<int>(std::ceil(hm / cell));
  if (!pu.empty() && nx > 0 && ny > 0) {
    std::vector<std::uint32_t> count(static_cast<std::size_t>(nx) * ny, 0);
    for (std::size_t i = 0; i < pu.size(); ++i) {
      const double fx = (pu[i] - box.u0) / cell, fy = (pv[i] - box.v0) / cell;
      if (!(fx >= 0 && fy >= 0 && fx < nx && fy < ny)) continue;
      ++count[static_cast<std::size_t>(fy) * nx + static_cast<std::size_t>(fx)];
    }
    const std::uint32_t cmax = *std::max_element(count.begin(), count.end());
    const int levels = 8;
    std::vector<std::string> paths(levels + 1);
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::uint32_t c = count[static_cast<std::size_t>(j) * nx + i];
        if (c == 0) continue;
        const int level = cmax <= 1 ? levels
                                    : std::max(1, static_cast<int>(std::ceil(levels * std::log1p(c) / std::log1p(cmax))));
        paths[level] += "M" + num(box.u0 + i * cell) + " " + num(box.v0 + j * cell) + "h" + num(cell) + "v" +
                        num(cell) + "h" + num(-cell) + "z";
      }
    o << "<g class=\"points\" data-cell-m=\"" << num(cell) << "\" data-points=\"" << pu.size() << "\">\n";
    for (int level = 1; level <= levels; ++level)
      if (!paths[level].empty())
        o << "<path class=\"density\" fill=\"#000000\" fill-opacity=\"" << num(0.08 + 0.6 * level / levels, 2)
          << "\" d=\"" << paths[level] << "\"/>\n";
    o << "</g>\n";
  }

  // Walls: the box of each wall's points, across and along its line.
  for (const WallResult& w : r.walls) {
    const Eigen::Vector3d dir = horizontal(w.line_direction, plan.up);
    if (dir.isZero()) continue;
    const Eigen::Vector3d n = plan.up.cross(dir);
    double t0 = std::numeric_limits<double>::infinity(), t1 = -t0, n0 = t0, n1 = -t0;
    for (const auto& c : w.corners) {
      const Eigen::Vector3d d = c - w.line_point;
      t0 = std::min(t0, d.dot(dir)), t1 = std::max(t1, d.dot(dir));
      n0 = std::min(n0, d.dot(n)), n1 = std::max(n1, d.dot(n));
    }
    o << "<polygon class=\"wall\" data-wall=\"" << w.id << "\" fill=\"#4a5a6a\" fill-opacity=\"0.55\" stroke=\"#2c3e50\""
      << " stroke-width=\"1\" vector-effect=\"non-scaling-stroke\" points=\"";
    const double corner[4][2] = {{t0, n0}, {t1, n0}, {t1, n1}, {t0, n1}};
    for (const auto& tn : corner) {
      const Eigen::Vector2d p = plan(w.line_point + tn[0] * dir + tn[1] * n);
      o << num(p.x()) << "," << num(p.y()) << " ";
    }
    o << "\"/>\n";
  }

  // Doors: the doorway, then the leaf from its hinge with its swing arc.
  for (const DoorResult& d : r.doors) {
    const std::string state = toString(d.state), colour = stateColour(state);
    const std::string dash = d.angle_is_lower_bound ? " stroke-dasharray=\"6,4\"" : "";
    const Eigen::Vector3d normal = horizontal(d.wall_normal, plan.up);
    const Eigen::Vector3d along = plan.up.cross(normal);
    const Eigen::Vector2d c = plan(d.opening_center);
    if (!along.isZero()) {
      const Eigen::Vector2d a = plan(d.opening_center - 0.5 * d.width * along),
                            b = plan(d.opening_center + 0.5 * d.width * along);
      o << "<line class=\"doorway\" data-door=\"" << d.id << "\" x1=\"" << num(a.x()) << "\" y1=\"" << num(a.y())
        << "\" x2=\"" << num(b.x()) << "\" y2=\"" << num(b.y())
        << "\" stroke=\"#ffffff\" stroke-width=\"0.12\" stroke-opacity=\"0.9\"/>\n";
      o << "<line class=\"doorway-line\" data-door=\"" << d.id << "\" x1=\"" << num(a.x()) << "\" y1=\"" << num(a.y())
        << "\" x2=\"" << num(b.x()) << "\" y2=\"" << num(b.y()) << "\" stroke=\"#7f8c8d\" stroke-width=\"1\""
        << " stroke-dasharray=\"3,3\" vector-effect=\"non-scaling-stroke\"/>\n";
    }
    const Eigen::Vector2d hinge = plan(d.hinge), h0 = plan(d.leaf_corners[0]), latch = plan(d.leaf_corners[1]);
    const double radius = (latch - h0).norm();
    // The swing: from the leaf closed (along the wall, towards the doorway's
    // middle) to where it stands, about the hinge.
    if (!along.isZero() && radius > 1e-3) {
      const double side = (d.opening_center - d.leaf_corners[0]).dot(along) >= 0 ? 1.0 : -1.0;
      const Eigen::Vector2d closed = plan(d.leaf_corners[0] + side * radius * along);
      const Eigen::Vector2d e0 = closed - h0, e1 = latch - h0;
      const double cross = e0.x() * e1.y() - e0.y() * e1.x();
      o << "<path class=\"swing\" data-door=\"" << d.id << "\" d=\"M" << num(closed.x()) << " " << num(closed.y())
        << " A" << num(radius) << " " << num(radius) << " 0 0 " << (cross >= 0 ? 1 : 0) << " " << num(latch.x()) << " "
        << num(latch.y()) << "\" fill=\"none\" stroke=\"" << colour << "\" stroke-width=\"1.2\" stroke-opacity=\"0.8\""
        << " stroke-dasharray=\"2,3\" vector-effect=\"non-scaling-stroke\"/>\n";
    }
    o << "<line class=\"leaf\" data-door=\"" << d.id << "\" data-state=\"" << escape(state)
      << "\" data-angle-deg=\"" << num(d.opening_angle_deg, 1) << "\" data-lower-bound=\""
      << (d.angle_is_lower_bound ? "true" : "false") << "\" x1=\"" << num(h0.x()) << "\" y1=\"" << num(h0.y())
      << "\" x2=\"" << num(latch.x()) << "\" y2=\"" << num(latch.y()) << "\" stroke=\"" << colour
      << "\" stroke-width=\"4\" stroke-linecap=\"round\"" << dash << " vector-effect=\"non-scaling-stroke\"/>\n";
    o << "<circle class=\"hinge\" data-door=\"" << d.id << "\" cx=\"" << num(hinge.x()) << "\" cy=\"" << num(hinge.y())
      << "\" r=\"0.05\" fill=\"" << colour << "\" stroke=\"#000000\" stroke-width=\"1\""
      << " vector-effect=\"non-scaling-stroke\"/>\n";
    o << "<circle class=\"opening-center\" data-door=\"" << d.id << "\" cx=\"" << num(c.x()) << "\" cy=\"" << num(c.y())
      << "\" r=\"0.03\" fill=\"#7f8c8d\"/>\n";
  }
  for (std::size_t k = 0; k < opt.viewpoints.size(); ++k) {
    const Eigen::Vector2d p = plan(opt.viewpoints[k]);
    if (!p.allFinite()) continue;
    o << "<circle class=\"viewpoint\" data-station=\"" << k << "\" cx=\"" << num(p.x()) << "\" cy=\"" << num(p.y())
      << "\" r=\"0.08\" fill=\"#1f77b4\" stroke=\"#ffffff\" stroke-width=\"1\" vector-effect=\"non-scaling-stroke\"/>\n";
  }
  o << "</g>\n";

  // Labels in pixels, on the side of the doorway away from the leaf.
  for (const DoorResult& d : r.doors) {
    const std::string state = toString(d.state);
    const Eigen::Vector3d normal = horizontal(d.wall_normal, plan.up);
    Eigen::Vector2d p = px(plan(d.opening_center - 0.45 * normal));
    // Kept inside the picture: about 7.5 px a character at 13 px bold.
    const double half = 3.75 * (std::to_string(d.id).size() + state.size() + 14);
    p.x() = std::clamp(p.x(), half + 2, std::max(half + 2, W - half - 2));
    p.y() = std::clamp(p.y(), top + 14, std::max(top + 14, H - bottom));
    o << "<text class=\"label\" data-door=\"" << d.id << "\" x=\"" << num(p.x(), 1) << "\" y=\"" << num(p.y(), 1)
      << "\" font-size=\"13\" text-anchor=\"middle\" fill=\"" << stateColour(state)
      << "\" stroke=\"#ffffff\" stroke-width=\"3\" paint-order=\"stroke\" font-weight=\"bold\">door " << d.id << ": "
      << escape(state) << " " << (d.angle_is_lower_bound ? "&#8805;" : "") << num(d.opening_angle_deg, 1)
      << "&#176;</text>\n";
  }
  for (std::size_t k = 0; k < opt.viewpoints.size(); ++k) {
    const Eigen::Vector2d p = px(plan(opt.viewpoints[k]));
    if (!p.allFinite()) continue;
    o << "<text class=\"viewpoint-label\" x=\"" << num(p.x() + 8, 1) << "\" y=\"" << num(p.y() - 6, 1)
      << "\" font-size=\"11\" fill=\"#1f77b4\">sensor" << (opt.viewpoints.size() > 1 ? " " + std::to_string(k) : "")
      << "</text>\n";
  }

  // Title, scale bar, legend, axes.
  o << "<text class=\"title\" x=\"" << margin << "\" y=\"24\" font-size=\"15\" fill=\"#000000\">"
    << escape(opt.title.empty() ? "door_state plan" : opt.title) << " &#8212; " << r.walls.size() << " wall(s), "
    << r.doors.size() << " door(s)</text>\n";
  const double bar_m = niceLength((W - 2 * margin) / 6 / s), bar_px = bar_m * s;
  const double by = H - 42;
  o << "<g class=\"scale-bar\" data-metres=\"" << num(bar_m, 2) << "\" data-px=\"" << num(bar_px, 2) << "\">"
    << "<line x1=\"" << margin << "\" y1=\"" << by << "\" x2=\"" << num(margin + bar_px, 2) << "\" y2=\"" << by
    << "\" stroke=\"#000000\" stroke-width=\"3\"/>"
    << "<line x1=\"" << margin << "\" y1=\"" << by - 6 << "\" x2=\"" << margin << "\" y2=\"" << by + 6
    << "\" stroke=\"#000000\" stroke-width=\"1.5\"/>"
    << "<line x1=\"" << num(margin + bar_px, 2) << "\" y1=\"" << by - 6 << "\" x2=\"" << num(margin + bar_px, 2)
    << "\" y2=\"" << by + 6 << "\" stroke=\"#000000\" stroke-width=\"1.5\"/>"
    << "<text x=\"" << num(margin + bar_px / 2, 1) << "\" y=\"" << by - 9
    << "\" font-size=\"12\" text-anchor=\"middle\">" << (bar_m < 1 ? num(bar_m, 1) : num(bar_m, 0)) << " m</text></g>\n";
  double lx = margin + bar_px + 30;
  o << "<g class=\"legend\">";
  for (const char* name : {"closed", "semi_open", "open", "not_closed"}) {
    o << "<line x1=\"" << num(lx, 1) << "\" y1=\"" << by << "\" x2=\"" << num(lx + 22, 1) << "\" y2=\"" << by
      << "\" stroke=\"" << stateColour(name) << "\" stroke-width=\"4\"/><text x=\"" << num(lx + 27, 1) << "\" y=\""
      << by + 4 << "\" font-size=\"12\">" << name << "</text>";
    lx += 34 + 7.5 * std::strlen(name);
  }
  o << "<line x1=\"" << num(lx, 1) << "\" y1=\"" << by << "\" x2=\"" << num(lx + 22, 1) << "\" y2=\"" << by
    << "\" stroke=\"#555555\" stroke-width=\"4\" stroke-dasharray=\"6,4\"/><text x=\"" << num(lx + 27, 1) << "\" y=\""
    << by + 4 << "\" font-size=\"12\">angle is a lower bound</text></g>\n";
  o << "<text class=\"axes\" x=\"" << margin << "\" y=\"" << H - 14
    << "\" font-size=\"11\" fill=\"#555555\">view from above; right: (" << num(plan.u.x(), 2) << " "
    << num(plan.u.y(), 2) << " " << num(plan.u.z(), 2) << "), up the page: (" << num(plan.v.x(), 2) << " "
    << num(plan.v.y(), 2) << " " << num(plan.v.z(), 2)
    << ") of the input frame; grey: points between floor and ceiling</text>\n";
  o << "</svg>\n";
  return o.str();
}

void writePlanSvg(const std::string& path, const PipelineResult& result,
                  const std::vector<const pcl::PointCloud<pcl::PointXYZ>*>& clouds, const PlanOptions& options) {
  const std::string doc = planSvg(result, clouds, options);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  out << doc;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
}

}  // namespace io
}  // namespace dsr
