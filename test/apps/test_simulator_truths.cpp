// The simulator's extra truths (camera delays, joint zero offsets, wrong
// intrinsics, a wide fisheye) are what the files hold: the images of a
// delayed camera show the board where the leg was at stamp + delay, joints.csv
// + offset reproduces the rendered pose, rig.yaml's intrinsics are off by
// exactly what ground_truth.yaml says, and every bad value is refused by name.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>

#include "apps_test_util.hpp"
#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/simulator.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal_test/pose_gap.hpp"
#include "sim_test_util.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {

// A small noise-free dataset: joints.csv and the detections are the truth.
SimulationOptions exactOptions(const std::string& out_dir, int frames) {
  SimulationOptions o;
  o.out_dir = out_dir;
  o.frames = frames;
  o.supersampling = 2;
  o.pixel_noise = 0.0;
  o.encoder_noise = 0.0;
  return o;
}

// The dataset as the calibration would read it: rig, truth, chain, joints.
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

  /// The board in camera `cam` from joints.csv at `stamp_ns` (+ offsets, chain order).
  SE3 boardInCamera(const std::string& cam, int64_t stamp_ns, const VecX& offsets) const {
    const auto q = interpolate(log, stamp_ns, cols);
    REQUIRE(q.has_value());
    return truth.T_base_cam.at(cam).inverse() * chain.forward(*q + offsets) * *truth.T_link_marker;
  }
  const CameraConfig& camera(const std::string& name) const {
    for (const auto& c : rig.cameras)
      if (c.name == name) return c;
    FAIL("no camera " << name);
    throw std::logic_error("unreachable");
  }
};

using fgcal::test::translationGap;

}  // namespace

TEST_CASE("simulator: a delayed camera's images show the board at stamp + delay, the others are unchanged",
          "[apps][simulator][truths]") {
  TempDir tmp;
  const SimulationOptions ref = exactOptions(tmp / "ref", 16);
  SimulationOptions o = ref;
  o.out_dir = tmp / "delayed";
  const double delay_ms = 40.0;
  o.camera_delay_ms = {{"multisense_left", delay_ms}};
  simulateDataset(ref);
  simulateDataset(o);

  const Dataset ds(o.out_dir);
  CHECK(ds.truth.time_offset_ms.at("multisense_left") == delay_ms);
  CHECK(ds.truth.time_offset_ms.at("xtion_rgb") == 0.0);
  // Stamps and joints are those of the undelayed run; only the delayed camera's pixels differ.
  CHECK(readFile(ref.out_dir + "/joints.csv") == readFile(o.out_dir + "/joints.csv"));
  for (const char* cam : {"multisense_left", "xtion_rgb"}) {
    const auto a = imagesOf(fs::path(ref.out_dir) / cam), b = imagesOf(fs::path(o.out_dir) / cam);
    REQUIRE(a.size() == b.size());
    int same = 0;
    for (std::size_t k = 0; k < a.size(); ++k) {
      CHECK(a[k].filename() == b[k].filename());
      same += readFile(a[k].string()) == readFile(b[k].string()) ? 1 : 0;
    }
    if (std::string(cam) == "xtion_rgb") CHECK(same == static_cast<int>(a.size()));
    else CHECK(same < static_cast<int>(a.size()) / 2);
  }

  // PnP on the delayed camera's images against forward kinematics at the stamp + delay, and at the stamp.
  const auto seen = seenBoards(fs::path(o.out_dir) / "multisense_left", cameraOf(ds.camera("multisense_left")),
                               targetOf(ds.rig.target));
  REQUIRE(seen.size() >= 10);
  const VecX none = VecX::Zero(ds.chain.numJoints());
  std::vector<double> at_delay, at_stamp;
  for (const SeenBoard& s : seen) {
    const int64_t delay_ns = std::llround(delay_ms * 1e6);
    at_delay.push_back(translationGap(s.T_cam_marker, ds.boardInCamera("multisense_left", s.stamp_ns + delay_ns, none)));
    at_stamp.push_back(translationGap(s.T_cam_marker, ds.boardInCamera("multisense_left", s.stamp_ns, none)));
  }
  WARN("PnP vs forward kinematics: rms " << rms(at_delay) * 1e3 << " mm at stamp + " << delay_ms << " ms, "
                                         << rms(at_stamp) * 1e3 << " mm at the stamp");
  CHECK(*std::max_element(at_delay.begin(), at_delay.end()) < 0.004);
  CHECK(rms(at_stamp) > 4.0 * rms(at_delay));
}

