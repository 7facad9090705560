// calibration.yaml, ground_truth.yaml, the URDF snippet, sigma_mm_deg and
// atomic writes.
#include <csignal>
#include <random>

#include <catch2/catch.hpp>
#include <sys/resource.h>
#include <yaml-cpp/yaml.h>

#include "apps_test_util.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/kinematics/default_robot.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {

Mat6 randomSpd(std::mt19937& rng, double rot_sigma, double trans_sigma) {
  std::normal_distribution<double> n(0.0, 1.0);
  Mat6 A;
  for (int i = 0; i < 36; ++i) A.data()[i] = n(rng);
  Mat6 S = A * A.transpose() / 6.0 + 0.2 * Mat6::Identity();
  Vec6 scale;
  scale << Vec3::Constant(rot_sigma), Vec3::Constant(trans_sigma);
  return scale.asDiagonal() * S * scale.asDiagonal();
}

CalibrationOutput sampleOutput() {
  std::mt19937 rng(7);
  CalibrationOutput out;
  const char* names[] = {"cam0", "cam1", "front_left"};
  for (int i = 0; i < 3; ++i) {
    CameraResult c;
    c.name = names[i];
    c.T_base_cam = SE3::exp((Vec6() << 0.3 * i - 1.0, 1.1, -0.4 + i, 0.25 * i, -0.1, 0.05 + 1.0 / 3.0).finished());
    c.covariance = randomSpd(rng, 1e-3, 5e-4);
    c.images_used = 100 + i;
    c.rms_reprojection_px = 0.31 + i / 7.0;
    if (i == 1) c.images_skipped = {{"no board", 12}, {"NaN joint", 1}, {"outside the recorded span", 3}};
    if (i == 2) {  // estimated intrinsics on one camera only
      c.intrinsics = {600.25 + 1.0 / 3.0, 601.5, 320.125, 239.75};
      c.intrinsics_sigma = {0.4, 0.41, 0.3 + 1e-9, 0.29};
      c.distortion_coeffs = {-0.28, 0.074, 1.9e-4, -1.7e-5};
      c.distortion_coeffs_sigma = {1e-3, 2e-3, 1e-5, 1.5e-5};
    }
    out.cameras.push_back(c);
  }
  out.mount.T_link_marker = SE3::exp((Vec6() << 0.01, -0.02, 0.03, 0.0, 0.0, 0.02).finished());
  out.mount.covariance = randomSpd(rng, 5e-3, 1e-3);
  out.mount.estimated = true;
  out.method = "corners";
  out.estimated = {"intrinsics"};
  out.info = {{"fgcal_version", "fgcal 0.1.0 (git 5e14d11)"},
              {"date_utc", "2026-03-01T12:34:56Z"},
              {"rig", "/data/run 3/rig.yaml"},
              {"dataset", "/data/run 3"},
              {"final_cost", "12.5"},
              {"note", "a \"quoted\" word"}};
  return out;
}

}  // namespace

TEST_CASE("rpyJacobian matches central differences", "[apps][results]") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.3, 1.3);
  for (int k = 0; k < 20; ++k) {
    const SO3 R = SO3::fromRpy(3 * u(rng), u(rng), 3 * u(rng));
    Mat3 Jn;
    const double h = 1e-6;
    for (int i = 0; i < 3; ++i) {
      const Vec3 d = h * Vec3::Unit(i);
      Vec3 diff = R.plus(d).rpy() - R.plus(-d).rpy();
      for (int j = 0; j < 3; ++j) diff[j] = std::remainder(diff[j], 2 * M_PI);
      Jn.col(i) = diff / (2 * h);
    }
    CHECK((rpyJacobian(R) - Jn).norm() < 1e-6);
  }
}

