// The simulator's leg and camera effects are what the files say: joints.csv
// holds the motor side of a joint with gear backlash and the images the joint
// behind it, readings are whole encoder steps, every image row shows the board
// where it was at that row's time (rolling shutter), a long exposure blurs the
// board but it is still detected; and every effect at zero leaves each file
// as it was without the option (the benchmarks' datasets depend on it).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>

#include "apps_test_util.hpp"
#include "commands/simulate/leg_motion.hpp"
#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/simulator.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "sim_test_util.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {

// A small noise-free dataset: joints.csv and the detections are the truth.
SimulationOptions exactOptions(const std::string& out_dir, int frames, int cameras) {
  SimulationOptions o;
  o.out_dir = out_dir;
  o.frames = frames;
  o.cameras = cameras;
  o.supersampling = 2;
  o.pixel_noise = 0.0;
  o.encoder_noise = 0.0;
  return o;
}

// Every file of a dataset: path relative to the folder -> bytes.
std::map<std::string, std::string> filesOf(const std::string& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files[fs::relative(e.path(), dir).string()] = readFile(e.path().string());
  return files;
}

// Images of one camera in two datasets with the same bytes.
int sameImages(const std::string& a_dir, const std::string& b_dir, const std::string& cam) {
  const auto a = imagesOf(fs::path(a_dir) / cam), b = imagesOf(fs::path(b_dir) / cam);
  REQUIRE(a.size() == b.size());
  int same = 0;
  for (std::size_t k = 0; k < a.size(); ++k) same += readFile(a[k].string()) == readFile(b[k].string()) ? 1 : 0;
  return same;
}

// The dataset as a calibration would read it, with the truth.
struct Dataset {
  RigConfig rig;
  GroundTruth truth;
  kinematics::KinematicChain chain;
  JointLog log;
  std::vector<int> cols;

  explicit Dataset(const std::string& dir)
      : rig(loadRigConfig(dir + "/rig.yaml")),
        truth(loadGroundTruth(dir + "/ground_truth.yaml")),
        chain(kinematics::RobotModel::fromFile(rig.robot.urdf).chain(rig.robot.base_link, rig.robot.marker_link)),
        log(loadJointsCsv(dir + "/joints.csv")),
        cols(columnIndices(log, chain.jointNames(), "joints.csv")) {}

  VecX joints(int64_t stamp_ns) const {
    const auto q = interpolate(log, stamp_ns, cols);
    REQUIRE(q.has_value());
    return *q;
  }
  SE3 boardInCamera(const std::string& cam, const VecX& q) const {
    return truth.T_base_cam.at(cam).inverse() * chain.forward(q) * *truth.T_link_marker;
  }
  const CameraConfig& camera(const std::string& name) const {
    for (const auto& c : rig.cameras)
      if (c.name == name) return c;
    FAIL("no camera " << name);
    throw std::logic_error("unreachable");
  }
};

double distance(const SE3& a, const SE3& b) { return (a.translation() - b.translation()).norm(); }

// The play operator run sample by sample over joints.csv's chain columns (an
// implementation independent of the simulator's): the joint stays where it
// was unless the motor pushes it, b/2 away. Started behind the first move.
std::vector<VecX> playOverLog(const Dataset& ds, const VecX& b) {
  const Eigen::Index n = ds.log.positions.rows();
  auto motor = [&](Eigen::Index s) {
    VecX q(ds.cols.size());
    for (std::size_t j = 0; j < ds.cols.size(); ++j) q(static_cast<Eigen::Index>(j)) = ds.log.positions(s, ds.cols[j]);
    return q;
  };
  std::vector<VecX> out;
  VecX y = motor(0);
  for (Eigen::Index j = 0; j < y.size(); ++j)
    for (Eigen::Index s = 1; s < n; ++s)
      if (const double d = ds.log.positions(s, ds.cols[static_cast<std::size_t>(j)]) - y(j); d != 0.0) {
        y(j) -= 0.5 * b(j) * (d > 0.0 ? 1.0 : -1.0);
        break;
      }
  for (Eigen::Index s = 0; s < n; ++s) {
    const VecX m = motor(s);
    y = y.cwiseMax(m - 0.5 * b).cwiseMin(m + 0.5 * b);
    out.push_back(y);
  }
  return out;
}

}  // namespace

