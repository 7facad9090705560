// simulateDataset as a pipeline of stages, each a function of small structs:
// the robot (URDF, marker chain, camera links), the scene (workspace, cameras,
// board mount), the clocks (joint samples, image stamps, camera delays), the
// leg's motion, joints.csv, each camera's images, the motion statistics and
// the files. Everything that can be refused is checked before the output
// folder is touched.
#include "fgcal/apps/simulator.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "commands/simulate/leg_motion.hpp"
#include "commands/simulate/options.hpp"
#include "commands/simulate/scene.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/kinematics/default_robot.hpp"
#include "fgcal/kinematics/errors.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal/vision/board_renderer.hpp"

namespace fgcal::apps {

namespace fs = std::filesystem;

namespace {

// Clocks: joints at 500 Hz from a realistic epoch; cam0 at 30 Hz on the joint
// grid (17, 16, 17 samples apart: exactly 30 Hz on average); cam1 at 15 Hz,
// hardware-synced with every other cam0 frame but stamped 200 us later.
constexpr int64_t kT0Ns = 1'700'000'000'000'000'000LL;
constexpr int64_t kJointPeriodNs = 2'000'000;
constexpr int kLeadSamples = 50;  // 0.1 s of joints before the first and after the last image
constexpr double kBlurSigmaPx = 0.6, kIntensityNoise = 2.0;
constexpr int kExposureInstants = 7;  // instants averaged over a row's exposure (--exposure-ms)

int cam0SampleIndex(int frame) { return kLeadSamples + (50 * frame + 1) / 3; }

const char* kDefaultRobotLabel = "default robot (fgcal_quadruped)";

[[noreturn]] void bad(const std::string& option, const std::string& detail, const std::string& file = "") {
  throw InputError(file, option, detail);
}

// The output folder: created, and empty unless an earlier simulation's files
// may be replaced.
void prepareOutDir(const SimulationOptions& o) {
  const fs::path dir(o.out_dir);
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) bad("--out", "exists and is not a folder", o.out_dir);
  if (fs::exists(dir, ec) && !fs::is_empty(dir, ec)) {
    if (!o.overwrite)
      bad("--out", "folder is not empty (choose an empty or new folder, or pass --force to replace an earlier simulation)", o.out_dir);
    for (const char* f : {"rig.yaml", "joints.csv", "ground_truth.yaml", "robot.urdf"}) fs::remove(dir / f, ec);
    for (const char* cam : {"multisense_left", "xtion_rgb", "multisense_right", "head_wide"}) {
      if (!fs::is_directory(dir / cam, ec)) continue;
      for (const auto& e : fs::directory_iterator(dir / cam, ec))
        if (e.path().extension() == ".png") fs::remove(e.path(), ec);
    }
  }
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) bad("--out", "cannot create the folder: " + ec.message(), o.out_dir);
}