TEST_CASE("simulator: joints.csv holds the true angle minus the joint offset", "[apps][simulator][truths]") {
  TempDir tmp;
  const SimulationOptions ref = exactOptions(tmp / "ref", 10);
  SimulationOptions o = ref;
  o.out_dir = tmp / "offsets";
  o.joint_offsets_rad = {{"lf_hfe_joint", 0.03}, {"lf_kfe_joint", -0.05}};
  simulateDataset(ref);
  simulateDataset(o);

  const Dataset ds(o.out_dir);
  // Every movable joint of the marker chain, 0 where none was asked for.
  CHECK(ds.truth.joint_offsets_rad ==
        std::map<std::string, double>{{"lf_haa_joint", 0.0}, {"lf_hfe_joint", 0.03}, {"lf_kfe_joint", -0.05}});
  // joints.csv: q_true - o in the offset columns, the other columns as without offsets.
  const JointLog base = loadJointsCsv(ref.out_dir + "/joints.csv");
  REQUIRE(base.names == ds.log.names);
  REQUIRE(base.stamps_ns == ds.log.stamps_ns);
  for (std::size_t j = 0; j < base.names.size(); ++j) {
    const auto it = o.joint_offsets_rad.find(base.names[j]);
    const double off = it == o.joint_offsets_rad.end() ? 0.0 : it->second;
    INFO(base.names[j]);
    CHECK((base.positions.col(j) - ds.log.positions.col(j) - VecX::Constant(base.positions.rows(), off))
              .cwiseAbs()
              .maxCoeff() < 1e-12);
  }
  // The images are rendered from the true angles: the same bytes as without offsets.
  for (const auto& e : fs::recursive_directory_iterator(ref.out_dir))
    if (e.path().extension() == ".png")
      CHECK(readFile(e.path().string()) == readFile(o.out_dir + "/" + fs::relative(e.path(), ref.out_dir).string()));

  // joints.csv + offset reproduces the pose PnP sees; joints.csv alone does not.
  VecX offsets = VecX::Zero(ds.chain.numJoints());
  for (const auto& [joint, rad] : ds.truth.joint_offsets_rad) offsets(ds.chain.indexOf(joint)) = rad;
  const auto seen = seenBoards(fs::path(o.out_dir) / "multisense_left", cameraOf(ds.camera("multisense_left")),
                               targetOf(ds.rig.target));
  REQUIRE(seen.size() >= 6);
  std::vector<double> with, without;
  const VecX none = VecX::Zero(offsets.size());
  for (const SeenBoard& s : seen) {
    with.push_back(translationGap(s.T_cam_marker, ds.boardInCamera("multisense_left", s.stamp_ns, offsets)));
    without.push_back(translationGap(s.T_cam_marker, ds.boardInCamera("multisense_left", s.stamp_ns, none)));
  }
  WARN("PnP vs forward kinematics: rms " << rms(with) * 1e3 << " mm with the offsets, " << rms(without) * 1e3
                                         << " mm without");
  CHECK(*std::max_element(with.begin(), with.end()) < 0.004);
  CHECK(rms(without) > 0.01);
  CHECK(rms(without) > 5.0 * rms(with));
}

