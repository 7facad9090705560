// The calibration report: the SVG plotting helper (well-formed
// output, axis ranges, ticks, escapes, image-style y axis) and the report
// writer (every section and plot present, the stamp in the page and in
// calibration.yaml, one results section, a coverage picture per camera, the
// robot's links and URDF camera poses in the rig views, overlay PNGs beside
// the page, nothing loaded from the network, atomic folder writes: no partial
// folder after a failure, an earlier report left intact, a foreign folder
// never replaced, no report from a failing run).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include <catch2/catch.hpp>

#include "apps_test_util.hpp"
#include "fgcal/apps/calibrate.hpp"
#include "fgcal/apps/report.hpp"
#include "fgcal/apps/simulator.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "io/text_format.hpp"
#include "report/svg_plot.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using fgcal::apps::test::readFile;
using fgcal::apps::test::TempDir;
using fgcal::apps::test::writeFile;
namespace fs = std::filesystem;

namespace {

/// A small XML well-formedness check: tags balance, attributes are quoted,
/// no raw '<' or '&' in text. Returns an empty string or what is wrong.
std::string xmlProblem(const std::string& s) {
  std::vector<std::string> stack;
  std::size_t i = 0;
  while (i < s.size()) {
    if (s[i] == '&') {
      const auto semi = s.find(';', i);
      if (semi == std::string::npos || semi - i > 8) return "raw '&' at " + std::to_string(i);
      i = semi + 1;
      continue;
    }
    if (s[i] != '<') {
      if (s[i] == '>') return "raw '>' at " + std::to_string(i);
      ++i;
      continue;
    }
    const auto end = s.find('>', i);
    if (end == std::string::npos) return "unclosed tag at " + std::to_string(i);
    std::string tag = s.substr(i + 1, end - i - 1);
    i = end + 1;
    if (tag.empty()) return "empty tag";
    if (tag[0] == '/') {
      if (stack.empty() || stack.back() != tag.substr(1)) return "mismatched </" + tag.substr(1) + ">";
      stack.pop_back();
      continue;
    }
    const bool self_closing = tag.back() == '/';
    if (self_closing) tag.pop_back();
    const std::string name = tag.substr(0, tag.find_first_of(" \n\t"));
    // Attributes: name="value" pairs only, with no '<' inside values.
    std::string rest = tag.substr(name.size());
    static const std::regex attr(R"(^\s+[a-zA-Z_:][-a-zA-Z0-9_:.]*="[^"<]*")");
    std::smatch m;
    while (std::regex_search(rest, m, attr)) rest = m.suffix();
    if (rest.find_first_not_of(" \n\t") != std::string::npos) return "bad attributes in <" + name + ">: " + rest;
    if (!self_closing) stack.push_back(name);
  }
  if (!stack.empty()) return "unclosed <" + stack.back() + ">";
  return "";
}

int count(const std::string& text, const std::string& part) {
  int n = 0;
  for (auto p = text.find(part); p != std::string::npos; p = text.find(part, p + 1)) ++n;
  return n;
}

svg::Series points(std::vector<double> x, std::vector<double> y) {
  svg::Series s;
  s.x = std::move(x);
  s.y = std::move(y);
  s.label = "data";
  return s;
}

}  // namespace

TEST_CASE("xmlEscape: text made safe for XML (URDF snippet and report)") {
  CHECK(apps::detail::xmlEscape("a<b>&\"c'") == "a&lt;b&gt;&amp;&quot;c&#39;");
  CHECK(apps::detail::xmlEscape("plain text 1.5 px") == "plain text 1.5 px");
  CHECK(apps::detail::xmlEscape(std::string("bell\x07")) == "bell ");
}

TEST_CASE("svg: nice ticks at 1-2-5 steps inside the range") {
  CHECK(svg::niceTicks(0.0, 1.0, 5) == std::vector<double>{0.0, 0.2, 0.4, 0.6, 0.8, 1.0});
  const auto t = svg::niceTicks(-3.7, 12.1, 6);
  REQUIRE(t.size() >= 3);
  CHECK(t.front() >= -3.7);
  CHECK(t.back() <= 12.1);
  const double step = t[1] - t[0];
  const double mant = step / std::pow(10.0, std::floor(std::log10(step)));
  CHECK((std::abs(mant - 1) < 1e-9 || std::abs(mant - 2) < 1e-9 || std::abs(mant - 5) < 1e-9));
  CHECK(svg::niceTicks(2.0, 2.0).size() == 1);
  CHECK(svg::niceTicks(NAN, 1.0).empty());
  CHECK(svg::formatNumber(0.25, 0.05) == "0.25");
  CHECK(svg::formatNumber(3.0, 1.0) == "3");
  CHECK(svg::formatNumber(-1e-17, 0.5) == "0.0");
  CHECK(svg::formatNumber(2.5e-7, 1e-7) == "2.5e-7");
  CHECK(svg::formatNumber(1e6, 1e6) == "1e6");
}

TEST_CASE("svg: a plot is well-formed, labelled and escaped") {
  svg::Plot p;
  p.id = "my-plot";
  p.title = "Errors <px> & more";
  p.x_label = "u (px)";
  p.y_label = "v (px)";
  p.add(points({0, 1, 2, 3}, {1, 4, 9, 16}));
  svg::Series line = points({0, 3}, {0, 16});
  line.kind = svg::Series::Kind::Line;
  line.label = "fit \"quoted\"";
  line.dash = "4 2";
  p.add(line);
  p.add(svg::histogram({0.1, 0.2, 0.2, 2.9}, 3, 0.0, 3.0, "hist", "#ff7f0e"));
  p.labels.push_back({1.0, 1.0, "a<b", "#000"});
  const std::string s = p.render();
  INFO(s);
  CHECK(xmlProblem(s).empty());
  CHECK(s.rfind("<svg id=\"my-plot\"", 0) == 0);
  CHECK(s.find("Errors &lt;px&gt; &amp; more") != std::string::npos);
  CHECK(s.find("<px>") == std::string::npos);
  CHECK(s.find("fit &quot;quoted&quot;") != std::string::npos);
  CHECK(s.find("a&lt;b") != std::string::npos);
  CHECK(s.find(">u (px)</text>") != std::string::npos);
  CHECK(s.find(">v (px)</text>") != std::string::npos);
  CHECK(s.find("http") == std::string::npos);  // inline: no namespace URL, nothing to fetch
  CHECK(count(s, "<circle") == 4 + 1);           // the points and the legend's dot
  CHECK(count(s, "<rect x=") >= 3);
  const std::string standalone = p.render(true);
  CHECK(standalone.find("xmlns=\"http://www.w3.org/2000/svg\"") != std::string::npos);
  CHECK(xmlProblem(standalone).empty());
}

TEST_CASE("svg: axis ranges cover the data, are tick-aligned and honour fixed limits") {
  svg::Plot p;
  p.add(points({0.3, 9.6}, {-2.2, 41.0}));
  auto r = p.ranges();
  CHECK(r.x_lo <= 0.3);
  CHECK(r.x_hi >= 9.6);
  CHECK(r.y_lo <= -2.2);
  CHECK(r.y_hi >= 41.0);
  CHECK(r.x_hi - r.x_lo < 2 * 9.3);  // padded, not blown up
  const double ystep = svg::niceStep(r.y_lo, r.y_hi);
  CHECK(std::abs(r.y_lo / ystep - std::round(r.y_lo / ystep)) < 1e-6);
  CHECK(std::abs(r.y_hi / ystep - std::round(r.y_hi / ystep)) < 1e-6);

  p.x_min = -1.0;
  p.x_max = 1.0;
  r = p.ranges();
  CHECK(r.x_lo == -1.0);
  CHECK(r.x_hi == 1.0);

  SECTION("equal aspect: one data unit is as long on both axes") {
    svg::Plot q;
    q.width = 500;
    q.height = 300;
    q.equal_aspect = true;
    q.add(points({0, 1}, {0, 5}));
    const auto e = q.ranges();
    const double pw = 500 - 64 - 18, ph = 300 - (26 + 18 + 8) - 46;  // the layout's margins with one legend row
    CHECK((e.x_hi - e.x_lo) / pw == Approx((e.y_hi - e.y_lo) / ph));
    CHECK(e.y_lo <= 0.0);
    CHECK(e.y_hi >= 5.0);
  }
  SECTION("log axis: whole decades, non-positive values left out") {
    svg::Plot q;
    q.log_y = true;
    q.add(points({0, 1, 2, 3}, {0.0, 3.0, 250.0, -1.0}));
    const auto e = q.ranges();
    CHECK(e.y_lo == 0.0);  // log10: 1
    CHECK(e.y_hi == 3.0);  // log10: 1000
    const std::string s = q.render();
    CHECK(xmlProblem(s).empty());
    CHECK(count(s, "<circle") == 2 + 1);
    CHECK(s.find(">1000</text>") != std::string::npos);
  }
  SECTION("no data: axes and a note, still well-formed") {
    svg::Plot q;
    q.id = "empty";
    const std::string s = q.render();
    CHECK(xmlProblem(s).empty());
    CHECK(s.find("no data") != std::string::npos);
  }
  SECTION("many points are thinned and the title says so") {
    svg::Plot q;
    q.title = "big";
    q.max_points = 100;
    std::vector<double> x(1000), y(1000);
    for (int i = 0; i < 1000; ++i) x[i] = y[i] = i;
    q.add(points(x, y));
    const std::string s = q.render();
    CHECK(count(s, "<circle") == 100 + 1);
    CHECK(s.find("1 point in 10 shown") != std::string::npos);
  }
}

TEST_CASE("svg: y_down draws y growing downward, as image rows do") {
  svg::Plot p;
  p.id = "image";
  p.add(points({5, 5}, {0, 10}));
  auto cys = [](const std::string& s) {
    std::vector<double> out;
    static const std::regex cy(R"re(<circle cx="[^"]*" cy="([^"]*)" r="2")re");
    for (auto it = std::sregex_iterator(s.begin(), s.end(), cy); it != std::sregex_iterator(); ++it)
      out.push_back(std::stod((*it)[1]));
    return out;
  };
  const auto up = cys(p.render());
  REQUIRE(up.size() == 2);
  CHECK(up[0] > up[1]);  // y = 0 below y = 10
  p.y_down = true;
  const std::string s = p.render();
  CHECK(xmlProblem(s).empty());
  const auto down = cys(s);
  REQUIRE(down.size() == 2);
  CHECK(down[0] < down[1]);  // y = 0 above y = 10
}

