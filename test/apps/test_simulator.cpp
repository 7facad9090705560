// The dataset simulator (fgcal simulate): the files it writes load with the
// pipeline's own readers, the board it renders is detected where the truth
// says, the corner noise is what was asked for, the same seed gives the same
// bytes, other robots' URDFs work, and bad options are named.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <iostream>
#include <numeric>

#include <opencv2/imgcodecs.hpp>

#include "apps_test_util.hpp"
#include "sim_test_util.hpp"
#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/simulator.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal/vision/board_renderer.hpp"
#include "fgcal/vision/charuco_detector.hpp"
#include "fgcal/vision/pnp.hpp"
#include "fgcal/vision/vision_error.hpp"
#include "fgcal_test/shared_data.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {

// Per camera: detections, pose errors against the truth (from a noise-free
// joints.csv) and corner errors against the projected true corners.
struct CameraCheck {
  int images = 0, detected = 0;
  double max_pos_err_m = 0.0, max_rot_err_rad = 0.0;
  std::vector<double> corner_err_px;  // u and v errors, all corners
};

std::vector<CameraCheck> checkDataset(const std::string& dir) {
  const RigConfig rig = loadRigConfig(dir + "/rig.yaml");
  const GroundTruth truth = loadGroundTruth(dir + "/ground_truth.yaml");
  REQUIRE(truth.T_link_marker.has_value());
  const auto model = kinematics::RobotModel::fromFile(rig.robot.urdf);
  const auto chain = model.chain(rig.robot.base_link, rig.robot.marker_link);
  const JointLog log = loadJointsCsv(dir + "/joints.csv");
  const std::vector<int> cols = columnIndices(log, chain.jointNames(), "joints.csv");
  const vision::CharucoTarget target = targetOf(rig.target);
  const vision::CharucoDetector detector(target);

  std::vector<CameraCheck> out;
  for (const CameraConfig& cc : rig.cameras) {
    const vision::CameraModel cam = cameraOf(cc);
    REQUIRE(truth.T_base_cam.count(cc.name) == 1);
    const SE3 T_cam_base = truth.T_base_cam.at(cc.name).inverse();
    CameraCheck check;
    for (const fs::path& file : imagesOf(fs::path(dir) / cc.name)) {
      ++check.images;
      const cv::Mat img = cv::imread(file.string(), cv::IMREAD_UNCHANGED);
      REQUIRE(img.type() == CV_8UC1);
      REQUIRE(img.cols == cc.resolution[0]);
      REQUIRE(img.rows == cc.resolution[1]);
      const auto det = detector.detect(img);
      if (!det.ok()) continue;
      ++check.detected;
      const auto q = interpolate(log, stampOf(file), cols);
      REQUIRE(q.has_value());
      const SE3 T_true = T_cam_base * chain.forward(*q) * *truth.T_link_marker;
      const auto est = vision::estimatePose(cam, det);
      const Vec6 err = T_true.minus(est.T_cam_marker);
      check.max_rot_err_rad = std::max(check.max_rot_err_rad, err.head<3>().norm());
      check.max_pos_err_m =
          std::max(check.max_pos_err_m, (T_true.translation() - est.T_cam_marker.translation()).norm());
      for (size_t i = 0; i < det.ids.size(); ++i) {
        const auto uv = cam.project(T_true * det.object_points[i]);
        REQUIRE(uv.has_value());
        check.corner_err_px.push_back(det.corners[i].x() - uv->x());
        check.corner_err_px.push_back(det.corners[i].y() - uv->y());
      }
    }
    out.push_back(check);
  }
  return out;
}

}  // namespace