std::string formatNumber(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string listNames(const std::vector<std::string>& names, size_t max = 12) {
  std::string s;
  for (size_t i = 0; i < names.size() && i < max; ++i) s += (i ? ", " : "") + names[i];
  if (names.size() > max) s += ", ... (" + std::to_string(names.size()) + " in all)";
  return s;
}

// Where the leg starts: the first movable joint of the chain, in the base frame.
SE3 hipPose(const kinematics::RobotModel& model, const kinematics::KinematicChain& chain,
            const std::string& base_link) {
  const auto& first = chain.joints().front();
  const auto& j = model.joint(first.name);
  const std::string& link = first.upward ? j.child_link : j.parent_link;
  const auto to_link = model.chain(base_link, link);
  const SE3 T_base_link = to_link.forward(VecX::Zero(to_link.numJoints()));
  return first.upward ? T_base_link : T_base_link * j.T_parent_joint;
}

// Per image: corner jitter whose pixel offsets are isotropic with std
// pixel_noise at the board centre (the board-plane shape undoes foreshortening).
void setCornerJitter(vision::RenderOptions* ro, const vision::CameraModel& cam, const SE3& T_cam_marker,
                     const vision::CharucoTarget& target, double pixel_noise) {
  if (!(pixel_noise > 0.0)) return;
  const Vec3 centre = T_cam_marker * Vec3(0.5 * target.squares_x * target.square_size,
                                          0.5 * target.squares_y * target.square_size, 0.0);
  if (centre.z() < 0.05) return;
  const double f = std::sqrt(cam.fx() * cam.fy()), z = centre.z();
  ro->corner_jitter_m = pixel_noise * z / f;
  vision::Mat23 J_uv_p;
  if (!cam.project(centre, &J_uv_p)) return;
  const Eigen::Matrix2d J_uv_xy = J_uv_p * T_cam_marker.rotation().leftCols<2>();
  const double det = J_uv_xy.determinant();
  // Beyond ~80 degrees of tilt the inverse explodes: keep it isotropic there.
  if (std::abs(det) > 0.17 * (f / z) * (f / z)) ro->corner_jitter_shape = (f / z) * J_uv_xy.inverse();
}

// --intrinsics-error: fx, fy scaled by (1 +- pct/100), cx, cy moved by +- px;
// the signs from the seed, per camera and parameter.
std::array<double, 4> perturbedIntrinsics(const vision::CameraModel& m, const SimulationOptions& o, int camera) {
  sim::Rng rng(sim::mixSeed(o.seed, 0x1Bu, static_cast<uint64_t>(camera)));
  std::array<double, 4> sign;
  for (double& s : sign) s = rng.uniform() < 0.5 ? -1.0 : 1.0;
  const double f = o.intrinsics_error_pct / 100.0, px = o.intrinsics_error_px;
  return {m.fx() * (1.0 + sign[0] * f), m.fy() * (1.0 + sign[1] * f), m.cx() + sign[2] * px, m.cy() + sign[3] * px};
}

// ---- The robot: URDF, marker chain, --camera-frames links ----

struct Robot {
  std::string label, urdf_text;
  std::optional<kinematics::RobotModel> model;
  std::optional<kinematics::KinematicChain> chain;  ///< base_link -> marker_link
  std::vector<SE3> T_base_frames;                   ///< --camera-frames: each link's pose
  /// --leg-origin-error: the real leg's origin corrections (6 per movable
  /// joint, chain order); empty when the leg is its URDF.
  VecX origin_errors;
  /// --backlash per movable joint of the chain (chain order), zeros without.
  VecX backlash;

  /// The real board pose at joint angles q (mount M): what the images show.
  SE3 board(const VecX& q, const SE3& M) const {
    return origin_errors.size() ? chain->forwardCorrected(q, origin_errors, M) : chain->forward(q) * M;
  }
};

std::string readUrdfText(const SimulationOptions& o) {
  if (o.urdf_path.empty()) return kinematics::defaultRobotUrdf();
  std::error_code ec;
  if (!fs::is_regular_file(o.urdf_path, ec)) bad("--urdf", "file not found", o.urdf_path);
  try {
    return readTextFile(o.urdf_path, "URDF");
  } catch (const InputError& e) {
    bad("--urdf", e.detail(), o.urdf_path);
  }
}

void requireLink(const Robot& r, const char* option, const std::string& link) {
  if (!r.model->hasLink(link))
    bad(option, "no link '" + link + "' in the URDF (links: " + listNames(r.model->linkNames()) + ")", r.label);
}

// --camera-frames: the cameras' CAD poses, links fixed to the base.
std::vector<SE3> cameraFramePoses(const SimulationOptions& o, const Robot& r) {
  if (!o.camera_frames.empty() && o.camera_frames.size() != static_cast<std::size_t>(o.cameras))
    bad("--camera-frames", "expected one link per camera (--cameras " + std::to_string(o.cameras) + "), got " +
                               std::to_string(o.camera_frames.size()));
  std::vector<SE3> poses;
  for (const std::string& link : o.camera_frames) {
    requireLink(r, "--camera-frames", link);
    std::optional<kinematics::KinematicChain> to_cam;
    try {
      to_cam = r.model->chain(o.base_link, link);
    } catch (const kinematics::KinematicsError& e) {
      bad("--camera-frames", e.what(), r.label);
    }
    if (to_cam->numJoints() != 0)
      bad("--camera-frames", "the chain '" + o.base_link + "' -> '" + link + "' has the movable joint '" +
                                 to_cam->jointNames().front() + "'; expected a camera fixed to the base",
          r.label);
    poses.push_back(to_cam->forward(VecX()));
  }
  return poses;
}

Robot loadRobot(const SimulationOptions& o) {
  Robot r;
  r.label = o.urdf_path.empty() ? kDefaultRobotLabel : o.urdf_path;
  r.urdf_text = readUrdfText(o);
  try {
    r.model = kinematics::RobotModel::fromString(r.urdf_text, r.label);
  } catch (const kinematics::KinematicsError& e) {
    bad("--urdf", std::string("not a usable URDF: ") + e.what(), r.label);
  }
  requireLink(r, "--base-link", o.base_link);
  requireLink(r, "--marker-link", o.marker_link);
  try {
    r.chain = r.model->chain(o.base_link, o.marker_link);
  } catch (const kinematics::KinematicsError& e) {
    bad("--marker-link", e.what(), r.label);
  }
  if (r.chain->numJoints() == 0)
    bad("--marker-link", "no movable joint between '" + o.base_link + "' and '" + o.marker_link +
                             "': the board must be on a limb", r.label);
  r.T_base_frames = cameraFramePoses(o, r);
  sim::checkJointOffsets(o, *r.chain);
  r.backlash = VecX::Constant(r.chain->numJoints(), o.backlash_rad);
  for (const auto& [joint, rad] : o.joint_backlash_rad) r.backlash(r.chain->indexOf(joint)) = rad;
  if (o.leg_origin_error_m > 0.0 || o.leg_origin_error_rad > 0.0) {
    sim::Rng rng(sim::mixSeed(o.seed, 0x0Fu, 0));
    r.origin_errors.resize(6 * r.chain->numJoints());
    for (Eigen::Index i = 0; i < r.origin_errors.size(); ++i)
      r.origin_errors[i] = (i % 6 < 3 ? o.leg_origin_error_rad : o.leg_origin_error_m) * rng.normal();
  }
  return r;
}

// ---- The scene: workspace, cameras, board and its mount ----

struct Scene {
  sim::Workspace ws;
  std::vector<sim::SimCamera> cams;
  vision::CharucoTarget target;
  SE3 T_link_marker;  ///< the true mount
};

Scene buildScene(const SimulationOptions& o, const Robot& r, sim::Rng& rng) {
  Scene s;
  s.ws = sim::sampleWorkspace(*r.chain, hipPose(*r.model, *r.chain, o.base_link), rng, 4000);
  s.cams = sim::makeCameras(o.cameras, o.distortion, s.ws, o.image_width, o.image_height, o.fov_deg);
  if (o.fov_deg > 0.0)
    for (const auto& cam : s.cams) {
      const std::string why = sim::projectionFolds(cam.model);
      if (!why.empty())
        bad("--fov-deg", "camera " + cam.name + " with " + formatNumber(o.fov_deg) + " deg and --distortion " +
                             o.distortion + ": " + why + "; expected a narrower field of view");
    }
  if (!o.camera_frames.empty()) {
    sim::Rng frame_rng(sim::mixSeed(o.seed, 0xCFu, 0));
    for (std::size_t c = 0; c < s.cams.size(); ++c) {
      Vec3 dr(frame_rng.normal(), frame_rng.normal(), frame_rng.normal());
      Vec3 dt(frame_rng.normal(), frame_rng.normal(), frame_rng.normal());
      s.cams[c].T_base_cam = r.T_base_frames[c] * SE3(SO3::exp(o.camera_frame_offset_rad * dr.normalized()),
                                                      o.camera_frame_offset_m * dt.normalized());
    }
  }
  s.target.squares_x = 5;  // 5 x 7 squares, 0.04 / 0.03 m, DICT_4X4_50
  s.target.squares_y = 7;
  s.target.square_size = 0.04;
  s.target.marker_size = 0.03;
  s.target.dictionary = "DICT_4X4_50";
  s.T_link_marker = sim::designMount(s.ws, *r.chain, s.cams, s.target);
  return s;
}

// ---- Clocks: joint samples and every camera's image stamps ----

struct ImageEvent {
  int64_t stamp_ns;
  double t;  // seconds since the first joint sample
  int cam0_frame;
};

struct Clocks {
  int n_samples = 0;     ///< rows of joints.csv
  double duration = 0.0;  ///< seconds from the first to the last joint sample
  std::vector<std::vector<ImageEvent>> events;  ///< per camera
  std::vector<double> delay_s;                  ///< per camera: --camera-delay-ms
};

Clocks planClocks(const SimulationOptions& o, const std::vector<sim::SimCamera>& cams) {
  Clocks k;
  k.n_samples = cam0SampleIndex(o.frames - 1) + kLeadSamples + 1;
  k.duration = (k.n_samples - 1) * kJointPeriodNs * 1e-9;
  const int64_t cam1_delay_ns = std::llround(o.cam1_delay_us * 1e3);
  k.events.resize(cams.size());
  for (int f = 0; f < o.frames; ++f) {
    const int idx = cam0SampleIndex(f);
    const int64_t stamp = kT0Ns + idx * kJointPeriodNs;
    for (size_t c = 0; c < cams.size(); ++c) {
      if (c == 1) {
        if (f % 2 == 0)
          k.events[c].push_back({stamp + cam1_delay_ns, (idx * kJointPeriodNs + cam1_delay_ns) * 1e-9, f});
      } else {
        k.events[c].push_back({stamp, idx * kJointPeriodNs * 1e-9, f});
      }
    }
  }
  // Each camera's images rendered at stamp + delay, inside joints.csv.
  k.delay_s.assign(cams.size(), 0.0);
  std::vector<std::string> names;
  std::vector<std::vector<int64_t>> stamps_ns(cams.size());
  for (size_t c = 0; c < cams.size(); ++c) {
    names.push_back(cams[c].name);
    for (const ImageEvent& ev : k.events[c]) stamps_ns[c].push_back(ev.stamp_ns);
    const auto it = o.camera_delay_ms.find(cams[c].name);
    if (it != o.camera_delay_ms.end()) k.delay_s[c] = it->second * 1e-3;
  }
  sim::checkCameraDelays(o, names, stamps_ns, kT0Ns, kT0Ns + (k.n_samples - 1) * kJointPeriodNs);
  return k;
}

// ---- joints.csv: every movable joint, the leg moving, the others standing ----

struct JointTable {
  std::vector<std::string> names;
  std::vector<int64_t> stamps;
  /// samples x names: the motor side (the leg's smooth motion; the joint
  /// behind any backlash differs) - offset + encoder noise, in encoder steps
  Eigen::MatrixXd positions;
};

JointTable simulateJoints(const SimulationOptions& o, const Robot& r, const sim::LegTrajectory& traj,
                          int n_samples) {
  JointTable t;
  t.names = r.model->movableJointNames();
  const auto n = static_cast<Eigen::Index>(t.names.size());
  t.positions.resize(n_samples, n);
  t.stamps.resize(static_cast<size_t>(n_samples));
  std::vector<int> chain_index(t.names.size());
  VecX nominal(n), offset = VecX::Zero(n);  // --joint-offsets: joints.csv = truth - o
  for (Eigen::Index j = 0; j < n; ++j) {
    const std::string& name = t.names[static_cast<size_t>(j)];
    chain_index[static_cast<size_t>(j)] = r.chain->indexOf(name);
    if (const auto it = o.joint_offsets_rad.find(name); it != o.joint_offsets_rad.end()) offset(j) = it->second;
    const auto& l = r.model->joint(name).limits;
    nominal(j) = l.has_position_limits ? std::clamp(0.0, l.lower, l.upper) : 0.0;
  }
  sim::Rng encoder_rng(sim::mixSeed(o.seed, 0xE1u, 0));
  const double steps_per_rad = o.encoder_resolution_rad > 0.0 ? 1.0 / o.encoder_resolution_rad : 0.0;
  for (int s = 0; s < n_samples; ++s) {
    t.stamps[static_cast<size_t>(s)] = kT0Ns + s * kJointPeriodNs;
    const VecX q = traj.at(s * kJointPeriodNs * 1e-9);
    for (Eigen::Index j = 0; j < n; ++j) {
      const int i = chain_index[static_cast<size_t>(j)];
      const double truth = i >= 0 ? q(i) : nominal(j);
      t.positions(s, j) = truth - offset(j) + o.encoder_noise * encoder_rng.normal();
      if (steps_per_rad > 0.0)  // whole encoder steps, after the noise; 0.571 rather than 571 * 0.001
        t.positions(s, j) = std::round(t.positions(s, j) * steps_per_rad) / steps_per_rad;
    }
  }
  return t;
}

// ---- Images: one camera's board poses, view checks and rendered PNGs ----

struct CameraImages {
  SimulatedCameraSummary summary;
  std::vector<bool> in_view;  ///< per image: the whole board seen by geometry
};

// The board in the camera while an image is taken from `t` seconds on: per
// row v (rolling shutter: from t + v / (H - 1) * readout) and per instant of
// the row's exposure (the middles of kExposureInstants equal parts of it), rows
// then instants; one pose when the camera takes the image at one instant.
struct ImagePoses {
  std::vector<SE3> T_cam_marker;
  int per_row = 1;
};

ImagePoses posesDuringImage(const SimulationOptions& o, const Robot& r, const Scene& s, const sim::JointPlay& joints,
                            std::size_t c, double t) {
  const sim::SimCamera& cam = s.cams[c];
  const SE3 T_cam_base = cam.T_base_cam.inverse();
  const auto readout = o.readout_ms.find(cam.name);
  const double readout_s = readout != o.readout_ms.end() ? readout->second * 1e-3 : 0.0;
  const double exposure_s = o.exposure_ms * 1e-3;
  ImagePoses p;
  p.per_row = exposure_s > 0.0 ? kExposureInstants : 1;
  const int H = cam.model.height();
  const int rows = readout_s > 0.0 && H > 1 ? H : 1;
  for (int v = 0; v < rows; ++v) {
    const double row_start = t + (rows > 1 ? readout_s * v / (H - 1) : 0.0);
    for (int k = 0; k < p.per_row; ++k) {
      const double instant = row_start + exposure_s * (k + 0.5) / p.per_row;
      p.T_cam_marker.push_back(T_cam_base * r.board(joints.at(instant), s.T_link_marker));
    }
  }
  return p;
}

// Renders image `ev` of camera `c` as a PNG in `folder`, from the board's
// poses while it is taken (one for an instant's image).
void writeImage(const SimulationOptions& o, const Scene& s, const vision::BoardRenderer& renderer, std::size_t c,
                const ImageEvent& ev, const ImagePoses& poses, const fs::path& folder) {
  vision::RenderOptions ro;
  ro.blur_sigma = kBlurSigmaPx;
  ro.noise_sigma = kIntensityNoise;
  ro.seed = sim::mixSeed(o.seed, 1 + c, static_cast<uint64_t>(ev.cam0_frame));
  ro.jitter_seed = sim::mixSeed(o.seed, 101 + c, static_cast<uint64_t>(ev.cam0_frame));
  // The printed board's jitter is one per image, shaped at its first pose.
  setCornerJitter(&ro, s.cams[c].model, poses.T_cam_marker.front(), s.target, o.pixel_noise);
  const cv::Mat img = poses.T_cam_marker.size() == 1 ? renderer.render(poses.T_cam_marker.front(), ro)
                                                     : renderer.renderMoving(poses.T_cam_marker, poses.per_row, ro);
  std::vector<uchar> png;
  if (!cv::imencode(".png", img, png)) throw DataError("simulate: PNG encoding failed");
  // Not synced one by one: rig.yaml, written last and synced, marks the dataset complete.
  writeFileAtomically((folder / (std::to_string(ev.stamp_ns) + ".png")).string(), std::string(png.begin(), png.end()),
                      Durability::Unsynced);
}

CameraImages renderCamera(const SimulationOptions& o, const Robot& r, const Scene& s, const Clocks& k,
                          const sim::JointPlay& joints, std::size_t c) {
  const sim::SimCamera& cam = s.cams[c];
  const fs::path folder = fs::path(o.out_dir) / cam.name;
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) bad("--out", "cannot create " + folder.string() + ": " + ec.message(), o.out_dir);
  const vision::BoardRenderer renderer(cam.model, s.target, o.supersampling);
  const SE3 T_cam_base = cam.T_base_cam.inverse();
  CameraImages out;
  out.summary.name = cam.name;
  out.summary.T_base_cam = cam.T_base_cam;
  const auto& events = k.events[c];
  for (const ImageEvent& ev : events) {
    const SE3 T_base_marker = r.board(joints.at(ev.t + k.delay_s[c]), s.T_link_marker);
    const sim::ViewQuality vq = sim::viewQuality(cam, T_base_marker, s.target, 0.0);
    const bool seen = vq.in_image && vq.angle < 75.0 * M_PI / 180.0;
    out.in_view.push_back(seen);
    out.summary.board_in_view += seen ? 1 : 0;
    if (!o.render_images) continue;
    const bool moving = o.exposure_ms > 0.0 || (o.readout_ms.count(cam.name) && o.readout_ms.at(cam.name) > 0.0);
    writeImage(o, s, renderer, c, ev,
               moving ? posesDuringImage(o, r, s, joints, c, ev.t + k.delay_s[c])
                      : ImagePoses{{T_cam_base * T_base_marker}, 1},
               folder);
    ++out.summary.images;
    if (o.progress) o.progress(cam.name, out.summary.images, static_cast<int>(events.size()));
  }
  return out;
}

