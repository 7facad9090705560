// runCalibrate (calibrate.hpp): the stages of calibrate_stages.hpp in order,
// timed; the solve and the reprojection; the written files and the report.
#include "fgcal/apps/calibrate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "calibration/offset_graph.hpp"
#include "commands/calibrate/calibrate_stages.hpp"
#include "commands/calibrate/corner_calibration_stage.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/report.hpp"
#include "quality/assess.hpp"
#include "quality/failure.hpp"
#include "quality/frames.hpp"

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
/// Whether the graph reads the joint log between samples (the trajectory):
/// a time offset, backlash, or a rolling shutter (estimated, or a readout in
/// rig.yaml) moves a board off its image's stamp.
bool needsWholeLog(const EstimateSet& e, const RigConfig& rig) {
  return e.time_offset || e.backlash || e.rolling_shutter ||
         std::any_of(rig.cameras.begin(), rig.cameras.end(), [](const CameraConfig& c) { return c.readout_ms > 0.0; });
}

void checkOptions(const CalibrateOptions& opt) {
  if (const std::string problem = fiducialCovarianceScaleProblem(opt.pnp_covariance_scale); !problem.empty())
    throw InputError("", "--pnp-covariance-scale", problem);
  if (opt.estimate.intrinsics && opt.method != Method::Corners)
    throw InputError("", "--estimate",
                     "intrinsics need --method corners: a PnP pose summarizes an image in 6 numbers, in which a "
                     "focal length error looks like a distance error and a principal point error like a rotation; "
                     "only the corners themselves tell them apart");
}

void checkOutputFolders(const CalibrateOptions& opt) {
  if (!opt.output.empty() && opt.write_files) {
    const auto parent = std::filesystem::absolute(opt.output).parent_path();
    if (!std::filesystem::is_directory(parent))
      throw InputError(opt.output, "-o", "the output folder " + parent.string() + " does not exist; create it first");
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
    s << in.images.size() << " images from " << in.rig.cameras.size() << " camera(s), " << in.joints.source_samples
      << " joint samples";
  }
  s << ", chain " << setup.chain.baseLink() << " -> " << setup.chain.tipLink() << " (" << setup.chain.numJoints()
    << " joints)\n";
  return s.str();
}

/// Where the outputs go, checked against rig.yaml and the URDF before any image is read.
struct OutputPlan {
  std::string stem;  ///< calibration.yaml -> calibration (the .urdf.xml and _report/ go beside it)
  RobotOutputPlan robot;
};
OutputPlan planOutputs(const CalibrateOptions& opt, const stages::Inputs& in) {
  OutputPlan plan;
  plan.stem = opt.output;
  if (plan.stem.size() > 5 && plan.stem.substr(plan.stem.size() - 5) == ".yaml") plan.stem.resize(plan.stem.size() - 5);
  // --urdf-out, --kalibr-out, --tf-out checked now, not after the solve.
  plan.robot = planRobotOutputs(
      opt.robot_outputs, in.rig, in.rig_path,
      opt.output.empty() ? std::vector<std::string>{} : std::vector<std::string>{opt.output, plan.stem + ".urdf.xml"});
  return plan;
}