TEST_CASE("simulator: rig.yaml's intrinsics are off by exactly the requested error, the images use the truth",
          "[apps][simulator][truths]") {
  TempDir tmp;
  const SimulationOptions ref = exactOptions(tmp / "ref", 6);
  SimulationOptions o = ref;
  o.out_dir = tmp / "wrong";
  o.intrinsics_error_pct = 1.0;
  o.intrinsics_error_px = 3.0;
  simulateDataset(ref);
  simulateDataset(o);

  const Dataset ds(o.out_dir);
  const RigConfig rig_ref = loadRigConfig(ref.out_dir + "/rig.yaml");
  REQUIRE(ds.rig.cameras.size() == 2);
  std::set<double> signs;
  for (std::size_t c = 0; c < ds.rig.cameras.size(); ++c) {
    const CameraConfig& cc = ds.rig.cameras[c];
    INFO(cc.name);
    const std::vector<double>& k = ds.truth.intrinsics.at(cc.name);
    // The truth is what the simulator renders with (rig.yaml without the error).
    CHECK(k == std::vector<double>(rig_ref.cameras[c].intrinsics.begin(), rig_ref.cameras[c].intrinsics.end()));
    CHECK(ds.truth.distortion_coeffs.at(cc.name) == rig_ref.cameras[c].distortion_coeffs);
    CHECK(cc.distortion_coeffs == rig_ref.cameras[c].distortion_coeffs);
    for (int i = 0; i < 2; ++i) {
      CHECK(std::abs(cc.intrinsics[i] / k[i] - 1.0) == Approx(0.01).epsilon(1e-9));
      CHECK(std::abs(cc.intrinsics[2 + i] - k[2 + i]) == Approx(3.0).epsilon(1e-9));
      signs.insert(std::copysign(1.0, cc.intrinsics[i] - k[i]));
      signs.insert(std::copysign(1.0, cc.intrinsics[2 + i] - k[2 + i]));
    }
  }
  CHECK(signs.size() == 2);  // the signs come from the seed, not all alike
  for (const auto& e : fs::recursive_directory_iterator(ref.out_dir))
    if (e.path().extension() == ".png")
      CHECK(readFile(e.path().string()) == readFile(o.out_dir + "/" + fs::relative(e.path(), ref.out_dir).string()));

  // The detected corners sit where the true intrinsics project them, not rig.yaml's.
  for (const CameraConfig& cc : ds.rig.cameras) {
    const std::vector<double>& k = ds.truth.intrinsics.at(cc.name);
    const auto true_cam = vision::CameraModel::fromKalibr("pinhole", cc.distortion_model, k,
                                                          ds.truth.distortion_coeffs.at(cc.name),
                                                          {cc.resolution[0], cc.resolution[1]});
    const auto rig_cam = cameraOf(cc);
    std::vector<double> err_true, err_rig;
    for (const SeenBoard& s : seenBoards(fs::path(o.out_dir) / cc.name, true_cam, targetOf(ds.rig.target))) {
      const SE3 T = ds.boardInCamera(cc.name, s.stamp_ns, VecX::Zero(ds.chain.numJoints()));
      for (std::size_t i = 0; i < s.detection.ids.size(); ++i) {
        const Vec3 p = T * s.detection.object_points[i];
        err_true.push_back((s.detection.corners[i] - *true_cam.project(p)).norm());
        err_rig.push_back((s.detection.corners[i] - *rig_cam.project(p)).norm());
      }
    }
    INFO(cc.name << ": corner rms " << rms(err_true) << " px with the truth, " << rms(err_rig) << " px with rig.yaml");
    REQUIRE(err_true.size() > 50);
    CHECK(rms(err_true) < 0.15);
    CHECK(rms(err_rig) > 2.0);
  }
}

TEST_CASE("simulator: ground_truth.yaml always holds time offsets, intrinsics and the chain's joint offsets",
          "[apps][simulator][truths]") {
  TempDir tmp;
  SimulationOptions o;
  o.out_dir = tmp / "plain";
  o.frames = 3;
  o.cameras = 3;
  o.distortion = "equidistant";
  o.render_images = false;
  simulateDataset(o);
  const RigConfig rig = loadRigConfig(o.out_dir + "/rig.yaml");
  const GroundTruth gt = loadGroundTruth(o.out_dir + "/ground_truth.yaml");
  REQUIRE(gt.time_offset_ms.size() == 3);
  for (const CameraConfig& cc : rig.cameras) {
    CHECK(gt.time_offset_ms.at(cc.name) == 0.0);
    CHECK(gt.intrinsics.at(cc.name) == std::vector<double>(cc.intrinsics.begin(), cc.intrinsics.end()));
    CHECK(gt.distortion_coeffs.at(cc.name) == cc.distortion_coeffs);
    CHECK(cc.distortion_coeffs.size() == 4);
  }
  CHECK(gt.joint_offsets_rad ==
        std::map<std::string, double>{{"lf_haa_joint", 0.0}, {"lf_hfe_joint", 0.0}, {"lf_kfe_joint", 0.0}});
}

TEST_CASE("simulator: a wide equidistant (fisheye) camera", "[apps][simulator][truths]") {
  TempDir tmp;
  SimulationOptions o = exactOptions(tmp / "fisheye", 24);
  o.distortion = "equidistant";
  o.fov_deg = 140.0;
  simulateDataset(o);
  const Dataset ds(o.out_dir);
  for (const CameraConfig& cc : ds.rig.cameras) {
    const vision::CameraModel cam = cameraOf(cc);
    // A ray at half the field of view meets the side of the image.
    const double half = 70.0 * M_PI / 180.0;
    CHECK(cam.project(Vec3(std::sin(half), 0.0, std::cos(half)))->x() - cam.cx() ==
          Approx(0.5 * cc.resolution[0]).epsilon(1e-9));
    const auto seen = seenBoards(fs::path(o.out_dir) / cc.name, cam, targetOf(ds.rig.target));
    const int images = static_cast<int>(imagesOf(fs::path(o.out_dir) / cc.name).size());
    // How far from a pinhole the detected corners are: the lens's own mark on them.
    double max_err = 0.0, max_angle = 0.0, max_departure = 0.0;
    for (const SeenBoard& s : seen) {
      const SE3 T = ds.boardInCamera(cc.name, s.stamp_ns, VecX::Zero(ds.chain.numJoints()));
      max_err = std::max(max_err, translationGap(s.T_cam_marker, T));
      for (const Vec3& X : s.detection.object_points) {
        const Vec3 p = T * X;
        max_angle = std::max(max_angle, std::atan2(p.head<2>().norm(), p.z()));
        const vision::Vec2 pinhole(cam.fx() * p.x() / p.z() + cam.cx(), cam.fy() * p.y() / p.z() + cam.cy());
        max_departure = std::max(max_departure, (*cam.project(p) - pinhole).norm());
      }
    }
    WARN(cc.name << " at 140 deg: board detected in " << seen.size() << "/" << images << " images, max PnP error "
                 << max_err * 1e3 << " mm, corners up to " << max_angle * 180 / M_PI
                 << " deg off the axis, up to " << max_departure << " px from a pinhole projection");
    CHECK(static_cast<int>(seen.size()) > images / 2);
    CHECK(max_err < 0.005);
    CHECK(max_departure > 20.0);
  }
}

