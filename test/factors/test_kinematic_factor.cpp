// The kinematic factor: Jacobians against central differences away from zero
// residual, zero residual at a consistent configuration, and the marker
// covariance against Monte Carlo.
#include <random>

#include "fgcal/factors/kinematic_factor.hpp"
#include "fgcal_test/jacobian_check.hpp"

using namespace fgcal;

TEST_CASE("kinematic factor Jacobians match central differences") {
  const auto pts = fgcal::test::se3TestPoints(41);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    Values v;
    v.insert(key('b', 0), pts[i]);
    v.insert(key('m', 0), pts[(i + 2) % pts.size()]);
    KinematicFactor f(key('b', 0), key('m', 0), pts[(i + 5) % pts.size()], NoiseModel::isotropic(6, 0.01));
    if (f.error(v).head<3>().norm() > M_PI - 1e-3) continue;
    const auto bad = checkFactorJacobians(f, v);
    INFO((bad.empty() ? "" : bad[0].message));
    CHECK(bad.empty());
  }
}

TEST_CASE("kinematic factor is zero where L = FK * M") {
  const auto pts = fgcal::test::se3TestPoints(43);
  const SE3 link = pts[4], mount = pts[6];
  Values v;
  v.insert(key('b', 0), link * mount);
  v.insert(key('m', 0), mount);
  KinematicFactor f(key('b', 0), key('m', 0), link, NoiseModel::isotropic(6, 0.01));
  CHECK(f.error(v).norm() < 1e-12);
}

TEST_CASE("marker covariance matches the Monte-Carlo spread of a perturbed link pose") {
  std::mt19937 gen(5);
  std::normal_distribution<double> n;
  const SE3 link = fgcal::test::se3TestPoints(47)[5];
  const SE3 mount(SO3::exp(Vec3(0.3, -0.2, 1.0)), Vec3(0.02, -0.05, 0.1));
  Mat6 S = Mat6::Zero();
  S.diagonal() << 1e-4, 2e-4, 1e-4, 4e-6, 1e-6, 9e-6;
  S(0, 4) = S(4, 0) = 5e-6;
  const Eigen::LLT<Mat6> llt(S);
  const Mat6 predicted = KinematicFactor::markerCovariance(S, mount);
  const SE3 marker = link * mount;
  Mat6 sample = Mat6::Zero();
  const int N = 40000;
  for (int k = 0; k < N; ++k) {
    Vec6 z;
    for (int i = 0; i < 6; ++i) z[i] = n(gen);
    const Vec6 e = marker.minus(link.plus(llt.matrixL() * z) * mount);
    sample += e * e.transpose();
  }
  sample /= N;
  for (int i = 0; i < 6; ++i) CHECK(sample(i, i) == Approx(predicted(i, i)).epsilon(0.05));
}