TEST_CASE("svg: histogram counts, values outside go to the end bins") {
  const auto h = svg::histogram({-1.0, 0.1, 0.2, 0.6, 5.0, NAN}, 2, 0.0, 1.0, "h", "#000");
  REQUIRE(h.y.size() == 2);
  CHECK(h.y[0] == 3.0);
  CHECK(h.y[1] == 2.0);
  CHECK(h.x[0] == Approx(0.25));
  CHECK(h.bar_width == Approx(0.5));
}

// ---- The report writer on a small simulated dataset ---------------------------

namespace {

struct Fixture {
  TempDir dir;
  std::string dataset;
  CalibrateResult result;
  ReportData report;  // what runCalibrate built for the report
  Fixture() {
    dataset = dir / "dataset";
    SimulationOptions sim;
    sim.out_dir = dataset;
    sim.frames = 30;
    sim.seed = 5;
    sim.supersampling = 1;
    sim.mount_error_m = 0.002;
    simulateDataset(sim);
    CalibrateOptions opt;
    opt.dataset = dataset;
    opt.write_files = false;
    opt.threads = 2;
    opt.trace.report_data = true;
    std::ostringstream log;
    result = runCalibrate(opt, log);
    report = *result.trace.report_data;
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

std::vector<std::string> imgSources(const std::string& html) {
  std::vector<std::string> out;
  static const std::regex img("<img src=\"([^\"]+)\"");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), img); it != std::sregex_iterator(); ++it)
    out.push_back((*it)[1]);
  return out;
}

