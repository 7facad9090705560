// runCalibrate's results (calibrate_stages.hpp): calibration.yaml's content,
// the gate's outliers, the errors against ground truth, the summary.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "calibration/graph_parts.hpp"
#include "commands/calibrate/calibrate_stages.hpp"
#include "version.hpp"

namespace fgcal::apps::stages {

namespace {

std::string fmt(double v, int precision = 2) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << v;
  return s.str();
}

void summarizeCamera(std::ostringstream& sum, const CameraResult& cr) {
  const Vec6 xr = cr.T_base_cam.xyzRpy();
  const Vec6 sg = sigmaMmDeg(cr.T_base_cam, cr.covariance);
  int total = cr.images_used;
  for (const auto& [r, k] : cr.images_skipped) total += k;
  sum << "  " << cr.name << ": xyz [" << fmt(xr[0], 4) << ", " << fmt(xr[1], 4) << ", " << fmt(xr[2], 4)
      << "] m, rpy [" << fmt(xr[3] * 180 / M_PI, 3) << ", " << fmt(xr[4] * 180 / M_PI, 3) << ", "
      << fmt(xr[5] * 180 / M_PI, 3) << "] deg\n"
      << "      1-sigma [" << fmt(sg[0]) << ", " << fmt(sg[1]) << ", " << fmt(sg[2]) << "] mm, [" << fmt(sg[3], 3)
      << ", " << fmt(sg[4], 3) << ", " << fmt(sg[5], 3) << "] deg; reprojection RMS " << fmt(cr.rms_reprojection_px)
      << " px\n"
      << "      images: " << cr.images_used << " used of " << total;
  for (const auto& [r, k] : cr.images_skipped) sum << ", " << k << " " << r;
  sum << "\n";
  if (!cr.intrinsics.empty()) {  // --estimate intrinsics
    sum << "      intrinsics [fx fy cx cy] (1-sigma):";
    for (std::size_t i = 0; i < cr.intrinsics.size(); ++i)
      sum << " " << fmt(cr.intrinsics[i], 2) << " (" << fmt(cr.intrinsics_sigma[i], 2) << ")";
    if (!cr.distortion_coeffs.empty()) {
      sum << "; distortion:";
      for (std::size_t i = 0; i < cr.distortion_coeffs.size(); ++i)
        sum << " " << fmt(cr.distortion_coeffs[i], 5) << " (" << fmt(cr.distortion_coeffs_sigma[i], 5) << ")";
    }
    sum << "\n";
  }
}

void summarizeMount(std::ostringstream& sum, const MountResult& mount, const RigConfig& rig) {
  if (!mount.estimated) {
    sum << "  board mount held fixed at the rig.yaml value\n";
    return;
  }
  const Vec6 xr = mount.T_link_marker.xyzRpy();
  const Vec6 sg = sigmaMmDeg(mount.T_link_marker, mount.covariance);
  const Vec6 d = rig.robot.T_link_marker.minus(mount.T_link_marker);
  sum << "  board mount (" << rig.robot.marker_link << " -> marker): xyz [" << fmt(xr[0], 4) << ", " << fmt(xr[1], 4)
      << ", " << fmt(xr[2], 4) << "] m, 1-sigma [" << fmt(sg[0]) << ", " << fmt(sg[1]) << ", " << fmt(sg[2])
      << "] mm; moved " << fmt(d.tail<3>().norm() * 1e3) << " mm, " << fmt(d.head<3>().norm() * 180 / M_PI, 3)
      << " deg from the rig.yaml prior\n";
}

/// "verdict: CHECK" and each finding with its fields, first in the summary.
void summarizeQuality(std::ostringstream& sum, const Quality& q) {
  std::string verdict = toString(q.verdict);
  std::transform(verdict.begin(), verdict.end(), verdict.begin(), [](unsigned char ch) { return std::toupper(ch); });
  sum << "verdict: " << verdict;
  if (q.verdict == Verdict::Ok) sum << " (no check flagged the result)";
  if (q.verdict == Verdict::Check) sum << " (the result is written; read the findings before trusting it)";
  if (q.verdict == Verdict::Unusable) sum << " (no calibration output is written)";
  sum << "\n";
  for (const Finding& f : q.findings) {
    sum << "  " << toString(f.severity) << " [" << f.check << "]";
    if (!f.fields.empty()) {
      sum << " fields:";
      for (const std::string& x : f.fields) sum << " " << x;
    }
    sum << "\n      " << f.message << "\n";
    if (!f.estimate.empty()) {
      sum << "      the data suggest:";
      for (const auto& [k, v] : f.estimate) sum << " " << k << " = " << v << ";";
      sum << "\n";
    }
    if (!f.command.empty()) sum << "      run: " << f.command << "\n";
  }
}


}  // namespace

