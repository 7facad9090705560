// The report's plots (report_parts.hpp), drawn with svg_plot.hpp from a
// ReportData.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "report/report_parts.hpp"
#include "report/svg_plot.hpp"

namespace fgcal::apps::report {

using svg::Plot;
using svg::Series;

std::string cameraColor(std::size_t c) {
  static const char* palette[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd",
                                  "#8c564b", "#e377c2", "#17becf", "#bcbd22"};
  return palette[c % (sizeof palette / sizeof palette[0])];
}

std::string fmt(double v, int precision) {
  if (!std::isfinite(v)) return "–";
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << v;
  return s.str();
}

double rad2deg(double r) { return r * 180.0 / M_PI; }

namespace {

// ---- the rig ----

/// The two base-frame axes a rig plot shows.
struct RigAxes {
  int a = 0, b = 1;
};

/// Per camera the board centres it saw alone, then those several cameras saw
/// (the mutual constraints of F2) in a dark colour of their own.
std::vector<Series> boardSeries(const ReportData& d, RigAxes v) {
  const std::size_t M = d.cameras.size();
  std::vector<Series> boards(M + 1);
  for (std::size_t c = 0; c <= M; ++c) {
    boards[c].color = c < M ? cameraColor(c) : "#333";
    boards[c].size = c < M ? 2.4 : 1.8;
    boards[c].opacity = 0.6;
    boards[c].label =
        c < M ? "board seen by " + d.cameras[c].result.name + " alone" : "board seen by several cameras";
  }
  for (const ReportBoard& b : d.boards) {
    const std::size_t cam = b.camera < 0 ? M : std::min(M, static_cast<std::size_t>(b.camera));
    boards[cam].x.push_back(b.centre_base[v.a]);
    boards[cam].y.push_back(b.centre_base[v.b]);
  }
  return boards;
}

/// How far the rig reaches from the base origin (scales axes and frustums).
double rigExtent(const ReportData& d) {
  double extent = 0.0;
  for (const ReportBoard& b : d.boards) extent = std::max(extent, b.centre_base.norm());
  for (const ReportCamera& c : d.cameras) extent = std::max(extent, c.result.T_base_cam.translation().norm());
  return extent;
}

void addBaseAxes(Plot& p, const ReportData& d, RigAxes v, double extent) {
  const double axis = std::clamp(0.12 * extent, 0.05, 0.3);
  const char* axis_color[] = {kRed, "#2ca02c", "#1f77b4"};
  const char* axis_name[] = {"base x", "base y", "base z"};
  for (int k : {v.a, v.b}) {
    Series s;
    s.kind = Series::Kind::Line;
    s.color = axis_color[k];
    s.size = 2.5;
    s.label = axis_name[k];
    s.x = {0.0, k == v.a ? axis : 0.0};
    s.y = {0.0, k == v.b ? axis : 0.0};
    p.add(s);
  }
  p.labels.push_back({0.0, 0.0, d.base_link.empty() ? "base" : d.base_link, "#444"});
}

/// Camera c's frustum at pose T: apex to the four image corners at `depth`,
/// and the far rectangle; `dash` empty: a solid line.
void addFrustum(Plot& p, const ReportCamera& cam, const SE3& T, std::size_t c, RigAxes v, double depth,
                const std::string& label, const std::string& dash) {
  const auto& k = cam.intrinsics;
  const double fx = k[0], fy = k[1], cx = k[2], cy = k[3];
  const double w = cam.resolution[0], h = cam.resolution[1];
  const Vec3 apex = T.translation();
  std::vector<Vec3> corner;
  for (const auto& [u, vv] : std::vector<std::pair<double, double>>{{0, 0}, {w, 0}, {w, h}, {0, h}})
    corner.push_back(T * Vec3(depth * (u - cx) / fx, depth * (vv - cy) / fy, depth));
  Series s;
  s.kind = Series::Kind::Line;
  s.color = cameraColor(c);
  s.size = dash.empty() ? 2.0 : 1.3;
  s.dash = dash;
  s.label = label;
  const double nan = std::nan("");
  for (const Vec3& q : corner) {
    s.x.insert(s.x.end(), {apex[v.a], q[v.a], nan});
    s.y.insert(s.y.end(), {apex[v.b], q[v.b], nan});
  }
  for (int i = 0; i <= 4; ++i) {
    s.x.push_back(corner[static_cast<std::size_t>(i % 4)][v.a]);
    s.y.push_back(corner[static_cast<std::size_t>(i % 4)][v.b]);
  }
  p.add(s);
}

/// The robot's links: a grey line from each link's origin to its parent's.
void addLinks(Plot& p, const ReportData& d, RigAxes v) {
  Series s;
  s.kind = Series::Kind::Line;
  s.color = "#a0a0a0";
  s.size = 1.5;
  s.label = "robot links (URDF zero pose)";
  const double nan = std::nan("");
  for (const ReportLink& l : d.links) {
    if (l.parent < 0 || static_cast<std::size_t>(l.parent) >= d.links.size()) continue;
    const Vec3& q = d.links[static_cast<std::size_t>(l.parent)].origin_base;
    s.x.insert(s.x.end(), {q[v.a], l.origin_base[v.a], nan});
    s.y.insert(s.y.end(), {q[v.b], l.origin_base[v.b], nan});
  }
  if (!s.x.empty()) p.add(std::move(s));
}

/// Each camera's origin as calibrated (dots) and, when its `frame:` is set,
/// at its URDF pose (crosses, with a dashed frustum in its colour).
void addCameraOrigins(Plot& p, const ReportData& d, RigAxes v, double depth) {
  Series calibrated, urdf;
  calibrated.label = "camera origin, calibrated";
  calibrated.color = "#222";
  calibrated.size = 3.5;
  urdf.kind = Series::Kind::Crosses;
  urdf.label = "camera origin, URDF (rig.yaml frame:)";
  urdf.color = "#c000c0";
  urdf.size = 6.0;
  for (std::size_t c = 0; c < d.cameras.size(); ++c) {
    const ReportCamera& cam = d.cameras[c];
    const Vec3 t = cam.result.T_base_cam.translation();
    calibrated.x.push_back(t[v.a]);
    calibrated.y.push_back(t[v.b]);
    if (!cam.T_base_cam_urdf) continue;
    const Vec3 u = cam.T_base_cam_urdf->translation();
    urdf.x.push_back(u[v.a]);
    urdf.y.push_back(u[v.b]);
    addFrustum(p, cam, *cam.T_base_cam_urdf, c, v, depth, cam.result.name + " URDF " + cam.frame, "5 3");
  }
  p.add(std::move(calibrated));
  if (!urdf.x.empty()) p.add(std::move(urdf));
}

}  // namespace

std::string rigPlot(const ReportData& d, RigView view) {
  const RigAxes v = view == RigView::Top ? RigAxes{0, 1} : view == RigView::Side ? RigAxes{0, 2} : RigAxes{1, 2};
  Plot p;
  p.id = view == RigView::Top ? "rig-top" : view == RigView::Side ? "rig-side" : "rig-front";
  p.title = view == RigView::Top    ? "Rig from above"
            : view == RigView::Side ? "Rig from the side"
                                    : "Rig from the front";
  p.x_label = view == RigView::Front ? "y (m, left)" : "x (m, forward)";
  p.y_label = view == RigView::Top ? "y (m, left)" : "z (m, up)";
  p.width = 570;
  p.height = 470;
  p.equal_aspect = true;
  const double extent = rigExtent(d);
  addLinks(p, d, v);
  addBaseAxes(p, d, v, extent);
  for (Series& s : boardSeries(d, v))
    if (!s.x.empty()) p.add(std::move(s));
  const double depth = std::clamp(0.15 * extent, 0.05, 0.3);
  for (std::size_t c = 0; c < d.cameras.size(); ++c) {
    const ReportCamera& cam = d.cameras[c];
    addFrustum(p, cam, cam.result.T_base_cam, c, v, depth, cam.result.name, "");
    p.labels.push_back({cam.result.T_base_cam.translation()[v.a], cam.result.T_base_cam.translation()[v.b],
                        cam.result.name, cameraColor(c), 6.0, -6.0 - 14.0 * static_cast<double>(c)});
  }
  addCameraOrigins(p, d, v, depth);
  return p.render();
}

std::string convergencePlot(const ReportData& d) {
  Plot p;
  p.id = "convergence";
  p.title = "Convergence: cost per iteration of every solve";
  p.x_label = "iteration";
  p.y_label = "cost (0.5 sum of squared whitened residuals)";
  p.width = 1140;
  p.height = 340;
  p.log_y = true;
  p.x_min = 0.0;
  p.integer_x = true;
  for (std::size_t s = 0; s < d.solves.size(); ++s) {
    const ReportSolve& o = d.solves[s];
    Series line;
    line.kind = Series::Kind::Line;
    line.label = o.label;
    line.color = cameraColor(s / 2);  // a robust solve and its final one share a colour
    line.size = 2.0;
    if (o.label.rfind("robust", 0) == 0) line.dash = "6 4";
    line.x.push_back(0.0);
    line.y.push_back(o.initial_cost);
    for (std::size_t it = 0; it < o.cost.size() && it < o.iteration.size(); ++it) {
      line.x.push_back(o.iteration[it]);
      line.y.push_back(o.cost[it]);
    }
    Series dots = line;
    dots.kind = Series::Kind::Points;
    dots.label.clear();
    dots.size = 2.5;
    p.add(line);
    p.add(dots);
  }
  return p.render();
}

namespace {

/// A plot of a camera's section: `id` with the camera's index appended.
Plot cameraPlot(const std::string& id, std::size_t c, std::string title, std::string x_label, std::string y_label,
                int width) {
  Plot p;
  p.id = id + std::to_string(c);
  p.title = std::move(title);
  p.x_label = std::move(x_label);
  p.y_label = std::move(y_label);
  p.width = width;
  p.height = 370;
  return p;
}

}  // namespace

std::string coveragePlot(const ReportCamera& cam, std::size_t c) {
  Plot p = cameraPlot("coverage-", c, "Coverage: the detected corners in the image", "u (px, right)",
                      "v (px, down)", 460);
  const double w = cam.resolution[0], h = cam.resolution[1];
  p.equal_aspect = true;
  p.y_down = true;
  p.x_min = p.y_min = 0.0;
  p.x_max = w > 0 ? w : 1.0;
  p.y_max = h > 0 ? h : 1.0;
  Series frame;
  frame.kind = Series::Kind::Line;
  frame.label = "image " + std::to_string(cam.resolution[0]) + " × " + std::to_string(cam.resolution[1]);
  frame.color = "#444";
  frame.size = 1.5;
  frame.x = {0.0, w, w, 0.0, 0.0};
  frame.y = {0.0, 0.0, h, h, 0.0};
  p.add(frame);
  auto corners = [](const std::vector<Eigen::Vector2d>& px, Series s) {
    for (const auto& q : px) {
      s.x.push_back(q.x());
      s.y.push_back(q.y());
    }
    return s;
  };
  Series used;
  used.label = std::to_string(cam.corners_used_px.size()) + " corners used";
  used.color = cameraColor(c);
  used.size = 1.4;
  used.opacity = 0.5;
  p.add(corners(cam.corners_used_px, used));
  if (!cam.corners_rejected_px.empty()) {
    Series rejected;
    rejected.kind = Series::Kind::Crosses;
    rejected.label = std::to_string(cam.corners_rejected_px.size()) + " of rejected images";
    rejected.color = kRed;
    rejected.size = 2.5;
    rejected.opacity = 0.7;
    p.add(corners(cam.corners_rejected_px, rejected));
  }
  return p.render();
}

std::string reprojectionScatter(const ReportCamera& cam, std::size_t c) {
  Plot p = cameraPlot("reprojection-scatter-", c, "Reprojection error vectors", "u: predicted − detected (px)",
                      "v: predicted − detected (px)", 360);
  p.equal_aspect = true;
  Series s;
  double m = 0.0;
  for (const auto& e : cam.residuals_px) {
    m = std::max({m, std::abs(e.x()), std::abs(e.y())});
    s.x.push_back(e.x());
    s.y.push_back(e.y());
  }
  m = m > 0.0 ? m * 1.05 : 1.0;
  p.x_min = p.y_min = -m;
  p.x_max = p.y_max = m;
  s.color = cameraColor(c);
  s.size = 1.6;
  s.opacity = 0.45;
  s.label = std::to_string(cam.residuals_px.size()) + " corners of the images used";
  p.add(s);
  return p.render();
}

std::string reprojectionHistogram(const ReportCamera& cam, std::size_t c) {
  Plot p = cameraPlot("reprojection-histogram-", c, "Reprojection error magnitude", "|predicted − detected| (px)",
                      "corners", 360);
  std::vector<double> norm;
  double hi = 0.0, sq = 0.0;
  for (const auto& e : cam.residuals_px) {
    norm.push_back(e.norm());
    hi = std::max(hi, norm.back());
    sq += norm.back() * norm.back();
  }
  hi = hi > 0.0 ? hi * 1.0001 : 1.0;
  const double rms = norm.empty() ? 0.0 : std::sqrt(sq / static_cast<double>(norm.size()));
  p.x_min = 0.0;
  p.add(svg::histogram(norm, 30, 0.0, hi, "RMS " + fmt(rms, 3) + " px", cameraColor(c)));
  return p.render();
}

namespace {

Series chi2Series(const std::vector<TimedChi2>& points, const std::string& label, const std::string& color) {
  Series s;
  s.label = label;
  s.color = color;
  for (const TimedChi2& q : points) {
    s.x.push_back(q.t);
    s.y.push_back(q.chi2);
  }
  return s;
}

/// The gate's threshold across the time the camera's used images span.
Series gateLine(const std::vector<TimedChi2>& used, double gate_chi2) {
  double t_lo = 0.0, t_hi = 1.0;
  if (!used.empty()) {
    const auto [lo, hi] = std::minmax_element(used.begin(), used.end(),
                                              [](const TimedChi2& a, const TimedChi2& b) { return a.t < b.t; });
    t_lo = lo->t;
    t_hi = hi->t;
  }
  Series gate;
  gate.kind = Series::Kind::Line;
  gate.label = "99.9 % gate";
  gate.color = kRed;
  gate.dash = "5 4";
  gate.size = 1.2;
  gate.x = {t_lo, t_hi};
  gate.y = {gate_chi2, gate_chi2};
  return gate;
}

}  // namespace

std::string residualsOverTime(const ReportCamera& cam, std::size_t c, double fiducial_gate) {
  Plot p = cameraPlot("residuals-time-", c, "Residuals over time", "time (s)", "chi-square (6 dof)", 400);
  p.log_y = true;
  Series kin = chi2Series(cam.kinematic, "kinematic", kGrey);
  kin.size = 1.8;
  kin.opacity = 0.7;
  Series fid = chi2Series(cam.fiducial_used, "fiducial", cameraColor(c));
  fid.size = 2.0;
  fid.opacity = 0.8;
  p.add(kin).add(fid);
  if (!cam.fiducial_rejected.empty()) {
    Series rej = chi2Series(cam.fiducial_rejected, "rejected", kRed);
    rej.kind = Series::Kind::Crosses;
    rej.size = 4.0;
    p.add(rej);
  }
  if (fiducial_gate > 0.0) p.add(gateLine(cam.fiducial_used, fiducial_gate));
  return p.render();
}


std::size_t sweepCamera(const ReportData& d, std::size_t k) {
  for (std::size_t c = 0; c < d.cameras.size(); ++c)
    if (d.cameras[c].result.name == d.time_offset_sweeps[k].camera) return c;
  return k;
}

std::string timeOffsetSweepPlot(const ReportTimeOffsetSweep& s, std::size_t c) {
  Plot p = cameraPlot("time-offset-sweep-", c, "Time offset of " + s.camera + ": estimate " + fmt(s.estimate_ms, 3) +
                                                   " ms, 1σ " + fmt(s.sigma_ms, 3) + " ms",
                      "time offset δ (ms): an image stamped t exposed at t + δ", "reprojection RMS (px)", 560);
  Series rms;
  rms.kind = Series::Kind::Line;
  rms.label = "RMS through kinematics + calibration at δ";
  rms.color = cameraColor(c);
  rms.size = 2.0;
  rms.x = s.delta_ms;
  rms.y = s.rms_px;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (double v : s.rms_px)
    if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  p.add(rms);
  if (std::isfinite(lo)) {
    Series estimate;
    estimate.kind = Series::Kind::Line;
    estimate.label = "estimate";
    estimate.color = kRed;
    estimate.dash = "6 4";
    estimate.x = {s.estimate_ms, s.estimate_ms};
    estimate.y = {lo, hi};
    p.add(estimate);
  }
  return p.render();
}

}  // namespace fgcal::apps::report