TEST_CASE("simulator: default robot: files load and the board is where the truth says", "[apps][simulator]") {
  TempDir tmp;
  SimulationOptions o;
  o.out_dir = tmp / "ds";
  o.frames = 20;
  o.pixel_noise = 0.0;
  o.encoder_noise = 0.0;  // joints.csv is the truth: T_cam_marker can be checked exactly
  o.mount_error_m = 0.01;
  o.mount_error_rad = 0.02;
  const SimulationSummary s = simulateDataset(o);

  CHECK(s.instants == 20);
  REQUIRE(s.cameras == std::vector<std::string>{"multisense_left", "xtion_rgb"});
  CHECK(s.per_camera[0].images == 20);
  CHECK(s.per_camera[1].images == 10);
  CHECK(s.images_written == 30);
  for (const char* f : {"rig.yaml", "joints.csv", "robot.urdf", "ground_truth.yaml"})
    CHECK(fs::is_regular_file(fs::path(o.out_dir) / f));

  // rig.yaml: what the pipeline reads.
  const RigConfig rig = loadRigConfig(o.out_dir + "/rig.yaml");
  CHECK(rig.warnings.empty());
  CHECK(rig.robot.base_link == "base_link");
  CHECK(rig.robot.marker_link == "lf_foot");
  CHECK(fs::path(rig.robot.urdf).filename() == "robot.urdf");
  CHECK(rig.target.squares_x == 5);
  CHECK(rig.target.squares_y == 7);
  CHECK(rig.target.dictionary == "DICT_4X4_50");
  CHECK(rig.sync_tolerance_ms == 1.0);
  REQUIRE(rig.cameras.size() == 2);
  CHECK(rig.cameras[0].resolution == std::array<int, 2>{1024, 544});
  CHECK(rig.cameras[1].resolution == std::array<int, 2>{640, 480});
  CHECK(rig.cameras[0].distortion_model == "radtan");
  CHECK_FALSE(rig.cameras[0].T_base_cam_guess.has_value());
  CHECK(rig.robot.mount_sigma_m == Approx(0.015));
  CHECK(rig.robot.mount_sigma_rad == Approx(0.03));

  // The prior is the truth moved by exactly the requested error.
  const GroundTruth truth = loadGroundTruth(o.out_dir + "/ground_truth.yaml");
  REQUIRE(truth.T_link_marker.has_value());
  const SE3 D = truth.T_link_marker->between(rig.robot.T_link_marker);
  CHECK(D.translation().norm() == Approx(0.01).epsilon(1e-9));
  CHECK(D.so3().log().norm() == Approx(0.02).epsilon(1e-9));
  CHECK(truth.T_base_cam.size() == 2);

  // joints.csv: every movable joint of the robot at 500 Hz, covering the images.
  const JointLog log = loadJointsCsv(o.out_dir + "/joints.csv");
  CHECK(log.names.size() == 12);
  CHECK(static_cast<int>(log.stamps_ns.size()) == s.joint_samples);
  for (size_t i = 1; i < log.stamps_ns.size(); ++i) REQUIRE(log.stamps_ns[i] - log.stamps_ns[i - 1] == 2'000'000);
  CHECK(log.stamps_ns.front() > 1'600'000'000'000'000'000LL);

  // Image stamps: cam0 on the joint grid at 30 Hz, cam1 synced to every other cam0 frame + 200 us.
  const auto cam0 = imagesOf(fs::path(o.out_dir) / "multisense_left");
  const auto cam1 = imagesOf(fs::path(o.out_dir) / "xtion_rgb");
  REQUIRE(cam0.size() == 20);
  REQUIRE(cam1.size() == 10);
  for (size_t k = 0; k < cam0.size(); ++k) {
    CHECK((stampOf(cam0[k]) - log.stamps_ns.front()) % 2'000'000 == 0);
    if (k > 0) {
      const int64_t dt = stampOf(cam0[k]) - stampOf(cam0[k - 1]);
      CHECK((dt == 32'000'000 || dt == 34'000'000));
    }
    if (k % 2 == 0) CHECK(stampOf(cam1[k / 2]) - stampOf(cam0[k]) == 200'000);
  }
  for (size_t k = 0; k < cam0.size(); k += 3)  // exactly 30 Hz: 3 frames every 100 ms
    CHECK(stampOf(cam0[k]) - stampOf(cam0[0]) == static_cast<int64_t>(k / 3) * 100'000'000);

  // Detection and PnP against the truth.
  const auto checks = checkDataset(o.out_dir);
  REQUIRE(checks.size() == 2);  // one per camera: a loop over nothing would pass
  for (size_t c = 0; c < checks.size(); ++c) {
    INFO("camera " << rig.cameras[c].name << ": " << checks[c].detected << " / " << checks[c].images
                   << " detected, max pos err " << checks[c].max_pos_err_m << " m, max rot err "
                   << checks[c].max_rot_err_rad * 180 / M_PI << " deg, corner rms " << rms(checks[c].corner_err_px));
    CHECK(checks[c].detected > checks[c].images / 2);
    CHECK(checks[c].max_pos_err_m < 0.004);
    CHECK(checks[c].max_rot_err_rad < 0.4 * M_PI / 180.0);
    CHECK(rms(checks[c].corner_err_px) < 0.1);
    WARN("cam " << rig.cameras[c].name << ": detected " << checks[c].detected << "/" << checks[c].images
                << ", max pos err " << checks[c].max_pos_err_m * 1000 << " mm, max rot err "
                << checks[c].max_rot_err_rad * 180 / M_PI << " deg, corner rms "
                << rms(checks[c].corner_err_px) << " px");
  }
}

TEST_CASE("simulator: the motion keeps the board in view of both cameras and varies its orientation",
          "[apps][simulator]") {
  TempDir tmp;
  SimulationOptions o;
  o.out_dir = tmp / "ds";
  o.frames = 150;  // 5 s of motion
  o.supersampling = 1;
  int calls = 0;
  o.progress = [&](const std::string&, int done, int total) {
    ++calls;
    CHECK(done <= total);
  };
  const auto s = simulateDataset(o);
  CHECK(calls == 150 + 75);
  WARN("all cameras see the board at " << s.fraction_all_in_view * 100 << " % of the instants; board rotation range "
                                       << s.board_rotation_range_deg << " deg, std about base x y z "
                                       << s.board_rotation_std_deg.transpose() << " deg");
  CHECK(s.fraction_all_in_view >= 0.6);
  for (const auto& c : s.per_camera) CHECK(c.board_in_view >= 0.6 * c.images);
  CHECK(s.board_rotation_range_deg > 50.0);
  // Orientation diversity about at least two axes (a 3-joint leg cannot give three).
  std::array<double, 3> sd{s.board_rotation_std_deg.x(), s.board_rotation_std_deg.y(), s.board_rotation_std_deg.z()};
  std::sort(sd.begin(), sd.end());
  CHECK(sd[1] > 8.0);
}

TEST_CASE("simulator: corner noise of the dataset equals pixel_noise", "[apps][simulator]") {
  TempDir tmp;
  SimulationOptions o;
  o.out_dir = tmp / "ds";
  o.frames = 16;
  o.pixel_noise = 0.5;
  o.encoder_noise = 0.0;
  o.seed = 7;
  simulateDataset(o);
  const auto checks = checkDataset(o.out_dir);
  REQUIRE(checks.size() == 2);
  for (const auto& c : checks) {
    REQUIRE(c.corner_err_px.size() > 200);
    const double r = rms(c.corner_err_px);
    INFO("corner error rms " << r << " px over " << c.corner_err_px.size() / 2 << " corners");
    WARN("dataset corner error rms " << r << " px (requested 0.5) over " << c.corner_err_px.size() / 2
                                      << " corners");
    CHECK(r == Approx(0.5).epsilon(0.12));
  }
}

TEST_CASE("board renderer: corner jitter gives the requested pixel noise", "[apps][simulator][jitter]") {
  const auto cam = vision::CameraModel::fromKalibr("pinhole", "none", {590, 590, 511.5, 271.5}, {}, {1024, 544});
  vision::CharucoTarget target;
  const vision::BoardRenderer renderer(cam, target, 3);
  const vision::CharucoDetector detector(target);
  const double z = 0.55, sigma_px = 0.5;
  // Board centred in front of the camera, slightly rotated in plane.
  const SE3 T_cam_marker(SO3::fromRpy(0.0, 0.0, 0.1), Vec3(-0.1, -0.14, z));

  for (const double requested : {sigma_px, 0.0}) {
    std::vector<double> err;
    for (int n = 0; n < 14; ++n) {
      vision::RenderOptions ro;
      ro.blur_sigma = 0.6;
      ro.noise_sigma = 2.0;
      ro.seed = 1000 + n;
      ro.jitter_seed = 77 + n;
      ro.corner_jitter_m = requested * z / cam.fx();
      const auto det = detector.detect(renderer.render(T_cam_marker, ro));
      REQUIRE(det.ok());
      REQUIRE(det.ids.size() == 24);
      // The offsets are known: detected corners sit at the jittered nodes.
      const auto offsets = vision::cornerJitterOffsets(target, ro);
      for (size_t i = 0; i < det.ids.size(); ++i) {
        const auto uv = cam.project(T_cam_marker * det.object_points[i]);
        err.push_back(det.corners[i].x() - uv->x());
        err.push_back(det.corners[i].y() - uv->y());
        const int id = det.ids[i];
        const auto& d = offsets[(id / (target.squares_x - 1) + 1) * (target.squares_x + 1) +
                                id % (target.squares_x - 1) + 1];
        const auto uv_j = cam.project(T_cam_marker * (det.object_points[i] + Vec3(d.x(), d.y(), 0.0)));
        CHECK((det.corners[i] - *uv_j).norm() < 0.2);
      }
    }
    const double r = rms(err);
    WARN("renderer jitter: requested " << requested << " px, measured rms " << r << " px");
    INFO("requested " << requested << " px, measured rms " << r << " px over " << err.size() / 2 << " corners");
    if (requested > 0)
      CHECK(r == Approx(requested).epsilon(0.10));
    else
      CHECK(r < 0.06);
  }
}

TEST_CASE("board renderer: zero jitter leaves the image unchanged", "[apps][simulator][jitter]") {
  const auto cam = vision::CameraModel::fromKalibr("pinhole", "radtan", {500, 500, 320, 240},
                                                   {-0.05, 0.01, 0, 0}, {640, 480});
  vision::CharucoTarget target;
  const vision::BoardRenderer renderer(cam, target, 2);
  const SE3 T(SO3::fromRpy(0.2, -0.1, 0.05), Vec3(-0.1, -0.14, 0.6));
  vision::RenderOptions a, b;
  b.jitter_seed = 12345;  // no effect while corner_jitter_m is 0
  CHECK(cv::norm(renderer.render(T, a), renderer.render(T, b), cv::NORM_INF) == 0.0);
  b.corner_jitter_m = 0.001;
  CHECK(cv::norm(renderer.render(T, a), renderer.render(T, b), cv::NORM_INF) > 0.0);
  // A negative or NaN jitter is an error, not jitter silently off.
  for (const double bad : {-0.001, std::nan(""), -std::numeric_limits<double>::infinity()}) {
    b.corner_jitter_m = bad;
    CHECK_THROWS_AS(renderer.render(T, b), vision::VisionError);
  }
}

TEST_CASE("simulator: same seed gives the same bytes", "[apps][simulator]") {
  TempDir tmp;
  SimulationOptions o;
  o.frames = 10;
  o.supersampling = 1;
  o.mount_error_m = 0.005;
  o.mount_error_rad = 0.01;
  o.out_dir = tmp / "a";
  simulateDataset(o);
  o.out_dir = tmp / "b";
  simulateDataset(o);
  o.out_dir = tmp / "c";
  o.seed = 2;
  simulateDataset(o);

  std::vector<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(tmp / "a"))
    if (e.is_regular_file()) files.push_back(fs::relative(e.path(), tmp / "a").string());
  CHECK(files.size() == 4 + 10 + 5);
  for (const auto& f : files) {
    INFO(f);
    CHECK(readFile(tmp / ("a/" + f)) == readFile(tmp / ("b/" + f)));
  }
  CHECK(readFile(tmp / "a/joints.csv") != readFile(tmp / "c/joints.csv"));
  CHECK(readFile(tmp / "a/rig.yaml") != readFile(tmp / "c/rig.yaml"));
}