std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST_CASE("report: the pipeline hands the report what it draws") {
  const Fixture& f = fixture();
  const ReportData& d = f.report;
  REQUIRE(f.result.evaluation.has_value());  // the simulated dataset has ground_truth.yaml
  CHECK(d.has_truth);
  REQUIRE(d.cameras.size() == 2);
  std::size_t used = 0, images = 0;
  for (std::size_t c = 0; c < d.cameras.size(); ++c) {
    const ReportCamera& cam = d.cameras[c];
    INFO("camera " << cam.result.name);
    CHECK(cam.result.name == f.result.output.cameras[c].name);
    CHECK(cam.result.T_base_cam.matrix() == f.result.output.cameras[c].T_base_cam.matrix());
    REQUIRE(cam.error.has_value());
    CHECK(cam.images >= static_cast<std::size_t>(cam.result.images_used));
    CHECK(cam.fiducial_used.size() == static_cast<std::size_t>(cam.result.images_used));
    CHECK(cam.kinematic.size() == cam.fiducial_used.size());
    // The residuals of every corner used: their RMS is the camera's reprojection RMS.
    REQUIRE(cam.residuals_px.size() >= 6 * static_cast<std::size_t>(cam.result.images_used));
    double sq = 0.0;
    for (const auto& e : cam.residuals_px) sq += e.squaredNorm();
    CHECK(std::sqrt(sq / static_cast<double>(cam.residuals_px.size())) == Approx(cam.result.rms_reprojection_px));
    // Best, median and worst overlays with their corners and predictions.
    REQUIRE(cam.overlays.size() == 3);
    CHECK(cam.overlays[0].tag == "best");
    CHECK(cam.overlays[2].tag == "worst");
    CHECK(cam.overlays[0].rms_px <= cam.overlays[1].rms_px);
    CHECK(cam.overlays[1].rms_px <= cam.overlays[2].rms_px);
    for (const ReportOverlay& o : cam.overlays) {
      CHECK(o.predicted_px.size() == o.detected_px.size());
      CHECK(o.detected_px.size() >= 6);
    }
    used += static_cast<std::size_t>(cam.result.images_used);
    images += cam.images;
  }
  CHECK(d.images_used == used);
  CHECK(d.images == images);
  CHECK(d.instants == f.result.solution.instants);
  CHECK(d.boards.size() == f.result.solution.instant_estimates.size());
  REQUIRE(d.solves.size() == f.result.solution.solves.size());
  CHECK(d.solves.back().final_cost == f.result.solution.solves.back().final_cost);
  CHECK(d.summary == f.result.summary);
}

