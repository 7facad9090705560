// runCalibrate's stages from the input to the estimation problem: load, set
// up the robot, detect (folder files), align the joints, build the
// observations (calibrate_stages.hpp). The bag's detection is in
// bag/bag_detection.cpp.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <map>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "calibrate_stages.hpp"
#include "progress.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/kinematics/errors.hpp"
#include "fgcal/vision/pnp.hpp"
#include "fgcal/vision/vision_error.hpp"
#include "../io/text_format.hpp"

namespace fgcal::apps::stages {

namespace {

using Clock = std::chrono::steady_clock;

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

}  // namespace

Inputs loadInputs(const CalibrateOptions& opt) {
  if (logs::looksLikeBag(opt.dataset)) return loadBagInputs(opt);
  Inputs in;
  Dataset ds = loadDataset(opt.dataset, opt.cameras, opt.rig);
  in.source = ds.root;
  in.rig_path = opt.rig.empty() ? (std::filesystem::path(ds.root) / "rig.yaml").string() : opt.rig;
  in.joints_name = (std::filesystem::path(ds.root) / "joints.csv").string();
  in.rig = std::move(ds.rig);
  in.joints = std::move(ds.joints);
  in.images = std::move(ds.images);
  in.warnings = std::move(ds.warnings);  // rig.yaml's, joints.csv's and the image folders'
  const std::filesystem::path gt = std::filesystem::path(ds.root) / "ground_truth.yaml";
  if (std::filesystem::exists(gt)) in.ground_truth = gt.string();
  return in;
}

RobotSetup setUpRobot(const Inputs& in) {
  const RigConfig& rig = in.rig;
  // The URDF's own errors name the URDF; what rig.yaml chose in it names rig.yaml's field.
  kinematics::RobotModel robot = kinematics::RobotModel::fromFile(rig.robot.urdf);
  kinematics::KinematicChain chain = [&] {
    try {
      return robot.chain(rig.robot.base_link, rig.robot.marker_link);
    } catch (const kinematics::KinematicsError& e) {
      throw InputError(in.rig_path, "robot.base_link / robot.marker_link", e.what());
    }
  }();
  VecX sigma_q = [&] {
    try {
      return rig.robot.encoder_sigmas.empty() ? chain.sigmaVector(rig.robot.encoder_sigma)
                                              : chain.sigmaVector(rig.robot.encoder_sigmas);
    } catch (const kinematics::KinematicsError& e) {
      throw InputError(in.rig_path, "robot.encoder_sigma", e.what());
    }
  }();
  vision::CharucoTarget target{rig.target.squares_x, rig.target.squares_y, rig.target.square_size,
                               rig.target.marker_size, rig.target.dictionary};
  std::unique_ptr<vision::CharucoDetector> detector;
  try {
    detector = std::make_unique<vision::CharucoDetector>(target);
  } catch (const vision::VisionError& e) {
    throw InputError(in.rig_path, "target", e.what());
  }
  return RobotSetup{std::move(robot), std::move(chain), std::move(sigma_q), std::move(detector)};
}

std::vector<int> jointColumns(Inputs& in, const RobotSetup& setup) {
  // Throws, naming every missing chain joint.
  std::vector<int> columns = columnIndices(in.joints, setup.chain.jointNames(), in.joints_name);
  // A log holds every joint of the robot: only columns the URDF does not know are worth a warning.
  std::vector<std::string> unknown;
  for (const auto& name : in.joints.names)
    if (!setup.robot.hasJoint(name)) unknown.push_back(name);
  if (!unknown.empty())
    in.warnings.push_back(in.joints_name + ": " + std::to_string(unknown.size()) + " column(s) that are not joints of " +
                        in.rig.robot.urdf + ", ignored: " + detail::joinNames(unknown));
  return columns;
}

std::vector<vision::CameraModel> cameraModels(const Inputs& in) {
  std::vector<vision::CameraModel> models;
  for (std::size_t c = 0; c < in.rig.cameras.size(); ++c) {
    const CameraConfig& cc = in.rig.cameras[c];
    try {
      models.push_back(vision::CameraModel::fromKalibr(
          cc.camera_model, cc.distortion_model, std::vector<double>(cc.intrinsics.begin(), cc.intrinsics.end()),
          cc.distortion_coeffs, {cc.resolution[0], cc.resolution[1]}));
    } catch (const vision::VisionError& e) {
      throw InputError(in.rig_path, "cameras[" + std::to_string(c) + "]", e.what());
    }
  }
  return models;
}

Detections detectFolder(const Inputs& in, const RobotSetup& setup, const std::vector<vision::CameraModel>& models,
                        const CalibrateOptions& opt, std::ostream& log) {
  Detections det;
  det.frames.resize(in.images.size());
  det.wrong_size.resize(in.images.size());
  std::atomic<std::int64_t> decode_ns{0};
  Progress progress(log, in.images.size(), Progress::isTerminal(log), false);
  // Camera by camera (each its own model and PnP options), every core on each.
  for (std::size_t c = 0; c < in.rig.cameras.size(); ++c) {
    const CameraConfig& cc = in.rig.cameras[c];
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < in.images.size(); ++i)
      if (in.images[i].camera == cc.name) idx.push_back(i);
    vision::PnpOptions pnp;
    pnp.pixel_sigma = cc.pixel_sigma;
    // Never less uncertain than an image's own corner scatter: when the
    // corners scatter more than rig.yaml's pixel_sigma, the stated value would
    // under-report the pose uncertainty and the gate would reject good images.
    pnp.sigma_source = vision::PnpOptions::SigmaSource::Larger;
    const auto results = vision::processImages(
        *setup.detector, idx.size(),
        [&](std::size_t k) {
          const auto t_decode = Clock::now();
          cv::Mat img = cv::imread(in.images[idx[k]].path, cv::IMREAD_GRAYSCALE);
          decode_ns += std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t_decode).count();
          progress.detected();
          if (!img.empty() && (img.cols != cc.resolution[0] || img.rows != cc.resolution[1])) {
            det.wrong_size[idx[k]] = std::to_string(img.cols) + "x" + std::to_string(img.rows) + ", rig.yaml says " +
                                     std::to_string(cc.resolution[0]) + "x" + std::to_string(cc.resolution[1]);
            return cv::Mat();
          }
          return img;
        },
        &models[c], pnp, opt.threads);
    for (std::size_t k = 0; k < idx.size(); ++k) det.frames[idx[k]] = results[k];
  }
  progress.finish();
  det.decode_seconds = static_cast<double>(decode_ns.load()) * 1e-9;
  return det;
}