TEST_CASE("sigma_mm_deg agrees with Monte Carlo", "[apps][results]") {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    const SE3 T = SE3::fromXyzRpy(Vec3(0.4, -0.2, 0.3), Vec3(0.3 + trial, -0.6 + 0.4 * trial, 2.5 - trial));
    const Mat6 cov = randomSpd(rng, 0.01, 0.005);
    const Vec6 sigma = sigmaMmDeg(T, cov);
    const Eigen::LLT<Mat6> llt(cov);
    const Mat6 L = llt.matrixL();
    const int N = 40000;
    Vec6 sum = Vec6::Zero(), sum2 = Vec6::Zero();
    const Vec3 rpy0 = T.so3().rpy();
    for (int s = 0; s < N; ++s) {
      Vec6 z;
      for (int i = 0; i < 6; ++i) z[i] = n(rng);
      const SE3 Ts = T.plus(L * z);
      Vec6 v;
      v.head<3>() = (Ts.translation() - T.translation()) * 1000.0;
      Vec3 d = Ts.so3().rpy() - rpy0;
      for (int j = 0; j < 3; ++j) d[j] = std::remainder(d[j], 2 * M_PI);
      v.tail<3>() = d * 180.0 / M_PI;
      sum += v;
      sum2 += v.cwiseProduct(v);
    }
    const Vec6 mean = sum / N;
    const Vec6 mc = (sum2 / N - mean.cwiseProduct(mean)).cwiseSqrt();
    INFO("trial " << trial << "\nanalytic " << sigma.transpose() << "\nmonte carlo " << mc.transpose());
    for (int i = 0; i < 6; ++i) CHECK(sigma[i] == Approx(mc[i]).epsilon(0.03));
  }
  CHECK(sigmaMmDeg(SE3(), Mat6::Zero()) == Vec6::Zero());
}

TEST_CASE("calibration.yaml: format -> load round trip", "[apps][results]") {
  const CalibrationOutput out = sampleOutput();
  const std::string text = formatCalibrationYaml(out);
  const CalibrationOutput back = parseCalibrationYaml(text, "calibration.yaml");
  REQUIRE(back.cameras.size() == out.cameras.size());
  for (std::size_t i = 0; i < out.cameras.size(); ++i) {
    const CameraResult &a = out.cameras[i], &b = back.cameras[i];
    CHECK(a.name == b.name);
    CHECK((a.T_base_cam.matrix() - b.T_base_cam.matrix()).norm() < 1e-15);
    CHECK(a.covariance == b.covariance);  // bit-exact
    CHECK(a.images_used == b.images_used);
    CHECK(a.rms_reprojection_px == b.rms_reprojection_px);
    CHECK(a.images_skipped == b.images_skipped);
    CHECK(a.intrinsics == b.intrinsics);  // bit-exact, empty where not estimated
    CHECK(a.intrinsics_sigma == b.intrinsics_sigma);
    CHECK(a.distortion_coeffs == b.distortion_coeffs);
    CHECK(a.distortion_coeffs_sigma == b.distortion_coeffs_sigma);
  }
  CHECK(back.estimated == out.estimated);
  CHECK((out.mount.T_link_marker.matrix() - back.mount.T_link_marker.matrix()).norm() < 1e-15);
  CHECK(out.mount.covariance == back.mount.covariance);
  CHECK(back.mount.estimated);
  CHECK(back.method == "corners");
  CHECK(back.info == out.info);
}

