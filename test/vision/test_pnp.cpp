// PnP through our camera models on synthetic corners: the reprojection
// Jacobian, exact recovery without noise, and the covariance formula
// sigma^2 (J^T J)^-1 against the spread under known Gaussian pixel noise.
#include <random>

#include <catch2/catch.hpp>

#include "fgcal/vision/pnp.hpp"
#include "fgcal/vision/vision_error.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "render_fixtures.hpp"

using namespace fgcal;
using namespace fgcal::vision;
using namespace fgcal::vision::testing;

namespace {
std::vector<Vec2> projectAll(const CameraModel& cam, const SE3& T, const std::vector<Vec3>& P) {
  std::vector<Vec2> uv;
  for (const auto& p : P) uv.push_back(*cam.project(T * p));
  return uv;
}
}  // namespace

TEST_CASE("pnp: reprojection Jacobian with respect to the pose [w v]", "[vision][pnp]") {
  const CharucoTarget board = testBoard();
  const auto P = board.cornerPositions();
  for (const auto& cam : {radtanCamera(), equidistantCamera()}) {
    const SE3 T = boardPose(board, Vec3(0.02, -0.01, 0.5), 0.3, -0.2, 0.7);
    const auto uv = projectAll(cam, T.plus((Vec6() << 0.01, -0.02, 0.01, 0.003, 0.002, -0.004).finished()), P);
    Eigen::VectorXd r;
    Eigen::Matrix<double, Eigen::Dynamic, 6> J;
    REQUIRE(reprojection(cam, T, P, uv, &r, &J));
    CHECK_JACOBIAN(
        J,
        [&](const SE3& X) -> Eigen::VectorXd {
          Eigen::VectorXd out;
          reprojection(cam, X, P, uv, &out, nullptr);
          return out;
        },
        T);
  }
}

TEST_CASE("pnp: exact corners give the exact pose, for every distortion model", "[vision][pnp]") {
  const CharucoTarget board = testBoard();
  const auto P = board.cornerPositions();
  const std::vector<CameraModel> cams = {
      CameraModel(Projection::Pinhole, Distortion::None, 600, 600, 320, 240, {}, 640, 480),
      radtanCamera(), equidistantCamera()};
  for (const auto& cam : cams) {
    for (const SE3& T : {boardPose(board, Vec3(0, 0, 0.3), 0.2, 0.1, 0.0),
                         boardPose(board, Vec3(0.1, -0.05, 0.8), -0.5, 0.4, 2.5)}) {
      const auto est = estimatePose(cam, P, projectAll(cam, T, P));
      CHECK(est.converged);
      CHECK(est.rms_px < 1e-8);
      CHECK(T.minus(est.T_cam_marker).norm() < 1e-9);
    }
  }
  CHECK_THROWS_WITH(estimatePose(cams[0], {P[0], P[1], P[2]}, {Vec2(1, 1), Vec2(2, 2), Vec2(3, 3)}),
                    Catch::Contains("at least 4"));
}

TEST_CASE("pnp: covariance equals the spread under Gaussian corner noise", "[vision][pnp][covariance]") {
  const CharucoTarget board = testBoard();
  const auto P = board.cornerPositions();
  const CameraModel cam = equidistantCamera();
  const SE3 T = boardPose(board, Vec3(0.03, 0.02, 0.6), 0.4, -0.3, 0.2);
  const auto uv0 = projectAll(cam, T, P);
  const double sigma = 0.3;
  std::mt19937 rng(17);
  std::normal_distribution<double> noise(0.0, sigma);
  PnpOptions opt;
  opt.pixel_sigma = sigma;
  const int N = 2000;
  Mat6 sample = Mat6::Zero();
  Mat6 predicted = Mat6::Zero();
  double s2 = 0.0;
  for (int k = 0; k < N; ++k) {
    auto uv = uv0;
    for (auto& p : uv) p += Vec2(noise(rng), noise(rng));
    const auto est = estimatePose(cam, P, uv, opt);
    const Vec6 x = T.minus(est.T_cam_marker);
    sample += x * x.transpose() / N;
    predicted += est.covariance / N;
    s2 += est.residual_sigma_px * est.residual_sigma_px / N;
  }
  for (int i = 0; i < 6; ++i) CHECK(sample(i, i) / predicted(i, i) == Approx(1.0).epsilon(0.1));
  CHECK(std::sqrt(s2) == Approx(sigma).epsilon(0.03));
}

TEST_CASE("pnp: the sigma source picks the stated, the residual or the larger sigma", "[vision][pnp][covariance]") {
  const CharucoTarget board = testBoard();
  const auto P = board.cornerPositions();
  const CameraModel cam = equidistantCamera();
  const SE3 T = boardPose(board, Vec3(0.03, 0.02, 0.6), 0.4, -0.3, 0.2);
  auto uv = projectAll(cam, T, P);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.3);
  for (auto& p : uv) p += Vec2(noise(rng), noise(rng));
  PnpOptions opt;
  opt.pixel_sigma = 0.05;  // understated: the corners scatter ~0.3 px
  const auto stated = estimatePose(cam, P, uv, opt);
  opt.sigma_source = PnpOptions::SigmaSource::Larger;
  const auto larger = estimatePose(cam, P, uv, opt);
  CHECK(stated.sigma_px == 0.05);
  CHECK(larger.sigma_px == Approx(larger.residual_sigma_px));
  CHECK(larger.residual_sigma_px > 0.2);
  CHECK(larger.covariance(5, 5) > 10.0 * stated.covariance(5, 5));
  opt.pixel_sigma = 2.0;  // overstated: the stated sigma wins
  CHECK(estimatePose(cam, P, uv, opt).sigma_px == 2.0);
}
