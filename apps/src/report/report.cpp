// The calibration report (fgcal/apps/report.hpp): the HTML page, the overlay
// images and the atomic folder write. Plots come from svg_plot.hpp.
#include "fgcal/apps/report.hpp"

#include <stdio.h>  // renameat2
#include <fcntl.h>  // AT_FDCWD
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "fgcal/apps/errors.hpp"
#include "../io/text_format.hpp"
#include "svg_plot.hpp"

namespace fgcal::apps {

namespace {

namespace fs = std::filesystem;
using detail::xmlEscape;
using svg::Plot;
using svg::Series;

constexpr const char* kGenerator = "fgcal calibration report";
constexpr const char* kRed = "#d62728";
constexpr const char* kGrey = "#8c8c8c";

/// Camera colours; red is kept for rejected and predicted things.
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

struct Overlay {
  std::size_t image = 0;  // index into CalibrateResult::images
  std::string tag;        // best, median, worst, rejected
  std::string file;       // relative to the report folder
  std::string error;      // set when the image could not be drawn
};

/// Per camera (result.output.cameras order) the indices of its images.
std::vector<std::vector<std::size_t>> imagesByCamera(const CalibrateResult& r) {
  std::map<std::string, std::size_t> index;
  for (std::size_t c = 0; c < r.output.cameras.size(); ++c) index[r.output.cameras[c].name] = c;
  std::vector<std::vector<std::size_t>> out(r.output.cameras.size());
  for (std::size_t i = 0; i < r.images.size(); ++i) {
    const auto it = index.find(r.images[i].camera);
    if (it != index.end()) out[it->second].push_back(i);
  }
  return out;
}

double fiducialChi2(const CalibrateResult& r, const ImageOutcome& im) {
  if (im.observation < 0 || static_cast<std::size_t>(im.observation) >= r.solution.fiducial_chi2.size())
    return std::nan("");
  return r.solution.fiducial_chi2[static_cast<std::size_t>(im.observation)];
}

bool hasPrediction(const ImageOutcome& im) {
  return !im.predicted_px.empty() && im.predicted_px.size() == im.corners_px.size();
}

/// Best, median and worst (quantiles of the reprojection RMS) of the images
/// a camera used, then its worst outlier.
std::vector<std::vector<Overlay>> pickOverlays(const CalibrateResult& r, int per_camera) {
  const auto by_cam = imagesByCamera(r);
  std::vector<std::vector<Overlay>> out(by_cam.size());
  for (std::size_t c = 0; c < by_cam.size(); ++c) {
    std::vector<std::size_t> used, outliers;
    for (std::size_t i : by_cam[c]) {
      const ImageOutcome& im = r.images[i];
      if (!hasPrediction(im)) continue;
      if (im.skipped.empty()) used.push_back(i);
      if (im.skipped == "outlier") outliers.push_back(i);
    }
    std::stable_sort(used.begin(), used.end(),
                     [&](std::size_t a, std::size_t b) { return r.images[a].rms_px < r.images[b].rms_px; });
    std::vector<std::size_t> positions;
    const std::size_t n = used.size(), k = static_cast<std::size_t>(std::max(0, per_camera));
    for (std::size_t q = 0; q < k && n > 0; ++q) {
      const std::size_t pos = k == 1 ? n / 2 : (q * (n - 1) + (k - 1) / 2) / (k - 1);
      if (std::find(positions.begin(), positions.end(), pos) == positions.end()) positions.push_back(pos);
    }
    for (std::size_t q = 0; q < positions.size(); ++q) {
      Overlay o;
      o.image = used[positions[q]];
      o.tag = positions.size() == 1 ? "median"
              : q == 0              ? "best"
              : q + 1 == positions.size() ? "worst"
              : positions.size() == 3     ? "median"
                                          : "rank " + std::to_string(positions[q] + 1) + " of " + std::to_string(n);
      out[c].push_back(o);
    }
    if (!outliers.empty()) {
      const auto worst = std::max_element(outliers.begin(), outliers.end(), [&](std::size_t a, std::size_t b) {
        return fiducialChi2(r, r.images[a]) < fiducialChi2(r, r.images[b]);
      });
      Overlay o;
      o.image = *worst;
      o.tag = "rejected";
      out[c].push_back(o);
    }
    for (std::size_t q = 0; q < out[c].size(); ++q)
      out[c][q].file = "images/cam" + std::to_string(c) + "_" + std::to_string(q) + ".png";
  }
  return out;
}

/// Draws the detected (green circles) and predicted (red crosses) corners over
/// the part of the image around the board, scaled to kOverlayWidth px wide so
/// that a pixel of error can be seen.
constexpr int kOverlayWidth = 720;
void drawOverlay(const ImageOutcome& im, const cv::Mat& loaded, bool from_loader, const std::string& path) {
  cv::Mat img;
  if (!from_loader) img = cv::imread(im.path, cv::IMREAD_COLOR);
  else if (loaded.channels() == 1) cv::cvtColor(loaded, img, cv::COLOR_GRAY2BGR);
  else img = loaded.clone();
  if (img.empty()) throw std::runtime_error("cannot read " + im.path);
  // The board's box (detected and predicted corners) with a margin, at the image's aspect ratio.
  double x0 = img.cols, y0 = img.rows, x1 = 0, y1 = 0;
  for (const auto* pts : {&im.corners_px, &im.predicted_px})
    for (const auto& p : *pts)
      if (p.allFinite()) {
        x0 = std::min(x0, p.x()), y0 = std::min(y0, p.y()), x1 = std::max(x1, p.x()), y1 = std::max(y1, p.y());
      }
  cv::Rect roi(0, 0, img.cols, img.rows);
  if (x1 > x0 && y1 > y0) {
    const double aspect = static_cast<double>(img.cols) / img.rows;
    double w = (x1 - x0) * 1.5 + 40.0, h = (y1 - y0) * 1.5 + 40.0;
    if (w / h < aspect) w = h * aspect; else h = w / aspect;
    w = std::min<double>(w, img.cols), h = std::min<double>(h, img.rows);
    const double cx = std::clamp(0.5 * (x0 + x1), w / 2, img.cols - w / 2);
    const double cy = std::clamp(0.5 * (y0 + y1), h / 2, img.rows - h / 2);
    roi = cv::Rect(static_cast<int>(cx - w / 2), static_cast<int>(cy - h / 2), static_cast<int>(w), static_cast<int>(h)) &
          cv::Rect(0, 0, img.cols, img.rows);
  }
  const double scale = static_cast<double>(kOverlayWidth) / roi.width;
  cv::resize(img(roi), img, cv::Size(), scale, scale, scale > 1.0 ? cv::INTER_LINEAR : cv::INTER_AREA);
  const int r = std::max(4, static_cast<int>(std::lround(kOverlayWidth / 110.0)));
  const int thick = 2;
  auto pt = [&](const Eigen::Vector2d& p) {
    // Sub-pixel drawing: OpenCV's fixed-point shift of 4 bits.
    return cv::Point(static_cast<int>(std::lround((p.x() - roi.x) * scale * 16.0)),
                     static_cast<int>(std::lround((p.y() - roi.y) * scale * 16.0)));
  };
  for (const auto& p : im.corners_px)
    if (p.allFinite()) cv::circle(img, pt(p), r * 16, cv::Scalar(0, 200, 0), thick, cv::LINE_AA, 4);
  for (const auto& p : im.predicted_px) {
    if (!p.allFinite()) continue;
    const cv::Point c = pt(p), dx(r * 16, 0), dy(0, r * 16);
    cv::line(img, c - dx, c + dx, cv::Scalar(40, 40, 230), thick, cv::LINE_AA, 4);
    cv::line(img, c - dy, c + dy, cv::Scalar(40, 40, 230), thick, cv::LINE_AA, 4);
  }
  if (!cv::imwrite(path, img)) throw std::runtime_error("cannot write " + path);
}

std::string relativeToDataset(const CalibrateResult& r, const std::string& path) {
  std::string root;
  for (const auto& [k, v] : r.output.info)
    if (k == "dataset") root = v;
  std::error_code ec;
  const fs::path rel = fs::relative(path, root, ec);
  return ec || rel.empty() || rel.native().rfind("..", 0) == 0 ? path : rel.string();
}

// ---- Plots -------------------------------------------------------------------

/// The rig seen from above (x, y) or from the side (x, z), base frame units m.
std::string rigPlot(const CalibrateResult& r, bool top) {
  const int a = 0, b = top ? 1 : 2;  // the two base-frame axes shown
  Plot p;
  p.id = top ? "rig-top" : "rig-side";
  p.title = top ? "Rig from above" : "Rig from the side";
  p.x_label = "x (m, forward)";
  p.y_label = top ? "y (m, left)" : "z (m, up)";
  p.width = 570;
  p.height = 470;
  p.equal_aspect = true;

  // Board centres per camera; the board centre in the board frame.
  const double bx = 0.5 * r.rig.target.squares_x * r.rig.target.square_size;
  const double by = 0.5 * r.rig.target.squares_y * r.rig.target.square_size;
  const Vec3 centre(bx, by, 0.0);
  const std::size_t M = r.output.cameras.size();
  // Per camera the instants it saw alone, then those several cameras saw
  // (the mutual constraints of F2) in a dark colour of their own.
  std::vector<Series> boards(M + 1);
  double extent = 0.0;
  for (std::size_t c = 0; c <= M; ++c) {
    boards[c].color = c < M ? cameraColor(c) : "#333";
    boards[c].size = c < M ? 2.4 : 1.8;
    boards[c].opacity = 0.6;
    boards[c].label = c < M ? "board seen by " + r.output.cameras[c].name + " alone" : "board seen by several cameras";
  }
  for (const InstantEstimate& ie : r.solution.instant_estimates) {
    const Vec3 p_b = ie.T_base_marker * centre;
    extent = std::max(extent, p_b.norm());
    std::size_t cam = M;
    if (ie.observations.size() == 1 && ie.observations[0] < r.problem.observations.size())
      cam = std::min(M, static_cast<std::size_t>(r.problem.observations[ie.observations[0]].camera));
    boards[cam].x.push_back(p_b[a]);
    boards[cam].y.push_back(p_b[b]);
  }
  for (const CameraResult& cr : r.output.cameras) extent = std::max(extent, cr.T_base_cam.translation().norm());
  const double depth = std::clamp(0.15 * extent, 0.05, 0.3);

  // Base frame axes.
  const double axis = std::clamp(0.12 * extent, 0.05, 0.3);
  const char* axis_color[] = {kRed, "#2ca02c", "#1f77b4"};
  const char* axis_name[] = {"base x", "base y", "base z"};
  for (int k : {a, b}) {
    Series s;
    s.kind = Series::Kind::Line;
    s.color = axis_color[k];
    s.size = 2.5;
    s.label = axis_name[k];
    s.x = {0.0, k == a ? axis : 0.0};
    s.y = {0.0, k == b ? axis : 0.0};
    p.add(s);
  }
  p.labels.push_back({0.0, 0.0, r.rig.robot.base_link.empty() ? "base" : r.rig.robot.base_link, "#444"});

  for (Series& s : boards)
    if (!s.x.empty()) p.add(s);

  // Frustums: apex to the four image corners at `depth`, and the far rectangle.
  for (std::size_t c = 0; c < M; ++c) {
    const SE3& T = r.output.cameras[c].T_base_cam;
    double fx = 500, fy = 500, cx = 320, cy = 240, w = 640, h = 480;
    for (const CameraConfig& cc : r.rig.cameras)
      if (cc.name == r.output.cameras[c].name) {
        fx = cc.intrinsics[0], fy = cc.intrinsics[1], cx = cc.intrinsics[2], cy = cc.intrinsics[3];
        w = cc.resolution[0], h = cc.resolution[1];
      }
    const Vec3 apex = T.translation();
    std::vector<Vec3> corner;
    for (const auto& [u, v] : std::vector<std::pair<double, double>>{{0, 0}, {w, 0}, {w, h}, {0, h}})
      corner.push_back(T * Vec3(depth * (u - cx) / fx, depth * (v - cy) / fy, depth));
    Series s;
    s.kind = Series::Kind::Line;
    s.color = cameraColor(c);
    s.size = 2.0;
    s.label = r.output.cameras[c].name;
    const double nan = std::nan("");
    for (const Vec3& q : corner) {
      s.x.insert(s.x.end(), {apex[a], q[a], nan});
      s.y.insert(s.y.end(), {apex[b], q[b], nan});
    }
    for (int k = 0; k <= 4; ++k) {
      s.x.push_back(corner[static_cast<std::size_t>(k % 4)][a]);
      s.y.push_back(corner[static_cast<std::size_t>(k % 4)][b]);
    }
    p.add(s);
    p.labels.push_back({apex[a], apex[b], r.output.cameras[c].name, cameraColor(c), 6.0, -6.0 - 14.0 * c});
  }
  return p.render();
}

std::string convergencePlot(const CalibrateResult& r) {
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
  for (std::size_t s = 0; s < r.solution.solves.size(); ++s) {
    const OptimizerResult& o = r.solution.solves[s];
    Series line;
    line.kind = Series::Kind::Line;
    const std::string label =
        s < r.solution.solve_labels.size() ? r.solution.solve_labels[s] : "solve " + std::to_string(s + 1);
    line.label = label;
    line.color = cameraColor(s / 2);  // a robust solve and its final one share a colour
    line.size = 2.0;
    if (label.rfind("robust", 0) == 0) line.dash = "6 4";
    line.x.push_back(0.0);
    line.y.push_back(o.initial_cost);
    for (const IterationReport& it : o.reports) {
      line.x.push_back(it.iteration);
      line.y.push_back(it.cost);
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

struct CameraData {
  std::vector<double> du, dv, norm;                   // residuals of used images, px
  std::vector<double> t_used, chi_used, t_rej, chi_rej;  // fiducial chi2 over time
  std::vector<double> t_kin, chi_kin;                  // kinematic chi2 of its instants
};

CameraData cameraData(const CalibrateResult& r, const std::vector<std::size_t>& images, std::int64_t t0) {
  CameraData d;
  for (std::size_t i : images) {
    const ImageOutcome& im = r.images[i];
    if (im.observation < 0) continue;
    const double t = static_cast<double>(im.stamp_ns - t0) * 1e-9;
    const double chi = fiducialChi2(r, im);
    if (im.skipped.empty()) {
      d.t_used.push_back(t);
      d.chi_used.push_back(chi);
      if (hasPrediction(im))
        for (std::size_t k = 0; k < im.corners_px.size(); ++k) {
          const Eigen::Vector2d e = im.predicted_px[k] - im.corners_px[k];
          if (!e.allFinite()) continue;
          d.du.push_back(e.x());
          d.dv.push_back(e.y());
          d.norm.push_back(e.norm());
        }
      const auto o = static_cast<std::size_t>(im.observation);
      if (o < r.solution.instant_of.size() && r.solution.instant_of[o] >= 0) {
        d.t_kin.push_back(t);
        d.chi_kin.push_back(r.solution.instant_estimates[static_cast<std::size_t>(r.solution.instant_of[o])].kinematic_chi2);
      }
    } else if (im.skipped == "outlier") {
      d.t_rej.push_back(t);
      d.chi_rej.push_back(chi);
    }
  }
  return d;
}

std::string reprojectionScatter(const CameraData& d, std::size_t c) {
  Plot p;
  p.id = "reprojection-scatter-" + std::to_string(c);
  p.title = "Reprojection error vectors";
  p.x_label = "u: predicted − detected (px)";
  p.y_label = "v: predicted − detected (px)";
  p.width = 360;
  p.height = 370;
  p.equal_aspect = true;
  double m = 0.0;
  for (std::size_t k = 0; k < d.du.size(); ++k) m = std::max({m, std::abs(d.du[k]), std::abs(d.dv[k])});
  m = m > 0.0 ? m * 1.05 : 1.0;
  p.x_min = p.y_min = -m;
  p.x_max = p.y_max = m;
  Series s;
  s.color = cameraColor(c);
  s.size = 1.6;
  s.opacity = 0.45;
  s.x = d.du;
  s.y = d.dv;
  s.label = std::to_string(d.du.size()) + " corners of the images used";
  p.add(s);
  return p.render();
}

std::string reprojectionHistogram(const CameraData& d, std::size_t c) {
  Plot p;
  p.id = "reprojection-histogram-" + std::to_string(c);
  p.title = "Reprojection error magnitude";
  p.x_label = "|predicted − detected| (px)";
  p.y_label = "corners";
  p.width = 360;
  p.height = 370;
  double hi = 0.0;
  for (double v : d.norm) hi = std::max(hi, v);
  hi = hi > 0.0 ? hi * 1.0001 : 1.0;
  double sq = 0.0;
  for (double v : d.norm) sq += v * v;
  const double rms = d.norm.empty() ? 0.0 : std::sqrt(sq / static_cast<double>(d.norm.size()));
  p.x_min = 0.0;
  p.add(svg::histogram(d.norm, 30, 0.0, hi, "RMS " + fmt(rms, 3) + " px", cameraColor(c)));
  return p.render();
}

std::string residualsOverTime(const CameraData& d, std::size_t c) {
  Plot p;
  p.id = "residuals-time-" + std::to_string(c);
  p.title = "Residuals over time";
  p.x_label = "time (s)";
  p.y_label = "chi-square (6 dof)";
  p.width = 400;
  p.height = 370;
  p.log_y = true;
  Series kin;
  kin.label = "kinematic";
  kin.color = kGrey;
  kin.size = 1.8;
  kin.opacity = 0.7;
  kin.x = d.t_kin;
  kin.y = d.chi_kin;
  Series fid;
  fid.label = "fiducial";
  fid.color = cameraColor(c);
  fid.size = 2.0;
  fid.opacity = 0.8;
  fid.x = d.t_used;
  fid.y = d.chi_used;
  p.add(kin).add(fid);
  if (!d.t_rej.empty()) {
    Series rej;
    rej.kind = Series::Kind::Crosses;
    rej.label = "rejected";
    rej.color = kRed;
    rej.size = 4.0;
    rej.x = d.t_rej;
    rej.y = d.chi_rej;
    p.add(rej);
  }
  double t_lo = 0.0, t_hi = 1.0;
  if (!d.t_used.empty()) {
    t_lo = *std::min_element(d.t_used.begin(), d.t_used.end());
    t_hi = *std::max_element(d.t_used.begin(), d.t_used.end());
  }
  Series gate;
  gate.kind = Series::Kind::Line;
  gate.label = "99.9 % gate";
  gate.color = kRed;
  gate.dash = "5 4";
  gate.size = 1.2;
  gate.x = {t_lo, t_hi};
  gate.y = {kFiducialGate, kFiducialGate};
  p.add(gate);
  return p.render();
}

// ---- The page ----------------------------------------------------------------

const char* kCss = R"(
body{font-family:sans-serif;font-size:14px;color:#222;max-width:1160px;margin:16px auto;padding:0 12px;background:#fafafa}
h1{font-size:22px;margin:4px 0}h2{font-size:18px;margin:22px 0 8px;border-bottom:1px solid #ddd;padding-bottom:4px}
.meta{color:#555;margin:4px 0 10px}
.verdict{padding:8px 12px;border-radius:4px;margin:10px 0;font-weight:bold}
.verdict.ok{background:#e8f5e9;border-left:5px solid #2e7d32}
.verdict.warn{background:#fff4e5;border-left:5px solid #ef6c00}
ul.warnings li{margin:4px 0;padding:6px 8px;background:#fff4e5;border-left:4px solid #ef6c00;list-style:none}
ul.warnings{padding-left:0}
table{border-collapse:collapse;background:#fff;margin:6px 0}
th,td{border:1px solid #ddd;padding:4px 7px;text-align:right;font-variant-numeric:tabular-nums}
th{background:#f0f0f0}td.name,th.name{text-align:left}
td.bad{background:#ffe0e0}
.plots{display:flex;flex-wrap:wrap;gap:8px}
svg.plot{background:#fff;border:1px solid #e0e0e0}
.overlays{display:grid;grid-template-columns:repeat(auto-fill,minmax(360px,1fr));gap:10px}
figure{margin:0;background:#fff;border:1px solid #e0e0e0;padding:4px}
figure img{width:100%;height:auto;display:block}
figcaption{font-size:12px;color:#444;padding:3px 2px}
.note{color:#555;font-size:12.5px}
.swatch{display:inline-block;width:10px;height:10px;border-radius:5px;margin-right:4px}
pre{background:#fff;border:1px solid #e0e0e0;padding:8px;white-space:pre-wrap;font-size:12px}
)";

std::string cameraCount(const CalibrateResult& r) {
  int used = 0;
  for (const auto& im : r.images) used += im.skipped.empty() && im.observation >= 0;
  return std::to_string(used) + " of " + std::to_string(r.images.size());
}

std::string info(const CalibrateResult& r, const std::string& key) {
  for (const auto& [k, v] : r.output.info)
    if (k == key) return v;
  return "";
}

std::string resultsTable(const CalibrateResult& r) {
  std::ostringstream h;
  const bool truth = r.evaluation.has_value();
  h << "<table id=\"results-table\"><tr><th class=\"name\">pose</th><th>x (m)</th><th>y (m)</th><th>z (m)</th>"
       "<th>roll (°)</th><th>pitch (°)</th><th>yaw (°)</th><th>1σ x, y, z (mm)</th><th>1σ r, p, y (°)</th>"
       "<th>images used</th><th>RMS (px)</th>";
  if (truth) h << "<th>error (mm)</th><th>error (°)</th><th>NEES</th>";
  h << "</tr>\n";
  auto row = [&](const std::string& name, const SE3& T, const Mat6& cov, bool has_cov, const std::string& used,
                 const std::string& rms, const std::optional<PoseError>& err) {
    const Vec6 xr = T.xyzRpy();
    h << "<tr><td class=\"name\">" << xmlEscape(name) << "</td>";
    for (int k = 0; k < 3; ++k) h << "<td>" << fmt(xr[k], 4) << "</td>";
    for (int k = 3; k < 6; ++k) h << "<td>" << fmt(rad2deg(xr[k]), 3) << "</td>";
    if (has_cov) {
      const Vec6 sg = sigmaMmDeg(T, cov);
      h << "<td>" << fmt(sg[0], 2) << ", " << fmt(sg[1], 2) << ", " << fmt(sg[2], 2) << "</td><td>" << fmt(sg[3], 3)
        << ", " << fmt(sg[4], 3) << ", " << fmt(sg[5], 3) << "</td>";
    } else {
      h << "<td colspan=\"2\" class=\"name\">held fixed</td>";
    }
    h << "<td>" << used << "</td><td>" << rms << "</td>";
    if (truth) {
      if (err) {
        const bool high = std::isfinite(err->nees) && err->nees > 12.59;
        h << "<td>" << fmt(err->translation_mm, 3) << "</td><td>" << fmt(err->rotation_deg, 4) << "</td><td"
          << (high ? " class=\"bad\"" : "") << ">" << fmt(err->nees, 2) << "</td>";
      } else {
        h << "<td>–</td><td>–</td><td>–</td>";
      }
    }
    h << "</tr>\n";
  };
  for (const CameraResult& cr : r.output.cameras) {
    int total = cr.images_used;
    for (const auto& [k, n] : cr.images_skipped) total += n;
    std::optional<PoseError> err;
    if (truth) {
      const auto it = r.evaluation->cameras.find(cr.name);
      if (it != r.evaluation->cameras.end()) err = it->second;
    }
    row(cr.name, cr.T_base_cam, cr.covariance, true, std::to_string(cr.images_used) + " / " + std::to_string(total),
        fmt(cr.rms_reprojection_px, 3), err);
  }
  const std::string link = r.rig.robot.marker_link.empty() ? "link" : r.rig.robot.marker_link;
  row("board mount (" + link + " → board)", r.output.mount.T_link_marker, r.output.mount.covariance,
      r.output.mount.estimated, "", "", truth ? r.evaluation->mount : std::nullopt);
  h << "</table>\n<p class=\"note\">Camera poses are T_base_cam in " << xmlEscape(r.rig.robot.base_link)
    << "; roll, pitch, yaw as in a URDF &lt;origin&gt;. 1σ from the marginal covariance of the final solve.";
  if (truth)
    h << " Errors against <code>" << xmlEscape(r.ground_truth_path)
      << "</code>; NEES = eᵀΣ⁻¹e is about 6 when the reported covariance is honest, cells above 12.6 (95 % of "
         "χ²(6)) are marked.";
  h << "</p>\n";
  return h.str();
}

std::string rejectedTable(const CalibrateResult& r, const std::vector<std::size_t>& images) {
  std::map<std::string, int> counts;
  std::vector<std::size_t> rows;
  for (std::size_t i : images)
    if (!r.images[i].skipped.empty()) {
      ++counts[r.images[i].skipped];
      rows.push_back(i);
    }
  std::ostringstream h;
  if (rows.empty()) {
    h << "<p class=\"note\">No image was rejected.</p>\n";
    return h.str();
  }
  // Outliers first: they say most about the calibration.
  std::stable_sort(rows.begin(), rows.end(), [&](std::size_t a, std::size_t b) {
    return (r.images[a].skipped == "outlier") > (r.images[b].skipped == "outlier");
  });
  h << "<p>Images not used: ";
  bool first = true;
  for (const auto& [reason, n] : counts) {
    h << (first ? "" : ", ") << n << " " << xmlEscape(reason);
    first = false;
  }
  h << ".</p>\n<table class=\"rejected\"><tr><th class=\"name\">image</th><th class=\"name\">reason</th>"
       "<th class=\"name\">detail</th></tr>\n";
  constexpr std::size_t kMaxRows = 30;
  for (std::size_t k = 0; k < std::min(rows.size(), kMaxRows); ++k) {
    const ImageOutcome& im = r.images[rows[k]];
    h << "<tr><td class=\"name\">" << xmlEscape(relativeToDataset(r, im.path)) << "</td><td class=\"name\">"
      << xmlEscape(im.skipped) << "</td><td class=\"name\">" << xmlEscape(im.detail) << "</td></tr>\n";
  }
  h << "</table>\n";
  if (rows.size() > kMaxRows) h << "<p class=\"note\">… and " << rows.size() - kMaxRows << " more.</p>\n";
  return h.str();
}

std::string overlaysHtml(const CalibrateResult& r, const std::vector<Overlay>& overlays) {
  std::ostringstream h;
  if (overlays.empty()) return "<p class=\"note\">No image to show.</p>\n";
  h << "<p class=\"note\"><span class=\"swatch\" style=\"background:#00c800\"></span>detected corners (green circles)"
       " &nbsp; <span class=\"swatch\" style=\"background:#e62828\"></span>corners predicted by kinematics + "
       "calibration (red crosses)</p>\n<div class=\"overlays\">\n";
  for (const Overlay& o : overlays) {
    const ImageOutcome& im = r.images[o.image];
    std::string caption = o.tag + " · " + relativeToDataset(r, im.path);
    if (o.tag == "rejected")
      caption += " · chi-square " + fmt(fiducialChi2(r, im), 1);
    else
      caption += " · RMS " + fmt(im.rms_px, 3) + " px";
    h << "<figure>";
    if (o.error.empty())
      h << "<img src=\"" << xmlEscape(o.file) << "\" alt=\"" << xmlEscape(caption) << "\">";
    else
      h << "<p class=\"note\">image not drawn: " << xmlEscape(o.error) << "</p>";
    h << "<figcaption>" << xmlEscape(caption) << "</figcaption></figure>\n";
  }
  h << "</div>\n";
  return h.str();
}

std::string pageHtml(const CalibrateResult& r, const std::vector<std::vector<Overlay>>& overlays) {
  std::ostringstream h;
  const std::string method = r.output.method.empty() ? "?" : r.output.method;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<meta name=\"generator\" content=\""
    << kGenerator << "\">\n<title>fgcal calibration report — " << xmlEscape(info(r, "dataset")) << "</title>\n<style>"
    << kCss << "</style></head>\n<body>\n";
  h << "<header id=\"header\"><h1>fgcal calibration report</h1>\n<p class=\"meta\">dataset <code>"
    << xmlEscape(info(r, "dataset")) << "</code> · method " << xmlEscape(method)
    << (method == "F1" ? " (each camera alone)" : method == "F2" ? " (cameras jointly)" : "") << " · "
    << r.solution.instants << " instants · images used " << cameraCount(r) << " · chain "
    << xmlEscape(r.rig.robot.base_link) << " → " << xmlEscape(r.rig.robot.marker_link) << "</p>\n";
  if (r.warnings.empty())
    h << "<div class=\"verdict ok\">No warnings: the data observe every camera and the board mount, and few images "
         "were rejected.</div>\n";
  else
    h << "<div class=\"verdict warn\">" << r.warnings.size() << " warning" << (r.warnings.size() > 1 ? "s" : "")
      << ": read before trusting the result.</div>\n";
  h << "</header>\n";

  h << "<section id=\"warnings\"><h2>Warnings</h2>\n";
  if (r.warnings.empty()) {
    h << "<p class=\"note\">None.</p>\n";
  } else {
    h << "<ul class=\"warnings\">\n";
    for (const auto& w : r.warnings) h << "<li>" << xmlEscape(w) << "</li>\n";
    h << "</ul>\n";
  }
  h << "</section>\n";

  h << "<section id=\"results\"><h2>Results</h2>\n" << resultsTable(r) << "</section>\n";

  h << "<section id=\"rig\"><h2>The rig</h2>\n<p class=\"note\">Base frame, each camera's frustum at its estimated "
       "pose, and the centre of the board at every instant it was used, coloured by the camera that saw it.</p>\n"
       "<div class=\"plots\">\n"
    << rigPlot(r, true) << rigPlot(r, false) << "</div></section>\n";

  h << "<section id=\"convergence-section\"><h2>Convergence</h2>\n" << convergencePlot(r);
  if (!r.solution.solves.empty()) {
    const OptimizerResult& last = r.solution.solves.back();
    h << "<p class=\"note\">Last solve: " << last.iterations << " iterations, cost " << fmt(last.initial_cost, 3)
      << " → " << fmt(last.final_cost, 3) << ", " << xmlEscape(last.message.empty() ? toString(last.termination) : last.message)
      << ", " << xmlEscape(last.linear_solver) << ". Robust solves (dashed) down-weight outliers; the chi-square gate "
         "then removes them and the final solve is plain least squares.</p>\n";
  }
  h << "</section>\n";

  const auto by_cam = imagesByCamera(r);
  std::int64_t t0 = 0;
  bool have_t0 = false;
  for (const auto& im : r.images)
    if (!have_t0 || im.stamp_ns < t0) {
      t0 = im.stamp_ns;
      have_t0 = true;
    }
  for (std::size_t c = 0; c < r.output.cameras.size(); ++c) {
    const CameraResult& cr = r.output.cameras[c];
    const CameraData d = cameraData(r, by_cam[c], t0);
    h << "<section id=\"camera-" << c << "\" class=\"camera\"><h2><span class=\"swatch\" style=\"background:"
      << cameraColor(c) << "\"></span>Camera " << xmlEscape(cr.name) << "</h2>\n<p class=\"meta\">" << cr.images_used
      << " images used of " << by_cam[c].size() << ", reprojection RMS " << fmt(cr.rms_reprojection_px, 3)
      << " px (final solution: board pose from the kinematics and the estimated mount, projected through the "
         "estimated camera pose).</p>\n<div class=\"plots\">\n"
      << reprojectionScatter(d, c) << reprojectionHistogram(d, c) << residualsOverTime(d, c)
      << "</div>\n<h3>Rejected images</h3>\n"
      << rejectedTable(r, by_cam[c]) << "<h3>Images</h3>\n"
      << overlaysHtml(r, c < overlays.size() ? overlays[c] : std::vector<Overlay>{}) << "</section>\n";
  }

  h << "<section id=\"summary\"><h2>Summary as printed</h2><pre>" << xmlEscape(r.summary) << "</pre></section>\n";
  h << "<footer class=\"note\">Written by fgcal: a self-contained page (no script, no network resource); the images "
       "are in images/ beside it.</footer>\n</body></html>\n";
  return h.str();
}

bool isOurReport(const fs::path& dir) {
  std::error_code ec;
  if (fs::is_empty(dir, ec) && !ec) return true;
  std::ifstream in(dir / "index.html");
  std::string head(4096, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return head.find(kGenerator) != std::string::npos;
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.flush();
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace

std::vector<std::string> reportPlotIds(const CalibrateResult& result) {
  std::vector<std::string> ids = {"rig-top", "rig-side", "convergence"};
  for (std::size_t c = 0; c < result.output.cameras.size(); ++c)
    for (const char* p : {"reprojection-scatter-", "reprojection-histogram-", "residuals-time-"})
      ids.push_back(p + std::to_string(c));
  return ids;
}

std::string formatReportHtml(const CalibrateResult& result, const ReportOptions& options) {
  return pageHtml(result, pickOverlays(result, options.images_per_camera));
}

void checkReportFolder(const std::string& dir) {
  const fs::path target = fs::absolute(dir).lexically_normal();
  const fs::path final_dir = target.filename().empty() ? target.parent_path() : target;
  const fs::path parent = final_dir.parent_path();
  if (!fs::is_directory(parent)) throw InputError(dir, "", "the report's parent folder " + parent.string() + " does not exist");
  if (fs::exists(final_dir) && !fs::is_directory(final_dir))
    throw InputError(dir, "", "exists and is not a folder; the report needs a folder");
  if (fs::exists(final_dir) && !isOurReport(final_dir))
    throw InputError(dir, "", "the folder exists and is not an fgcal report; it is left untouched (choose another report folder)");
}

std::string writeReport(const CalibrateResult& result, const std::string& dir, const ReportOptions& options) {
  checkReportFolder(dir);
  const fs::path target = fs::absolute(dir).lexically_normal();
  const fs::path name = target.filename().empty() ? target.parent_path().filename() : target.filename();
  const fs::path final_dir = target.filename().empty() ? target.parent_path() : target;
  const fs::path parent = final_dir.parent_path();

  static std::atomic<int> counter{0};
  const std::string suffix = std::to_string(::getpid()) + "-" + std::to_string(counter++);
  const fs::path tmp = parent / ("." + name.string() + ".tmp-" + suffix);
  try {
    fs::create_directory(tmp);
    fs::create_directory(tmp / "images");
    auto overlays = pickOverlays(result, options.images_per_camera);
    std::map<std::size_t, cv::Mat> loaded;
    if (options.load_images) {
      std::vector<std::size_t> wanted;
      for (const auto& cam : overlays)
        for (const Overlay& o : cam) wanted.push_back(o.image);
      try {
        loaded = options.load_images(wanted);
      } catch (const std::exception&) {
        // Every picture then says it could not be read; the report itself stands.
      }
    }
    for (auto& cam : overlays)
      for (Overlay& o : cam) {
        try {
          const auto it = loaded.find(o.image);
          drawOverlay(result.images[o.image], it == loaded.end() ? cv::Mat() : it->second,
                      static_cast<bool>(options.load_images), (tmp / o.file).string());
        } catch (const std::exception& e) {
          o.error = e.what();  // a moved or unreadable image costs its picture only
        }
      }
    writeText(tmp / "index.html", pageHtml(result, overlays));
    if (options.before_commit) options.before_commit(tmp.string());
    // Swap the new folder in atomically when an earlier report is there, then
    // drop the earlier one; a plain rename otherwise.
    if (fs::exists(final_dir)) {
      if (::renameat2(AT_FDCWD, tmp.c_str(), AT_FDCWD, final_dir.c_str(), RENAME_EXCHANGE) != 0) {
        const fs::path old = parent / ("." + name.string() + ".old-" + suffix);
        fs::rename(final_dir, old);
        try {
          fs::rename(tmp, final_dir);
        } catch (...) {
          fs::rename(old, final_dir);
          throw;
        }
        std::error_code ignored;  // committed: a leftover old copy costs disk, not the report
        fs::remove_all(old, ignored);
      } else {
        std::error_code ignored;
        fs::remove_all(tmp, ignored);  // now the earlier report
      }
    } else {
      fs::rename(tmp, final_dir);
    }
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  }
  return (final_dir / "index.html").string();
}

}  // namespace fgcal::apps