TEST_CASE("calibration.yaml: the layout docs/outputs.md fixes, read by an independent YAML parser", "[apps][results]") {
  const CalibrationOutput out = sampleOutput();
  const YAML::Node y = YAML::Load(formatCalibrationYaml(out));
  for (const CameraResult& c : out.cameras) {
    const YAML::Node n = y["cameras"][c.name];
    REQUIRE(n.IsMap());
    for (int r = 0; r < 4; ++r)
      for (int k = 0; k < 4; ++k) CHECK(n["T_base_cam"][r][k].as<double>() == c.T_base_cam.matrix()(r, k));
    for (int r = 0; r < 6; ++r)
      for (int k = 0; k < 6; ++k) CHECK(n["covariance"][r][k].as<double>() == c.covariance(r, k));
    const Vec6 s = sigmaMmDeg(c.T_base_cam, c.covariance), p = c.T_base_cam.xyzRpy();
    for (int i = 0; i < 6; ++i) {
      CHECK(n["sigma_mm_deg"][i].as<double>() == s[i]);
      CHECK(n["xyz_rpy"][i].as<double>() == p[i]);
    }
    CHECK(n["images_used"].as<int>() == c.images_used);
    CHECK(n["rms_reprojection_px"].as<double>() == c.rms_reprojection_px);
  }
  // Relative poses of every pair, in camera order.
  for (std::size_t i = 0; i < out.cameras.size(); ++i)
    for (std::size_t j = i + 1; j < out.cameras.size(); ++j) {
      const auto &a = out.cameras[i], &b = out.cameras[j];
      const std::string key = "T_" + a.name + "_" + b.name;
      const YAML::Node n = y[key];
      REQUIRE(n.IsMap());
      const Mat4 expected = (a.T_base_cam.inverse() * b.T_base_cam).matrix();
      for (int r = 0; r < 4; ++r)
        for (int k = 0; k < 4; ++k) CHECK(n[key][r][k].as<double>() == expected(r, k));
      // Its own covariance: with no cross-covariance given, the two cameras'
      // covariances carried into b's frame (independent cameras).
      const RelativePoseResult rel = relativePose(a, b, Mat6::Zero());
      REQUIRE(n["covariance"].size() == 6);
      for (int r = 0; r < 6; ++r)
        for (int k = 0; k < 6; ++k) CHECK(n["covariance"][r][k].as<double>() == Approx(rel.covariance(r, k)));
      CHECK(n["sigma_mm_deg"].size() == 6);
    }
  CHECK_FALSE(y["T_cam1_cam0"].IsDefined());
  CHECK(y["mount"]["T_link_marker"].IsSequence());
  CHECK(y["mount"]["covariance"].size() == 6);
  CHECK(y["mount"]["sigma_mm_deg"].size() == 6);
  CHECK(y["mount"]["estimated"].as<bool>());
  CHECK(y["method"].as<std::string>() == "corners");
  CHECK(y["info"]["note"].as<std::string>() == "a \"quoted\" word");
  CHECK(y["cameras"]["cam1"]["images_skipped"]["no board"].as<int>() == 12);
}

TEST_CASE("calibration.yaml: floats keep a '.', NaN covariances survive", "[apps][results]") {
  CalibrationOutput out = sampleOutput();
  out.cameras[0].covariance(0, 0) = std::nan("");
  out.cameras[0].T_base_cam = SE3(Mat3::Identity(), Vec3(1e-5, 2.0, 0.0));
  out.mount.estimated = false;
  out.mount.covariance.setZero();
  const std::string text = formatCalibrationYaml(out);
  CHECK_THAT(text, Catch::Contains("1.0e-05") && Catch::Contains("2.0") && Catch::Contains(".nan"));
  CHECK_THAT(text, !Catch::Contains(" 1e-05"));
  const CalibrationOutput back = parseCalibrationYaml(text, "c.yaml");
  CHECK(std::isnan(back.cameras[0].covariance(0, 0)));
  CHECK_FALSE(back.mount.estimated);
}

TEST_CASE("calibration.yaml: a file written before the stamp keys, or without info, reads back",
          "[apps][results]") {
  CalibrationOutput out = sampleOutput();
  out.info = {{"dataset", "/data/run 3"}, {"final_cost", "12.5"}};
  CHECK(parseCalibrationYaml(formatCalibrationYaml(out), "old.yaml").info == out.info);
  std::string text = formatCalibrationYaml(out);
  const auto info = text.find("\ninfo:");
  REQUIRE(info != std::string::npos);
  text.erase(info + 1);  // info is the last block
  REQUIRE(text.find("\ninfo") == std::string::npos);
  const CalibrationOutput back = parseCalibrationYaml(text, "older.yaml");
  CHECK(back.info.empty());
  CHECK(back.cameras.size() == out.cameras.size());
}

TEST_CASE("calibration.yaml: load errors", "[apps][results]") {
  TempDir tmp;
  CHECK_INPUT_ERROR(loadCalibrationYaml(tmp / "calibration.yaml"), "calibration.yaml", "", "not found");
  const std::string good = formatCalibrationYaml(sampleOutput());
  CHECK_INPUT_ERROR(parseCalibrationYaml(good.substr(0, good.find("mount:")), "c.yaml"), "c.yaml", "mount",
                    "missing");
  const auto pos = good.find("    covariance:");
  const auto end = good.find("    sigma_mm_deg:");
  std::string bad = good;
  bad.replace(pos, end - pos, "    covariance: [[1, 2], [3, 4]]\n");
  CHECK_INPUT_ERROR(parseCalibrationYaml(bad, "c.yaml"), "c.yaml", "cameras.cam0.covariance", "6x6");
}

