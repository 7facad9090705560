// runCalibrate's stages from the input to the estimation problem: load, set
// up the robot, read the folder's joints, detect (folder files), build the
// observations (calibrate_stages.hpp). The bag's load and detection are in
// calibrate_bag.cpp.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <map>
#include <mutex>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "bag/detection_pool.hpp"
#include "commands/calibrate/calibrate_stages.hpp"
#include "commands/calibrate/parallel_for.hpp"
#include "commands/calibrate/progress.hpp"
#include "fgcal/apps/dataset.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/kinematics/errors.hpp"
#include "fgcal/vision/image_header.hpp"
#include "fgcal/vision/pnp.hpp"
#include "fgcal/vision/vision_error.hpp"
#include "io/text_format.hpp"

namespace fgcal::apps::stages {

namespace fs = std::filesystem;

namespace {

/// A folder image's file name, interned: the part after the stamp when the
/// name is the stamp's digits and an extension (the usual case: one entry
/// for every image), else the whole name (flagged in the locator's top bit).
constexpr std::uint64_t kWholeName = std::uint64_t{1} << 63;
std::uint64_t fileLocator(const std::string& path, std::int64_t stamp, Interned& names) {
  const std::string name = fs::path(path).filename().string();
  const std::string digits = std::to_string(stamp);
  if (name.compare(0, digits.size(), digits) == 0) return names.add(name.substr(digits.size()));
  return kWholeName | names.add(name);
}

ImageStatus statusOf(vision::DetectionStatus s) {
  switch (s) {
    case vision::DetectionStatus::Ok: return ImageStatus::Used;
    case vision::DetectionStatus::UnreadableImage: return ImageStatus::Unreadable;
    case vision::DetectionStatus::NoMarkers: return ImageStatus::NoBoard;
    case vision::DetectionStatus::TooFewCorners: return ImageStatus::TooFewCorners;
    case vision::DetectionStatus::Collinear: return ImageStatus::Collinear;
  }
  return ImageStatus::NotDetected;
}

}  // namespace

const char* skipKey(ImageStatus s) {
  switch (s) {
    case ImageStatus::Used: return "";
    case ImageStatus::WrongSize: return "wrong image size";
    case ImageStatus::Unreadable: return "unreadable image";
    case ImageStatus::NoBoard: return "no board";
    case ImageStatus::TooFewCorners: return "too few corners";
    case ImageStatus::Collinear: return "collinear corners";
    case ImageStatus::NotDetected: return "not detected";
    case ImageStatus::PoseFailed: return "pose failed";
    case ImageStatus::OutsideJointSpan: return "outside joint span";
    case ImageStatus::InvalidJoints: return "invalid joint values";
    case ImageStatus::Outlier: return "outlier";
  }
  return "not detected";
}

std::uint32_t Interned::add(const std::string& s) {
  const auto [it, added] = index_.emplace(s, static_cast<std::uint32_t>(strings_.size()));
  if (added) strings_.push_back(s);
  return it->second;
}

const std::string& Interned::operator[](std::uint32_t i) const {
  static const std::string none;
  return i == kNone ? none : strings_.at(i);
}

std::string Inputs::imageName(std::size_t i) const {
  const ImageRecord& r = images.at(i);
  if (from_bag)
    return bag_path + ": topic " + plan.image_topics[r.camera] + ", message " + std::to_string(r.locator) +
           " (stamp " + std::to_string(r.stamp_ns) + ")";
  const std::string& part = file_names[static_cast<std::uint32_t>(r.locator & ~kWholeName)];
  const std::string name = (r.locator & kWholeName) ? part : std::to_string(r.stamp_ns) + part;
  return (fs::path(source) / rig.cameras[r.camera].name / name).string();
}

Inputs loadInputs(const CalibrateOptions& opt) {
  if (logs::looksLikeBag(opt.dataset)) return loadBagInputs(opt);
  Inputs in;
  Dataset ds = loadDataset(opt.dataset, opt.cameras, opt.rig, /*read_joints=*/false);
  in.source = ds.root;
  in.rig_path = opt.rig.empty() ? (fs::path(ds.root) / "rig.yaml").string() : opt.rig;
  in.joints_name = (fs::path(ds.root) / "joints.csv").string();
  in.rig = std::move(ds.rig);
  in.images.reserve(ds.images.size());
  for (const ImageEntry& e : ds.images) {
    ImageRecord r;
    r.stamp_ns = e.stamp_ns;
    r.camera = static_cast<std::uint16_t>(in.rig.cameraIndex(e.camera));
    r.locator = fileLocator(e.path, e.stamp_ns, in.file_names);
    in.images.push_back(r);
  }
  in.warnings = std::move(ds.warnings);  // rig.yaml's and the image folders'
  const fs::path gt = fs::path(ds.root) / "ground_truth.yaml";
  if (fs::exists(gt)) in.ground_truth = gt.string();
  return in;
}

RobotSetup setUpRobot(const Inputs& in) {
  const RigConfig& rig = in.rig;
  // The URDF's own errors name the URDF; what rig.yaml chose in it names rig.yaml's field.
  kinematics::RobotModel robot = kinematics::RobotModel::fromFile(rig.robot.urdf);
  for (const auto& [field, link] : {std::pair<const char*, const std::string&>{"robot.base_link", rig.robot.base_link},
                                    {"robot.marker_link", rig.robot.marker_link}})
    if (!robot.hasLink(link))
      throw rigFieldError(rig, field,
                          "expected a link of " + rig.robot.urdf + ", got '" + link + "'" +
                              closestNote(link, robot.linkNames(), "links"));
  kinematics::KinematicChain chain = [&] {
    try {
      return robot.chain(rig.robot.base_link, rig.robot.marker_link);
    } catch (const kinematics::KinematicsError& e) {
      throw rigFieldError(rig, "robot.marker_link", e.what());
    }
  }();
  VecX sigma_q = [&] {
    try {
      return rig.robot.encoder_sigmas.empty() ? chain.sigmaVector(rig.robot.encoder_sigma)
                                              : chain.sigmaVector(rig.robot.encoder_sigmas);
    } catch (const kinematics::KinematicsError& e) {
      throw rigFieldError(rig, "robot.encoder_sigma", e.what());
    }
  }();
  vision::CharucoTarget target{rig.target.squares_x, rig.target.squares_y, rig.target.square_size,
                               rig.target.marker_size, rig.target.dictionary};
  std::unique_ptr<vision::CharucoDetector> detector;
  try {
    detector = std::make_unique<vision::CharucoDetector>(target);
  } catch (const vision::VisionError& e) {
    throw rigFieldError(rig, "target", e.what());
  }
  return RobotSetup{std::move(robot), std::move(chain), std::move(sigma_q), std::move(detector)};
}

namespace {

/// Keeps the chain's joints, around every image's stamp.
struct JointNeeds {
  JointLogFilter filter;
  std::vector<std::int64_t> stamps;  ///< sorted
};
JointNeeds jointNeeds(const Inputs& in, const RobotSetup& setup) {
  JointNeeds n;
  n.filter.columns = setup.chain.jointNames();
  n.stamps.reserve(in.images.size());
  for (const ImageRecord& r : in.images) n.stamps.push_back(r.stamp_ns);
  std::sort(n.stamps.begin(), n.stamps.end());
  return n;
}

/// A log holds every joint of the robot: only columns the URDF does not know are worth a warning.
void warnUnknownJoints(Inputs& in, const RobotSetup& setup) {
  std::vector<std::string> unknown;
  for (const auto& name : in.joints.source_names.empty() ? in.joints.names : in.joints.source_names)
    if (!setup.robot.hasJoint(name)) unknown.push_back(name);
  if (!unknown.empty())
    in.warnings.push_back(in.joints_name + ": " + std::to_string(unknown.size()) + " column(s) that are not joints of " +
                          in.rig.robot.urdf + ", ignored: " + detail::joinNames(unknown));
}

}  // namespace

void readFolderJoints(Inputs& in, const RobotSetup& setup, bool every_sample) {
  JointNeeds needs = jointNeeds(in, setup);
  if (!every_sample) needs.filter.around_stamps_ns = &needs.stamps;
  in.joints = loadJointsCsv(in.joints_name, &needs.filter);
  in.warnings.insert(in.warnings.end(), in.joints.warnings.begin(), in.joints.warnings.end());
  warnUnknownJoints(in, setup);
}

void reduceBagJoints(Inputs& in, const RobotSetup& setup, bool every_sample) {
  JointNeeds needs = jointNeeds(in, setup);
  if (!every_sample) needs.filter.around_stamps_ns = &needs.stamps;
  in.joints = filterJointLog(in.joints, needs.filter, in.joints_name);
  warnUnknownJoints(in, setup);
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
      throw rigFieldError(in.rig, cameraField(cc.name), e.what());
    }
  }
  return models;
}

