// fgcal evaluate: known perturbations give known errors; NEES of samples drawn
// from the covariance averages 6.
#include <cmath>
#include <limits>
#include <random>

#include <catch2/catch.hpp>

#include "apps_test_util.hpp"
#include "fgcal/apps/evaluate.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {
CameraResult camera(const std::string& name, const SE3& T, const Mat6& cov) {
  CameraResult c;
  c.name = name;
  c.T_base_cam = T;
  c.covariance = cov;
  return c;
}
constexpr double kDeg = M_PI / 180.0;
}  // namespace

TEST_CASE("evaluate: a known perturbation gives known errors", "[apps][evaluate]") {
  const SE3 truth = SE3::fromXyzRpy(Vec3(0.3, -0.1, 0.2), Vec3(0.1, -0.2, 0.7));
  // 1 mm in x, -2 mm in z (base frame), 0.5 deg more yaw: R_est = Rz(0.5 deg) R_true.
  const SE3 est(SO3::fromRpy(0, 0, 0.5 * kDeg) * truth.so3(), truth.translation() + Vec3(0.001, 0, -0.002));
  const PoseError e = poseError(est, Mat6::Identity() * 1e-6, truth);
  CHECK(e.x_mm == Approx(1.0));
  CHECK(e.y_mm == Approx(0.0).margin(1e-9));
  CHECK(e.z_mm == Approx(2.0));
  CHECK(e.translation_mm == Approx(std::sqrt(5.0)));
  CHECK(e.roll_deg == Approx(0.0).margin(1e-9));
  CHECK(e.pitch_deg == Approx(0.0).margin(1e-9));
  CHECK(e.yaw_deg == Approx(0.5));
  CHECK(e.rotation_deg == Approx(0.5));
  const Vec6 xi = est.minus(truth);
  CHECK(e.nees == Approx(xi.squaredNorm() / 1e-6));
}

TEST_CASE("evaluate: angle differences wrap across +-180 deg", "[apps][evaluate]") {
  const SE3 truth = SE3::fromXyzRpy(Vec3::Zero(), Vec3(179.9 * kDeg, 0.0, -179.95 * kDeg));
  const SE3 est = SE3::fromXyzRpy(Vec3::Zero(), Vec3(-179.9 * kDeg, 0.0, 179.95 * kDeg));
  const PoseError e = poseError(est, Mat6::Identity(), truth);
  CHECK(e.roll_deg == Approx(0.2));
  CHECK(e.yaw_deg == Approx(0.1));
  CHECK(e.rotation_deg < 0.3);
}

TEST_CASE("evaluate: NEES of samples drawn from the covariance averages 6", "[apps][evaluate]") {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  Mat6 A;
  for (int i = 0; i < 36; ++i) A.data()[i] = n(rng);
  Mat6 cov = 1e-4 * (A * A.transpose() + 0.5 * Mat6::Identity());
  const Mat6 L = Eigen::LLT<Mat6>(cov).matrixL();
  const SE3 est = SE3::fromXyzRpy(Vec3(0.2, 0.1, 0.4), Vec3(-1.5, 0.3, 2.0));
  const int N = 5000;
  double sum = 0.0;
  for (int k = 0; k < N; ++k) {
    Vec6 z;
    for (int i = 0; i < 6; ++i) z[i] = n(rng);
    const SE3 truth = est.plus(L * z);  // truth = est Exp(xi), xi ~ N(0, cov)
    sum += poseError(est, cov, truth).nees;
  }
  // chi^2(6): mean 6, std of the mean sqrt(12 / N) ~ 0.05.
  CHECK(sum / N == Approx(6.0).margin(0.2));
}