// ---- Statistics: F2 share and the board's orientation diversity ----

// Share of cam1's instants (cam0's with one camera) at which every camera sees the board.
double fractionAllInView(int frames, const std::vector<std::vector<bool>>& in_view) {
  int instants = 0, all_seen = 0;
  for (int f = 0; f < frames; ++f) {
    if (in_view.size() > 1 && f % 2 != 0) continue;
    ++instants;
    bool all = true;
    for (size_t c = 0; c < in_view.size(); ++c) all = all && in_view[c][static_cast<size_t>(c == 1 ? f / 2 : f)];
    all_seen += all ? 1 : 0;
  }
  return instants ? static_cast<double>(all_seen) / instants : 0.0;
}

// The board's largest rotation between two instants and the spread of its
// orientation about the base axes (at most 400 of cam0's instants).
void boardRotationSpread(const SimulationOptions& o, const Robot& r, const Scene& s, const Clocks& k,
                         const sim::JointPlay& joints, SimulationSummary* summary) {
  std::vector<SO3> R;
  const int step = std::max(1, o.frames / 400);
  for (int f = 0; f < o.frames; f += step)
    R.push_back(r.board(joints.at(k.events[0][static_cast<size_t>(f)].t), s.T_link_marker).so3());
  Mat3 sum = Mat3::Zero();
  for (const SO3& rot : R) sum += rot.matrix();
  const SO3 R_mean = SO3(sum).normalized();
  Vec3 mean = Vec3::Zero(), sq = Vec3::Zero();
  for (const SO3& rot : R) {
    const Vec3 w = R_mean.matrix() * R_mean.between(rot).log();  // base-frame axes
    mean += w;
    sq += w.cwiseProduct(w);
  }
  mean /= static_cast<double>(R.size());
  sq /= static_cast<double>(R.size());
  summary->board_rotation_std_deg = (sq - mean.cwiseProduct(mean)).cwiseMax(0.0).cwiseSqrt() * 180.0 / M_PI;
  double range = 0.0;
  for (size_t a = 0; a < R.size(); ++a)
    for (size_t b = a + 1; b < R.size(); ++b) range = std::max(range, R[a].between(R[b]).log().norm());
  summary->board_rotation_range_deg = range * 180.0 / M_PI;
}

