// The report's HTML page (report_parts.hpp): header, stamp and verdict,
// warnings, the results (poses, then what --estimate added), the rig,
// convergence, one section per camera, the summary.
#include <algorithm>
#include <filesystem>
#include <numeric>
#include <sstream>

#include "io/text_format.hpp"
#include "report/report_parts.hpp"

namespace fgcal::apps::report {

namespace {

using detail::xmlEscape;

const char* kCss = R"(
body{font-family:sans-serif;font-size:14px;color:#222;max-width:1160px;margin:16px auto;padding:0 12px;background:#fafafa}
h1{font-size:22px;margin:4px 0}h2{font-size:18px;margin:22px 0 8px;border-bottom:1px solid #ddd;padding-bottom:4px}
.meta{color:#555;margin:4px 0 10px}
.verdict{padding:8px 12px;border-radius:4px;margin:10px 0;font-weight:bold}
.verdict.ok{background:#e8f5e9;border-left:5px solid #2e7d32}
.verdict.warn{background:#fff4e5;border-left:5px solid #ef6c00}
.verdict.bad{background:#ffebee;border-left:5px solid #c62828}
table.findings td,table.findings th{text-align:left;vertical-align:top}
td.sev-check{background:#fff4e5}td.sev-unusable{background:#ffebee}
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

/// An image as the page names it: relative to the dataset folder when inside it.
std::string shownName(const ReportData& d, const std::string& image) {
  if (d.from_bag) return image;
  std::error_code ec;
  const std::filesystem::path rel = std::filesystem::relative(image, d.dataset, ec);
  return ec || rel.empty() || rel.native().rfind("..", 0) == 0 ? image : rel.string();
}

// ---- results table ----

/// One row of the results table.
struct PoseRow {
  std::string name;
  const SE3* T = nullptr;
  const Mat6* cov = nullptr;
  bool has_cov = false;
  std::string used, rms;
  const std::optional<PoseError>* error = nullptr;
};

void poseRow(std::ostringstream& h, const PoseRow& r, bool truth) {
  const Vec6 xr = r.T->xyzRpy();
  h << "<tr><td class=\"name\">" << xmlEscape(r.name) << "</td>";
  for (int k = 0; k < 3; ++k) h << "<td>" << fmt(xr[k], 4) << "</td>";
  for (int k = 3; k < 6; ++k) h << "<td>" << fmt(rad2deg(xr[k]), 3) << "</td>";
  if (r.has_cov) {
    const Vec6 sg = sigmaMmDeg(*r.T, *r.cov);
    h << "<td>" << fmt(sg[0], 2) << ", " << fmt(sg[1], 2) << ", " << fmt(sg[2], 2) << "</td><td>" << fmt(sg[3], 3)
      << ", " << fmt(sg[4], 3) << ", " << fmt(sg[5], 3) << "</td>";
  } else {
    h << "<td colspan=\"2\" class=\"name\">held fixed</td>";
  }
  h << "<td>" << r.used << "</td><td>" << r.rms << "</td>";
  if (truth) {
    if (const auto& err = *r.error) {
      const bool high = std::isfinite(err->nees) && err->nees > 12.59;
      h << "<td>" << fmt(err->translation_mm, 3) << "</td><td>" << fmt(err->rotation_deg, 4) << "</td><td"
        << (high ? " class=\"bad\"" : "") << ">" << fmt(err->nees, 2) << "</td>";
    } else {
      h << "<td>–</td><td>–</td><td>–</td>";
    }
  }
  h << "</tr>\n";
}

int imagesOf(const CameraResult& cr) {
  int total = cr.images_used;
  for (const auto& [k, n] : cr.images_skipped) total += n;
  return total;
}

std::string resultsTable(const ReportData& d) {
  std::ostringstream h;
  const bool truth = d.has_truth;
  h << "<table id=\"results-table\"><tr><th class=\"name\">pose</th><th>x (m)</th><th>y (m)</th><th>z (m)</th>"
       "<th>roll (°)</th><th>pitch (°)</th><th>yaw (°)</th><th>1σ x, y, z (mm)</th><th>1σ r, p, y (°)</th>"
       "<th>images used</th><th>RMS (px)</th>";
  if (truth) h << "<th>error (mm)</th><th>error (°)</th><th>NEES</th>";
  h << "</tr>\n";
  for (const ReportCamera& cam : d.cameras) {
    const CameraResult& cr = cam.result;
    poseRow(h,
            {cr.name, &cr.T_base_cam, &cr.covariance, true,
             std::to_string(cr.images_used) + " / " + std::to_string(imagesOf(cr)), fmt(cr.rms_reprojection_px, 3),
             &cam.error},
            truth);
  }
  const std::string link = d.marker_link.empty() ? "link" : d.marker_link;
  poseRow(h,
          {"board mount (" + link + " → board)", &d.mount.T_link_marker, &d.mount.covariance, d.mount.estimated, "",
           "", &d.mount_error},
          truth);
  h << "</table>\n<p class=\"note\">Camera poses are T_base_cam in " << xmlEscape(d.base_link)
    << "; roll, pitch, yaw as in a URDF &lt;origin&gt;. 1σ from the marginal covariance of the final solve.";
  if (truth)
    h << " Errors against <code>" << xmlEscape(d.ground_truth_path)
      << "</code>; NEES = eᵀΣ⁻¹e is about 6 when the reported covariance is honest, cells above 12.6 (95 % of "
         "χ²(6)) are marked.";
  h << "</p>\n";
  return h.str();
}

// ---- what --estimate added ----

/// The quantities beyond the poses (the results table has those), below it in
/// the same section: each quantity is shown once.
std::string estimatesHtml(const ReportData& d) {
  if (d.estimates.empty() && d.time_offset_sweeps.empty()) return "";
  std::ostringstream h;
  h << "<h3>Time offsets, joint offsets, intrinsics</h3>\n<table id=\"estimates-table\"><tr>"
       "<th class=\"name\">quantity</th><th class=\"name\">of</th><th class=\"name\">estimate</th>"
       "<th class=\"name\">1σ</th><th class=\"name\">note</th></tr>\n";
  for (const ReportEstimate& e : d.estimates)
    h << "<tr><td class=\"name\">" << xmlEscape(e.group) << "</td><td class=\"name\">" << xmlEscape(e.name)
      << "</td><td class=\"name\">" << xmlEscape(e.value) << "</td><td class=\"name\">" << xmlEscape(e.sigma)
      << "</td><td class=\"name\">" << xmlEscape(e.note) << "</td></tr>\n";
  h << "</table>\n<p class=\"note\">1σ from the marginal covariance of the final solve, the priors included. "
       "A quantity the data do not observe is written as its prior (see the warnings).</p>\n";
  if (!d.time_offset_sweeps.empty()) {
    h << "<p class=\"note\">Each camera's time offset swept around its estimate: the reprojection RMS of the "
         "camera's corners with the board from the kinematics at t + δ and everything else at the solution. A "
         "sharp minimum at the estimate means the leg moved enough for the data to tell the offset.</p>\n"
         "<div class=\"plots\">\n";
    for (std::size_t k = 0; k < d.time_offset_sweeps.size(); ++k)
      h << timeOffsetSweepPlot(d.time_offset_sweeps[k], sweepCamera(d, k));
    h << "</div>\n";
  }
  return h.str();
}

// ---- per camera ----

std::string rejectedTable(const ReportData& d, const ReportCamera& cam) {
  const std::map<std::string, int>& counts = cam.result.images_skipped;
  const int total = std::accumulate(counts.begin(), counts.end(), 0,
                                    [](int s, const auto& kv) { return s + kv.second; });
  std::ostringstream h;
  if (total == 0) {
    h << "<p class=\"note\">No image was rejected.</p>\n";
    return h.str();
  }
  h << "<p>Images not used: ";
  bool first = true;
  for (const auto& [reason, n] : counts) {
    h << (first ? "" : ", ") << n << " " << xmlEscape(reason);
    first = false;
  }
  h << ".</p>\n<table class=\"rejected\"><tr><th class=\"name\">image</th><th class=\"name\">reason</th>"
       "<th class=\"name\">detail</th></tr>\n";
  for (const ReportRejection& r : cam.rejected)
    h << "<tr><td class=\"name\">" << xmlEscape(shownName(d, r.image)) << "</td><td class=\"name\">"
      << xmlEscape(r.reason) << "</td><td class=\"name\">" << xmlEscape(r.detail) << "</td></tr>\n";
  h << "</table>\n";
  if (static_cast<std::size_t>(total) > cam.rejected.size())
    h << "<p class=\"note\">… and " << static_cast<std::size_t>(total) - cam.rejected.size() << " more.</p>\n";
  return h.str();
}

std::string overlaysHtml(const ReportData& d, const ReportCamera& cam, std::size_t c,
                         const std::vector<std::string>& errors) {
  if (cam.overlays.empty()) return "<p class=\"note\">No image to show.</p>\n";
  std::ostringstream h;
  h << "<p class=\"note\"><span class=\"swatch\" style=\"background:#00c800\"></span>detected corners (green circles)"
       " &nbsp; <span class=\"swatch\" style=\"background:#e62828\"></span>corners predicted by kinematics + "
       "calibration (red crosses)</p>\n<div class=\"overlays\">\n";
  for (std::size_t q = 0; q < cam.overlays.size(); ++q) {
    const ReportOverlay& o = cam.overlays[q];
    std::string caption = o.tag + " · " + shownName(d, o.image);
    if (o.tag == "rejected")
      caption += " · chi-square " + fmt(o.fiducial_chi2, 1);
    else
      caption += " · RMS " + fmt(o.rms_px, 3) + " px";
    const std::string error = q < errors.size() ? errors[q] : "";
    h << "<figure>";
    if (error.empty())
      h << "<img src=\"" << xmlEscape(overlayFile(c, q)) << "\" alt=\"" << xmlEscape(caption) << "\">";
    else
      h << "<p class=\"note\">image not drawn: " << xmlEscape(error) << "</p>";
    h << "<figcaption>" << xmlEscape(caption) << "</figcaption></figure>\n";
  }
  h << "</div>\n";
  return h.str();
}

std::string cameraSection(const ReportData& d, std::size_t c, const std::vector<std::string>& overlay_errors) {
  const ReportCamera& cam = d.cameras[c];
  const CameraResult& cr = cam.result;
  std::ostringstream h;
  h << "<section id=\"camera-" << c << "\" class=\"camera\"><h2><span class=\"swatch\" style=\"background:"
    << cameraColor(c) << "\"></span>Camera " << xmlEscape(cr.name) << "</h2>\n<p class=\"meta\">" << cr.images_used
    << " images used of " << cam.images << ", reprojection RMS " << fmt(cr.rms_reprojection_px, 3)
    << " px (final solution: board pose from the kinematics and the estimated mount, projected through the "
       "estimated camera pose).</p>\n<div class=\"plots\">\n"
    << coveragePlot(cam, c) << reprojectionScatter(cam, c) << reprojectionHistogram(cam, c)
    << residualsOverTime(cam, c, d.fiducial_gate)
    << "</div>\n<p class=\"note\">Coverage: every corner detected in the images used (dots), and in the "
       "images with a board pose that the chi-square gate rejected (red crosses), drawn over the image frame with v "
       "downward as the image is shown; images without a board pose are left out. Corners over the whole frame, "
       "the edges and corners included, constrain the calibration best.</p>\n<h3>Rejected images</h3>\n"
    << rejectedTable(d, cam) << "<h3>Images</h3>\n"
    << overlaysHtml(d, cam, c, overlay_errors) << "</section>\n";
  return h.str();
}

// ---- the page's other sections ----

/// The run's warnings that are not already a finding's message.
std::vector<std::string> otherWarnings(const ReportData& d) {
  std::vector<std::string> out;
  for (const auto& w : d.warnings)
    if (std::none_of(d.quality.findings.begin(), d.quality.findings.end(),
                     [&](const Finding& f) { return f.message == w; }))
      out.push_back(w);
  return out;
}

std::string verdictHtml(const ReportData& d) {
  std::ostringstream h;
  switch (d.quality.verdict) {
    case Verdict::Unusable:
      h << "<div class=\"verdict bad\">Verdict: UNUSABLE. No calibration output was written; the findings below "
           "name the input to fix.</div>\n";
      break;
    case Verdict::Check:
      h << "<div class=\"verdict warn\">Verdict: CHECK. Read the findings before trusting the result.</div>\n";
      break;
    case Verdict::Ok:
      h << "<div class=\"verdict ok\">Verdict: OK. No check flagged the result.</div>\n";
      break;
  }
  const std::size_t n = otherWarnings(d).size();
  if (n > 0)
    h << "<div class=\"verdict warn\">" << n << " warning" << (n > 1 ? "s" : "")
      << ": read before trusting the result.</div>\n";
  return h.str();
}

std::string headerHtml(const ReportData& d) {
  std::ostringstream h;
  const std::string method = d.method.empty() ? "?" : d.method;
  const char* source = d.from_bag ? "bag" : "dataset";
  const bool failed = d.quality.verdict == Verdict::Unusable;
  const char* title = failed ? "fgcal: failed calibration" : "fgcal calibration report";
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<meta name=\"generator\" content=\""
    << kGenerator << "\">\n<title>" << title << " — " << xmlEscape(d.dataset) << "</title>\n<style>" << kCss
    << "</style></head>\n<body>\n";
  h << "<header id=\"header\"><h1>" << title << "</h1>\n<p class=\"meta\">" << source << " <code>"
    << xmlEscape(d.dataset) << "</code> · method " << xmlEscape(method)
    << (d.solve.empty() ? "" : ", " + xmlEscape(d.solve)) << " · " << d.instants
    << " instants · images used " << d.images_used << " of " << d.images << " · chain " << xmlEscape(d.base_link)
    << " → " << xmlEscape(d.marker_link) << "</p>\n";
  // The stamp: enough to tell, from a page found later, which fgcal made it,
  // when, and from which inputs (calibration.yaml's info block says the same).
  h << "<p class=\"meta\" id=\"stamp\">" << xmlEscape(d.fgcal_version.empty() ? "fgcal" : d.fgcal_version)
    << " · " << xmlEscape(d.date_utc.empty() ? "date unknown" : d.date_utc) << " · rig <code>"
    << xmlEscape(d.rig.empty() ? "?" : d.rig) << "</code> · " << source << " <code>" << xmlEscape(d.dataset)
    << "</code></p>\n";
  h << verdictHtml(d) << "</header>\n";
  return h.str();
}

/// The findings as calibration.yaml's quality block has them (docs/outputs.md).
std::string qualityHtml(const ReportData& d) {
  std::ostringstream h;
  h << "<section id=\"quality\"><h2>Quality: verdict " << toString(d.quality.verdict) << "</h2>\n";
  if (d.quality.findings.empty()) {
    h << "<p class=\"note\">No findings.</p>\n";
  } else {
    h << "<table class=\"findings\" id=\"findings-table\"><tr><th>severity</th><th>check</th><th>fields</th>"
         "<th>finding</th></tr>\n";
    for (const Finding& f : d.quality.findings) {
      h << "<tr><td class=\"sev-" << toString(f.severity) << "\">" << toString(f.severity) << "</td><td><code>"
        << xmlEscape(f.check) << "</code></td><td>";
      for (const auto& x : f.fields) h << "<code>" << xmlEscape(x) << "</code><br>";
      h << "</td><td>" << xmlEscape(f.message);
      if (!f.estimate.empty()) {
        h << "<br>The data suggest:";
        for (const auto& [k, v] : f.estimate) h << " <code>" << xmlEscape(k) << ": " << xmlEscape(v) << "</code>";
      }
      if (!f.command.empty()) h << "<br>Run: <code>" << xmlEscape(f.command) << "</code>";
      h << "</td></tr>\n";
    }
    h << "</table>\n";
  }
  h << "</section>\n";
  return h.str();
}

std::string warningsHtml(const ReportData& d) {
  std::ostringstream h;
  h << "<section id=\"warnings\"><h2>Other warnings</h2>\n";
  const std::vector<std::string> other = otherWarnings(d);
  if (other.empty()) {
    h << "<p class=\"note\">None beyond the findings.</p>\n";
  } else {
    h << "<ul class=\"warnings\">\n";
    for (const auto& w : other) h << "<li>" << xmlEscape(w) << "</li>\n";
    h << "</ul>\n";
  }
  h << "</section>\n";
  return h.str();
}

// Damaged messages: skipped, counted with the unreadable images, and named here.
std::string damagedHtml(const ReportData& d) {
  if (d.damaged.empty()) return "";
  std::ostringstream h;
  h << "<section id=\"damaged\"><h2>Damaged messages skipped</h2>\n<p>" << d.damaged.size()
    << " image message(s) could not be read and were skipped.</p>\n<table class=\"rejected\"><tr><th "
       "class=\"name\">message</th><th class=\"name\">why</th></tr>\n";
  for (std::size_t k = 0; k < d.damaged.size() && k < ReportCamera::kMaxRejectedRows; ++k)
    h << "<tr><td class=\"name\">" << xmlEscape(shownName(d, d.damaged[k].image)) << "</td><td class=\"name\">"
      << xmlEscape(d.damaged[k].detail) << "</td></tr>\n";
  h << "</table>\n";
  if (d.damaged.size() > ReportCamera::kMaxRejectedRows)
    h << "<p class=\"note\">… and " << d.damaged.size() - ReportCamera::kMaxRejectedRows << " more.</p>\n";
  h << "</section>\n";
  return h.str();
}

std::string convergenceHtml(const ReportData& d) {
  std::ostringstream h;
  h << "<section id=\"convergence-section\"><h2>Convergence</h2>\n" << convergencePlot(d);
  if (!d.solves.empty()) {
    const ReportSolve& last = d.solves.back();
    h << "<p class=\"note\">Last solve: " << last.iterations << " iterations, cost " << fmt(last.initial_cost, 3)
      << " → " << fmt(last.final_cost, 3) << ", " << xmlEscape(last.termination) << ", "
      << xmlEscape(last.linear_solver) << ". Robust solves (dashed) down-weight outliers; the chi-square gate then removes them and the final solve "
         "is plain least squares.</p>\n";
  }
  h << "</section>\n";
  return h.str();
}

}  // namespace

std::string overlayFile(std::size_t c, std::size_t q) {
  return "images/cam" + std::to_string(c) + "_" + std::to_string(q) + ".png";
}

std::string pageHtml(const ReportData& d, const std::vector<std::vector<std::string>>& overlay_errors) {
  std::ostringstream h;
  h << headerHtml(d) << qualityHtml(d) << warningsHtml(d) << damagedHtml(d);
  h << "<section id=\"results\"><h2>Results</h2>\n" << resultsTable(d) << estimatesHtml(d) << "</section>\n";
  h << "<section id=\"rig\"><h2>The rig</h2>\n<p class=\"note\">Base frame; the robot's links as grey lines "
       "between link origins, at the URDF's zero pose (every joint at 0, not the pose of any instant); each "
       "camera's frustum at its estimated pose (solid, its origin a dot) and, for a camera whose <code>frame:</code> "
       "rig.yaml sets, at that link's URDF pose (dashed, its origin a cross); and the centre of the board at every "
       "instant it was used, coloured by the camera that saw it.</p>\n<div class=\"plots\">\n"
    << rigPlot(d, RigView::Top) << rigPlot(d, RigView::Side) << rigPlot(d, RigView::Front) << "</div></section>\n";
  h << convergenceHtml(d);
  for (std::size_t c = 0; c < d.cameras.size(); ++c)
    h << cameraSection(d, c, c < overlay_errors.size() ? overlay_errors[c] : std::vector<std::string>{});
  h << "<section id=\"summary\"><h2>Summary as printed</h2><pre>" << xmlEscape(d.summary) << "</pre></section>\n";
  h << "<footer class=\"note\">Written by fgcal: a self-contained page (no script, no network resource); the images "
       "are in images/ beside it.</footer>\n</body></html>\n";
  return h.str();
}

}  // namespace fgcal::apps::report