TEST_CASE("evaluate: cameras and mount, mismatches, table", "[apps][evaluate]") {
  const SE3 T0 = SE3::fromXyzRpy(Vec3(0.3, 0, 0.1), Vec3(0, 0, 0));
  const SE3 T1 = SE3::fromXyzRpy(Vec3(-0.3, 0, 0.1), Vec3(0, 0, M_PI));
  CalibrationOutput out;
  out.cameras = {camera("cam0", T0, Mat6::Identity() * 1e-6), camera("cam1", T1, Mat6::Identity() * 1e-6)};
  out.mount.T_link_marker = SE3(Mat3::Identity(), Vec3(0, 0, 0.021));
  out.mount.estimated = false;  // zero covariance: NEES undefined
  GroundTruth gt;
  gt.T_base_cam = {{"cam0", T0}, {"cam1", T1}};
  gt.T_link_marker = SE3(Mat3::Identity(), Vec3(0, 0, 0.02));

  const Evaluation ev = evaluate(out, gt);
  CHECK(ev.cameras.size() == 2);
  CHECK(ev.cameras.at("cam0").translation_mm == 0.0);
  CHECK(ev.cameras.at("cam1").nees == Approx(0.0).margin(1e-12));
  REQUIRE(ev.mount);
  CHECK(ev.mount->z_mm == Approx(1.0));
  CHECK(std::isnan(ev.mount->nees));

  const std::string table = formatEvaluationTable(ev);
  CHECK_THAT(table, Catch::Contains("cam0") && Catch::Contains("cam1") && Catch::Contains("mount") &&
                        Catch::Contains("NEES") && Catch::Contains("1.000"));

  gt.T_link_marker.reset();
  const Evaluation no_mount = evaluate(out, gt);
  CHECK_FALSE(no_mount.mount);
  CHECK_THAT(formatEvaluationTable(no_mount),
             Catch::Contains("mount: not scored (the ground truth holds no mount: neither mount.T_link_marker nor "
                             "robot.T_link_marker)"));

  GroundTruth other;
  other.T_base_cam = {{"cam0", T0}, {"cam2", T1}};
  CHECK_INPUT_ERROR(evaluate(out, other), "ground truth", "cameras", "without ground truth: cam1",
                    "without calibration result: cam2");
}

// ---- Estimated quantities beyond the poses (calibrate --estimate) ----------

namespace {

// calibration.yaml as `fgcal calibrate` writes it for two cameras, with the
// keys of docs/outputs.md added by hand: cam0 with a time offset, intrinsics
// and distortion coefficients, cam1 with a time offset and intrinsics, and
// three joint offsets.
CalibrationOutput twoCameras() {
  CalibrationOutput out;
  out.cameras = {camera("cam0", SE3::fromXyzRpy(Vec3(0.3, 0, 0.1), Vec3::Zero()), Mat6::Identity() * 1e-6),
                 camera("cam1", SE3::fromXyzRpy(Vec3(-0.3, 0, 0.1), Vec3(0, 0, M_PI)), Mat6::Identity() * 1e-6)};
  out.mount.T_link_marker = SE3(Mat3::Identity(), Vec3(0, 0, 0.02));
  out.mount.covariance = Mat6::Identity() * 1e-6;
  out.mount.estimated = true;
  out.method = "corners";
  return out;
}

std::string estimatedYaml(const std::string& cam0_extra = "", const std::string& tail = "") {
  std::string text = formatCalibrationYaml(twoCameras());
  text = replaced(text, "    images_skipped: {}\n",
                  "    images_skipped: {}\n"
                  "    time_offset_ms: 15.2\n"
                  "    time_offset_sigma_ms: 0.1\n"
                  "    intrinsics: [591.0, 589.5, 514.3, 268.6]\n"
                  "    intrinsics_sigma: [0.5, 0.5, 1.0, 1.0]\n"
                  "    distortion_coeffs: [-0.0495, 0.0101, 0.0001, -0.0001]\n"
                  "    distortion_coeffs_sigma: [0.001, 0.001, 0.00005, .inf]\n" +
                      cam0_extra);
  // cam1's block: its images_skipped line is the second one.
  const auto second = text.find("    images_skipped: {}\n", text.find("cam1:"));
  text.insert(second + std::string("    images_skipped: {}\n").size(),
              "    time_offset_ms: -0.3\n    time_offset_sigma_ms: 0.2\n"
              "    intrinsics: [525.0, 525.0, 319.2, 241.7]\n    intrinsics_sigma: [1.0, 1.0, 2.0, 2.0]\n");
  text = replaced(text, "method: corners\n", "method: corners\nestimated: [time-offset, joint-offsets, intrinsics]\n");
  return text +
         "joint_offsets:\n"
         "  lf_haa_joint: {offset_rad: 0.004, sigma_rad: 0.05, observed: false}\n"
         "  lf_hfe_joint: {offset_rad: 0.0104, sigma_rad: 0.0002, observed: true}\n"
         "  lf_kfe_joint: {offset_rad: -0.0193, sigma_rad: 0.0005, observed: true}\n" +
         tail;
}

GroundTruth truthOf(const CalibrationOutput& out) {
  GroundTruth gt;
  for (const auto& c : out.cameras) gt.T_base_cam[c.name] = c.T_base_cam;
  gt.T_link_marker = out.mount.T_link_marker;
  gt.time_offset_ms = {{"cam0", 15.0}, {"cam1", 0.0}};
  gt.intrinsics = {{"cam0", {590.0, 590.0, 514.3, 270.6}}, {"cam1", {525.0, 525.0, 319.2, 241.7}}};
  gt.distortion_coeffs = {{"cam0", {-0.05, 0.01, 1e-4, -1e-4}}, {"cam1", {0.03, -0.08, 2e-4, 1e-4}}};
  gt.joint_offsets_rad = {{"lf_haa_joint", 0.0}, {"lf_hfe_joint", 0.01}, {"lf_kfe_joint", -0.02}};
  return gt;
}

}  // namespace

