#include "fgcal/apps/calibrate.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <ostream>
#include <sstream>

#include "calibrate_stages.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/report.hpp"

namespace fgcal::apps {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::string fmt(double v, int precision = 2) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << v;
  return s.str();
}

/// Fails at once on a bad option or output folder, before any image is read (exit 2).
void checkOptions(const CalibrateOptions& opt) {
  if (const std::string problem = fiducialCovarianceScaleProblem(opt.pnp_covariance_scale); !problem.empty())
    throw InputError("", "--pnp-covariance-scale", problem);
}

void checkOutputFolders(const CalibrateOptions& opt) {
  if (!opt.output.empty() && opt.write_files) {
    const auto parent = std::filesystem::absolute(opt.output).parent_path();
    if (!std::filesystem::is_directory(parent))
      throw InputError(opt.output, "", "the output folder " + parent.string() + " does not exist");
  }
  if (!opt.report_dir.empty() && opt.write_files && opt.report) checkReportFolder(opt.report_dir);
}

std::string headline(const stages::Inputs& in, const stages::RobotSetup& setup) {
  std::ostringstream s;
  s << "fgcal calibrate: ";
  if (in.from_bag) {
    std::size_t n = 0;
    for (auto c : in.plan.image_counts) n += c;
    s << in.source << " (" << in.bag->format() << "): " << n << " image messages from " << in.rig.cameras.size()
      << " camera(s), joint states on " << in.plan.joints_topic;
  } else {
    s << in.images.size() << " images from " << in.rig.cameras.size() << " camera(s), " << in.joints.stamps_ns.size()
      << " joint samples";
  }
  s << ", chain " << setup.chain.baseLink() << " -> " << setup.chain.tipLink() << " (" << setup.chain.numJoints()
    << " joints)\n";
  return s.str();
}

/// calibration.yaml -> calibration (the .urdf.xml and _report/ go beside it).
std::string outputStem(const std::string& output) {
  std::string stem = output;
  if (stem.size() > 5 && stem.substr(stem.size() - 5) == ".yaml") stem.resize(stem.size() - 5);
  return stem;
}

/// Per camera, the squared reprojection error and corner count of its used images.
struct Reprojection {
  std::vector<double> squared;
  std::vector<long> corners;
};

// ---- solve and gate --------------------------------------------------------

/// Solves the graph, marks the gated images as outliers and reprojects every
/// detected corner through kinematics + calibration.
Reprojection solveAndGate(const stages::Inputs& in, stages::BuiltProblem& built, const stages::Detections& det,
                          const std::vector<vision::CameraModel>& models, const CalibrateOptions& opt,
                          CalibrateResult& res) {
  CalibrationProblemInput& problem = built.problem;
  problem.mount_prior = in.rig.robot.T_link_marker;
  problem.mount_sigma_m = in.rig.robot.mount_sigma_m;
  problem.mount_sigma_rad = in.rig.robot.mount_sigma_rad;
  problem.fix_mount = opt.fix_mount || in.rig.robot.isMountFixed();
  problem.sync_tolerance_ms = in.rig.sync_tolerance_ms;
  problem.single_camera = opt.single_camera;
  problem.fiducial_covariance_scale = opt.pnp_covariance_scale;
  const auto t_solve = Clock::now();
  res.solution = solveCalibration(problem);
  res.solve_seconds = since(t_solve);
  for (const auto& r : res.solution.solves) res.optimizer_seconds += r.total_seconds;
  for (const auto& w : res.solution.warnings) res.warnings.push_back(w);
  for (const auto& rj : res.solution.rejected) {
    ImageOutcome& out = res.images[built.obs_image[rj.observation]];
    out.skipped = "outlier";
    out.detail = rj.reason;
  }

  // Final reprojection through kinematics + calibration.
  const SE3& mount = res.solution.T_link_marker;
  Reprojection rp{std::vector<double>(in.rig.cameras.size(), 0.0), std::vector<long>(in.rig.cameras.size(), 0)};
  const bool keep_corners = opt.report;  // what a report (written here or by the caller) draws
  for (std::size_t k = 0; k < problem.observations.size(); ++k) {
    const BoardObservation& o = problem.observations[k];
    const std::size_t i = built.obs_image[k];
    const auto cam = static_cast<std::size_t>(o.camera);
    const SE3 T_cam_marker = res.solution.cameras[cam].T_base_cam.inverse() * o.T_base_link * mount;
    const auto& d = det.frames[i].detection;
    double s = 0.0;
    int m = 0;
    // Kept for the report only (memory per image otherwise), rejected images
    // too (the prediction shows why).
    if (keep_corners) {
      res.images[i].corners_px = d.corners;
      res.images[i].predicted_px.assign(d.corners.size(), Eigen::Vector2d::Constant(std::nan("")));
    }
    for (std::size_t p = 0; p < d.corners.size(); ++p) {
      const auto uv = models[cam].project(T_cam_marker * d.object_points[p]);
      if (!uv) continue;
      if (keep_corners) res.images[i].predicted_px[p] = *uv;
      s += (*uv - d.corners[p]).squaredNorm();
      ++m;
    }
    if (!res.solution.used[k]) continue;
    res.images[i].rms_px = m ? std::sqrt(s / m) : 0.0;
    rp.squared[cam] += s;
    rp.corners[cam] += m;
  }
  return rp;
}