TEST_CASE("simulator: options and distortion models and camera count", "[apps][simulator]") {
  TempDir tmp;
  SimulationOptions o;
  o.frames = 4;
  o.supersampling = 1;
  o.cameras = 4;
  o.distortion = "equidistant";
  o.out_dir = tmp / "four";
  const auto s = simulateDataset(o);
  CHECK(s.cameras.size() == 4);
  CHECK(s.images_written == 4 + 2 + 4 + 4);
  const RigConfig rig = loadRigConfig(o.out_dir + "/rig.yaml");
  REQUIRE(rig.cameras.size() == 4);
  for (const auto& c : rig.cameras) CHECK(c.distortion_model == "equidistant");

  o.cameras = 1;
  o.distortion = "none";
  o.out_dir = tmp / "one";
  const auto s1 = simulateDataset(o);
  CHECK(s1.images_written == 4);
  CHECK(loadRigConfig(o.out_dir + "/rig.yaml").cameras.at(0).distortion_coeffs.empty());

  // A non-empty folder is refused unless overwriting is allowed.
  requireInputError(o, "--out");
  o.overwrite = true;
  CHECK(simulateDataset(o).images_written == 4);
}

TEST_CASE("simulator: render_images=false and the image size option", "[apps][simulator]") {
  TempDir tmp;
  SimulationOptions o;
  o.frames = 6;
  o.supersampling = 1;
  o.out_dir = tmp / "full";
  simulateDataset(o);
  // Without images: the same joints, truth and rig, and no image; other
  // encoder noise and mount error change the text files only (the benchmarks
  // pair such variants with the full simulation's images).
  SimulationOptions v = o;
  v.out_dir = tmp / "text";
  v.render_images = false;
  const auto sv = simulateDataset(v);
  CHECK(sv.images_written == 0);
  CHECK(readFile(tmp / "full/joints.csv") == readFile(tmp / "text/joints.csv"));
  CHECK(readFile(tmp / "full/ground_truth.yaml") == readFile(tmp / "text/ground_truth.yaml"));
  for (const auto& e : fs::recursive_directory_iterator(tmp / "text")) CHECK(e.path().extension() != ".png");
  SimulationOptions w = o;
  w.out_dir = tmp / "noisier";
  w.encoder_noise = 0.01;
  w.mount_error_m = 0.003;
  w.mount_error_rad = 0.0175;
  simulateDataset(w);
  for (const auto& e : fs::recursive_directory_iterator(tmp / "full"))
    if (e.path().extension() == ".png") {
      const std::string rel = fs::relative(e.path(), tmp / "full").string();
      INFO(rel);
      CHECK(readFile(e.path().string()) == readFile(tmp / ("noisier/" + rel)));
    }
  CHECK(readFile(tmp / "full/joints.csv") != readFile(tmp / "noisier/joints.csv"));

  // Every camera at 1280x720: the field of view is at least each camera's own.
  SimulationOptions r = o;
  r.out_dir = tmp / "hd";
  r.image_width = 1280;
  r.image_height = 720;
  simulateDataset(r);
  const RigConfig rig0 = loadRigConfig(o.out_dir + "/rig.yaml"), rig = loadRigConfig(r.out_dir + "/rig.yaml");
  REQUIRE(rig.cameras.size() == rig0.cameras.size());
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    const auto& a = rig0.cameras[c];
    const auto& b = rig.cameras[c];
    CHECK(b.resolution[0] == 1280);
    CHECK(b.resolution[1] == 720);
    CHECK(0.5 * b.resolution[0] / b.intrinsics[0] >= 0.5 * a.resolution[0] / a.intrinsics[0] - 1e-9);
    CHECK(0.5 * b.resolution[1] / b.intrinsics[1] >= 0.5 * a.resolution[1] / a.intrinsics[1] - 1e-9);
    for (const auto& e : fs::directory_iterator(fs::path(r.out_dir) / b.name)) {
      const cv::Mat img = cv::imread(e.path().string(), cv::IMREAD_GRAYSCALE);
      CHECK(img.cols == 1280);
      CHECK(img.rows == 720);
    }
  }
  SimulationOptions bad = o;
  bad.out_dir = tmp / "bad";
  bad.image_width = 640;
  requireInputError(bad, "image_width, image_height");
}