std::string utcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

CalibrationOutput assembleOutput(const Inputs& in, const BuiltProblem& built, const Reprojection& rp,
                                 const CalibrateOptions& opt, const CalibrationSolution& sol) {
  CalibrationOutput out;
  out.method = toString(opt.method);
  out.estimated = names(opt.estimate);
  for (std::size_t c = 0; c < in.rig.cameras.size(); ++c) {
    CameraResult cr;
    cr.name = in.rig.cameras[c].name;
    cr.T_base_cam = sol.cameras[c].T_base_cam;
    cr.covariance = sol.cameras[c].covariance;
    cr.images_used = sol.cameras[c].observations_used;
    cr.rms_reprojection_px = rp.corners[c] ? std::sqrt(rp.squared[c] / static_cast<double>(rp.corners[c])) : 0.0;
    for (const ImageRecord& r : in.images)
      if (r.camera == c && r.status != ImageStatus::Used) ++cr.images_skipped[skipKey(r.status)];
    // rig.yaml's readout, held; an estimate replaces it (addOffsetResults).
    if (in.rig.cameras[c].readout_ms > 0.0) cr.readout_ms = in.rig.cameras[c].readout_ms;
    out.cameras.push_back(cr);
  }
  out.mount.T_link_marker = sol.T_link_marker;
  out.mount.covariance = sol.mount_covariance;
  out.mount.estimated = sol.mount_estimated;
  addOffsetResults(sol.offsets, &out);
  for (std::size_t i = 0; i < out.cameras.size(); ++i)
    for (std::size_t j = i + 1; j < out.cameras.size(); ++j) {
      Mat6 cross = Mat6::Zero();
      for (const CalibrationSolution::CrossCovariance& c : sol.camera_cross_covariances)
        if (c.a == i && c.b == j) cross = c.cov;
      out.relative_poses.push_back(relativePose(out.cameras[i], out.cameras[j], cross));
    }
  const OptimizerResult& last = sol.solves.back();
  // The stamp first (which fgcal, when, from which rig.yaml and data): what a
  // reader needs to reproduce or date a result found later.
  out.info = {{"fgcal_version", versionText()},
              {"date_utc", utcNow()},
              {"rig", stampedRigPath(in)},
              {in.from_bag ? "bag" : "dataset", in.source},
              {"solve", solveLabel(opt)},
              {"base_link", in.rig.robot.base_link},
              {"marker_link", in.rig.robot.marker_link},
              {"instants", std::to_string(sol.instants)},
              {"images", std::to_string(in.images.size())},
              {"final_cost", fmt(last.final_cost, 6)},
              {"iterations", std::to_string(last.iterations)},
              {"linear_solver", last.linear_solver},
              {"pnp_covariance_scale", fmt(built.problem.fiducial_covariance_scale, 6)}};
  return out;
}

std::vector<RejectedImage> damagedImages(const Inputs& in) {
  std::vector<RejectedImage> out;
  for (std::size_t i = 0; i < in.images.size(); ++i)
    if (in.images[i].status == ImageStatus::Unreadable) out.push_back({in.imageName(i), in.details[in.images[i].detail]});
  return out;
}