TEST_CASE("ground_truth.yaml: round trip, and calibration.yaml read as truth", "[apps][results]") {
  TempDir tmp;
  GroundTruth gt;
  gt.T_base_cam["cam0"] = SE3::exp((Vec6() << 0.1, 0.2, 0.3, 0.4, 0.5, 0.6).finished());
  gt.T_base_cam["cam1"] = SE3::exp((Vec6() << -3.0, 0.2, 0.1, -0.4, 0.5, 1.0 / 3.0).finished());
  gt.T_link_marker = SE3(Mat3::Identity(), Vec3(0, 0, 0.02));
  writeFileAtomically(tmp / "ground_truth.yaml", formatGroundTruthYaml(gt));
  const GroundTruth back = loadGroundTruth(tmp / "ground_truth.yaml");
  REQUIRE(back.T_base_cam.size() == 2);
  for (const auto& [name, T] : gt.T_base_cam) CHECK((back.T_base_cam.at(name).matrix() - T.matrix()).norm() < 1e-15);
  REQUIRE(back.T_link_marker);
  CHECK(back.T_link_marker->translation() == Vec3(0, 0, 0.02));

  gt.T_link_marker.reset();
  CHECK_FALSE(parseGroundTruth(formatGroundTruthYaml(gt), "gt.yaml").T_link_marker);
  CHECK_FALSE(back.encoder_resolution_rad);

  // The simulated legs' and cameras' effects (fgcal simulate --backlash, --readout-ms, ...).
  gt.backlash_rad = {{"lf_hfe_joint", 0.002}, {"lf_kfe_joint", 0.0}};
  gt.readout_ms = {{"cam0", 25.5}, {"cam1", 0.0}};
  gt.exposure_ms = {{"cam0", 4.0}, {"cam1", 4.0}};
  gt.encoder_resolution_rad = 1e-4;
  const GroundTruth effects = parseGroundTruth(formatGroundTruthYaml(gt), "gt.yaml");
  CHECK(effects.backlash_rad == gt.backlash_rad);
  CHECK(effects.readout_ms == gt.readout_ms);
  CHECK(effects.exposure_ms == gt.exposure_ms);
  CHECK(effects.encoder_resolution_rad == gt.encoder_resolution_rad);
  CHECK_INPUT_ERROR(parseGroundTruth("cameras: {}\nbacklash: {j: 0.1}\n", "gt.yaml"), "gt.yaml", "backlash.j", "rad");

  const CalibrationOutput out = sampleOutput();
  const GroundTruth from_calib = parseGroundTruth(formatCalibrationYaml(out), "calibration.yaml");
  CHECK(from_calib.T_base_cam.size() == 3);
  CHECK(from_calib.T_link_marker);

  CHECK_INPUT_ERROR(parseGroundTruth("cameras:\n  cam0:\n    T_base_cam: [[1,0,0],[0,1,0],[0,0,1]]\n", "gt.yaml"),
                    "gt.yaml", "cameras.cam0.T_base_cam", "4x4");
  CHECK_INPUT_ERROR(parseGroundTruth("mount: {}\n", "gt.yaml"), "gt.yaml", "cameras", "missing");
}

TEST_CASE("URDF snippet: pasted into the default robot, FK gives T_base_cam", "[apps][results]") {
  const CalibrationOutput out = sampleOutput();
  const std::string snippet = formatUrdfSnippet(out, "base_link");
  CHECK_THAT(snippet, Catch::Contains("<joint name=\"cam0_joint\" type=\"fixed\">") &&
                          Catch::Contains("<parent link=\"base_link\"/>") && Catch::Contains("<link name=\"cam1\"/>"));
  std::string urdf = kinematics::defaultRobotUrdf();
  const auto end = urdf.rfind("</robot>");
  REQUIRE(end != std::string::npos);
  urdf.insert(end, snippet);
  const auto robot = kinematics::RobotModel::fromString(urdf, "robot+snippet");
  for (const CameraResult& c : out.cameras) {
    const auto chain = robot.chain("base_link", c.name);
    CHECK(chain.numJoints() == 0);
    const SE3 T = chain.forward(VecX(0));
    INFO(c.name);
    CHECK((T.matrix() - c.T_base_cam.matrix()).cwiseAbs().maxCoeff() < 1e-9);
  }
}