TEST_CASE("evaluate: calibration.yaml's estimated quantities are read as documented", "[apps][evaluate]") {
  const EstimatedQuantities q = parseEstimatedQuantities(estimatedYaml(), "calibration.yaml");
  CHECK(q.method == "corners");
  CHECK(q.estimated == std::vector<std::string>{"time-offset", "joint-offsets", "intrinsics"});
  REQUIRE(q.cameras.size() == 2);
  const EstimatedCamera& c0 = q.cameras.at("cam0");
  REQUIRE(c0.time_offset_ms);
  CHECK(c0.time_offset_ms->value == 15.2);
  CHECK(c0.time_offset_ms->sigma == 0.1);
  REQUIRE(c0.intrinsics.size() == 4);
  CHECK(c0.intrinsics[1].value == 589.5);
  CHECK(c0.intrinsics[2].sigma == 1.0);
  REQUIRE(c0.distortion_coeffs.size() == 4);
  CHECK(std::isinf(c0.distortion_coeffs[3].sigma));
  const EstimatedCamera& c1 = q.cameras.at("cam1");
  CHECK(c1.time_offset_ms->value == -0.3);
  CHECK(c1.intrinsics.size() == 4);
  CHECK(c1.distortion_coeffs.empty());
  REQUIRE(q.joint_offsets.size() == 3);
  CHECK_FALSE(q.joint_offsets.at("lf_haa_joint").observed);
  CHECK(q.joint_offsets.at("lf_kfe_joint").offset_rad.value == -0.0193);
  CHECK(q.joint_offsets.at("lf_kfe_joint").offset_rad.sigma == 0.0005);

  // A calibration that estimated nothing more (today's files): nothing to read.
  const EstimatedQuantities none = parseEstimatedQuantities(formatCalibrationYaml(twoCameras()), "c.yaml");
  CHECK(none.cameras.empty());
  CHECK(none.joint_offsets.empty());
  CHECK(none.estimated.empty());
}