std::vector<Finding> damagedFindings(const Inputs& in) {
  std::vector<Finding> out;
  for (std::size_t c = 0; c < in.rig.cameras.size(); ++c) {
    std::size_t total = 0, damaged = 0;
    for (const ImageRecord& r : in.images) {
      if (r.camera != c) continue;
      ++total;
      if (r.status == ImageStatus::Unreadable) ++damaged;
    }
    // Most of a camera's images: the recording (or its transport), not a stray message.
    if (total == 0 || 2 * damaged <= total) continue;
    const CameraConfig& cc = in.rig.cameras[c];
    const bool none_left = damaged == total;
    const std::string where = in.from_bag ? "topic " + cc.topic : "folder " + cc.name + "/";
    out.push_back({"damaged_messages", none_left ? Severity::Unusable : Severity::Check,
                   {cameraField(cc.name, in.from_bag ? "topic" : "name")},
                   std::to_string(damaged) + " of the " + std::to_string(total) + " images of camera " + cc.name +
                       " (" + where + ") are damaged and were skipped" +
                       (none_left ? ": nothing is left to calibrate it with"
                                  : ": the rest may not be what the camera saw") +
                       ". Check the recording (a raw Image's data shorter than its step x height, a "
                       "CompressedImage that does not decode) and record again, or leave the camera out (--cameras)",
                   {},
                   {}});
  }
  return out;
}

std::vector<RejectedImage> rejectedImages(const Inputs& in) {
  std::vector<RejectedImage> out;
  for (std::size_t i = 0; i < in.images.size(); ++i)
    if (in.images[i].status == ImageStatus::Outlier) out.push_back({in.imageName(i), in.details[in.images[i].detail]});
  return out;
}

void evaluateAgainstTruth(const std::string& ground_truth, CalibrateResult& res) {
  if (ground_truth.empty()) return;
  try {
    GroundTruth truth = loadGroundTruth(ground_truth);
    for (auto it = truth.T_base_cam.begin(); it != truth.T_base_cam.end();) {  // --cameras: a subset
      const bool calibrated = std::any_of(res.output.cameras.begin(), res.output.cameras.end(),
                                          [&](const CameraResult& c) { return c.name == it->first; });
      it = calibrated ? std::next(it) : truth.T_base_cam.erase(it);
    }
    res.evaluation = evaluate(res.output, truth);
    res.ground_truth_path = ground_truth;
  } catch (const std::exception& e) {
    res.warnings.push_back(ground_truth + " not used: " + e.what());
  }
}

std::string formatSummary(const CalibrateResult& res) {
  const CalibrationOutput& out = res.output;
  std::ostringstream sum;
  std::string solve = "F2";
  for (const auto& [k, v] : out.info)
    if (k == "solve") solve = v.substr(0, 2);
  sum << "\n";
  summarizeQuality(sum, out.quality);
  sum << "Calibration (" << out.method << ", " << solve << ", " << res.solution.instants << " instants):\n";
  for (const CameraResult& cr : out.cameras) summarizeCamera(sum, cr);
  summarizeMount(sum, out.mount, res.rig);
  sum << formatOffsetSummary(res.solution.offsets);
  for (std::size_t k = 0; k < std::min<std::size_t>(res.rejected.size(), 5); ++k)
    sum << "  rejected " << res.rejected[k].image << ": " << res.rejected[k].reason << "\n";
  if (res.rejected.size() > 5) sum << "  ... " << res.rejected.size() - 5 << " more rejected\n";
  // Damaged messages are skipped, never fatal alone: each is named (topic and stamp) so the recording can be checked.
  for (std::size_t k = 0; k < std::min<std::size_t>(res.damaged.size(), 5); ++k)
    sum << "  damaged, skipped: " << res.damaged[k].reason << "\n";
  if (res.damaged.size() > 5) sum << "  ... " << res.damaged.size() - 5 << " more damaged messages skipped\n";
  return sum.str();  // every warning of the run so far is one of the findings above
}

std::string stampedRigPath(const Inputs& in) {
  std::error_code ec;
  const std::filesystem::path rig = std::filesystem::absolute(in.rig_path, ec).lexically_normal();
  return ec ? in.rig_path : rig.string();
}

std::string solveLabel(const CalibrateOptions& opt) {
  return opt.single_camera ? "F1 (each camera alone)" : "F2 (cameras jointly)";
}

bool mostImagesRejected(const CalibrationProblemInput& problem, const CalibrationSolution& sol) {
  const auto [total, rejected] = detail::gatedImages(problem, sol);
  for (std::size_t c = 0; c < total.size(); ++c)
    if (2 * rejected[c] > total[c]) return true;
  return false;
}

}  // namespace fgcal::apps::stages