TEST_CASE("simulator: every new effect at zero leaves each file byte-identical to a run without the option",
          "[apps][simulator][effects]") {
  TempDir tmp;
  SimulationOptions ref;  // with noise: a zero effect must not draw a random number either
  ref.out_dir = tmp / "ref";
  ref.frames = 4;
  ref.supersampling = 1;
  SimulationOptions zero = ref;
  zero.out_dir = tmp / "zero";
  zero.backlash_rad = 0.0;
  zero.joint_backlash_rad = {{"lf_kfe_joint", 0.0}};
  zero.encoder_resolution_rad = 0.0;
  zero.readout_ms = {{"multisense_left", 0.0}, {"xtion_rgb", 0.0}};
  zero.exposure_ms = 0.0;
  simulateDataset(ref);
  simulateDataset(zero);
  const auto a = filesOf(ref.out_dir), b = filesOf(zero.out_dir);
  REQUIRE(a.size() == 10);  // rig.yaml, joints.csv, robot.urdf, ground_truth.yaml, 4 + 2 images
  for (const auto& [path, bytes] : a) {
    INFO(path);
    REQUIRE(b.count(path) == 1);
    CHECK(bytes == b.at(path));
  }
  CHECK(readFile(zero.out_dir + "/ground_truth.yaml").find("backlash") == std::string::npos);
}

TEST_CASE("simulator: the joint behind gear backlash lags its motor by b/2 and stands still while the motor turns "
          "back through the dead zone",
          "[apps][simulator][effects]") {
  // Joint 0 rises 0 -> 1 then falls to 0.4; joint 1 stands still.
  VecX w0(2), w1(2), w2(2);
  w0 << 0.0, 0.2;
  w1 << 1.0, 0.2;
  w2 << 0.4, 0.2;
  const sim::LegTrajectory motor({0.0, 1.0, 2.0}, {w0, w1, w2});
  VecX b(2);
  b << 0.1, 0.05;
  const sim::JointPlay joint(motor, b);
  CHECK(joint.at(0.0)(0) == Approx(-0.05));  // started behind the first move
  CHECK(joint.at(0.5)(0) == Approx(0.45));   // rising: b/2 below the motor
  CHECK(joint.at(1.0)(0) == Approx(0.95));
  for (double t = 0.0; t <= 3.0; t += 0.25) CHECK(joint.at(t)(1) == 0.2);  // no motion, no lag
  // Falling: the joint waits until the motor has turned back by b, then leads it by b/2.
  for (double t = 1.0; t < 2.0; t += 0.01) {
    const double m = motor.at(t)(0);
    INFO("t " << t << " motor " << m);
    if (m > 0.9) CHECK(joint.at(t)(0) == Approx(0.95));
    else CHECK(joint.at(t)(0) == Approx(m + 0.05));
  }
  CHECK(joint.at(5.0)(0) == Approx(0.45));  // after the last waypoint
  // The closed form per segment equals the play operator stepped finely.
  double y = -0.05;
  for (int k = 0; k <= 3000; ++k) {
    const double t = k * 1e-3, m = motor.at(t)(0);
    y = std::clamp(y, m - 0.05, m + 0.05);
    REQUIRE(std::abs(joint.at(t)(0) - y) < 1e-12);
  }
  // Without backlash the joint is the motor, to the last bit.
  const sim::JointPlay none(motor, VecX::Zero(2));
  for (double t = 0.0; t <= 2.0; t += 0.1) CHECK(none.at(t) == motor.at(t));
}