TEST_CASE("report: every section and plot, PNGs beside the page, nothing from the network") {
  const ReportData& r = fixture().report;
  TempDir out;
  const std::string index = writeReport(r, out / "report");
  CHECK(index == (fs::path(out / "report") / "index.html").string());
  const std::string html = readFile(index);
  for (const std::string& id : reportPlotIds(r)) {
    INFO("plot " << id);
    CHECK(count(html, "<svg id=\"" + id + "\"") == 1);
  }
  CHECK(reportPlotIds(r).size() == 4 + 4 * 2);
  for (const char* section : {"id=\"warnings\"", "id=\"results\"", "id=\"rig\"", "id=\"convergence-section\"",
                              "id=\"camera-0\"", "id=\"camera-1\"", "id=\"summary\"", "id=\"results-table\""}) {
    INFO(section);
    CHECK(count(html, section) == 1);
  }
  // The results table with the errors against the truth.
  CHECK(html.find("<th>NEES</th>") != std::string::npos);
  CHECK(html.find("board mount (lf_foot") != std::string::npos);
  for (const auto& cam : r.cameras) CHECK(html.find(cam.result.name) != std::string::npos);
  // Overlays: best, median, worst per camera, each a PNG beside the page.
  const auto imgs = imgSources(html);
  CHECK(imgs.size() == 6);
  for (const auto& src : imgs) {
    INFO(src);
    const fs::path png = fs::path(index).parent_path() / src;
    REQUIRE(fs::exists(png));
    CHECK(readFile(png.string()).substr(0, 8) == "\x89PNG\r\n\x1a\n");
  }
  // Self-contained: no script, no stylesheet link, no remote src/href/url().
  static const std::regex remote(R"((src|href)\s*=\s*["']?\s*(https?:|//)|url\(\s*["']?\s*(https?:|//))",
                                 std::regex::icase);
  CHECK_FALSE(std::regex_search(html, remote));
  CHECK(html.find("<script") == std::string::npos);
  CHECK(html.find("<link") == std::string::npos);
  // Nothing left beside it.
  CHECK(entries(out.path()) == std::vector<std::string>{"report"});
}