TEST_CASE("simulator: bad options name the option", "[apps][simulator]") {
  TempDir tmp;
  SimulationOptions o;
  o.out_dir = tmp / "x";
  o.frames = 2;
  requireInputError(changed(o, [](auto& c) { c.cameras = 0; }), "--camera-count");
  requireInputError(changed(o, [](auto& c) { c.cameras = 5; }), "--camera-count");
  requireInputError(changed(o, [](auto& c) { c.frames = 0; }), "--frames");
  requireInputError(changed(o, [](auto& c) { c.distortion = "fisheye"; }), "--distortion");
  requireInputError(changed(o, [](auto& c) { c.pixel_noise = -1; }), "--pixel-noise");
  requireInputError(changed(o, [](auto& c) { c.encoder_noise = NAN; }), "--encoder-noise");
  requireInputError(changed(o, [](auto& c) { c.supersampling = 0; }), "supersampling");
  requireInputError(changed(o, [](auto& c) { c.out_dir = ""; }), "--out");
  requireInputError(changed(o, [&](auto& c) { c.urdf_path = tmp / "missing.urdf"; }), "--urdf");
  writeFile(tmp / "broken.urdf", "<robot name='x'><link name='a'/>");
  requireInputError(changed(o, [&](auto& c) { c.urdf_path = tmp / "broken.urdf"; }), "--urdf");
  requireInputError(changed(o, [](auto& c) { c.marker_link = "no_such_foot"; }), "--marker-link");
  requireInputError(changed(o, [](auto& c) { c.base_link = "trunk"; }), "--base-link");
  requireInputError(changed(o, [](auto& c) { c.marker_link = "base_link"; }), "--marker-link");
  CHECK_FALSE(fs::exists(o.out_dir));  // nothing written on a bad option
}

