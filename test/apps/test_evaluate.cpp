// fgcal evaluate: known perturbations give known errors; NEES of samples drawn
// from the covariance averages 6.
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
  CHECK_FALSE(evaluate(out, gt).mount);

  GroundTruth other;
  other.T_base_cam = {{"cam0", T0}, {"cam2", T1}};
  CHECK_INPUT_ERROR(evaluate(out, other), "ground truth", "cameras", "without ground truth: cam1",
                    "without calibration result: cam2");
}