TEST_CASE("evaluate: estimated time offsets, joint offsets and intrinsics against the truth", "[apps][evaluate]") {
  const CalibrationOutput out = twoCameras();
  const EstimatedQuantities q = parseEstimatedQuantities(estimatedYaml(), "calibration.yaml");
  GroundTruth gt = truthOf(out);
  gt.time_offset_ms.erase("cam1");  // e.g. a ground truth from another tool
  const Evaluation ev = evaluate(out, q, gt);
  CHECK(ev.method == "corners");
  CHECK(ev.cameras.size() == 2);
  REQUIRE(ev.time_offsets_ms.count("cam0"));
  CHECK(ev.time_offsets_ms.at("cam0").error == Approx(0.2));
  CHECK(ev.time_offsets_ms.at("cam0").sigmas == Approx(2.0));
  CHECK_FALSE(ev.time_offsets_ms.count("cam1"));
  CHECK(ev.without_truth == std::vector<std::string>{"cam1.time_offset_ms"});
  // Joint offsets: the unobserved one is reported, not scored.
  CHECK(ev.joint_offsets_rad.size() == 2);
  CHECK(ev.joint_offsets_rad.at("lf_hfe_joint").error == Approx(0.0004));
  CHECK(ev.joint_offsets_rad.at("lf_hfe_joint").sigmas == Approx(2.0));
  CHECK(ev.joint_offsets_rad.at("lf_kfe_joint").sigmas == Approx(1.4));
  CHECK(ev.joint_offsets_not_observed.count("lf_haa_joint") == 1);
  // Intrinsics per parameter, in pixels and sigmas; distortion coefficients likewise.
  REQUIRE(ev.intrinsics.at("cam0").size() == 4);
  const auto& k = ev.intrinsics.at("cam0");
  CHECK(k[0].error == Approx(1.0));
  CHECK(k[1].sigmas == Approx(-1.0));
  CHECK(k[2].error == Approx(0.0).margin(1e-12));
  CHECK(k[3].sigmas == Approx(-2.0));
  for (const ScalarError& e : ev.intrinsics.at("cam1")) CHECK(e.error == 0.0);
  const auto& d = ev.distortion_coeffs.at("cam0");
  CHECK(d[0].error == Approx(0.0005));
  CHECK(d[0].sigmas == Approx(0.5));
  CHECK(std::isnan(d[3].sigmas));  // an infinite sigma scores nothing

  const std::string table = formatEvaluationTable(ev);
  INFO(table);
  CHECK_THAT(table, Catch::Contains("time offset") && Catch::Contains("estimate ms") &&
                        Catch::Contains("joint offset") && Catch::Contains("error mrad") &&
                        Catch::Contains("intrinsics") && Catch::Contains("lf_haa_joint") &&
                        Catch::Contains("not observed by the data: not scored") &&
                        Catch::Contains("No ground truth for (not scored): cam1.time_offset_ms"));
  CHECK_THAT(table, Catch::Contains("0.2000") && Catch::Contains("0.4000") && Catch::Contains("2.00"));
  // Scored: 1 time offset, 2 joint offsets, 2 x 4 intrinsics, 4 coefficients; all within 3 sigma
  // but one (the .inf sigma gives nan, which is not within).
  CHECK_THAT(table, Catch::Contains("Method: corners. 14 of 15 estimated quantities within 3 sigma"));

  // Today's calibration.yaml: the table stops after the poses.
  const std::string plain = formatEvaluationTable(evaluate(out, gt));
  CHECK(plain.find("time offset") == std::string::npos);
  CHECK(plain == formatEvaluationTable(evaluate(out, EstimatedQuantities{}, gt)));
}

TEST_CASE("evaluate: both files read, the ground truth's new keys round-trip", "[apps][evaluate]") {
  TempDir tmp;
  const CalibrationOutput out = twoCameras();
  const GroundTruth gt = truthOf(out);
  writeFile(tmp / "calibration.yaml", estimatedYaml());
  writeFile(tmp / "ground_truth.yaml", formatGroundTruthYaml(gt));
  const GroundTruth back = loadGroundTruth(tmp / "ground_truth.yaml");
  CHECK(back.time_offset_ms == gt.time_offset_ms);
  CHECK(back.intrinsics == gt.intrinsics);
  CHECK(back.distortion_coeffs == gt.distortion_coeffs);
  CHECK(back.joint_offsets_rad == gt.joint_offsets_rad);
  const Evaluation ev = evaluateFiles(tmp / "calibration.yaml", tmp / "ground_truth.yaml");
  CHECK(ev.time_offsets_ms.at("cam1").error == Approx(-0.3));
  CHECK(ev.joint_offsets_rad.at("lf_kfe_joint").error == Approx(0.0007));
  CHECK(ev.cameras.at("cam0").translation_mm == Approx(0.0).margin(1e-9));
  // A ground truth written before these keys existed: the estimates are listed as without truth.
  GroundTruth poses_only;  // field by field: the struct gains keys
  poses_only.T_base_cam = gt.T_base_cam;
  poses_only.T_link_marker = gt.T_link_marker;
  writeFile(tmp / "old_truth.yaml", formatGroundTruthYaml(poses_only));
  const Evaluation old = evaluateFiles(tmp / "calibration.yaml", tmp / "old_truth.yaml");
  CHECK(old.time_offsets_ms.empty());
  CHECK(old.without_truth.size() == 2 + 3 + 2);  // two time offsets, three intrinsics lists, two joints
}