TEST_CASE("simulator: with backlash joints.csv holds the motor side and the images show the lagging joint",
          "[apps][simulator][effects]") {
  TempDir tmp;
  const SimulationOptions ref = exactOptions(tmp / "ref", 30, 1);
  SimulationOptions o = ref;
  o.out_dir = tmp / "backlash";
  o.backlash_rad = 0.02;
  o.joint_backlash_rad = {{"lf_kfe_joint", 0.03}};
  simulateDataset(ref);
  simulateDataset(o);

  const Dataset ds(o.out_dir);
  CHECK(ds.truth.backlash_rad ==
        std::map<std::string, double>{{"lf_haa_joint", 0.02}, {"lf_hfe_joint", 0.02}, {"lf_kfe_joint", 0.03}});
  // The motor follows the smooth motion the leg had without backlash; the images do not.
  CHECK(readFile(ref.out_dir + "/joints.csv") == readFile(o.out_dir + "/joints.csv"));
  CHECK(sameImages(ref.out_dir, o.out_dir, "multisense_left") < 5);

  VecX b(ds.chain.numJoints());
  for (int j = 0; j < b.size(); ++j)
    b(j) = ds.truth.backlash_rad.at(ds.chain.jointNames()[static_cast<std::size_t>(j)]);
  const std::vector<VecX> joint_side = playOverLog(ds, b);
  const auto seen = seenBoards(fs::path(o.out_dir) / "multisense_left", cameraOf(ds.camera("multisense_left")),
                               targetOf(ds.rig.target));
  REQUIRE(seen.size() >= 25);
  std::vector<double> at_joint, at_motor, steady;
  for (const SeenBoard& s : seen) {
    const auto idx = static_cast<std::size_t>(
        std::find(ds.log.stamps_ns.begin(), ds.log.stamps_ns.end(), s.stamp_ns) - ds.log.stamps_ns.begin());
    REQUIRE(idx + 1 < ds.log.stamps_ns.size());
    const VecX q_motor = ds.joints(s.stamp_ns);
    at_joint.push_back(distance(s.T_cam_marker, ds.boardInCamera("multisense_left", joint_side[idx])));
    at_motor.push_back(distance(s.T_cam_marker, ds.boardInCamera("multisense_left", q_motor)));
    // Steady motion: every joint of the chain has turned one way by more than
    // its backlash up to this image; then the joint is b/2 behind the motor.
    VecX q_lag = q_motor;
    bool all_steady = true;
    for (int j = 0; j < b.size() && all_steady; ++j) {
      const int col = ds.cols[static_cast<std::size_t>(j)];
      const double v = ds.log.positions(static_cast<Eigen::Index>(idx + 1), col) -
                       ds.log.positions(static_cast<Eigen::Index>(idx), col);
      double moved = 0.0;
      for (auto k = static_cast<Eigen::Index>(idx); k > 0 && moved <= b(j); --k) {
        const double d = ds.log.positions(k, col) - ds.log.positions(k - 1, col);
        if (d * v <= 0.0) break;
        moved += std::abs(d);
      }
      all_steady = moved > b(j);
      q_lag(j) -= 0.5 * b(j) * (v > 0.0 ? 1.0 : -1.0);
    }
    if (all_steady) steady.push_back(distance(s.T_cam_marker, ds.boardInCamera("multisense_left", q_lag)));
  }
  WARN("PnP vs forward kinematics: rms " << rms(at_joint) * 1e3 << " mm at the joint side, " << rms(at_motor) * 1e3
                                         << " mm at joints.csv; " << steady.size() << " steady images, rms "
                                         << rms(steady) * 1e3 << " mm at joints.csv - b/2 against the motion");
  CHECK(*std::max_element(at_joint.begin(), at_joint.end()) < 0.004);
  CHECK(rms(at_motor) > 3.0 * rms(at_joint));
  REQUIRE(steady.size() >= 3);
  CHECK(*std::max_element(steady.begin(), steady.end()) < 0.004);
}

TEST_CASE("simulator: every joints.csv reading is a whole number of encoder steps", "[apps][simulator][effects]") {
  TempDir tmp;
  SimulationOptions ref;
  ref.out_dir = tmp / "ref";
  ref.frames = 10;
  ref.render_images = false;
  ref.joint_offsets_rad = {{"lf_hfe_joint", 0.0123}};
  SimulationOptions o = ref;
  o.out_dir = tmp / "steps";
  o.encoder_resolution_rad = 0.001;
  simulateDataset(ref);
  simulateDataset(o);
  const JointLog raw = loadJointsCsv(ref.out_dir + "/joints.csv"), stepped = loadJointsCsv(o.out_dir + "/joints.csv");
  REQUIRE(raw.positions.rows() == stepped.positions.rows());
  REQUIRE(raw.positions.cols() == stepped.positions.cols());
  for (Eigen::Index r = 0; r < raw.positions.rows(); ++r)
    for (Eigen::Index c = 0; c < raw.positions.cols(); ++c) {
      const double x = stepped.positions(r, c) / 0.001;
      REQUIRE(std::abs(x - std::round(x)) < 1e-6);
      // Rounded after the noise: the nearest step to the reading without steps.
      REQUIRE(std::abs(stepped.positions(r, c) - raw.positions(r, c)) <= 0.0005 + 1e-9);
    }
  CHECK(loadGroundTruth(o.out_dir + "/ground_truth.yaml").encoder_resolution_rad == 0.001);
}