TEST_CASE("simulator: bad values of the truth options name the option, nothing is written",
          "[apps][simulator][truths]") {
  TempDir tmp;
  SimulationOptions o;
  o.out_dir = tmp / "x";
  o.frames = 2;
  requireInputError(changed(o, [](auto& c) { c.camera_delay_ms = {{"cam0", 5.0}}; }), "--camera-delay-ms",
                    "expected one of multisense_left, xtion_rgb");
  requireInputError(changed(o, [](auto& c) { c.camera_delay_ms = {{"head_wide", 5.0}}; }), "--camera-delay-ms",
                    "--camera-count 2");
  requireInputError(changed(o, [](auto& c) { c.camera_delay_ms = {{"xtion_rgb", 150.0}}; }), "--camera-delay-ms",
                    "outside joints.csv");
  requireInputError(changed(o, [](auto& c) { c.camera_delay_ms = {{"multisense_left", -100.5}}; }), "--camera-delay-ms",
                    "[-100, ");
  requireInputError(changed(o, [](auto& c) { c.camera_delay_ms = {{"xtion_rgb", NAN}}; }), "--camera-delay-ms");
  requireInputError(changed(o, [](auto& c) { c.joint_offsets_rad = {{"knee", 0.01}}; }), "--joint-offsets",
                    "lf_haa_joint, lf_hfe_joint, lf_kfe_joint");
  requireInputError(changed(o, [](auto& c) { c.joint_offsets_rad = {{"rf_kfe_joint", 0.01}}; }), "--joint-offsets",
                    "no movable joint 'rf_kfe_joint' on the chain");
  requireInputError(changed(o, [](auto& c) { c.joint_offsets_rad = {{"lf_kfe_joint", 0.6}}; }), "--joint-offsets");
  requireInputError(changed(o, [](auto& c) { c.joint_offsets_rad = {{"lf_kfe_joint", INFINITY}}; }), "--joint-offsets");
  requireInputError(changed(o, [](auto& c) { c.intrinsics_error_pct = -1.0; }), "--intrinsics-error", "PCT");
  requireInputError(changed(o, [](auto& c) { c.intrinsics_error_pct = 60.0; }), "--intrinsics-error", "PCT");
  requireInputError(changed(o, [](auto& c) { c.intrinsics_error_px = NAN; }), "--intrinsics-error", "PX");
  requireInputError(changed(o, [](auto& c) { c.fov_deg = 10.0; }), "--fov-deg", "[30, 120]");
  requireInputError(changed(o, [](auto& c) { c.fov_deg = 130.0; }), "--fov-deg", "--distortion equidistant");
  requireInputError(changed(o, [](auto& c) {
                      c.distortion = "equidistant";
                      c.fov_deg = 150.0;  // the 4:3 camera's image corners would be behind it
                    }),
                    "--fov-deg", "camera xtion_rgb with 150 deg");
  CHECK_FALSE(fs::exists(o.out_dir));

  // The command line's texts.
  CHECK(parseNamedValues({"a=1,b=-2.5", "c=1e-3"}, "--x") ==
        std::map<std::string, double>{{"a", 1.0}, {"b", -2.5}, {"c", 1e-3}});
  CHECK(parseNamedValues({}, "--x").empty());
  for (const std::string bad : {"a", "=1", "a=", "a=x", "a=1x", "a= 1", "a=nan", "a=inf", "a=1e999", "a=1,a=2",
                                "a=1,", ",a=1"})
    CHECK_INPUT_ERROR(parseNamedValues({bad}, "--camera-delay-ms"), "", "--camera-delay-ms", "");
  CHECK(parseNumberList("1,3.5", "--intrinsics-error", 2, "PCT,PX") == std::vector<double>{1.0, 3.5});
  for (const std::string bad : {"", "1", "1,2,3", "a,b", "1,", "1,nan"})
    CHECK_INPUT_ERROR(parseNumberList(bad, "--intrinsics-error", 2, "PCT,PX"), "", "--intrinsics-error",
                      "PCT,PX");
}
