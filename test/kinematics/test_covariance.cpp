// Encoder-noise propagation: J diag(sigma^2) J^T against the Monte-Carlo spread
// of T(q0) ⊖ T(q0 + dq) for sampled encoder noise dq.
//
// Tolerances: with N = 20000 independent samples, a sample variance has
// relative standard deviation sqrt(2 / N) = 1.0%, and a sample correlation a
// standard deviation of at most 1/sqrt(N) = 0.7%. We allow 5% on variances and
// 0.04 on correlations (>= 5 sigma; with a fixed seed the test is
// deterministic). A negative control shows the test can fail: the same samples
// compared with the covariance expressed in the base frame (a classic
// convention slip) are off by far more than the tolerance.
#include <random>

#include <catch2/catch.hpp>

#include "fgcal/kinematics/default_robot.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal_test/shared_data.hpp"
#include "kin_test_util.hpp"

using namespace fgcal;
using namespace fgcal::kinematics;

namespace {

struct Comparison {
  double worst_variance_ratio_error = 0.0;  // max_i |S_ii / Sigma_ii - 1| over non-negligible Sigma_ii
  double worst_correlation_error = 0.0;     // max_ij |rho_S - rho_Sigma|
};

Mat6 monteCarloCovariance(const KinematicChain& c, const VecX& q0, const VecX& sigma, const SE3& T_tip_marker,
                          int samples, unsigned seed) {
  std::mt19937 gen(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  const SE3 T0 = c.forward(q0) * T_tip_marker;
  Mat6 S = Mat6::Zero();
  Vec6 mean = Vec6::Zero();
  std::vector<Vec6> xs(static_cast<std::size_t>(samples));
  for (auto& xi : xs) {
    VecX dq(q0.size());
    for (Eigen::Index i = 0; i < dq.size(); ++i) dq[i] = sigma[i] * n01(gen);
    xi = T0.minus(c.forward(VecX(q0 + dq)) * T_tip_marker);
    mean += xi;
  }
  mean /= samples;
  for (const auto& xi : xs) S += (xi - mean) * (xi - mean).transpose();
  return S / (samples - 1);
}

Comparison compare(const Mat6& S, const Mat6& Sigma) {
  Comparison out;
  const double scale = Sigma.diagonal().maxCoeff();
  for (int i = 0; i < 6; ++i) {
    if (Sigma(i, i) < 1e-6 * scale) {
      // A direction the joints cannot move (rank-deficient Sigma): the samples
      // must not move there either, beyond second-order effects.
      out.worst_variance_ratio_error = std::max(out.worst_variance_ratio_error, S(i, i) / scale > 1e-4 ? 1.0 : 0.0);
      continue;
    }
    out.worst_variance_ratio_error = std::max(out.worst_variance_ratio_error, std::abs(S(i, i) / Sigma(i, i) - 1.0));
    for (int j = 0; j < i; ++j) {
      if (Sigma(j, j) < 1e-6 * scale) continue;
      const double rs = S(i, j) / std::sqrt(S(i, i) * S(j, j));
      const double rt = Sigma(i, j) / std::sqrt(Sigma(i, i) * Sigma(j, j));
      out.worst_correlation_error = std::max(out.worst_correlation_error, std::abs(rs - rt));
    }
  }
  return out;
}

void checkAgainstMonteCarlo(const KinematicChain& c, const VecX& q0, const VecX& sigma, const SE3& T_tip_marker,
                            unsigned seed) {
  const Mat6 Sigma = c.covariance(q0, sigma, T_tip_marker);
  const Mat6 S = monteCarloCovariance(c, q0, sigma, T_tip_marker, 20000, seed);
  const Comparison ok = compare(S, Sigma);
  INFO("propagated:\n" << Sigma << "\nMonte Carlo:\n" << S);
  CHECK(ok.worst_variance_ratio_error < 0.05);
  CHECK(ok.worst_correlation_error < 0.04);
  // Negative control: the covariance in base-frame axes (left perturbation) is wrong here.
  const Mat6 Ad = (c.forward(q0) * T_tip_marker).adjoint();
  const Comparison wrong = compare(S, Ad * Sigma * Ad.transpose());
  CHECK((wrong.worst_variance_ratio_error > 0.2 || wrong.worst_correlation_error > 0.2));
}

}  // namespace

TEST_CASE("propagated covariance matches Monte Carlo on the default robot's leg", "[kinematics][covariance]") {
  const RobotModel m = loadDefaultRobot();
  const KinematicChain leg = m.chain("base_link", "lf_foot");
  VecX q0(3);
  q0 << -0.2, 0.6, -1.3;
  const SE3 T_foot_board = SE3::fromXyzRpy(Vec3(0.03, -0.01, 0.04), Vec3(0.2, -0.4, 1.1));
  SECTION("one sigma for all joints") { checkAgainstMonteCarlo(leg, q0, leg.sigmaVector(0.002), SE3(), 1); }
  SECTION("per-joint sigmas and a board on the foot") {
    checkAgainstMonteCarlo(leg, q0, (VecX(3) << 0.004, 0.001, 0.002).finished(), T_foot_board, 2);
  }
}

TEST_CASE("propagated covariance matches Monte Carlo on long real chains", "[kinematics][covariance][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "urdf");
  std::mt19937 gen(9);
  const SE3 T_tip_marker = SE3::fromXyzRpy(Vec3(0.0, 0.05, 0.02), Vec3(0.0, 0.3, 0.0));
  {
    const RobotModel m = RobotModel::fromFile(dir + "/anymal_c.urdf");
    const KinematicChain c = m.chain("LF_FOOT", "RH_FOOT");  // 6 joints: full-rank 6x6 Sigma
    checkAgainstMonteCarlo(c, fgcal::test::randomJointValues(c, gen), c.sigmaVector(0.003), T_tip_marker, 3);
  }
  {
    const RobotModel m = RobotModel::fromFile(dir + "/spot_with_arm.urdf");
    const KinematicChain c = m.chain("body", "arm_link_fngr");
    checkAgainstMonteCarlo(c, fgcal::test::randomJointValues(c, gen), c.sigmaVector(0.002), T_tip_marker, 4);
  }
}