AlignedJoints alignJoints(const Inputs& in, const std::vector<int>& columns) {
  AlignedJoints a;
  a.q.resize(in.images.size());
  a.why.resize(in.images.size());
  for (std::size_t i = 0; i < in.images.size(); ++i)
    a.q[i] = interpolate(in.joints, in.images[i].stamp_ns, columns, &a.why[i]);
  return a;
}

BuiltProblem buildProblem(const Inputs& in, const RobotSetup& setup, const Detections& det,
                          const AlignedJoints& joints) {
  BuiltProblem b;
  b.images.resize(in.images.size());
  // Observations camera by camera, each in stamp order.
  for (std::size_t c = 0; c < in.rig.cameras.size(); ++c) {
    const CameraConfig& cc = in.rig.cameras[c];
    b.problem.camera_names.push_back(cc.name);
    b.problem.camera_guesses.push_back(cc.T_base_cam_guess);
    for (std::size_t i = 0; i < in.images.size(); ++i) {
      if (in.images[i].camera != cc.name) continue;
      ImageOutcome& out = b.images[i];
      out.camera = cc.name;
      out.path = in.images[i].path;
      out.stamp_ns = in.images[i].stamp_ns;
      const vision::FrameResult& fr = det.frames[i];
      if (!det.wrong_size[i].empty()) {
        out.skipped = "wrong image size";
        out.detail = det.wrong_size[i];
      } else if (!fr.detection.ok()) {
        out.skipped = skipKey(fr.detection.status);
        out.detail = fr.detection.message;
      } else if (!fr.pose) {
        out.skipped = "pose failed";
        out.detail = fr.pose_error;
      } else if (!joints.q[i]) {
        out.skipped = joints.why[i].find("outside") != std::string::npos ? "outside joint span" : "invalid joint values";
        out.detail = joints.why[i];
      }
      if (!out.skipped.empty()) continue;
      BoardObservation o;
      o.camera = static_cast<int>(c);
      o.stamp_ns = out.stamp_ns;
      o.T_cam_marker = fr.pose->T_cam_marker;
      o.covariance = fr.pose->covariance;
      o.T_base_link = setup.chain.forwardWithCovariance(*joints.q[i], setup.sigma_q, &o.link_covariance);
      o.joint_positions = *joints.q[i];
      o.image = out.path;
      out.observation = static_cast<int>(b.problem.observations.size());
      b.problem.observations.push_back(o);
      b.obs_image.push_back(i);
    }
  }
  return b;
}

void checkCoverage(const Inputs& in, const BuiltProblem& built, const CalibrateOptions& opt) {
  const auto& cameras = in.rig.cameras;
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    const auto n = std::count_if(built.problem.observations.begin(), built.problem.observations.end(),
                                 [&](const BoardObservation& o) { return o.camera == static_cast<int>(c); });
    if (n >= 3) continue;
    std::map<std::string, int> reasons;
    std::map<std::string, std::string> example;  // reason -> "file: detail" of its first image
    int total = 0;
    for (const auto& im : built.images)
      if (im.camera == cameras[c].name) {
        ++total;
        if (im.skipped.empty()) continue;
        if (reasons[im.skipped]++ == 0) example[im.skipped] = im.path + (im.detail.empty() ? "" : ": " + im.detail);
      }
    // Every image of another size than rig.yaml says: the rig description is wrong, not the data.
    const auto wrong = reasons.find("wrong image size");
    if (total > 0 && wrong != reasons.end() && wrong->second == total)
      throw InputError(in.rig_path,
                       opt.cameras.empty() ? "cameras[" + std::to_string(c) + "].resolution"
                                           : "resolution of camera " + cameras[c].name,
                       "expected the size of camera " + cameras[c].name + "'s images, but all " +
                           std::to_string(total) + " of them differ (e.g. " + example[wrong->first] + ")");
    std::ostringstream msg;
    msg << "camera " << cameras[c].name << ": the board is usable in " << n << " of " << total
        << " images (at least 3 needed)";
    for (const auto& [r, k] : reasons) msg << "; " << k << " " << r << " (e.g. " << example[r] << ")";
    throw DataError(msg.str());
  }
}

}  // namespace fgcal::apps::stages