// ---- Files: the URDF, joints, truth, and rig.yaml last (its presence marks a complete dataset) ----

GroundTruth groundTruth(const SimulationOptions& o, const Robot& r, const Scene& s) {
  GroundTruth truth;
  for (const sim::SimCamera& cam : s.cams) {
    truth.T_base_cam[cam.name] = cam.T_base_cam;
    const auto it = o.camera_delay_ms.find(cam.name);
    // fgcal's time offset is the first row's mid-exposure (docs/outputs.md):
    // a blurred corner is found where the board was halfway through it.
    truth.time_offset_ms[cam.name] = (it != o.camera_delay_ms.end() ? it->second : 0.0) + 0.5 * o.exposure_ms;
    truth.intrinsics[cam.name] = {cam.model.fx(), cam.model.fy(), cam.model.cx(), cam.model.cy()};
    truth.distortion_coeffs[cam.name] = cam.model.coeffs();
  }
  truth.T_link_marker = s.T_link_marker;
  for (const std::string& joint : r.chain->jointNames()) {
    const auto it = o.joint_offsets_rad.find(joint);
    truth.joint_offsets_rad[joint] = it != o.joint_offsets_rad.end() ? it->second : 0.0;
  }
  for (std::size_t j = 0; j < r.chain->jointNames().size() && r.origin_errors.size(); ++j)
    truth.kinematic_origins[r.chain->jointNames()[j]] = r.origin_errors.segment<6>(6 * static_cast<Eigen::Index>(j));
  // The effects' keys only when an effect is on: without, the file is as before them.
  if ((r.backlash.array() != 0.0).any())
    for (std::size_t j = 0; j < r.chain->jointNames().size(); ++j)
      truth.backlash_rad[r.chain->jointNames()[j]] = r.backlash(static_cast<Eigen::Index>(j));
  const bool rolling =
      std::any_of(o.readout_ms.begin(), o.readout_ms.end(), [](const auto& e) { return e.second != 0.0; });
  for (const sim::SimCamera& cam : s.cams) {
    if (rolling) truth.readout_ms[cam.name] = o.readout_ms.count(cam.name) ? o.readout_ms.at(cam.name) : 0.0;
    if (o.exposure_ms > 0.0) truth.exposure_ms[cam.name] = o.exposure_ms;
  }
  if (o.encoder_resolution_rad > 0.0) truth.encoder_resolution_rad = o.encoder_resolution_rad;
  return truth;
}