TEST_CASE("report: a stamp says which fgcal wrote it, when, from which rig.yaml and dataset") {
  const Fixture& f = fixture();
  const ReportData& d = f.report;
  std::map<std::string, std::string> info(f.result.output.info.begin(), f.result.output.info.end());
  // calibration.yaml's info block carries the same stamp.
  CHECK(std::regex_search(info["fgcal_version"], std::regex(R"(^fgcal \d+\.\d+\.\d+)")));
  CHECK(std::regex_match(info["date_utc"], std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")));
  CHECK(info["rig"] == (fs::path(f.dataset) / "rig.yaml").string());
  CHECK(info["dataset"] == f.dataset);
  CHECK(d.fgcal_version == info["fgcal_version"]);
  CHECK(d.date_utc == info["date_utc"]);
  CHECK(d.rig == info["rig"]);
  // ... and it reads back from the file.
  const CalibrationOutput back = parseCalibrationYaml(formatCalibrationYaml(f.result.output), "calibration.yaml");
  CHECK(back.info == f.result.output.info);

  const std::string html = formatReportHtml(d);
  const auto at = html.find("id=\"stamp\"");
  REQUIRE(at != std::string::npos);
  const std::string stamp = html.substr(at, html.find("</p>", at) - at);
  INFO(stamp);
  CHECK(stamp.find(apps::detail::xmlEscape(d.fgcal_version)) != std::string::npos);
  CHECK(stamp.find(d.date_utc) != std::string::npos);
  CHECK(stamp.find(apps::detail::xmlEscape(d.rig)) != std::string::npos);
  CHECK(stamp.find(apps::detail::xmlEscape(f.dataset)) != std::string::npos);
  CHECK(html.find(d.date_utc) < html.find("id=\"quality\""));  // at the top, not buried
}

TEST_CASE("report: one results section, each quantity once: the poses, then what --estimate added") {
  ReportData r = fixture().report;
  // The poses are the results table's; the other estimates do not repeat them.
  for (const ReportEstimate& e : r.estimates) {
    INFO(e.group << " " << e.name);
    CHECK(e.group != "camera pose");
    CHECK(e.group != "board mount");
  }
  std::string html = formatReportHtml(r);
  CHECK(count(html, "<h2>Results</h2>") == 1);
  CHECK(count(html, "<table id=") == 1);  // no estimate beyond the poses: the results table alone
  CHECK(html.find("Estimated quantities") == std::string::npos);
  CHECK(html.find("id=\"estimates\"") == std::string::npos);

  r.estimates.push_back({"time offset", r.cameras[0].result.name, "+1.250 ms", "0.100 ms", "a note <of its own>"});
  html = formatReportHtml(r);
  CHECK(count(html, "<h2>Results</h2>") == 1);
  CHECK(count(html, "id=\"estimates-table\"") == 1);
  const auto results = html.find("id=\"results\""), poses = html.find("id=\"results-table\""),
             extra = html.find("id=\"estimates-table\""), end = html.find("</section>", results);
  CHECK(results < poses);
  CHECK(poses < extra);
  CHECK(extra < end);  // in the same section, below the poses
  CHECK(html.find("a note &lt;of its own&gt;") != std::string::npos);
  CHECK(count(html, "<td class=\"name\">time offset</td>") == 1);
}

namespace {

/// The <svg id="id"> element of `html`, "" when there is none.
std::string svgOf(const std::string& html, const std::string& id) {
  const auto at = html.find("<svg id=\"" + id + "\"");
  if (at == std::string::npos) return "";
  return html.substr(at, html.find("</svg>", at) + 6 - at);
}

/// The centres of the data circles (radius `r`) of an SVG, in order.
std::vector<std::pair<double, double>> circleCentres(const std::string& svg, const std::string& r) {
  std::vector<std::pair<double, double>> out;
  const std::regex circle("<circle cx=\"([^\"]*)\" cy=\"([^\"]*)\" r=\"" + r + "\"");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), circle); it != std::sregex_iterator(); ++it)
    out.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
  return out;
}

}  // namespace

