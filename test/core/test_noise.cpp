// Noise models (whitening, rejection of bad covariances) and robust kernels.
#include <random>

#include "fgcal/core/internal/noise_model_access.hpp"
#include "fgcal/core/noise_model.hpp"
#include "fgcal/core/robust_kernel.hpp"
#include "fgcal_test/jacobian_check.hpp"

using namespace fgcal;

namespace {
MatX randomSpd(int n, unsigned seed) {
  std::mt19937 gen(seed);
  std::normal_distribution<double> d;
  MatX A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = d(gen);
  return A * A.transpose() + 0.1 * MatX::Identity(n, n);
}
}  // namespace

TEST_CASE("whitening from a full covariance gives W^T W = Sigma^-1") {
  const MatX S = randomSpd(6, 1);
  const auto nm = NoiseModel::fromCovariance(S);
  const MatX& W = nm->sqrtInformation();
  CHECK((W.transpose() * W - S.inverse()).norm() < 1e-9 * S.inverse().norm());
  CHECK((nm->covariance() - S).norm() < 1e-9 * S.norm());
  // whitenResidual and whitenJacobian agree with W r and W J.
  VecX r = VecX::LinSpaced(6, -1.0, 2.0);
  CHECK((nm->whiten(r) - W * r).norm() < 1e-12);
  MatX J = randomSpd(6, 2).leftCols(4);
  MatX Jw = J;
  nm->whitenJacobian(Jw.data(), 4, 6);
  CHECK((Jw - W * J).norm() < 1e-12);
  // The packed triangle the factors' fast paths whiten with is W's upper
  // triangle, column by column, and W is zero below its diagonal.
  using Access = internal::NoiseModelAccess;
  for (int k = 0; k < 6; ++k)
    for (int i = 0; i < 6; ++i) {
      if (i <= k)
        CHECK(Access::upperTriangle(*nm)[Access::upperIndex(i, k)] == W(i, k));
      else
        CHECK(W(i, k) == 0.0);
    }
}

TEST_CASE("general-size whitening of a Jacobian block with a column stride matches W J") {
  const MatX S = randomSpd(9, 5);
  const auto nm = NoiseModel::fromCovariance(S);
  const MatX W = nm->sqrtInformation();
  CHECK((W.transpose() * W - S.inverse()).norm() < 1e-9 * S.inverse().norm());
  // A 9x3 block inside a 12-row buffer: the rows past 9 must stay untouched.
  MatX buffer = MatX::Constant(12, 3, 7.0);
  buffer.topRows(9) = randomSpd(9, 6).leftCols(3);
  const MatX J = buffer.topRows(9);
  nm->whitenJacobian(buffer.data(), 3, 12);
  CHECK((buffer.topRows(9) - W * J).norm() < 1e-12 * (W * J).norm());
  CHECK((buffer.bottomRows(3).array() == 7.0).all());
  const auto dg = NoiseModel::diagonal(VecX::LinSpaced(9, 0.5, 4.5));
  MatX Jd = J;
  dg->whitenJacobian(Jd.data(), 3, 9);
  CHECK((Jd - dg->sqrtInformation() * J).norm() < 1e-12 * J.norm());
}

TEST_CASE("whitening from an information matrix, diagonal and isotropic") {
  const MatX L = randomSpd(4, 3);
  const auto nm = NoiseModel::fromInformation(L);
  CHECK((nm->information() - L).norm() < 1e-9 * L.norm());
  // whitenResidual's general-size triangular path (n = 4).
  const VecX r4 = VecX::LinSpaced(4, -1.0, 2.0);
  CHECK((nm->whiten(r4) - nm->sqrtInformation() * r4).norm() < 1e-12);
  const auto dg = NoiseModel::diagonal(Eigen::Vector3d(0.1, 2.0, 0.5));
  CHECK(dg->isDiagonal());
  CHECK((dg->whiten(Eigen::Vector3d(1, 1, 1)) - Eigen::Vector3d(10, 0.5, 2)).norm() < 1e-12);
  const auto iso = NoiseModel::isotropic(6, 0.01);
  CHECK(iso->whiten(VecX::Ones(6)).isApprox(VecX::Constant(6, 100.0)));
  // A diagonal covariance becomes the cheap diagonal model.
  CHECK(NoiseModel::fromCovariance(Eigen::Vector2d(4.0, 9.0).asDiagonal().toDenseMatrix())->isDiagonal());
}

TEST_CASE("covariances that are not SPD or hold NaN are rejected with a clear error") {
  MatX S = randomSpd(3, 4);
  MatX asym = S;
  asym(0, 1) += 0.5;
  CHECK_THROWS_WITH(NoiseModel::fromCovariance(asym), Catch::Contains("not symmetric"));
  MatX indef = S;
  indef(2, 2) = -5.0;
  CHECK_THROWS_WITH(NoiseModel::fromCovariance(indef), Catch::Contains("not positive definite"));
  MatX singular = MatX::Zero(3, 3);
  singular(0, 0) = 1.0;
  CHECK_THROWS_AS(NoiseModel::fromCovariance(singular), InvalidNoiseModel);
  MatX nan = S;
  nan(1, 1) = std::nan("");
  CHECK_THROWS_WITH(NoiseModel::fromCovariance(nan), Catch::Contains("NaN"));
  CHECK_THROWS_WITH(NoiseModel::fromInformation(MatX::Zero(2, 3)), Catch::Contains("square"));
  CHECK_THROWS_AS(NoiseModel::diagonal(Eigen::Vector2d(1.0, 0.0)), InvalidNoiseModel);
  CHECK_THROWS_AS(NoiseModel::diagonal(Eigen::Vector2d(1.0, -2.0)), InvalidNoiseModel);
  CHECK_THROWS_AS(NoiseModel::isotropic(3, std::numeric_limits<double>::infinity()), InvalidNoiseModel);
}

TEST_CASE("robust kernels: rho ~ s near zero, weight is rho', outliers down-weighted") {
  for (const auto& k : {huber(1.5), cauchy(1.5), tukey(3.0)}) {
    INFO(k->name());
    CHECK(k->rho(1e-6) == Approx(1e-6).epsilon(1e-3));
    CHECK(k->weight(0.0) == Approx(1.0));
    for (double s : {0.01, 0.5, 2.0, 4.0, 30.0, 400.0}) {
      const double h = 1e-6 * std::max(1.0, s);
      const double numeric = (k->rho(s + h) - k->rho(s - h)) / (2 * h);
      CHECK(k->weight(s) == Approx(numeric).margin(1e-6));
    }
    CHECK(k->weight(400.0) < 0.1);
  }
  CHECK(tukey(3.0)->weight(10.0) == 0.0);
  CHECK_THROWS_AS(huber(0.0), std::invalid_argument);
  CHECK_THROWS_AS(cauchy(-1.0), std::invalid_argument);
}
