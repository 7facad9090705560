// Is the reported uncertainty honest? 200 renders of one view with
// independent pixel noise; the spread of the estimated poses must match the
// predicted vertex-jitter covariance sigma^2 (J^T J)^-1, each diagonal term
// within 25 %.
//
// The corner jitter sigma that a given image noise produces is not known a
// priori, so it is not tuned: each solve estimates it from its own residuals,
// s^2 = RSS / (2n - 6) (PnpOptions::SigmaSource::Residuals), and the predicted
// covariance is the mean of the per-solve covariances. Nothing is fitted to
// the spread being checked.
#include <catch2/catch.hpp>

#include "fgcal/vision/batch_detection.hpp"
#include "fgcal/vision/board_renderer.hpp"
#include "render_fixtures.hpp"

using namespace fgcal;
using namespace fgcal::vision;
using namespace fgcal::vision::testing;

TEST_CASE("covariance honesty: pose spread over 200 noisy renders matches the prediction",
          "[vision][covariance][accuracy]") {
  const CharucoTarget board = testBoard();
  const CameraModel cam = radtanCamera();
  const BoardRenderer renderer(cam, board, 3);
  const SE3 T_true = boardPose(board, Vec3(0.03, -0.02, 0.55), 0.35, -0.25, 0.4);
  const CharucoDetector detector(board);
  PnpOptions pnp;
  pnp.sigma_source = PnpOptions::SigmaSource::Residuals;

  const int N = 200;
  const auto results = processImages(
      detector, N,
      [&](std::size_t i) {
        RenderOptions o;
        o.noise_sigma = 8.0;  // gray levels, board contrast 205 levels
        o.blur_sigma = 0.6;   // applied before the noise: the noise stays white
        o.seed = 1000 + i;
        return renderer.render(T_true, o);
      },
      &cam, pnp);

  std::vector<Vec6> xs;
  Mat6 predicted = Mat6::Zero();
  double sigma_sum = 0.0, corner_count = 0.0;
  for (const auto& r : results) {
    REQUIRE(r.detection.ok());
    REQUIRE(r.pose);
    corner_count += static_cast<double>(r.detection.ids.size()) / N;
    xs.push_back(T_true.minus(r.pose->T_cam_marker));
    predicted += r.pose->covariance;
    sigma_sum += r.pose->residual_sigma_px;
  }
  predicted /= N;
  Vec6 mean = Vec6::Zero();
  for (const auto& x : xs) mean += x;
  mean /= N;
  Mat6 sample = Mat6::Zero();
  for (const auto& x : xs) sample += (x - mean) * (x - mean).transpose();
  sample /= (N - 1);

  const char* names[6] = {"wx", "wy", "wz", "vx", "vy", "vz"};
  for (int k = 0; k < 6; ++k) {
    const double ratio = sample(k, k) / predicted(k, k);
    WARN("covariance " << names[k] << ": sample/predicted variance " << ratio << " (std "
                       << std::sqrt(sample(k, k)) << " vs " << std::sqrt(predicted(k, k))
                       << "), mean offset " << mean(k));
    CHECK(ratio > 0.75);
    CHECK(ratio < 1.25);
  }
  WARN("mean corner jitter estimated from residuals: " << sigma_sum / N << " px, mean corners per view " << corner_count);
}