void keepDetection(Inputs& in, std::size_t i, const StreamedDetection& s, Detections& det) {
  ImageRecord& r = in.images[i];
  r.width = static_cast<std::uint16_t>(std::clamp(s.width, 0, 0xffff));
  r.height = static_cast<std::uint16_t>(std::clamp(s.height, 0, 0xffff));
  det.decode_seconds += s.decode_seconds;
  const vision::CharucoDetection& d = s.detection;
  r.status = statusOf(d.status);
  if (!d.ok()) {
    r.detail = in.details.add(d.message);
    return;
  }
  DetectedCorners& c = det.corners;
  r.corners_begin = static_cast<std::uint32_t>(c.px.size());
  r.corners_count = static_cast<std::uint16_t>(d.corners.size());
  for (const auto& p : d.corners) c.px.push_back(p.cast<float>());
  for (std::size_t k = 0; k < d.ids.size(); ++k) {
    const auto id = static_cast<std::size_t>(d.ids[k]);
    c.id.push_back(static_cast<std::uint16_t>(id));
    if (id >= c.board_points.size()) c.board_points.resize(id + 1, Vec3::Constant(std::nan("")));
    c.board_points[id] = d.object_points[k];
  }
}

void checkSize(Inputs& in, std::size_t i, const std::string& says) {
  ImageRecord& r = in.images[i];
  const CameraConfig& cc = in.rig.cameras[r.camera];
  if (r.width == 0 || (r.width == cc.resolution[0] && r.height == cc.resolution[1])) return;
  r.status = ImageStatus::WrongSize;
  r.detail = in.details.add(std::to_string(r.width) + "x" + std::to_string(r.height) + ", " + says + " " +
                            std::to_string(cc.resolution[0]) + "x" + std::to_string(cc.resolution[1]));
}