// rig.yaml: the robot with the mount prior (the truth moved by exactly
// mount_error_m / mount_error_rad), the board, and the cameras with
// intrinsics as --intrinsics-error leaves them.
RigConfig rigConfig(const SimulationOptions& o, const Scene& s, const fs::path& out) {
  RigConfig rig;
  rig.robot.urdf = (out / "robot.urdf").string();
  rig.robot.base_link = o.base_link;
  rig.robot.marker_link = o.marker_link;
  sim::Rng mount_rng(sim::mixSeed(o.seed, 0x3Du, 0));
  const Vec3 dir_rot = mount_rng.unitVector(), dir_pos = mount_rng.unitVector();
  rig.robot.T_link_marker = s.T_link_marker * SE3(SO3::exp(o.mount_error_rad * dir_rot), o.mount_error_m * dir_pos);
  rig.robot.mount_sigma_m = std::max(0.002, 1.5 * o.mount_error_m);
  rig.robot.mount_sigma_rad = std::max(0.01, 1.5 * o.mount_error_rad);
  rig.robot.encoder_sigma = std::max(o.encoder_noise, 1e-5);
  if (o.leg_origin_error_m > 0.0 || o.leg_origin_error_rad > 0.0)  // the URDF's tolerance, as large as the error
    rig.robot.kinematic_sigma = {std::max(o.leg_origin_error_m, 1e-6), std::max(o.leg_origin_error_rad, 1e-6)};
  rig.target.type = "charuco";
  rig.target.squares_x = s.target.squares_x;
  rig.target.squares_y = s.target.squares_y;
  rig.target.square_size = s.target.square_size;
  rig.target.marker_size = s.target.marker_size;
  rig.target.dictionary = s.target.dictionary;
  for (size_t c = 0; c < s.cams.size(); ++c) {
    const sim::SimCamera& cam = s.cams[c];
    CameraConfig cc;
    cc.name = cam.name;
    cc.camera_model = "pinhole";
    cc.distortion_model = o.distortion;
    cc.intrinsics = perturbedIntrinsics(cam.model, o, static_cast<int>(c));
    cc.distortion_coeffs = cam.model.coeffs();
    cc.resolution = {cam.model.width(), cam.model.height()};
    cc.pixel_sigma = std::max(o.pixel_noise, 0.05);
    if (!o.camera_frames.empty()) cc.frame = o.camera_frames[c];
    rig.cameras.push_back(cc);
  }
  rig.sync_tolerance_ms = 1.0;
  return rig;
}

