// What the report draws (buildReportData, calibrate_stages.hpp), from the
// run's per-image outcomes, the solution and the results.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "calibration/report_estimates.hpp"
#include "commands/calibrate/calibrate_stages.hpp"
#include "version.hpp"

namespace fgcal::apps::stages {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double fiducialChi2(const CalibrationSolution& sol, const ImageRecord& im) {
  if (im.observation < 0 || static_cast<std::size_t>(im.observation) >= sol.fiducial_chi2.size()) return kNaN;
  return sol.fiducial_chi2[static_cast<std::size_t>(im.observation)];
}

bool used(const ImageRecord& r) { return r.status == ImageStatus::Used; }
bool outlier(const ImageRecord& r) { return r.status == ImageStatus::Outlier; }

/// Per camera (rig order) the indices of its images.
std::vector<std::vector<std::size_t>> imagesByCamera(const Inputs& in) {
  std::vector<std::vector<std::size_t>> out(in.rig.cameras.size());
  for (std::size_t i = 0; i < in.images.size(); ++i) out[in.images[i].camera].push_back(i);
  return out;
}

ReportOverlay overlayOf(const RunView& run, std::size_t image, const std::string& tag) {
  const ImageRecord& im = run.in.images[image];
  const CalibrationProblemInput& problem = run.built.problem;
  ReportOverlay o;
  o.tag = tag;
  o.image = run.in.imageName(image);
  o.image_index = image;
  o.rms_px = im.rms_px;
  o.fiducial_chi2 = fiducialChi2(run.res.solution, im);
  for (std::size_t p = im.corners_begin; p < im.corners_begin + im.corners_count; ++p)
    o.detected_px.push_back(problem.corners.pixel(p));
  o.predicted_px = predictedCorners(problem, run.models, run.res.solution, static_cast<std::size_t>(im.observation));
  return o;
}

/// Best, median and worst (quantiles of the reprojection RMS) of the images
/// a camera used, then its worst outlier.
std::vector<ReportOverlay> pickOverlays(const RunView& run, const std::vector<std::size_t>& images) {
  constexpr std::size_t kPerCamera = 3;
  std::vector<std::size_t> used, outliers;
  for (std::size_t i : images) {
    const ImageRecord& im = run.in.images[i];
    if (im.observation < 0) continue;
    if (stages::used(im)) used.push_back(i);
    if (outlier(im)) outliers.push_back(i);
  }
  std::stable_sort(used.begin(), used.end(), [&](std::size_t a, std::size_t b) {
    return run.in.images[a].rms_px < run.in.images[b].rms_px;
  });
  std::vector<std::size_t> positions;
  const std::size_t n = used.size(), k = kPerCamera;
  for (std::size_t q = 0; q < k && n > 0; ++q) {
    const std::size_t pos = (q * (n - 1) + (k - 1) / 2) / (k - 1);
    if (std::find(positions.begin(), positions.end(), pos) == positions.end()) positions.push_back(pos);
  }
  std::vector<ReportOverlay> out;
  for (std::size_t q = 0; q < positions.size(); ++q) {
    const std::string tag = positions.size() == 1 ? "median"
                            : q == 0              ? "best"
                            : q + 1 == positions.size() ? "worst"
                                                        : "median";
    out.push_back(overlayOf(run, used[positions[q]], tag));
  }
  if (!outliers.empty()) {
    const auto worst = std::max_element(outliers.begin(), outliers.end(), [&](std::size_t a, std::size_t b) {
      return fiducialChi2(run.res.solution, run.in.images[a]) < fiducialChi2(run.res.solution, run.in.images[b]);
    });
    out.push_back(overlayOf(run, *worst, "rejected"));
  }
  return out;
}

/// The images a camera did not use, outliers first (they say most about the
/// calibration), at most ReportCamera::kMaxRejectedRows.
std::vector<ReportRejection> rejectedRows(const Inputs& in, const std::vector<std::size_t>& images) {
  std::vector<std::size_t> rows;
  for (std::size_t i : images)
    if (!used(in.images[i])) rows.push_back(i);
  std::stable_sort(rows.begin(), rows.end(),
                   [&](std::size_t a, std::size_t b) { return outlier(in.images[a]) > outlier(in.images[b]); });
  rows.resize(std::min(rows.size(), ReportCamera::kMaxRejectedRows));
  std::vector<ReportRejection> out;
  for (std::size_t i : rows)
    out.push_back({in.imageName(i), skipKey(in.images[i].status), in.details[in.images[i].detail]});
  return out;
}

/// Every detected corner of the camera's images with a board pose: used, or
/// not (the gate's outliers).
void cornersOf(const RunView& run, const std::vector<std::size_t>& images, ReportCamera& cam) {
  const DetectedCorners& corners = run.built.problem.corners;
  for (std::size_t i : images) {
    const ImageRecord& im = run.in.images[i];
    if (im.observation < 0) continue;
    auto& out = used(im) ? cam.corners_used_px : cam.corners_rejected_px;
    for (std::size_t p = im.corners_begin; p < im.corners_begin + im.corners_count; ++p)
      out.push_back(corners.pixel(p));
  }
}

/// The fiducial chi-square of each image with a board pose over time, and the
/// kinematic chi-square of the instants of the used ones.
void chi2OverTime(const RunView& run, const std::vector<std::size_t>& images, std::int64_t t0, ReportCamera& cam) {
  const CalibrationSolution& sol = run.res.solution;
  for (std::size_t i : images) {
    const ImageRecord& im = run.in.images[i];
    if (im.observation < 0) continue;
    const double t = static_cast<double>(im.stamp_ns - t0) * 1e-9;
    const double chi = fiducialChi2(sol, im);
    if (used(im)) {
      cam.fiducial_used.push_back({t, chi});
      const auto o = static_cast<std::size_t>(im.observation);
      if (o < sol.instant_of.size() && sol.instant_of[o] >= 0)
        cam.kinematic.push_back({t, sol.instant_estimates[static_cast<std::size_t>(sol.instant_of[o])].kinematic_chi2});
    } else if (outlier(im)) {
      cam.fiducial_rejected.push_back({t, chi});
    }
  }
}

/// Every link's pose in the base frame with every joint at zero (the URDF's
/// own pose), by name; empty when the base link is not in the URDF.
std::map<std::string, SE3> zeroPose(const kinematics::RobotModel& robot, const std::string& base_link) {
  std::map<std::string, SE3> T_root_link{{robot.rootLink(), SE3()}};
  for (const kinematics::JointInfo& j : robot.joints()) {  // a joint comes after its parent link's
    const auto parent = T_root_link.find(j.parent_link);
    if (parent != T_root_link.end()) T_root_link[j.child_link] = parent->second * j.T_parent_joint;
  }
  const auto base = T_root_link.find(base_link);
  if (base == T_root_link.end()) return {};
  const SE3 T_base_root = base->second.inverse();
  for (auto& [name, T] : T_root_link) T = T_base_root * T;
  return T_root_link;
}

std::vector<ReportLink> linksOf(const kinematics::RobotModel& robot, const std::map<std::string, SE3>& T_base) {
  std::vector<ReportLink> out;
  std::map<std::string, int> index;
  for (const kinematics::LinkInfo& l : robot.links()) {  // parents first
    const auto T = T_base.find(l.name);
    if (T == T_base.end()) continue;
    ReportLink link{l.name, T->second.translation(), -1};
    if (!l.parent_joint.empty()) {
      const auto p = index.find(robot.joint(l.parent_joint).parent_link);
      if (p != index.end()) link.parent = p->second;
    }
    index[l.name] = static_cast<int>(out.size());
    out.push_back(std::move(link));
  }
  return out;
}

ReportCamera reportCamera(const RunView& run, std::size_t c, const std::vector<std::size_t>& images,
                          std::int64_t t0, const std::map<std::string, SE3>& zero_pose) {
  ReportCamera cam;
  cam.result = run.res.output.cameras[c];
  if (run.res.evaluation) {
    const auto it = run.res.evaluation->cameras.find(cam.result.name);
    if (it != run.res.evaluation->cameras.end()) cam.error = it->second;
  }
  const CameraConfig& cc = run.in.rig.cameras[c];
  cam.intrinsics = cc.intrinsics;
  cam.resolution = cc.resolution;
  cam.frame = cc.frame;
  if (const auto T = zero_pose.find(cc.frame); !cc.frame.empty() && T != zero_pose.end())
    cam.T_base_cam_urdf = T->second;
  cam.images = images.size();
  chi2OverTime(run, images, t0, cam);
  cornersOf(run, images, cam);
  cam.rejected = rejectedRows(run.in, images);
  cam.overlays = pickOverlays(run, images);
  return cam;
}

/// The board's centre at every instant of the final solve(s), with the one camera that saw it.
std::vector<ReportBoard> boardsOf(const RunView& run) {
  const RigConfig& rig = run.in.rig;
  const Vec3 centre(0.5 * rig.target.squares_x * rig.target.square_size,
                    0.5 * rig.target.squares_y * rig.target.square_size, 0.0);
  const auto& observations = run.built.problem.observations;
  std::vector<ReportBoard> out;
  for (const InstantEstimate& ie : run.res.solution.instant_estimates) {
    ReportBoard b{ie.T_base_marker * centre, -1};
    if (ie.observations.size() == 1 && ie.observations[0] < observations.size())
      b.camera = observations[ie.observations[0]].camera;
    out.push_back(b);
  }
  return out;
}

std::vector<ReportSolve> solvesOf(const CalibrationSolution& sol) {
  std::vector<ReportSolve> out;
  for (std::size_t s = 0; s < sol.solves.size(); ++s) {
    const OptimizerResult& o = sol.solves[s];
    ReportSolve r;
    r.label = s < sol.solve_labels.size() ? sol.solve_labels[s] : "solve " + std::to_string(s + 1);
    r.initial_cost = o.initial_cost;
    r.final_cost = o.final_cost;
    r.iterations = o.iterations;
    r.termination = o.message.empty() ? toString(o.termination) : o.message;
    r.linear_solver = o.linear_solver;
    for (const IterationReport& it : o.reports) {
      r.iteration.push_back(it.iteration);
      r.cost.push_back(it.cost);
    }
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace

ReportData buildReportData(const RunView& run, Reprojection& rp) {
  const CalibrateResult& res = run.res;
  ReportData d;
  for (const auto& [key, value] : res.output.info) {  // the stamp calibration.yaml has
    if (key == "fgcal_version") d.fgcal_version = value;
    if (key == "date_utc") d.date_utc = value;
    if (key == "rig") d.rig = value;
    if (key == "solve") d.solve = value;
  }
  d.dataset = run.in.source;
  d.from_bag = run.in.from_bag;
  d.method = res.output.method;
  d.fiducial_gate = kFiducialGate;
  d.base_link = run.in.rig.robot.base_link;
  d.marker_link = run.in.rig.robot.marker_link;
  d.instants = res.solution.instants;
  d.images = run.in.images.size();
  for (const ImageRecord& im : run.in.images) d.images_used += used(im) && im.observation >= 0;
  d.warnings = res.warnings;
  for (const RejectedImage& r : res.damaged) d.damaged.push_back({r.image, "unreadable image", r.reason});
  d.quality = res.output.quality;
  d.summary = res.summary;
  d.mount = res.output.mount;
  d.has_truth = res.evaluation.has_value();
  if (res.evaluation) d.mount_error = res.evaluation->mount;
  d.ground_truth_path = res.ground_truth_path;
  d.boards = boardsOf(run);
  const std::map<std::string, SE3> zero_pose = zeroPose(run.robot, d.base_link);
  d.links = linksOf(run.robot, zero_pose);
  d.solves = solvesOf(res.solution);
  d.estimates = estimateRows(res);
  d.time_offset_sweeps = timeOffsetSweeps(run);
  std::int64_t t0 = std::numeric_limits<std::int64_t>::max();
  for (const ImageRecord& im : run.in.images) t0 = std::min(t0, im.stamp_ns);
  const auto by_camera = imagesByCamera(run.in);
  for (std::size_t c = 0; c < res.output.cameras.size(); ++c) {
    d.cameras.push_back(reportCamera(run, c, by_camera[c], t0, zero_pose));
    if (c < rp.residuals.size()) d.cameras.back().residuals_px = std::move(rp.residuals[c]);
  }
  return d;
}

ReportData failedReportData(const Inputs& in, const CalibrateOptions& opt, const std::vector<Finding>& findings) {
  ReportData d;
  d.fgcal_version = versionText();
  d.date_utc = utcNow();
  d.rig = stampedRigPath(in);
  d.dataset = in.source;
  d.from_bag = in.from_bag;
  d.method = toString(opt.method);
  d.solve = solveLabel(opt);
  d.base_link = in.rig.robot.base_link;
  d.marker_link = in.rig.robot.marker_link;
  d.images = in.images.size();
  d.warnings = in.warnings;
  for (const RejectedImage& r : damagedImages(in)) d.damaged.push_back({r.image, "unreadable image", r.reason});
  for (const Finding& f : findings) d.quality.add(f);
  return d;
}

}  // namespace fgcal::apps::stages