TEST_CASE("report: a coverage picture per camera, one dot per corner used, over the image frame") {
  const Fixture& f = fixture();
  ReportData r = f.report;
  const std::string html = formatReportHtml(r);
  for (std::size_t c = 0; c < r.cameras.size(); ++c) {
    const ReportCamera& cam = r.cameras[c];
    INFO("camera " << cam.result.name);
    // Every corner of the images used (the simulated corners all project, so
    // as many as there are residuals), each inside the image.
    CHECK(cam.corners_used_px.size() == cam.residuals_px.size());
    for (const auto& q : cam.corners_used_px) {
      CHECK(q.x() >= 0.0);
      CHECK(q.y() >= 0.0);
      CHECK(q.x() <= cam.resolution[0]);
      CHECK(q.y() <= cam.resolution[1]);
    }
    const std::string svg = svgOf(html, "coverage-" + std::to_string(c));
    REQUIRE(!svg.empty());
    CHECK(xmlProblem(svg).empty());
    CHECK(circleCentres(svg, "1.4").size() == cam.corners_used_px.size());
    CHECK(svg.find(std::to_string(cam.corners_used_px.size()) + " corners used") != std::string::npos);
    CHECK(svg.find("image " + std::to_string(cam.resolution[0]) + " × " + std::to_string(cam.resolution[1])) !=
          std::string::npos);
  }

  // v downward: a corner in the top row is drawn above one in the bottom row;
  // the rejected images' corners are red crosses with a count of their own.
  ReportCamera& cam = r.cameras[0];
  const double h = cam.resolution[1];
  cam.corners_used_px = {{10.0, 5.0}, {10.0, h - 5.0}};
  cam.corners_rejected_px = {{100.0, 100.0}, {120.0, 100.0}, {140.0, 100.0}};
  const std::string svg = svgOf(formatReportHtml(r), "coverage-0");
  const auto dots = circleCentres(svg, "1.4");
  REQUIRE(dots.size() == 2);
  CHECK(dots[0].second < dots[1].second);
  CHECK(svg.find("3 of rejected images") != std::string::npos);
  CHECK(svg.find("stroke=\"#d62728\"") != std::string::npos);
}

namespace {

/// The `d` attribute of the first <path> of `svg` with `stroke`, "" when none.
std::string pathWithStroke(const std::string& svg, const std::string& stroke) {
  const auto at = svg.find("stroke=\"" + stroke + "\"");
  if (at == std::string::npos) return "";
  const auto d = svg.find(" d=\"", at);
  return d == std::string::npos ? "" : svg.substr(d + 4, svg.find('"', d + 4) - d - 4);
}

}  // namespace

TEST_CASE("report: the rig views draw the robot's links at the URDF zero pose, from above, the side and the front") {
  const Fixture& f = fixture();
  const ReportData& d = f.report;
  // Every link of the dataset's URDF, parents first, at the zero pose in the base frame.
  const auto robot = kinematics::RobotModel::fromFile(f.dataset + "/robot.urdf");
  REQUIRE(d.links.size() == robot.links().size());
  std::size_t segments = 0;
  for (std::size_t k = 0; k < d.links.size(); ++k) {
    INFO(d.links[k].name);
    CHECK(d.links[k].parent < static_cast<int>(k));
    segments += d.links[k].parent >= 0;
    if (d.links[k].name == d.base_link) CHECK(d.links[k].origin_base.norm() == 0.0);
    if (d.links[k].name == "lf_foot")  // hip 0.3735, 0.207; leg 0.08 out, 0.35 + 0.35 down (the URDF's origins)
      CHECK((d.links[k].origin_base - Vec3(0.3735, 0.287, -0.70)).norm() < 1e-12);
  }
  CHECK(segments + 1 == d.links.size());  // a tree: one root

  const std::string html = formatReportHtml(d);
  for (const char* id : {"rig-top", "rig-side", "rig-front"}) {
    INFO(id);
    const std::string svg = svgOf(html, id);
    REQUIRE(!svg.empty());
    CHECK(xmlProblem(svg).empty());
    const std::string links = pathWithStroke(svg, "#a0a0a0");
    CHECK(static_cast<std::size_t>(count(links, "M")) == segments);  // one line per link to its parent
    CHECK(svg.find("robot links (URDF zero pose)") != std::string::npos);
    CHECK(svg.find("camera origin, calibrated") != std::string::npos);
    CHECK(svg.find("URDF (rig.yaml frame:)") == std::string::npos);  // no camera has a frame here
  }
  CHECK(svgOf(html, "rig-front").find(">y (m, left)</text>") != std::string::npos);
  CHECK(svgOf(html, "rig-front").find(">z (m, up)</text>") != std::string::npos);
  CHECK(html.find("zero pose") != std::string::npos);  // the caption says which configuration
}