namespace {
// Runs f with files limited to 1 KiB (RLIMIT_FSIZE makes write() fail with
// EFBIG: a full disk in miniature; SIGXFSZ is ignored so the process survives
// to see the error) and returns the InputError's message, empty when none.
// The writers' temporaries (<name>.tmp.<pid>) left in a folder.
int temporaryFilesIn(const fs::path& folder) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(folder))
    if (e.path().filename().string().find(".tmp.") != std::string::npos) ++n;
  return n;
}

template <class F>
std::string inputErrorWithFileSizeLimit(F f) {
  rlimit old{};
  REQUIRE(getrlimit(RLIMIT_FSIZE, &old) == 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit small = old;
  small.rlim_cur = 1024;
  REQUIRE(setrlimit(RLIMIT_FSIZE, &small) == 0);
  std::string what;
  try {
    f();
  } catch (const InputError& e) {
    what = e.what();
  }
  setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, old_handler);
  return what;
}
}  // namespace

TEST_CASE("writeFileAtomically: whole file or nothing", "[apps][results]") {
  TempDir tmp;
  const std::string path = tmp / "calibration.yaml";
  const auto leftovers = [&] { return temporaryFilesIn(tmp.path()); };

  writeFileAtomically(path, "first\n");
  CHECK(readFile(path) == "first\n");
  writeFileAtomically(path, "second, longer\n");
  CHECK(readFile(path) == "second, longer\n");
  CHECK(leftovers() == 0);

  SECTION("missing folder: InputError naming it, nothing created") {
    const std::string missing = tmp / "no_such_folder/calibration.yaml";
    CHECK_INPUT_ERROR(writeFileAtomically(missing, "x"), "no_such_folder/calibration.yaml", "",
                      "no_such_folder does not exist");
    CHECK_FALSE(fs::exists(tmp.path() / "no_such_folder"));
  }
  SECTION("the target is a folder") {
    fs::create_directories(tmp.path() / "out");
    CHECK_INPUT_ERROR(writeFileAtomically(tmp / "out", "x"), "out", "", "existing folder");
    CHECK(leftovers() == 0);
  }
  SECTION("a write that fails half-way leaves the old file intact and no temporary") {
    const std::string what = inputErrorWithFileSizeLimit([&] { writeFileAtomically(path, std::string(100000, 'x')); });
    CHECK_THAT(what, Catch::Contains("calibration.yaml") && Catch::Contains("unchanged"));
    CHECK(readFile(path) == "second, longer\n");
    CHECK(leftovers() == 0);
  }
}

TEST_CASE("writeFilesAtomically: a set of files is written whole or not at all", "[apps][results]") {
  TempDir tmp;
  const std::string yaml = tmp / "calibration.yaml", urdf = tmp / "calibration.urdf.xml";
  const auto leftovers = [&] { return temporaryFilesIn(tmp.path()); };
  writeFilesAtomically({{yaml, "yaml 1\n"}, {urdf, "urdf 1\n"}});
  CHECK(readFile(yaml) == "yaml 1\n");
  CHECK(readFile(urdf) == "urdf 1\n");

  SECTION("the second path is a folder: neither file is replaced") {
    fs::create_directories(tmp.path() / "taken");
    CHECK_INPUT_ERROR(writeFilesAtomically({{yaml, "yaml 2\n"}, {tmp / "taken", "urdf 2\n"}}), "taken", "",
                      "existing folder");
    CHECK(readFile(yaml) == "yaml 1\n");
    CHECK(leftovers() == 0);
  }
  SECTION("the second file fails half-way: the first keeps its old version too") {
    const std::string what = inputErrorWithFileSizeLimit(
        [&] { writeFilesAtomically({{yaml, "yaml 2\n"}, {urdf, std::string(100000, 'x')}}); });
    CHECK_THAT(what, Catch::Contains("calibration.urdf.xml") && Catch::Contains("unchanged"));
    CHECK(readFile(yaml) == "yaml 1\n");
    CHECK(readFile(urdf) == "urdf 1\n");
    CHECK(leftovers() == 0);
  }
  SECTION("success replaces both") {
    writeFilesAtomically({{yaml, "yaml 3\n"}, {urdf, "urdf 3\n"}});
    CHECK(readFile(yaml) == "yaml 3\n");
    CHECK(readFile(urdf) == "urdf 3\n");
    CHECK(leftovers() == 0);
  }
}