/// The detect and build stages: every image's outcome and the estimation problem.
struct Detected {
  std::vector<vision::CameraModel> models;
  stages::BuiltProblem built;
};
Detected detectAndBuild(stages::Inputs& in, const stages::RobotSetup& setup, const CalibrateOptions& opt,
                        std::ostream& log, CalibrateTimings& t) {
  Detected d;
  if (!in.from_bag) {  // a bag's joints and camera_info are known once it is read
    stages::readFolderJoints(in, setup, needsWholeLog(opt.estimate, in.rig));
    d.models = stages::cameraModels(in);
  }
  log << headline(in, setup);
  const auto t_detect = Clock::now();
  stages::Detections det = in.from_bag ? stages::detectBag(in, setup, opt, log)
                                       : stages::detectFolder(in, setup, opt, log);
  if (in.from_bag) {
    log << "  read " << in.images.size() << " images and " << in.joints.stamps_ns.size() << " joint samples\n";
    stages::reduceBagJoints(in, setup, needsWholeLog(opt.estimate, in.rig));
    d.models = stages::cameraModels(in);
  }
  t.decode = det.decode_seconds;
  const auto t_kinematics = Clock::now();
  d.built = stages::buildProblem(in, setup, d.models, det, opt.threads);
  // --estimate time-offset, joint-offsets, backlash, rolling-shutter and rig.yaml's readouts: the chain, the joint
  // log's trajectory, the priors (offset_graph.hpp).
  d.built.problem.offsets =
      offsets::makeModel(opt.estimate, in.rig, setup.chain,
                         in.joints, columnIndices(in.joints, setup.chain.jointNames(), in.joints_name), in.joints_name);
  t.kinematics = since(t_kinematics);
  t.detection = since(t_detect);
  stages::checkReadouts(in);
  stages::checkCoverage(in, d.built);
#if defined(__GLIBC__)
  // Reading and detecting freed far more than they keep (decoded images,
  // chunk buffers, per-thread arenas); glibc keeps those pages resident
  // unless asked. Returned here, the solve's graph does not stack on them:
  // 4-6 MB less peak RSS on 2,000- and 20,000-image bags (docs/studies/calibrate_memory.md).
  malloc_trim(0);
#endif
  return d;
}