Detections detectFolder(Inputs& in, const RobotSetup& setup, const CalibrateOptions& opt, std::ostream& log) {
  Detections det;
  std::mutex mutex;
  Progress progress(log, in.images.size(), Progress::isTerminal(log), false);
  {
    DetectionPool pool(*setup.detector, opt.threads, [&](std::size_t i, StreamedDetection&& s) {
      progress.detected();
      std::lock_guard<std::mutex> lock(mutex);
      keepDetection(in, i, s, det);
      checkSize(in, i, "rig.yaml says");
    });
    for (std::size_t i = 0; i < in.images.size(); ++i) {
      std::string path = in.imageName(i);
      // The size is read from the file's header first: an image of another
      // size than rig.yaml's is never decoded (a few-kB PNG may declare
      // gigapixels), and is counted as a wrong image size.
      const auto& res = in.rig.cameras[in.images[i].camera].resolution;
      const vision::ExpectedSize expected{res[0], res[1]};
      pool.submit([path, expected] { return vision::readGrayChecked(path, expected); },
                  path + ": cannot be read (a missing file, or not an image OpenCV can decode)");
    }
    pool.finish();
  }
  progress.finish();
  return det;
}

namespace {

/// The images with an Ok detection, camera by camera in image order: the
/// order of the observations.
std::vector<std::size_t> detectedImages(const Inputs& in) {
  std::vector<std::size_t> out;
  for (std::size_t c = 0; c < in.rig.cameras.size(); ++c)
    for (std::size_t i = 0; i < in.images.size(); ++i)
      if (in.images[i].camera == c && in.images[i].status == ImageStatus::Used) out.push_back(i);
  return out;
}

/// Each detected image's pose by PnP, on every core, into its observation's
/// slot; the error of each that has none.
std::map<std::size_t, std::string> estimatePoses(const Inputs& in, const std::vector<vision::CameraModel>& models,
                                                 const DetectedCorners& corners, const std::vector<std::size_t>& images,
                                                 int threads, std::vector<BoardObservation>& obs) {
  std::map<std::size_t, std::string> failed;
  std::mutex mutex;
  parallelFor(images.size(), threads, [&](std::size_t k) {
    const ImageRecord& r = in.images[images[k]];
    const CameraConfig& cc = in.rig.cameras[r.camera];
    vision::PnpOptions pnp;
    pnp.pixel_sigma = cc.pixel_sigma;
    // Never less uncertain than an image's own corner scatter: when the
    // corners scatter more than rig.yaml's pixel_sigma, the stated value would
    // under-report the pose uncertainty and the gate would reject good images.
    pnp.sigma_source = vision::PnpOptions::SigmaSource::Larger;
    std::vector<Vec3> points;
    std::vector<vision::Vec2> pixels;
    corners.appendCorrespondences(r.corners_begin, r.corners_count, points, pixels);
    try {
      const vision::PoseEstimate pose = vision::estimatePose(models[r.camera], points, pixels, pnp);
      obs[k].T_cam_marker = pose.T_cam_marker;
      obs[k].covariance = pose.covariance;
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex);
      failed[k] = e.what();
    }
  });
  return failed;
}

}  // namespace