TEST_CASE("evaluate: a malformed estimate names the file and field", "[apps][evaluate]") {
  const std::string f = "calibration.yaml";
  CHECK_INPUT_ERROR(parseEstimatedQuantities(replaced(estimatedYaml(), "    time_offset_sigma_ms: 0.1\n", ""), f), f,
                    "cameras.cam0.time_offset_sigma_ms", "missing");
  CHECK_INPUT_ERROR(parseEstimatedQuantities(replaced(estimatedYaml(), "[591.0, 589.5, 514.3, 268.6]", "[591.0, 589.5]"), f),
                    f, "cameras.cam0.intrinsics", "expected 4 numbers");
  CHECK_INPUT_ERROR(parseEstimatedQuantities(replaced(estimatedYaml(), "[0.5, 0.5, 1.0, 1.0]", "[0.5, -0.5, 1.0, 1.0]"), f),
                    f, "cameras.cam0.intrinsics_sigma[1]", "sigma >= 0");
  CHECK_INPUT_ERROR(parseEstimatedQuantities(replaced(estimatedYaml(), "0.00005, .inf]", "0.00005]"), f), f,
                    "cameras.cam0.distortion_coeffs_sigma", "expected 4 sigmas");
  CHECK_INPUT_ERROR(parseEstimatedQuantities(replaced(estimatedYaml(), "time_offset_sigma_ms: 0.2", "time_offset_sigma_ms: .nan"), f),
                    f, "cameras.cam1.time_offset_sigma_ms", "sigma >= 0");
  CHECK_INPUT_ERROR(parseEstimatedQuantities(replaced(estimatedYaml(), "time_offset_ms: -0.3", "time_offset_ms: soon"), f),
                    f, "cameras.cam1.time_offset_ms", "expected a number");
  CHECK_INPUT_ERROR(parseEstimatedQuantities(replaced(estimatedYaml(), "joint-offsets, intrinsics]", "skew]"), f), f,
                    "estimated[1]", "expected time-offset, joint-offsets, intrinsics, backlash or rolling-shutter", "'skew'");
  CHECK_INPUT_ERROR(parseEstimatedQuantities(replaced(estimatedYaml(), "    time_offset_ms: -0.3\n    time_offset_sigma_ms: 0.2\n", ""), f),
                    f, "cameras.cam1.time_offset_ms", "`estimated` lists time-offset");
  CHECK_INPUT_ERROR(parseEstimatedQuantities(replaced(estimatedYaml(), "sigma_rad: 0.0005, ", ""), f), f,
                    "joint_offsets.lf_kfe_joint.sigma_rad", "missing");
  CHECK_INPUT_ERROR(parseEstimatedQuantities(replaced(estimatedYaml(), "observed: false", "observed: maybe"), f), f,
                    "joint_offsets.lf_haa_joint.observed", "true or false");
  const std::string no_joints = estimatedYaml().substr(0, estimatedYaml().find("joint_offsets:\n"));
  CHECK_INPUT_ERROR(parseEstimatedQuantities(no_joints, f), f, "joint_offsets", "`estimated` lists joint-offsets");
  // The camera models differ: 5 radtan coefficients against 4.
  GroundTruth gt = truthOf(twoCameras());
  gt.distortion_coeffs["cam0"].push_back(0.001);
  CHECK_INPUT_ERROR(evaluate(twoCameras(), parseEstimatedQuantities(estimatedYaml(), f), gt), "ground truth",
                    "cameras.cam0.distortion_coeffs", "4 values and the ground truth 5");
  // The ground truth's own keys.
  CHECK_INPUT_ERROR(parseGroundTruth(replaced(formatGroundTruthYaml(gt), "{offset_rad: 0.01}", "{offset: 0.01}"), "gt.yaml"),
                    "gt.yaml", "joint_offsets.lf_hfe_joint.offset_rad", "missing");
  CHECK_INPUT_ERROR(parseGroundTruth(replaced(formatGroundTruthYaml(gt), "[590.0, 590.0, 514.3, 270.6]", "[590.0]"), "gt.yaml"),
                    "gt.yaml", "cameras.cam0.intrinsics", "expected 4 numbers");
}