/// calibration.yaml, the URDF snippet beside it and the robot outputs
/// (--urdf-out, --kalibr-out, --tf-out), all or nothing.
void writeOutputs(const CalibrateOptions& opt, const OutputPlan& out_plan, const RigConfig& rig, CalibrateResult& res,
                  std::ostream& log) {
  if (!opt.write_files || opt.output.empty()) return;
  res.yaml_path = opt.output;
  res.urdf_path = out_plan.stem + ".urdf.xml";
  std::vector<std::pair<std::string, std::string>> files{
      {res.yaml_path, formatCalibrationYaml(res.output)},
      {res.urdf_path, formatUrdfSnippet(res.output, rig.robot.base_link)}};
  // The plan was made before a bag was read: its cameras take the intrinsics
  // the bag's camera_info gave since.
  RobotOutputPlan plan = out_plan.robot;
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

/// `fgcal calibrate` as run, without --estimate: a finding's suggested fix
/// appends its own.
std::string commandLine(const CalibrateOptions& opt) {
  std::string s = "fgcal calibrate " + opt.dataset;
  if (!opt.rig.empty()) s += " --rig " + opt.rig;
  if (!opt.output.empty() && opt.output != "calibration.yaml") s += " -o " + opt.output;
  if (!opt.cameras.empty()) {
    s += " --cameras ";
    for (std::size_t i = 0; i < opt.cameras.size(); ++i) s += (i ? "," : "") + opt.cameras[i];
  }
  if (opt.single_camera) s += " --single-camera";
  if (opt.fix_mount) s += " --fix-mount";
  if (opt.method == Method::Corners) s += " --method corners";
  return s;
}

/// The quality checks (src/quality/assess.hpp) on the solved problem: the
/// verdict and findings into the output, the input's own warnings as notes,
/// and each camera's covariance inflated by the variance factor of what the
/// model did not explain.
void assessQuality(const stages::Inputs& in, const stages::RobotSetup& setup, const Detected& d,
                   const CalibrateOptions& opt, std::size_t input_warnings, CalibrateResult& res) {
  const quality::Context ctx{d.built.problem, res.solution, in.rig,     setup.chain,       setup.sigma_q,
                             in.joints,       d.models,     in.from_bag ? in.plan.joints_topic : "joints.csv",
                             opt.method,      opt.estimate, commandLine(opt)};
  quality::Assessment a = quality::assess(ctx);
  Quality q;
  for (std::size_t k = 0; k < input_warnings && k < res.warnings.size(); ++k)  // the inputs', before the solve's
    q.add({"input", Severity::Note, {}, res.warnings[k], {}, {}});
  for (Finding& f : a.quality.findings) q.add(std::move(f));
  for (Finding& f : quality::frameFindings(in.rig, setup.robot, res.output.cameras)) q.add(std::move(f));
  for (Finding& f : stages::damagedFindings(in)) q.add(std::move(f));
  q.statistics = std::move(a.quality.statistics);
  res.output.quality = std::move(q);
  for (std::size_t c = 0; c < res.output.cameras.size() && c < a.inflation.size(); ++c)
    res.output.cameras[c].covariance *= a.inflation[c];
}

/// A solve that failed (DataError), or one that kept a minority of a
/// camera's images: the findings of the failure diagnosis
/// (src/quality/failure.hpp). `mount`: the solved mount, to judge the images'
/// agreement with instead of rig.yaml's (null: rig.yaml's).
std::vector<Finding> failureFindings(const stages::Inputs& in, const stages::RobotSetup& setup, const Detected& d,
                                     const SE3* mount = nullptr) {
  std::optional<JointLog> all;
  if (!in.from_bag) {  // the other legs' joints, to try other marker links
    try {
      all = loadJointsCsv(in.joints_name);
    } catch (const std::exception&) {
      all.reset();
    }
  }
  const quality::FailureContext ctx{d.built.problem,
                                    in.rig,
                                    setup.robot,
                                    setup.chain,
                                    setup.sigma_q,
                                    in.joints,
                                    all ? &*all : nullptr,
                                    in.from_bag ? in.plan.joints_topic : "joints.csv",
                                    &d.models,
                                    mount};
  return quality::diagnoseFailure(ctx);
}

/// The failure's findings as lines to append to its message, "" when none.
std::string formatFailure(const std::vector<Finding>& findings) {
  std::ostringstream s;
  for (const Finding& f : findings) {
    s << "\nverdict: UNUSABLE\n  " << toString(f.severity) << " [" << f.check << "] fields:";
    for (const std::string& x : f.fields) s << " " << x;
    s << "\n      " << f.message;
  }
  return s.str();
}

bool reportWanted(const CalibrateOptions& opt) {
  return opt.trace.report_data || (opt.write_files && opt.report && !(opt.report_dir.empty() && opt.output.empty()));
}

/// After the results: a report that cannot be written costs a warning, never the calibration.
void writeReportStage(const CalibrateOptions& opt, const OutputPlan& plan, const ReportData& data,
                      stages::Inputs& in, CalibrateResult& res, std::ostream& log) {
  if (!opt.write_files || !opt.report || (opt.report_dir.empty() && opt.output.empty())) return;
  const std::string dir = opt.report_dir.empty() ? plan.stem + "_report" : opt.report_dir;
  ReportOptions options;
  if (in.from_bag)  // the overlays' images are messages: read back from the bag in one pass
    options.load_images = [&in](const std::vector<std::size_t>& images) { return stages::readBagImages(in, images); };
  const auto t_report = Clock::now();
  try {
    res.report_path = writeReport(data, dir, options);
    res.timings.report = since(t_report);
    log << "  report: " << res.report_path << " (" << fmt(res.timings.report) << " s)\n";
  } catch (const std::exception& e) {
    res.warnings.push_back(std::string("report not written: ") + e.what());
    log << "  warning: report not written: " << e.what() << "\n";
  }
}

}  // namespace