BuiltProblem buildProblem(Inputs& in, const RobotSetup& setup, const std::vector<vision::CameraModel>& models,
                          Detections& det, int threads) {
  BuiltProblem b;
  CalibrationProblemInput& p = b.problem;
  for (const CameraConfig& cc : in.rig.cameras) {
    p.camera_names.push_back(cc.name);
    p.camera_guesses.push_back(cc.T_base_cam_guess);
  }
  const std::vector<int> columns = columnIndices(in.joints, setup.chain.jointNames(), in.joints_name);
  const std::vector<std::size_t> images = detectedImages(in);
  std::vector<BoardObservation> obs(images.size());
  const auto failed = estimatePoses(in, models, det.corners, images, threads, obs);
  // In observation order: the pose, then the joints at the image's stamp and
  // the forward kinematics; the observations that have both moved to the front.
  std::size_t kept = 0;
  for (std::size_t k = 0; k < images.size(); ++k) {
    ImageRecord& r = in.images[images[k]];
    std::string why;
    if (const auto f = failed.find(k); f != failed.end()) {
      r.status = ImageStatus::PoseFailed;
      r.detail = in.details.add(f->second);
      continue;
    }
    JointLookupFailure failure = JointLookupFailure::NotFinite;
    const std::optional<Eigen::VectorXd> q = interpolate(in.joints, r.stamp_ns, columns, &why, &failure);
    if (!q) {
      r.status = failure == JointLookupFailure::OutsideSpan ? ImageStatus::OutsideJointSpan : ImageStatus::InvalidJoints;
      r.detail = in.details.add(why);
      continue;
    }
    BoardObservation& o = obs[kept];
    if (kept != k) o = std::move(obs[k]);
    o.camera = r.camera;
    o.stamp_ns = r.stamp_ns;
    Mat6 link_covariance;
    o.T_base_link = setup.chain.forwardWithCovariance(*q, setup.sigma_q, &link_covariance);
    o.link_covariance = link_covariance;
    o.joint_positions = *q;
    o.corners_begin = r.corners_begin;
    o.corners_count = r.corners_count;
    r.observation = static_cast<std::int32_t>(kept++);
    b.obs_image.push_back(images[k]);
  }
  obs.resize(kept);
  obs.shrink_to_fit();  // sized for every detected image; ~750 bytes each that the solve would carry
  b.obs_image.shrink_to_fit();
  p.observations = std::move(obs);
  // The corners grew as images came: drop the growth's slack before the
  // solve, now that little else is held.
  det.corners.px.shrink_to_fit();
  det.corners.id.shrink_to_fit();
  p.corners = std::move(det.corners);
  return b;
}

