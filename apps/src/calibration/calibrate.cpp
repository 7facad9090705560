#include "fgcal/apps/calibrate.hpp"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <mutex>
#include <ostream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "fgcal/apps/dataset.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/report.hpp"
#include "../io/text_format.hpp"
#include "fgcal/kinematics/errors.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal/vision/batch_detection.hpp"
#include "fgcal/vision/camera_model.hpp"
#include "fgcal/vision/charuco_detector.hpp"
#include "fgcal/vision/pnp.hpp"
#include "fgcal/vision/vision_error.hpp"

namespace fgcal::apps {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::string skipKey(vision::DetectionStatus s) {
  switch (s) {
    case vision::DetectionStatus::Ok: return "";
    case vision::DetectionStatus::UnreadableImage: return "unreadable image";
    case vision::DetectionStatus::NoMarkers: return "no board";
    case vision::DetectionStatus::TooFewCorners: return "too few corners";
    case vision::DetectionStatus::Collinear: return "collinear corners";
  }
  return "not detected";
}

/// Progress over many images: a bar on a terminal, a line every ~10 % otherwise.
class Progress {
 public:
  Progress(std::ostream& log, std::size_t total, bool tty) : log_(log), total_(total), tty_(tty) {}
  void tick() {
    const std::size_t done = ++done_;
    std::lock_guard<std::mutex> lock(mutex_);
    if (tty_) {
      if (done != total_ && since(last_) < 0.1) return;
      last_ = Clock::now();
      const int width = 40, filled = static_cast<int>(width * done / std::max<std::size_t>(total_, 1));
      log_ << "\r  detecting [" << std::string(filled, '#') << std::string(width - filled, '.') << "] " << done << "/"
           << total_ << (done == total_ ? "\n" : "") << std::flush;
    } else {
      const std::size_t step = std::max<std::size_t>(total_ / 10, 1);
      if (done % step == 0 || done == total_) log_ << "  detected " << done << "/" << total_ << " images\n" << std::flush;
    }
  }

 private:
  std::ostream& log_;
  std::size_t total_;
  bool tty_;
  std::atomic<std::size_t> done_{0};
  std::mutex mutex_;
  Clock::time_point last_ = Clock::now();
};

std::string fmt(double v, int precision = 2) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << v;
  return s.str();
}

}  // namespace