void writeDatasetFiles(const SimulationOptions& o, const Robot& r, const Scene& s, const JointTable& joints) {
  const fs::path out = fs::absolute(fs::path(o.out_dir)).lexically_normal();
  writeFileAtomically((out / "robot.urdf").string(), r.urdf_text);
  writeJointsCsv((out / "joints.csv").string(), joints.names, joints.stamps, joints.positions);
  writeFileAtomically((out / "ground_truth.yaml").string(), formatGroundTruthYaml(groundTruth(o, r, s)));
  writeFileAtomically((out / "rig.yaml").string(), writeRigConfig(rigConfig(o, s, out), out.string()));
}

}  // namespace

std::vector<std::string> simulatedCameraNames(int count) { return sim::cameraNames(count); }

SimulationSummary simulateDataset(const SimulationOptions& o) {
  const auto wall_start = std::chrono::steady_clock::now();
  // Everything that can be refused is checked before anything is written.
  sim::validateOptions(o);
  const Robot robot = loadRobot(o);
  sim::Rng rng(sim::mixSeed(o.seed, 0x51u, 0));  // the workspace, then the motion
  const Scene scene = buildScene(o, robot, rng);
  const Clocks clocks = planClocks(o, scene.cams);
  const sim::LegTrajectory traj =
      sim::planLegMotion(*robot.chain, scene.T_link_marker, scene.cams, scene.target, scene.ws, clocks.duration, rng);
  const sim::JointPlay joint_side(traj, robot.backlash);  // what the images show; traj is the motors'
  prepareOutDir(o);

  const JointTable joints = simulateJoints(o, robot, traj, clocks.n_samples);
  SimulationSummary summary;
  summary.instants = o.frames;
  summary.joint_samples = clocks.n_samples;
  summary.T_link_marker = scene.T_link_marker;
  std::vector<std::vector<bool>> in_view;
  for (size_t c = 0; c < scene.cams.size(); ++c) {
    CameraImages images = renderCamera(o, robot, scene, clocks, joint_side, c);
    summary.images_written += images.summary.images;
    summary.cameras.push_back(images.summary.name);
    summary.per_camera.push_back(images.summary);
    in_view.push_back(std::move(images.in_view));
  }
  summary.fraction_all_in_view = fractionAllInView(o.frames, in_view);
  boardRotationSpread(o, robot, scene, clocks, joint_side, &summary);
  writeDatasetFiles(o, robot, scene, joints);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return summary;
}

}  // namespace fgcal::apps