void checkReadouts(const Inputs& in) {
  for (std::size_t c = 0; c < in.rig.cameras.size(); ++c) {
    const CameraConfig& cam = in.rig.cameras[c];
    if (!(cam.readout_ms > 0.0)) continue;
    std::vector<std::int64_t> stamps;
    for (const ImageRecord& r : in.images)
      if (r.camera == c) stamps.push_back(r.stamp_ns);
    std::sort(stamps.begin(), stamps.end());
    std::vector<std::int64_t> gaps;
    for (std::size_t i = 1; i < stamps.size(); ++i)
      if (stamps[i] > stamps[i - 1]) gaps.push_back(stamps[i] - stamps[i - 1]);
    if (gaps.empty()) continue;
    const auto mid = gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2);
    std::nth_element(gaps.begin(), mid, gaps.end());
    const double period_ms = static_cast<double>(*mid) * 1e-6;
    if (cam.readout_ms <= period_ms) continue;
    std::ostringstream m;
    m << std::fixed << std::setprecision(2) << "camera " << cam.name << "'s readout " << cam.readout_ms
      << " ms is longer than its frame period " << period_ms << " ms (the median spacing of its " << stamps.size()
      << " images' stamps): a rolling shutter reads every row within one frame. Expected the time from the first "
         "row's exposure start to the last row's (a datasheet's readout, or its line time x rows), in ms";
    throw rigFieldError(in.rig, cameraField(cam.name, "readout_ms"), m.str());
  }
}

void checkCoverage(const Inputs& in, const BuiltProblem& built) {
  const auto& cameras = in.rig.cameras;
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    const auto n = std::count_if(built.problem.observations.begin(), built.problem.observations.end(),
                                 [&](const BoardObservation& o) { return o.camera == static_cast<int>(c); });
    if (n >= 3) continue;
    std::map<std::string, int> reasons;
    std::map<std::string, std::string> example;  // reason -> "file: detail" of its first image
    int total = 0;
    for (std::size_t i = 0; i < in.images.size(); ++i) {
      const ImageRecord& r = in.images[i];
      if (r.camera != c) continue;
      ++total;
      if (r.status == ImageStatus::Used) continue;
      const std::string key = skipKey(r.status);
      const std::string& detail = in.details[r.detail];
      if (reasons[key]++ == 0) example[key] = in.imageName(i) + (detail.empty() ? "" : ": " + detail);
    }
    // Every image of another size than rig.yaml says: the rig description is wrong, not the data.
    const auto wrong = reasons.find("wrong image size");
    if (total > 0 && wrong != reasons.end() && wrong->second == total)
      throw rigFieldError(in.rig, cameraField(cameras[c].name, "resolution"),
                          "expected the size of camera " + cameras[c].name + "'s images, but all " +
                              std::to_string(total) + " of them differ (e.g. " + example[wrong->first] + ")");
    std::ostringstream msg;
    msg << "camera " << cameras[c].name << ": the board is usable in " << n << " of " << total
        << " images (at least 3 needed)";
    for (const auto& [reason, k] : reasons) msg << "; " << k << " " << reason << " (e.g. " << example[reason] << ")";
    // Damaged messages the camera's images mostly are: the quality finding, as a failed solve prints its own.
    for (const Finding& f : damagedFindings(in)) {
      if (f.fields.empty() || f.fields.front().rfind(cameraField(cameras[c].name), 0) != 0) continue;
      msg << "\nverdict: UNUSABLE\n  " << toString(f.severity) << " [" << f.check << "] fields:";
      for (const std::string& x : f.fields) msg << " " << x;
      msg << "\n      " << f.message;
    }
    throw DataError(msg.str());
  }
}

}  // namespace fgcal::apps::stages