CalibrateResult runCalibrate(const CalibrateOptions& opt, std::ostream& log) {
  const auto t_start = Clock::now();
  CalibrateResult res;
  // Before the detection, so that a bad option fails at once (exit 2).
  if (const std::string problem = fiducialCovarianceScaleProblem(opt.pnp_covariance_scale); !problem.empty())
    throw InputError("", "--pnp-covariance-scale", problem);

  // ---- Inputs ------------------------------------------------------------
  Dataset ds = loadDataset(opt.dataset, opt.cameras);
  const std::string rig_path = (std::filesystem::path(ds.root) / "rig.yaml").string();
  const std::string joints_path = (std::filesystem::path(ds.root) / "joints.csv").string();
  res.warnings = ds.warnings;  // rig.yaml's, joints.csv's and the image folders'
  res.rig = ds.rig;

  if (!opt.output.empty() && opt.write_files) {
    const auto parent = std::filesystem::absolute(opt.output).parent_path();
    if (!std::filesystem::is_directory(parent))
      throw InputError(opt.output, "", "the output folder " + parent.string() + " does not exist");
  }
  if (!opt.report_dir.empty() && opt.write_files && opt.report) checkReportFolder(opt.report_dir);
  // calibration.yaml -> calibration.urdf.xml and calibration_report/.
  std::string output_stem = opt.output;
  if (output_stem.size() > 5 && output_stem.substr(output_stem.size() - 5) == ".yaml") output_stem.resize(output_stem.size() - 5);
  // --urdf-out, --kalibr-out, --tf-out checked against rig.yaml and the URDF now, not after the solve.
  const RobotOutputPlan robot_outputs =
      planRobotOutputs(opt.robot_outputs, ds.rig, rig_path,
                       opt.output.empty() ? std::vector<std::string>{} : std::vector<std::string>{opt.output, output_stem + ".urdf.xml"});

  // The URDF's own errors name the URDF; what rig.yaml chose in it names rig.yaml's field.
  const kinematics::RobotModel robot = kinematics::RobotModel::fromFile(ds.rig.robot.urdf);
  const kinematics::KinematicChain chain = [&] {
    try {
      return robot.chain(ds.rig.robot.base_link, ds.rig.robot.marker_link);
    } catch (const kinematics::KinematicsError& e) {
      throw InputError(rig_path, "robot.base_link / robot.marker_link", e.what());
    }
  }();
  // Throws, naming every missing chain joint.
  const std::vector<int> columns = columnIndices(ds.joints, chain.jointNames(), joints_path);
  // A log holds every joint of the robot: only columns the URDF does not know are worth a warning.
  std::vector<std::string> unknown;
  for (const auto& name : ds.joints.names)
    if (!robot.hasJoint(name)) unknown.push_back(name);
  if (!unknown.empty())
    res.warnings.push_back(joints_path + ": " + std::to_string(unknown.size()) + " column(s) that are not joints of " +
                           ds.rig.robot.urdf + ", ignored: " + detail::joinNames(unknown));
  const VecX sigma_q = [&] {
    try {
      return ds.rig.robot.encoder_sigmas.empty() ? chain.sigmaVector(ds.rig.robot.encoder_sigma)
                                                 : chain.sigmaVector(ds.rig.robot.encoder_sigmas);
    } catch (const kinematics::KinematicsError& e) {
      throw InputError(rig_path, "robot.encoder_sigma", e.what());
    }
  }();

  vision::CharucoTarget target{ds.rig.target.squares_x, ds.rig.target.squares_y, ds.rig.target.square_size,
                               ds.rig.target.marker_size, ds.rig.target.dictionary};
  std::unique_ptr<vision::CharucoDetector> detector;
  try {
    detector = std::make_unique<vision::CharucoDetector>(target);
  } catch (const vision::VisionError& e) {
    throw InputError(rig_path, "target", e.what());
  }
  std::vector<vision::CameraModel> models;
  for (std::size_t c = 0; c < ds.rig.cameras.size(); ++c) {
    const CameraConfig& cc = ds.rig.cameras[c];
    try {
      models.push_back(vision::CameraModel::fromKalibr(
          cc.camera_model, cc.distortion_model, std::vector<double>(cc.intrinsics.begin(), cc.intrinsics.end()),
          cc.distortion_coeffs, {cc.resolution[0], cc.resolution[1]}));
    } catch (const vision::VisionError& e) {
      throw InputError(rig_path, "cameras[" + std::to_string(c) + "]", e.what());
    }
  }

  // ---- Detection, camera by camera, on every core ------------------------
  log << "fgcal calibrate: " << ds.images.size() << " images from " << ds.rig.cameras.size() << " camera(s), "
      << ds.joints.stamps_ns.size() << " joint samples, chain " << chain.baseLink() << " -> " << chain.tipLink()
      << " (" << chain.numJoints() << " joints)\n";
  res.load_seconds = since(t_start);
  const auto t_detect = Clock::now();
  std::atomic<std::int64_t> decode_ns{0};
  res.images.resize(ds.images.size());
  CalibrationProblemInput problem;
  std::vector<std::size_t> obs_image;  // observation -> image index
  std::vector<vision::FrameResult> frames(ds.images.size());
  const bool tty = (&log == &std::cerr && isatty(STDERR_FILENO)) || (&log == &std::cout && isatty(STDOUT_FILENO));
  Progress progress(log, ds.images.size(), tty);
  for (std::size_t c = 0; c < ds.rig.cameras.size(); ++c) {
    const CameraConfig& cc = ds.rig.cameras[c];
    problem.camera_names.push_back(cc.name);
    problem.camera_guesses.push_back(cc.T_base_cam_guess);
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < ds.images.size(); ++i)
      if (ds.images[i].camera == cc.name) idx.push_back(i);
    std::vector<char> wrong_size(idx.size(), 0);
    std::vector<std::string> size_msg(idx.size());
    vision::PnpOptions pnp;
    pnp.pixel_sigma = cc.pixel_sigma;
    // Never less uncertain than an image's own corner scatter: when the
    // corners scatter more than rig.yaml's pixel_sigma, the stated value would
    // under-report the pose uncertainty and the gate would reject good images.
    pnp.sigma_source = vision::PnpOptions::SigmaSource::Larger;
    const auto results = vision::processImages(
        *detector, idx.size(),
        [&](std::size_t k) {
          const auto t_decode = Clock::now();
          cv::Mat img = cv::imread(ds.images[idx[k]].path, cv::IMREAD_GRAYSCALE);
          decode_ns += std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t_decode).count();
          progress.tick();
          if (!img.empty() && (img.cols != cc.resolution[0] || img.rows != cc.resolution[1])) {
            wrong_size[k] = 1;
            size_msg[k] = std::to_string(img.cols) + "x" + std::to_string(img.rows) + ", rig.yaml says " +
                          std::to_string(cc.resolution[0]) + "x" + std::to_string(cc.resolution[1]);
            return cv::Mat();
          }
          return img;
        },
        &models[c], pnp, opt.threads);
    const auto t_kinematics = Clock::now();
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const std::size_t i = idx[k];
      ImageOutcome& out = res.images[i];
      out.camera = cc.name;
      out.path = ds.images[i].path;
      out.stamp_ns = ds.images[i].stamp_ns;
      frames[i] = results[k];
      const auto& fr = results[k];
      if (wrong_size[k]) {
        out.skipped = "wrong image size";
        out.detail = size_msg[k];
      } else if (!fr.detection.ok()) {
        out.skipped = skipKey(fr.detection.status);
        out.detail = fr.detection.message;
      } else if (!fr.pose) {
        out.skipped = "pose failed";
        out.detail = fr.pose_error;
      }
      if (!out.skipped.empty()) continue;
      std::string why;
      const auto q = interpolate(ds.joints, out.stamp_ns, columns, &why);
      if (!q) {
        out.skipped = why.find("outside") != std::string::npos ? "outside joint span" : "invalid joint values";
        out.detail = why;
        continue;
      }
      BoardObservation o;
      o.camera = static_cast<int>(c);
      o.stamp_ns = out.stamp_ns;
      o.T_cam_marker = fr.pose->T_cam_marker;
      o.covariance = fr.pose->covariance;
      o.T_base_link = chain.forwardWithCovariance(*q, sigma_q, &o.link_covariance);
      o.joint_positions = *q;
      o.image = out.path;
      out.observation = static_cast<int>(problem.observations.size());
      problem.observations.push_back(o);
      obs_image.push_back(i);
    }
    res.kinematics_seconds += since(t_kinematics);
  }
  res.detection_seconds = since(t_detect);
  res.decode_seconds = static_cast<double>(decode_ns.load()) * 1e-9;

  // A camera without enough images: say why, with the reasons counted.
  for (std::size_t c = 0; c < ds.rig.cameras.size(); ++c) {
    const auto n = std::count_if(problem.observations.begin(), problem.observations.end(),
                                 [&](const BoardObservation& o) { return o.camera == static_cast<int>(c); });
    if (n >= 3) continue;
    std::map<std::string, int> reasons;
    std::map<std::string, std::string> example;  // reason -> "file: detail" of its first image
    int total = 0;
    for (const auto& im : res.images)
      if (im.camera == ds.rig.cameras[c].name) {
        ++total;
        if (im.skipped.empty()) continue;
        if (reasons[im.skipped]++ == 0) example[im.skipped] = im.path + (im.detail.empty() ? "" : ": " + im.detail);
      }
    // Every image of another size than rig.yaml says: the rig description is wrong, not the data.
    const auto wrong = reasons.find("wrong image size");
    if (total > 0 && wrong != reasons.end() && wrong->second == total)
      throw InputError(rig_path,
                       opt.cameras.empty() ? "cameras[" + std::to_string(c) + "].resolution"
                                           : "resolution of camera " + ds.rig.cameras[c].name,
                       "expected the size of camera " + ds.rig.cameras[c].name + "'s images, but all " +
                           std::to_string(total) + " of them differ (e.g. " + example[wrong->first] + ")");
    std::ostringstream msg;
    msg << "camera " << ds.rig.cameras[c].name << ": the board is usable in " << n << " of " << total
        << " images (at least 3 needed)";
    for (const auto& [r, k] : reasons) msg << "; " << k << " " << r << " (e.g. " << example[r] << ")";
    throw DataError(msg.str());
  }

  // ---- Solve ----------------------------------------------------------------
  problem.mount_prior = ds.rig.robot.T_link_marker;
  problem.mount_sigma_m = ds.rig.robot.mount_sigma_m;
  problem.mount_sigma_rad = ds.rig.robot.mount_sigma_rad;
  problem.fix_mount = opt.fix_mount || ds.rig.robot.isMountFixed();
  problem.sync_tolerance_ms = ds.rig.sync_tolerance_ms;
  problem.single_camera = opt.single_camera;
  problem.fiducial_covariance_scale = opt.pnp_covariance_scale;
  const auto t_solve = Clock::now();
  res.solution = solveCalibration(problem);
  res.solve_seconds = since(t_solve);
  for (const auto& r : res.solution.solves) res.optimizer_seconds += r.total_seconds;
  const auto t_output = Clock::now();
  for (const auto& w : res.solution.warnings) res.warnings.push_back(w);
  for (const auto& rj : res.solution.rejected) {
    ImageOutcome& out = res.images[obs_image[rj.observation]];
    out.skipped = "outlier";
    out.detail = rj.reason;
  }

  // ---- Final reprojection through kinematics + calibration -----------------
  const SE3& mount = res.solution.T_link_marker;
  std::vector<double> sq(ds.rig.cameras.size(), 0.0);
  std::vector<long> n_corners(ds.rig.cameras.size(), 0);
  const bool keep_corners = opt.report;  // what a report (written here or by the caller) draws
  for (std::size_t k = 0; k < problem.observations.size(); ++k) {
    const BoardObservation& o = problem.observations[k];
    const std::size_t i = obs_image[k];
    const SE3 T_cam_marker =
        res.solution.cameras[static_cast<std::size_t>(o.camera)].T_base_cam.inverse() * o.T_base_link * mount;
    const auto& det = frames[i].detection;
    double s = 0.0;
    int m = 0;
    // Kept for the report only (memory per image otherwise), rejected images
    // too (the prediction shows why).
    if (keep_corners) {
      res.images[i].corners_px = det.corners;
      res.images[i].predicted_px.assign(det.corners.size(), Eigen::Vector2d::Constant(std::nan("")));
    }
    for (std::size_t p = 0; p < det.corners.size(); ++p) {
      const auto uv = models[static_cast<std::size_t>(o.camera)].project(T_cam_marker * det.object_points[p]);
      if (!uv) continue;
      if (keep_corners) res.images[i].predicted_px[p] = *uv;
      s += (*uv - det.corners[p]).squaredNorm();
      ++m;
    }
    if (!res.solution.used[k]) continue;
    res.images[i].rms_px = m ? std::sqrt(s / m) : 0.0;
    sq[static_cast<std::size_t>(o.camera)] += s;
    n_corners[static_cast<std::size_t>(o.camera)] += m;
  }

  // ---- Output -----------------------------------------------------------------
  CalibrationOutput& out = res.output;
  out.method = opt.single_camera ? "F1" : "F2";
  for (std::size_t c = 0; c < ds.rig.cameras.size(); ++c) {
    CameraResult cr;
    cr.name = ds.rig.cameras[c].name;
    cr.T_base_cam = res.solution.cameras[c].T_base_cam;
    cr.covariance = res.solution.cameras[c].covariance;
    cr.images_used = res.solution.cameras[c].observations_used;
    cr.rms_reprojection_px = n_corners[c] ? std::sqrt(sq[c] / static_cast<double>(n_corners[c])) : 0.0;
    for (const auto& im : res.images)
      if (im.camera == cr.name && !im.skipped.empty()) ++cr.images_skipped[im.skipped];
    out.cameras.push_back(cr);
  }
  out.mount.T_link_marker = res.solution.T_link_marker;
  out.mount.covariance = res.solution.mount_covariance;
  out.mount.estimated = res.solution.mount_estimated;
  const OptimizerResult& last = res.solution.solves.back();
  out.info = {{"dataset", ds.root},
              {"method", out.method},
              {"base_link", ds.rig.robot.base_link},
              {"marker_link", ds.rig.robot.marker_link},
              {"instants", std::to_string(res.solution.instants)},
              {"images", std::to_string(ds.images.size())},
              {"final_cost", fmt(last.final_cost, 6)},
              {"iterations", std::to_string(last.iterations)},
              {"linear_solver", last.linear_solver},
              {"pnp_covariance_scale", fmt(problem.fiducial_covariance_scale, 6)}};

  // Errors against the truth when the dataset has it (simulated ones do).
  const std::filesystem::path gt_path = std::filesystem::path(ds.root) / "ground_truth.yaml";
  if (std::filesystem::exists(gt_path)) {
    try {
      GroundTruth truth = loadGroundTruth(gt_path.string());
      for (auto it = truth.T_base_cam.begin(); it != truth.T_base_cam.end();) {  // --cameras: a subset
        const bool calibrated = std::any_of(out.cameras.begin(), out.cameras.end(),
                                            [&](const CameraResult& c) { return c.name == it->first; });
        it = calibrated ? std::next(it) : truth.T_base_cam.erase(it);
      }
      res.evaluation = evaluate(out, truth);
      res.ground_truth_path = gt_path.string();
    } catch (const std::exception& e) {
      res.warnings.push_back(gt_path.string() + " not used: " + e.what());
    }
  }

  // The summary a user reads.
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
    const Vec6 d = ds.rig.robot.T_link_marker.minus(out.mount.T_link_marker);
    sum << "  board mount (" << ds.rig.robot.marker_link << " -> marker): xyz [" << fmt(xr[0], 4) << ", "
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
  res.summary = sum.str();
  log << res.summary;

  if (opt.write_files && !opt.output.empty()) {
    res.yaml_path = opt.output;
    res.urdf_path = output_stem + ".urdf.xml";
    const std::string yaml = formatCalibrationYaml(out);
    const std::string urdf = formatUrdfSnippet(out, ds.rig.robot.base_link);
    std::vector<std::pair<std::string, std::string>> files{{res.yaml_path, yaml}, {res.urdf_path, urdf}};
    const RobotOutputFiles extra = robotOutputFiles(robot_outputs, out);
    files.insert(files.end(), extra.files.begin(), extra.files.end());
    writeFilesAtomically(files);
    for (const auto& f : extra.files) res.robot_output_paths.push_back(f.first);
    res.summary += extra.summary;
    log << extra.summary << "  wrote " << res.yaml_path << " and " << res.urdf_path;
    for (const auto& f : extra.files) log << ", " << f.first;
    log << "\n";
  }
  res.output_seconds = since(t_output);
  res.total_seconds = since(t_start);
  res.problem = std::move(problem);
  log << "  time: " << fmt(res.total_seconds) << " s (detection " << fmt(res.detection_seconds) << " s, solve "
      << fmt(res.solve_seconds) << " s)\n";
  if (opt.write_files && opt.report && (!opt.report_dir.empty() || !opt.output.empty())) {
    // After the results: a report that cannot be written costs a warning, never the calibration.
    const std::string dir = opt.report_dir.empty() ? output_stem + "_report" : opt.report_dir;
    const auto t_report = Clock::now();
    try {
      res.report_path = writeReport(res, dir);
      res.report_seconds = since(t_report);
      log << "  report: " << res.report_path << " (" << fmt(res.report_seconds) << " s)\n";
    } catch (const std::exception& e) {
      res.warnings.push_back(std::string("report not written: ") + e.what());
      log << "  warning: report not written: " << e.what() << "\n";
    }
  }
  return res;
}

}  // namespace fgcal::apps