TEST_CASE("simulator: with a rolling shutter each image row shows the board at its own time",
          "[apps][simulator][effects]") {
  TempDir tmp;
  const SimulationOptions ref = exactOptions(tmp / "ref", 12, 2);
  SimulationOptions o = ref;
  o.out_dir = tmp / "rolling";
  const double readout_ms = 30.0;
  o.readout_ms = {{"multisense_left", readout_ms}};
  simulateDataset(ref);
  simulateDataset(o);

  const Dataset ds(o.out_dir);
  CHECK(ds.truth.readout_ms == std::map<std::string, double>{{"multisense_left", readout_ms}, {"xtion_rgb", 0.0}});
  // calibrate does not read a readout from rig.yaml: only the truth has it.
  CHECK(readFile(o.out_dir + "/rig.yaml").find("readout") == std::string::npos);
  CHECK(readFile(ref.out_dir + "/joints.csv") == readFile(o.out_dir + "/joints.csv"));
  CHECK(sameImages(ref.out_dir, o.out_dir, "xtion_rgb") == 6);  // a global-shutter camera is unchanged
  CHECK(sameImages(ref.out_dir, o.out_dir, "multisense_left") < 3);

  // Row v of an image stamped t starts exposing at t + v / (H - 1) * readout.
  const CameraConfig& cc = ds.camera("multisense_left");
  const vision::CameraModel cam = cameraOf(cc);
  const double H = cc.resolution[1];
  const vision::CharucoDetector detector(targetOf(ds.rig.target));
  std::vector<double> at_row, at_stamp_bottom, at_row_bottom;
  int images = 0;
  for (const auto& file : imagesOf(fs::path(o.out_dir) / "multisense_left")) {
    const auto det = detector.detect(cv::imread(file.string(), cv::IMREAD_UNCHANGED));
    if (!det.ok()) continue;
    ++images;
    const int64_t stamp = stampOf(file);
    const SE3 T_at_stamp = ds.boardInCamera("multisense_left", ds.joints(stamp));
    for (std::size_t k = 0; k < det.corners.size(); ++k) {
      const double row = det.corners[k].y();
      const auto t_row = stamp + std::llround(row / (H - 1.0) * readout_ms * 1e6);
      const auto uv_row = cam.project(ds.boardInCamera("multisense_left", ds.joints(t_row)) * det.object_points[k]);
      const auto uv_stamp = cam.project(T_at_stamp * det.object_points[k]);
      REQUIRE((uv_row && uv_stamp));
      at_row.push_back((*uv_row - det.corners[k]).norm());
      if (row > 0.5 * H) {
        at_row_bottom.push_back(at_row.back());
        at_stamp_bottom.push_back((*uv_stamp - det.corners[k]).norm());
      }
    }
  }
  WARN(images << " images: corner vs projection at the row's time rms " << rms(at_row) << " px; lower half "
              << rms(at_row_bottom) << " px at the row's time, " << rms(at_stamp_bottom) << " px at the stamp");
  REQUIRE(images >= 10);
  REQUIRE(at_row_bottom.size() > 50);
  CHECK(rms(at_row) < 0.3);
  CHECK(rms(at_stamp_bottom) > 4.0 * rms(at_row_bottom));
}

TEST_CASE("simulator: a long exposure blurs the moving board and it is still detected", "[apps][simulator][effects]") {
  TempDir tmp;
  const SimulationOptions ref = exactOptions(tmp / "ref", 10, 1);
  SimulationOptions o = ref;
  o.out_dir = tmp / "blur";
  const double exposure_ms = 20.0;
  o.exposure_ms = exposure_ms;
  simulateDataset(ref);
  simulateDataset(o);

  const Dataset ds(o.out_dir);
  CHECK(ds.truth.exposure_ms == std::map<std::string, double>{{"multisense_left", exposure_ms}});
  // The time offset fgcal estimates is the first row's mid-exposure: a blurred
  // corner is found where the board was halfway through it.
  CHECK(ds.truth.time_offset_ms.at("multisense_left") == Approx(0.5 * exposure_ms));
  CHECK(sameImages(ref.out_dir, o.out_dir, "multisense_left") < 3);
  const auto sharp = seenBoards(fs::path(ref.out_dir) / "multisense_left", cameraOf(ds.camera("multisense_left")),
                                targetOf(ds.rig.target));
  const auto blurred = seenBoards(fs::path(o.out_dir) / "multisense_left", cameraOf(ds.camera("multisense_left")),
                                  targetOf(ds.rig.target));
  REQUIRE(sharp.size() >= 8);
  CHECK(blurred.size() >= sharp.size() - 1);
  // The image integrates [stamp, stamp + exposure]: the board's pose is the
  // one in the middle of it more than the one at the stamp.
  std::vector<double> at_middle, at_stamp;
  for (const SeenBoard& s : blurred) {
    const int64_t middle = s.stamp_ns + std::llround(0.5 * exposure_ms * 1e6);
    at_middle.push_back(distance(s.T_cam_marker, ds.boardInCamera("multisense_left", ds.joints(middle))));
    at_stamp.push_back(distance(s.T_cam_marker, ds.boardInCamera("multisense_left", ds.joints(s.stamp_ns))));
  }
  WARN("PnP on blurred images vs forward kinematics: rms " << rms(at_middle) * 1e3 << " mm mid-exposure, "
                                                             << rms(at_stamp) * 1e3 << " mm at the stamp");
  CHECK(rms(at_middle) < rms(at_stamp));
}