// ---- results ---------------------------------------------------------------

CalibrationOutput assembleOutput(const stages::Inputs& in, const Reprojection& rp, double fiducial_scale,
                                 const CalibrateOptions& opt, const CalibrateResult& res) {
  CalibrationOutput out;
  out.method = opt.single_camera ? "F1" : "F2";
  for (std::size_t c = 0; c < in.rig.cameras.size(); ++c) {
    CameraResult cr;
    cr.name = in.rig.cameras[c].name;
    cr.T_base_cam = res.solution.cameras[c].T_base_cam;
    cr.covariance = res.solution.cameras[c].covariance;
    cr.images_used = res.solution.cameras[c].observations_used;
    cr.rms_reprojection_px = rp.corners[c] ? std::sqrt(rp.squared[c] / static_cast<double>(rp.corners[c])) : 0.0;
    for (const auto& im : res.images)
      if (im.camera == cr.name && !im.skipped.empty()) ++cr.images_skipped[im.skipped];
    out.cameras.push_back(cr);
  }
  out.mount.T_link_marker = res.solution.T_link_marker;
  out.mount.covariance = res.solution.mount_covariance;
  out.mount.estimated = res.solution.mount_estimated;
  const OptimizerResult& last = res.solution.solves.back();
  out.info = {{in.from_bag ? "bag" : "dataset", in.source},
              {"method", out.method},
              {"base_link", in.rig.robot.base_link},
              {"marker_link", in.rig.robot.marker_link},
              {"instants", std::to_string(res.solution.instants)},
              {"images", std::to_string(in.images.size())},
              {"final_cost", fmt(last.final_cost, 6)},
              {"iterations", std::to_string(last.iterations)},
              {"linear_solver", last.linear_solver},
              {"pnp_covariance_scale", fmt(fiducial_scale, 6)}};
  return out;
}

/// Errors against the truth when the dataset has it (simulated ones do).
void evaluateAgainstTruth(const std::string& gt_path, CalibrateResult& res) {
  if (gt_path.empty()) return;
  try {
    GroundTruth truth = loadGroundTruth(gt_path);
    for (auto it = truth.T_base_cam.begin(); it != truth.T_base_cam.end();) {  // --cameras: a subset
      const bool calibrated = std::any_of(res.output.cameras.begin(), res.output.cameras.end(),
                                          [&](const CameraResult& c) { return c.name == it->first; });
      it = calibrated ? std::next(it) : truth.T_base_cam.erase(it);
    }
    res.evaluation = evaluate(res.output, truth);
    res.ground_truth_path = gt_path;
  } catch (const std::exception& e) {
    res.warnings.push_back(gt_path + " not used: " + e.what());
  }
}