TEST_CASE("report: a camera with a URDF frame is drawn at its URDF pose beside its calibrated one") {
  const Fixture& f = fixture();
  // cam0's frame: a link whose zero pose the URDF fixes at (0.3735, -0.207, 0), no rotation.
  TempDir tmp;
  fs::copy(f.dataset, tmp / "dataset", fs::copy_options::recursive);
  std::string rig = readFile(tmp / "dataset/rig.yaml");
  const auto first = rig.find("    camera_model:");  // the first camera's
  REQUIRE(first != std::string::npos);
  rig.insert(first, "    frame: rf_hipassembly\n");
  writeFile(tmp / "dataset/rig.yaml", rig);
  CalibrateOptions opt;
  opt.dataset = tmp / "dataset";
  opt.write_files = false;
  opt.threads = 2;
  opt.trace.report_data = true;
  std::ostringstream log;
  const ReportData d = *runCalibrate(opt, log).trace.report_data;
  REQUIRE(d.cameras.size() == 2);
  CHECK(d.cameras[0].frame == "rf_hipassembly");
  REQUIRE(d.cameras[0].T_base_cam_urdf.has_value());
  CHECK((d.cameras[0].T_base_cam_urdf->translation() - Vec3(0.3735, -0.207, 0.0)).norm() < 1e-12);
  CHECK((d.cameras[0].T_base_cam_urdf->rotation().matrix() - Mat3::Identity()).norm() < 1e-12);
  CHECK_FALSE(d.cameras[1].T_base_cam_urdf.has_value());

  const std::string html = formatReportHtml(d);
  for (const char* id : {"rig-top", "rig-side", "rig-front"}) {
    INFO(id);
    const std::string svg = svgOf(html, id);
    CHECK(xmlProblem(svg).empty());
    // Two markers with a legend: calibrated origins (dots), URDF origins (crosses, another colour).
    CHECK(svg.find("camera origin, calibrated") != std::string::npos);
    CHECK(svg.find("camera origin, URDF (rig.yaml frame:)") != std::string::npos);
    const std::string crosses = pathWithStroke(svg, "#c000c0");
    CHECK(count(crosses, "M") == 2);  // one '+' (two strokes) for the one camera with a frame
    CHECK(svg.find(d.cameras[0].result.name + " URDF rf_hipassembly") != std::string::npos);
    CHECK(svg.find("stroke-dasharray=\"5 3\"") != std::string::npos);  // its frustum at the URDF pose, dashed
  }
}

TEST_CASE("report: warnings and rejected images are shown in plain words") {
  ReportData r = fixture().report;
  r.warnings = {"little rotation of the board: <test> & more"};
  // One image of the second camera rejected as an outlier: the counts and the
  // table name it, a 'rejected' overlay shows it.
  ReportCamera& cam = r.cameras[1];
  REQUIRE(cam.result.images_skipped.count("outlier") == 0);
  cam.result.images_skipped["outlier"] = 1;
  cam.rejected.insert(cam.rejected.begin(),
                      {"cam1/123.png", "outlier", "inconsistent with the other images (chi-square 99 > 22.4577)"});
  ReportOverlay rejected = cam.overlays.front();
  rejected.tag = "rejected";
  rejected.image = "cam1/123.png";
  rejected.fiducial_chi2 = 99.0;
  cam.overlays.push_back(rejected);
  const std::string html = formatReportHtml(r);
  CHECK(html.find("little rotation of the board: &lt;test&gt; &amp; more") != std::string::npos);
  CHECK(html.find("1 warning: read before trusting the result") != std::string::npos);
  CHECK(html.find("1 outlier") != std::string::npos);
  CHECK(html.find("inconsistent with the other images") != std::string::npos);
  CHECK(html.find("rejected · cam1/123.png · chi-square 99.0") != std::string::npos);
  CHECK(imgSources(html).size() == 7);
}