TEST_CASE("calibration.yaml: estimated intrinsics keys, read by an independent YAML parser", "[apps][results]") {
  const CalibrationOutput out = sampleOutput();
  const YAML::Node y = YAML::Load(formatCalibrationYaml(out));
  REQUIRE(y["estimated"].IsSequence());
  CHECK(y["estimated"][0].as<std::string>() == "intrinsics");
  CHECK_FALSE(y["cameras"]["cam0"]["intrinsics"].IsDefined());  // written only where estimated
  const YAML::Node c = y["cameras"]["front_left"];
  for (int i = 0; i < 4; ++i) {
    CHECK(c["intrinsics"][i].as<double>() == out.cameras[2].intrinsics[static_cast<std::size_t>(i)]);
    CHECK(c["intrinsics_sigma"][i].as<double>() == out.cameras[2].intrinsics_sigma[static_cast<std::size_t>(i)]);
    CHECK(c["distortion_coeffs"][i].as<double>() == out.cameras[2].distortion_coeffs[static_cast<std::size_t>(i)]);
    CHECK(c["distortion_coeffs_sigma"][i].as<double>() ==
          out.cameras[2].distortion_coeffs_sigma[static_cast<std::size_t>(i)]);
  }
  // Nothing estimated: an empty list.
  CalibrationOutput plain = out;
  plain.estimated.clear();
  CHECK(YAML::Load(formatCalibrationYaml(plain))["estimated"].size() == 0);
  // A half-written group is an error naming the field.
  const std::string text = formatCalibrationYaml(out);
  const auto at = text.find("    distortion_coeffs_sigma:");
  REQUIRE(at != std::string::npos);
  std::string cut = text;
  cut.erase(at, text.find('\n', at) + 1 - at);
  CHECK_THROWS_WITH(parseCalibrationYaml(cut, "calibration.yaml"),
                    Catch::Contains("cameras.front_left.distortion_coeffs_sigma") || Catch::Contains("distortion_coeffs_sigma"));
}

TEST_CASE("relative pose covariance: what two cameras share cancels, what they do not adds") {
  CameraResult a, b;
  a.name = "front";
  b.name = "rear";
  a.T_base_cam = SE3::fromXyzRpy(Vec3(0.3, 0.05, 0.1), Vec3(-1.6, 0.0, -1.5));
  b.T_base_cam = SE3::fromXyzRpy(Vec3(-0.3, -0.05, 0.1), Vec3(-1.6, 0.0, 1.6));
  // Both cameras moved by one common base-frame error e (T Exp(xi) = Exp(e) T):
  // xi_c = Ad(T_c^-1) e, so their covariances are fully correlated.
  Mat6 Se = Vec6(1e-4, 2e-4, 1e-4, 4e-6, 1e-6, 9e-6).asDiagonal();
  const Mat6 Aa = a.T_base_cam.inverse().adjoint(), Ab = b.T_base_cam.inverse().adjoint();
  a.covariance = Aa * Se * Aa.transpose();
  b.covariance = Ab * Se * Ab.transpose();
  const Mat6 cross = Aa * Se * Ab.transpose();
  const RelativePoseResult shared = relativePose(a, b, cross);
  CHECK(shared.covariance.norm() < 1e-12 * a.covariance.norm() + 1e-18);
  // Independent: the sum of both carried into b's frame, larger than either.
  const RelativePoseResult apart = relativePose(a, b, Mat6::Zero());
  CHECK(apart.covariance.trace() > b.covariance.trace());
  CHECK(apart.covariance.isApprox(apart.covariance.transpose()));
  CHECK(apart.T_a_b.between(a.T_base_cam.inverse() * b.T_base_cam).log().norm() < 1e-12);
  // Written and read back with the result.
  CalibrationOutput out;
  out.cameras = {a, b};
  out.relative_poses = {shared};
  const CalibrationOutput back = parseCalibrationYaml(formatCalibrationYaml(out), "calibration.yaml");
  REQUIRE(back.relative_poses.size() == 1);
  CHECK(back.relative_poses[0].a == "front");
  CHECK(back.relative_poses[0].covariance.norm() < 1e-12);
}