TEST_CASE("simulator: other robots ANYmal C and Unitree A1", "[apps][simulator][shared_data]") {
  FGCAL_REQUIRE_SHARED_DATA(urdf_dir, "urdf");
  struct Robot {
    const char* file;
    const char* base;
    const char* foot;
  };
  for (const Robot& r : {Robot{"anymal_c.urdf", "base", "LF_FOOT"}, Robot{"a1.urdf", "trunk", "FL_foot"},
                         Robot{"a1.urdf", "base", "FL_foot"}}) {
    INFO(r.file << " " << r.base << " -> " << r.foot);
    TempDir tmp;
    SimulationOptions o;
    o.urdf_path = urdf_dir + "/" + r.file;
    o.base_link = r.base;
    o.marker_link = r.foot;
    o.frames = 8;
    o.supersampling = 2;
    o.pixel_noise = 0.0;
    o.encoder_noise = 0.0;
    o.out_dir = tmp / "ds";
    const auto s = simulateDataset(o);
    WARN(r.file << ": board in view " << s.per_camera[0].board_in_view << "/" << s.per_camera[0].images << ", "
                << s.per_camera[1].board_in_view << "/" << s.per_camera[1].images << ", all cameras "
                << s.fraction_all_in_view);
    // The dataset is self-contained: the URDF was copied in.
    CHECK(readFile(o.out_dir + "/robot.urdf") == readFile(o.urdf_path));
    const auto checks = checkDataset(o.out_dir);
    REQUIRE(checks.size() == 2);
    for (const auto& c : checks) {
      CHECK(c.detected > c.images / 2);
      CHECK(c.max_pos_err_m < 0.005);
    }
  }
}

// Not run by default: the full default dataset, for timings and statistics.
TEST_CASE("simulator: default 300 frames for timing", "[.][simulator_timing]") {
  TempDir tmp;
  SimulationOptions o;
  o.out_dir = tmp / "ds";
  const auto s = simulateDataset(o);
  std::cout << "simulated " << s.images_written << " images in " << s.seconds << " s; all cameras in view "
            << s.fraction_all_in_view << "; rotation range " << s.board_rotation_range_deg << " deg, std "
            << s.board_rotation_std_deg.transpose() << " deg\n";
  for (const auto& c : s.per_camera) std::cout << c.name << ": in view " << c.board_in_view << "/" << c.images << "\n";
  const auto checks = checkDataset(o.out_dir);
  for (size_t c = 0; c < checks.size(); ++c)
    std::cout << s.cameras[c] << ": detected " << checks[c].detected << "/" << checks[c].images << ", corner rms "
              << rms(checks[c].corner_err_px) << " px\n";
}