TEST_CASE("report: atomic, no partial folder after a failure, earlier report intact") {
  const ReportData& r = fixture().report;
  TempDir out;
  const std::string dir = out / "report";
  ReportOptions failing;
  failing.before_commit = [](const std::string& tmp) {
    CHECK(fs::exists(fs::path(tmp) / "index.html"));  // fully written, not yet in place
    throw std::runtime_error("disk full (injected)");
  };
  CHECK_THROWS_WITH(writeReport(r, dir, failing), Catch::Contains("injected"));
  CHECK(entries(out.path()).empty());  // neither the report nor a temporary folder

  writeReport(r, dir);
  const std::string first = readFile(dir + "/index.html");
  writeFile(dir + "/marker.txt", "earlier");
  CHECK_THROWS(writeReport(r, dir, failing));
  CHECK(entries(out.path()) == std::vector<std::string>{"report"});
  CHECK(readFile(dir + "/index.html") == first);
  CHECK(fs::exists(dir + "/marker.txt"));

  // A successful write replaces the earlier report as a whole.
  writeReport(r, dir);
  CHECK_FALSE(fs::exists(dir + "/marker.txt"));
  CHECK(entries(out.path()) == std::vector<std::string>{"report"});
}

TEST_CASE("report: a folder that is not an fgcal report is never replaced") {
  const ReportData& r = fixture().report;
  TempDir out;
  writeFile(out / "mine/notes.txt", "keep me");
  CHECK_THROWS_AS(writeReport(r, out / "mine"), InputError);
  CHECK(readFile(out / "mine/notes.txt") == "keep me");
  writeFile(out / "file", "x");
  CHECK_THROWS_AS(writeReport(r, out / "file"), InputError);
  CHECK(entries(out.path()) == std::vector<std::string>{"file", "mine"});
}

TEST_CASE("report: runCalibrate writes it beside the output by default, not with report off, not on failure") {
  const Fixture& f = fixture();
  TempDir out;
  CalibrateOptions opt;
  opt.dataset = f.dataset;
  opt.threads = 2;
  opt.output = out / "cal.yaml";
  std::ostringstream log;
  const CalibrateResult r = runCalibrate(opt, log);
  CHECK(r.report_path == (fs::path(out / "cal_report") / "index.html").string());
  CHECK(fs::exists(r.report_path));
  CHECK(log.str().find("report: " + r.report_path) != std::string::npos);
  CHECK(r.timings.report > 0.0);

  TempDir quiet;
  opt.output = quiet / "cal.yaml";
  opt.report = false;
  runCalibrate(opt, log);
  CHECK(entries(quiet.path()) == std::vector<std::string>{"cal.urdf.xml", "cal.yaml"});

  // A dataset that cannot be calibrated (the wrong board dictionary: no board
  // found) writes neither results nor a report.
  TempDir bad;
  fs::copy(f.dataset, bad / "dataset", fs::copy_options::recursive);
  std::string rig = readFile(bad / "dataset/rig.yaml");
  const auto pos = rig.find("DICT_");
  REQUIRE(pos != std::string::npos);
  rig.replace(pos, rig.find_first_of(" \n", pos) - pos, "DICT_6X6_250");
  writeFile(bad / "dataset/rig.yaml", rig);
  opt.dataset = bad / "dataset";
  opt.output = bad / "cal.yaml";
  opt.report = true;
  CHECK_THROWS_AS(runCalibrate(opt, log), DataError);
  CHECK(entries(bad.path()) == std::vector<std::string>{"dataset"});

  // --report naming a folder that is not a report is bad input, found before
  // any work: exit 2, no results written, the folder untouched.
  TempDir mine;
  writeFile(mine / "notes/keep.txt", "keep me");
  opt.dataset = f.dataset;
  opt.output = mine / "cal.yaml";
  opt.report_dir = mine / "notes";
  std::ostringstream early;
  CHECK_THROWS_AS(runCalibrate(opt, early), InputError);
  CHECK(early.str().find("detecting") == std::string::npos);
  CHECK(early.str().find("detected") == std::string::npos);
  CHECK(entries(mine.path()) == std::vector<std::string>{"notes"});
  CHECK(readFile(mine / "notes/keep.txt") == "keep me");
}