TEST_CASE("evaluate: calibration.yaml of a camera without distortion, intrinsics estimated, reads back as written",
          "[apps][evaluate]") {
  // What fgcal calibrate writes for distortion_model none: intrinsics but no
  // distortion lists; and an unbounded sigma is written and read as .inf.
  CalibrationOutput out = twoCameras();
  out.cameras[0].intrinsics = {591.0, 589.5, 514.3, 268.6};
  out.cameras[0].intrinsics_sigma = {0.5, 0.5, 1.0, std::numeric_limits<double>::infinity()};
  const std::string text = formatCalibrationYaml(out);
  CHECK(text.find("distortion_coeffs") == std::string::npos);
  const CalibrationOutput back = parseCalibrationYaml(text, "calibration.yaml");
  CHECK(back.cameras[0].intrinsics == out.cameras[0].intrinsics);
  CHECK(std::isinf(back.cameras[0].intrinsics_sigma[3]));
  CHECK(back.cameras[0].distortion_coeffs.empty());
  CHECK_INPUT_ERROR(parseCalibrationYaml(replaced(text, "1.0, .inf]", "1.0, -1.0]"), "calibration.yaml"),
                    "calibration.yaml", "intrinsics_sigma[3]", "sigma >= 0");
}

TEST_CASE("evaluate: the truth's mount is read as mount.T_link_marker or robot.T_link_marker", "[apps][evaluate]") {
  TempDir tmp;
  const CalibrationOutput out = twoCameras();
  GroundTruth gt = truthOf(out);
  gt.T_link_marker = SE3(Mat3::Identity(), Vec3(0, 0, 0.023));  // 3 mm from the result's
  writeFile(tmp / "calibration.yaml", estimatedYaml());
  const std::string fgcal_truth = formatGroundTruthYaml(gt);
  REQUIRE(fgcal_truth.find("mount:\n  T_link_marker:") != std::string::npos);
  // rig.yaml's spelling, as other generators write it (shared/data/bags/anymal_small/ground_truth.yaml).
  const std::string robot_truth = replaced(fgcal_truth, "mount:\n  T_link_marker:", "robot:\n  T_link_marker:");
  writeFile(tmp / "robot_truth.yaml", robot_truth);
  const Evaluation ev = evaluateFiles(tmp / "calibration.yaml", tmp / "robot_truth.yaml");
  REQUIRE(ev.mount);
  CHECK(ev.mount->z_mm == Approx(3.0));
  CHECK(ev.mount_not_scored.empty());
  CHECK_THAT(formatEvaluationTable(ev), !Catch::Contains("not scored (the ground truth"));
  // Both spellings: the same mount is fine, two different ones are refused.
  GroundTruth mount_only;
  mount_only.T_link_marker = gt.T_link_marker;
  const std::string mount_text = formatGroundTruthYaml(mount_only);
  const std::string both = fgcal_truth + replaced(mount_text.substr(mount_text.find("mount:\n")), "mount:\n", "robot:\n");
  CHECK(parseGroundTruth(both, "gt.yaml").T_link_marker);
  const std::string differ = fgcal_truth + "robot:\n  T_link_marker: [[1,0,0,0],[0,1,0,0],[0,0,1,0.5],[0,0,0,1]]\n";
  CHECK_INPUT_ERROR(parseGroundTruth(differ, "gt.yaml"), "gt.yaml", "robot.T_link_marker",
                    "same mount as mount.T_link_marker");
  // Without either, the table says the mount is not scored, and why.
  writeFile(tmp / "no_mount.yaml", replaced(robot_truth, "robot:\n  T_link_marker:", "rig:\n  T_link_marker:"));
  const Evaluation none = evaluateFiles(tmp / "calibration.yaml", tmp / "no_mount.yaml");
  CHECK_FALSE(none.mount);
  CHECK_THAT(formatEvaluationTable(none), Catch::Contains("mount: not scored (the ground truth holds no mount"));
}

TEST_CASE("evaluate: swapped arguments are named as such (result first, then truth)", "[apps][evaluate]") {
  TempDir tmp;
  writeFile(tmp / "calibration.yaml", estimatedYaml());
  writeFile(tmp / "ground_truth.yaml", formatGroundTruthYaml(truthOf(twoCameras())));
  CHECK_INPUT_ERROR(evaluateFiles(tmp / "ground_truth.yaml", tmp / "calibration.yaml"), "ground_truth.yaml", "",
                    "expected a calibration result first, then the ground truth", "arguments look swapped",
                    "calibration.yaml");
  // A file that is neither keeps its own message.
  writeFile(tmp / "other.yaml", "cameras: {}\n");
  const InputError e = expectInputError([&] { evaluateFiles(tmp / "ground_truth.yaml", tmp / "other.yaml"); });
  CHECK_THAT(std::string(e.what()), !Catch::Contains("swapped"));
  CHECK_FALSE(swappedEvaluateArguments(tmp / "calibration.yaml", tmp / "ground_truth.yaml"));
}