/// The summary a user reads.
std::string formatSummary(const CalibrateResult& res, const RigConfig& rig) {
  const CalibrationOutput& out = res.output;
  std::ostringstream sum;
  sum << "\nCalibration (" << out.method << ", " << res.solution.instants << " instants):\n";
  for (const CameraResult& cr : out.cameras) {
    const Vec6 xr = cr.T_base_cam.xyzRpy();
    const Vec6 sg = sigmaMmDeg(cr.T_base_cam, cr.covariance);
    int total = cr.images_used;
    for (const auto& [r, k] : cr.images_skipped) total += k;
    sum << "  " << cr.name << ": xyz [" << fmt(xr[0], 4) << ", " << fmt(xr[1], 4) << ", " << fmt(xr[2], 4)
        << "] m, rpy [" << fmt(xr[3] * 180 / M_PI, 3) << ", " << fmt(xr[4] * 180 / M_PI, 3) << ", "
        << fmt(xr[5] * 180 / M_PI, 3) << "] deg\n"
        << "      1-sigma [" << fmt(sg[0]) << ", " << fmt(sg[1]) << ", " << fmt(sg[2]) << "] mm, [" << fmt(sg[3], 3)
        << ", " << fmt(sg[4], 3) << ", " << fmt(sg[5], 3) << "] deg; reprojection RMS "
        << fmt(cr.rms_reprojection_px) << " px\n"
        << "      images: " << cr.images_used << " used of " << total;
    for (const auto& [r, k] : cr.images_skipped) sum << ", " << k << " " << r;
    sum << "\n";
  }
  if (out.mount.estimated) {
    const Vec6 xr = out.mount.T_link_marker.xyzRpy();
    const Vec6 sg = sigmaMmDeg(out.mount.T_link_marker, out.mount.covariance);
    const Vec6 d = rig.robot.T_link_marker.minus(out.mount.T_link_marker);
    sum << "  board mount (" << rig.robot.marker_link << " -> marker): xyz [" << fmt(xr[0], 4) << ", "
        << fmt(xr[1], 4) << ", " << fmt(xr[2], 4) << "] m, 1-sigma [" << fmt(sg[0]) << ", " << fmt(sg[1]) << ", "
        << fmt(sg[2]) << "] mm; moved " << fmt(d.tail<3>().norm() * 1e3) << " mm, "
        << fmt(d.head<3>().norm() * 180 / M_PI, 3) << " deg from the rig.yaml prior\n";
  } else {
    sum << "  board mount held fixed at the rig.yaml value\n";
  }
  int outliers = 0;
  for (const auto& im : res.images)
    if (im.skipped == "outlier") {
      if (outliers++ < 5) sum << "  rejected " << im.path << ": " << im.detail << "\n";
    }
  if (outliers > 5) sum << "  ... " << outliers - 5 << " more rejected\n";
  for (const auto& w : res.warnings) sum << "  warning: " << w << "\n";
  return sum.str();
}

// ---- write outputs ---------------------------------------------------------

/// calibration.yaml, the URDF snippet beside it and the robot outputs
/// (--urdf-out, --kalibr-out, --tf-out), all or nothing.
void writeOutputs(const CalibrateOptions& opt, const std::string& output_stem, const RigConfig& rig,
                  const RobotOutputPlan& robot_plan, CalibrateResult& res, std::ostream& log) {
  if (!opt.write_files || opt.output.empty()) return;
  res.yaml_path = opt.output;
  res.urdf_path = output_stem + ".urdf.xml";
  std::vector<std::pair<std::string, std::string>> files{
      {res.yaml_path, formatCalibrationYaml(res.output)},
      {res.urdf_path, formatUrdfSnippet(res.output, rig.robot.base_link)}};
  // The plan was made before a bag was read: its cameras take the intrinsics
  // the bag's camera_info gave since.
  RobotOutputPlan plan = robot_plan;
  plan.cameras = rig.cameras;
  const RobotOutputFiles extra = robotOutputFiles(plan, res.output);
  files.insert(files.end(), extra.files.begin(), extra.files.end());
  writeFilesAtomically(files);
  for (const auto& f : extra.files) res.robot_output_paths.push_back(f.first);
  res.summary += extra.summary;
  log << extra.summary << "  wrote " << res.yaml_path << " and " << res.urdf_path;
  for (const auto& f : extra.files) log << ", " << f.first;
  log << "\n";
}