TEST_CASE("simulator: bad values of the leg and camera effects name the option, nothing is written",
          "[apps][simulator][effects]") {
  TempDir tmp;
  SimulationOptions o;
  o.out_dir = tmp / "x";
  o.frames = 2;
  requireInputError(changed(o, [](auto& c) { c.backlash_rad = -0.01; }), "--backlash", "[0, 0.1]");
  requireInputError(changed(o, [](auto& c) { c.backlash_rad = NAN; }), "--backlash");
  requireInputError(changed(o, [](auto& c) { c.joint_backlash_rad = {{"lf_kfe_joint", 0.2}}; }), "--backlash",
                    "lf_kfe_joint");
  requireInputError(changed(o, [](auto& c) { c.joint_backlash_rad = {{"knee", 0.01}}; }), "--backlash",
                    "lf_haa_joint, lf_hfe_joint, lf_kfe_joint");
  requireInputError(changed(o, [](auto& c) { c.encoder_resolution_rad = -1e-3; }), "--encoder-resolution",
                    "[0, 0.1]");
  requireInputError(changed(o, [](auto& c) { c.encoder_resolution_rad = INFINITY; }), "--encoder-resolution");
  requireInputError(changed(o, [](auto& c) { c.readout_ms = {{"multisense_left", 40.0}}; }), "--readout-ms",
                    "multisense_left");
  requireInputError(changed(o, [](auto& c) { c.readout_ms = {{"xtion_rgb", 70.0}}; }), "--readout-ms",
                    "xtion_rgb's frame period");
  requireInputError(changed(o, [](auto& c) { c.readout_ms = {{"xtion_rgb", -1.0}}; }), "--readout-ms", "xtion_rgb");
  requireInputError(changed(o, [](auto& c) { c.readout_ms = {{"head_wide", 1.0}}; }), "--readout-ms",
                    "expected one of multisense_left, xtion_rgb");
  requireInputError(changed(o, [](auto& c) { c.exposure_ms = 40.0; }), "--exposure-ms", "[0, 33.3");
  requireInputError(changed(o, [](auto& c) { c.exposure_ms = -1.0; }), "--exposure-ms");
  CHECK_FALSE(fs::exists(o.out_dir));
  // A frame period's readout is allowed (15 Hz for xtion_rgb).
  o.render_images = false;
  o.readout_ms = {{"xtion_rgb", 60.0}};
  CHECK_NOTHROW(simulateDataset(o));

  // --backlash's texts: RAD for every joint of the chain, JOINT=RAD for one.
  double all = -1.0;
  std::map<std::string, double> per_joint;
  parseBacklash({"0.002"}, &all, &per_joint);
  CHECK(all == 0.002);
  CHECK(per_joint.empty());
  parseBacklash({"0.002,lf_kfe_joint=0.004", "lf_hfe_joint=0"}, &all, &per_joint);
  CHECK(all == 0.002);
  CHECK(per_joint == std::map<std::string, double>{{"lf_hfe_joint", 0.0}, {"lf_kfe_joint", 0.004}});
  parseBacklash({"lf_kfe_joint=0.004"}, &all, &per_joint);
  CHECK(all == 0.0);
  for (const std::string bad : {"x", "0.1,0.2", "a=1,a=2", "a=", "nan", "1,", "-"})
    CHECK_INPUT_ERROR(parseBacklash({bad}, &all, &per_joint), "", "--backlash", "");
}