namespace stages {

CalibrationSolution solveAndGate(Inputs& in, const CalibrateOptions& opt, BuiltProblem& built) {
  CalibrationProblemInput& problem = built.problem;
  problem.mount_prior = in.rig.robot.T_link_marker;
  problem.mount_sigma_m = in.rig.robot.mount_sigma_m;
  problem.mount_sigma_rad = in.rig.robot.mount_sigma_rad;
  problem.fix_mount = opt.fix_mount || in.rig.robot.isMountFixed();
  problem.sync_tolerance_ms = in.rig.sync_tolerance_ms;
  problem.single_camera = opt.single_camera;
  problem.fiducial_covariance_scale = opt.pnp_covariance_scale;
  CalibrationSolution sol = solveCalibration(problem);
  for (const auto& rj : sol.rejected) {
    ImageRecord& r = in.images[built.obs_image[rj.observation]];
    r.status = ImageStatus::Outlier;
    r.detail = in.details.add(rj.reason);
  }
  return sol;
}

std::vector<Eigen::Vector2d> predictedCorners(const CalibrationProblemInput& problem,
                                              const std::vector<vision::CameraModel>& models,
                                              const CalibrationSolution& sol, std::size_t k) {
  const BoardObservation& o = problem.observations[k];
  const auto cam = static_cast<std::size_t>(o.camera);
  const SE3 T_cam_base = sol.cameras[cam].T_base_cam.inverse();
  const SE3 T_cam_marker = T_cam_base * offsets::boardFromKinematics(problem, sol, k);
  // A rolling shutter sees each corner at its own row's time.
  const bool per_row = offsets::hasReadout(problem, sol, cam);
  std::vector<Eigen::Vector2d> out(o.corners_count, Eigen::Vector2d::Constant(std::nan("")));
  for (std::size_t p = 0; p < o.corners_count; ++p) {
    const std::size_t c = o.corners_begin + p;
    const SE3 T = per_row ? T_cam_base * offsets::boardFromKinematics(problem, sol, k, std::nullopt,
                                                                      problem.corners.pixel(c).y())
                          : T_cam_marker;
    if (const auto uv = models[cam].project(T * problem.corners.boardPoint(c))) out[p] = *uv;
  }
  return out;
}

Reprojection reproject(const BuiltProblem& built, const std::vector<vision::CameraModel>& models,
                       const CalibrationSolution& sol, bool keep_residuals, Inputs& in) {
  const CalibrationProblemInput& problem = built.problem;
  const std::size_t M = problem.camera_names.size();
  Reprojection rp{std::vector<double>(M, 0.0), std::vector<long>(M, 0), {}};
  if (keep_residuals) rp.residuals.resize(M);
  for (std::size_t k = 0; k < problem.observations.size(); ++k) {
    if (!sol.used[k]) continue;
    const BoardObservation& o = problem.observations[k];
    const auto cam = static_cast<std::size_t>(o.camera);
    const std::vector<Eigen::Vector2d> predicted = predictedCorners(problem, models, sol, k);
    double s = 0.0;
    int m = 0;
    for (std::size_t p = 0; p < o.corners_count; ++p) {
      if (!predicted[p].allFinite()) continue;
      const Eigen::Vector2d e = predicted[p] - problem.corners.pixel(o.corners_begin + p);
      s += e.squaredNorm();
      ++m;
      if (keep_residuals) rp.residuals[cam].push_back(e);
    }
    in.images[built.obs_image[k]].rms_px = m ? std::sqrt(s / m) : 0.0;
    rp.squared[cam] += s;
    rp.corners[cam] += m;
  }
  return rp;
}

}  // namespace stages