// ---- report ----------------------------------------------------------------

/// After the results: a report that cannot be written costs a warning, never the calibration.
void writeReportStage(const CalibrateOptions& opt, const std::string& output_stem, const ReportOptions& options,
                      CalibrateResult& res, std::ostream& log) {
  if (!opt.write_files || !opt.report || (opt.report_dir.empty() && opt.output.empty())) return;
  const std::string dir = opt.report_dir.empty() ? output_stem + "_report" : opt.report_dir;
  const auto t_report = Clock::now();
  try {
    res.report_path = writeReport(res, dir, options);
    res.report_seconds = since(t_report);
    log << "  report: " << res.report_path << " (" << fmt(res.report_seconds) << " s)\n";
  } catch (const std::exception& e) {
    res.warnings.push_back(std::string("report not written: ") + e.what());
    log << "  warning: report not written: " << e.what() << "\n";
  }
}

}  // namespace

CalibrateResult runCalibrate(const CalibrateOptions& opt, std::ostream& log) {
  const auto t_start = Clock::now();
  CalibrateResult res;
  checkOptions(opt);

  // load -> setup -> detect -> align -> build
  stages::Inputs in = stages::loadInputs(opt);
  checkOutputFolders(opt);
  const std::string output_stem = outputStem(opt.output);
  // --urdf-out, --kalibr-out, --tf-out checked against rig.yaml and the URDF now, not after the solve.
  const RobotOutputPlan robot_plan = planRobotOutputs(
      opt.robot_outputs, in.rig, in.rig_path,
      opt.output.empty() ? std::vector<std::string>{} : std::vector<std::string>{opt.output, output_stem + ".urdf.xml"});
  const stages::RobotSetup setup = stages::setUpRobot(in);
  std::vector<int> columns;
  std::vector<vision::CameraModel> models;
  if (!in.from_bag) {  // a bag's joints and camera_info are known once it is read
    columns = stages::jointColumns(in, setup);
    models = stages::cameraModels(in);
  }
  log << headline(in, setup);
  res.load_seconds = since(t_start);
  const auto t_detect = Clock::now();
  const stages::Detections det = in.from_bag ? stages::detectBag(in, setup, opt, log, &models)
                                             : stages::detectFolder(in, setup, models, opt, log);
  if (in.from_bag) {
    log << "  read " << in.images.size() << " images and " << in.joints.stamps_ns.size() << " joint samples\n";
    columns = stages::jointColumns(in, setup);
  }
  res.warnings = in.warnings;
  res.decode_seconds = det.decode_seconds;
  const auto t_kinematics = Clock::now();
  const stages::AlignedJoints joints = stages::alignJoints(in, columns);
  stages::BuiltProblem built = stages::buildProblem(in, setup, det, joints);
  res.kinematics_seconds = since(t_kinematics);
  res.detection_seconds = since(t_detect);
  res.images = built.images;
  res.rig = in.rig;
  stages::checkCoverage(in, built, opt);

  // solve and gate
  const Reprojection rp = solveAndGate(in, built, det, models, opt, res);
  const auto t_output = Clock::now();

  // results, summary, outputs, report
  res.output = assembleOutput(in, rp, built.problem.fiducial_covariance_scale, opt, res);
  evaluateAgainstTruth(in.ground_truth, res);
  res.summary = formatSummary(res, in.rig);
  log << res.summary;
  writeOutputs(opt, output_stem, in.rig, robot_plan, res, log);
  res.output_seconds = since(t_output);
  res.total_seconds = since(t_start);
  res.problem = std::move(built.problem);
  log << "  time: " << fmt(res.total_seconds) << " s (detection " << fmt(res.detection_seconds) << " s, solve "
      << fmt(res.solve_seconds) << " s)\n";
  ReportOptions report_options;
  if (in.from_bag)  // the overlays' images are messages: read back from the bag in one pass
    report_options.load_images = [&in](const std::vector<std::size_t>& images) {
      return stages::readBagImages(in, images);
    };
  writeReportStage(opt, output_stem, report_options, res, log);
  return res;
}

}  // namespace fgcal::apps