namespace {

/// A result that kept a minority of a camera's images, or whose gate kept
/// rejecting, is judged as a failed solve is (with the solved mount): a
/// diagnosis makes it unusable.
void judgeAsFailedWhereSuspect(const stages::Inputs& in, const stages::RobotSetup& setup, const Detected& d,
                               CalibrateResult& res) {
  if (!stages::mostImagesRejected(d.built.problem, res.solution) && res.solution.gate_settled) return;
  for (Finding& f : failureFindings(in, setup, d, &res.solution.T_link_marker)) {
    const auto& have = res.output.quality.findings;
    if (std::none_of(have.begin(), have.end(),
                     [&](const Finding& h) { return h.check == f.check && h.fields == f.fields; }))
      res.output.quality.add(std::move(f));
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
  const OutputPlan out_plan = planOutputs(opt, in);
  const stages::RobotSetup setup = stages::setUpRobot(in);
  res.timings.load = since(t_start);  // the detection stage's own clock starts after the headline
  Detected d = detectAndBuild(in, setup, opt, log, res.timings);
  res.warnings = in.warnings;

  // For programs that re-solve with the corners (before --estimate
  // intrinsics replaces the models by the estimated ones).
  if (opt.trace.corners) {
    std::vector<std::string> ignored;  // the defaults' warnings belong to a run that estimates
    res.trace.corners = stages::cornerInput(in, d.built, d.models, true, &ignored);
    res.trace.corners->estimate_intrinsics = opt.estimate.intrinsics;
  }

  // solve and gate
  const auto t_solve = Clock::now();
  CornerSolution corners;  // --method corners: its extras (estimated intrinsics)
  try {
    res.solution = opt.method == Method::Corners
                       ? stages::solveCornersAndGate(in, opt, d.built, d.models, &corners, &res.warnings)
                       : stages::solveAndGate(in, opt, d.built);
  } catch (const DataError& e) {
    // A diagnosis makes the failure an unusable verdict: its findings name
    // the input to fix, and the report, titled as a failed calibration, shows
    // them with the input (docs/outputs.md, quality). Without one it stays
    // an error that writes nothing.
    const std::vector<Finding> findings = failureFindings(in, setup, d);
    if (findings.empty()) throw;
    CalibrateResult failed;
    writeReportStage(opt, out_plan, stages::failedReportData(in, opt, findings), in, failed, log);
    std::string message = e.what() + formatFailure(findings);
    if (!failed.report_path.empty()) message += "\nthe report of the failed calibration: " + failed.report_path;
    throw DataError(message);
  }
  res.timings.solve = since(t_solve);
  for (const auto& r : res.solution.solves) res.timings.optimizer += r.total_seconds;
  const std::size_t input_warnings = res.warnings.size();  // the solve's own are findings already
  res.warnings.insert(res.warnings.end(), res.solution.warnings.begin(), res.solution.warnings.end());

  // results, summary, outputs
  const auto t_output = Clock::now();
  const bool report = reportWanted(opt);
  stages::Reprojection rp = stages::reproject(d.built, d.models, res.solution, report, in);
  res.rig = in.rig;
  res.output = stages::assembleOutput(in, d.built, rp, opt, res.solution);
  stages::addEstimatedIntrinsics(corners, res.output);
  assessQuality(in, setup, d, opt, input_warnings, res);
  judgeAsFailedWhereSuspect(in, setup, d, res);
  res.rejected = stages::rejectedImages(in);
  res.damaged = stages::damagedImages(in);
  stages::evaluateAgainstTruth(in.ground_truth, res);
  res.summary = stages::formatSummary(res);
  log << res.summary;
  // An unusable result writes no calibration output (docs/outputs.md); the report still says why.
  if (res.output.quality.verdict != Verdict::Unusable) writeOutputs(opt, out_plan, in.rig, res, log);
  res.timings.output = since(t_output);
  res.timings.total = since(t_start);
  log << "  time: " << fmt(res.timings.total) << " s (detection " << fmt(res.timings.detection) << " s, solve "
      << fmt(res.timings.solve) << " s)\n";

  // report
  if (report) {
    ReportData data = stages::buildReportData({in, d.built, d.models, res, setup.robot}, rp);
    writeReportStage(opt, out_plan, data, in, res, log);
    if (opt.trace.report_data) res.trace.report_data = std::make_shared<ReportData>(std::move(data));
  }
  if (opt.trace.problem) res.trace.problem = std::move(d.built.problem);
  return res;
}

}  // namespace fgcal::apps
