// The stored whitened Jacobian J and the normal equations formed from it,
// against a dense assembly from the factors.
#include <random>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "linear_problems.hpp"

using namespace fgcal;
using namespace fgcal::test;

TEST_CASE("linearization: J, H and g equal a dense assembly from the factors") {
  const auto pts = fgcal::test::se3TestPoints(31, 6);
  Values v;
  for (int i = 0; i < 5; ++i) v.insert(key('x', i), pts[i + 3]);
  v.insert(key('f', 0), pts[2]);  // held fixed
  FactorGraph g;
  const MatX S = [] {
    MatX A = MatX::Random(6, 6);
    return MatX(A * A.transpose() + MatX::Identity(6, 6));
  }();
  g.emplace<PriorFactorSE3>(key('x', 0), pts[1], NoiseModel::fromCovariance(S));
  for (int i = 0; i + 1 < 5; ++i)
    g.emplace<RelativePoseFactor>(key('x', i), key('x', i + 1), pts[i], NoiseModel::isotropic(6, 0.5));
  g.emplace<RelativePoseFactor>(key('x', 4), key('x', 0), pts[8], NoiseModel::isotropic(6, 0.2), huber(0.5));
  g.emplace<RelativePoseFactor>(key('f', 0), key('x', 2), pts[9], NoiseModel::isotropic(6, 0.3));

  LinearSystem sys(g, v, {key('f', 0)});
  REQUIRE(sys.numColumns() == 30);
  REQUIRE(sys.numRows() == 6 * static_cast<long>(g.size()));
  const double cost = sys.linearize(v);
  // H and g accumulated during linearization equal those recomputed from J.
  const std::vector<double> H_fused = sys.hessianUpper().values;
  const VecX g_fused = sys.gradient();
  sys.formNormalEquations();
  for (std::size_t i = 0; i < H_fused.size(); ++i)
    CHECK(H_fused[i] == Approx(sys.hessianUpper().values[i]).margin(1e-9));
  CHECK((g_fused - sys.gradient()).norm() < 1e-9 * (1.0 + g_fused.norm()));
  CHECK(cost == Approx(g.cost(v)).epsilon(1e-12));
  CHECK(sys.cost(v) == Approx(cost).epsilon(1e-12));

  // Dense assembly straight from Factor::error.
  MatX Jd = MatX::Zero(sys.numRows(), sys.numColumns());
  VecX rd(sys.numRows());
  int row = 0;
  for (std::size_t f = 0; f < g.size(); ++f) {
    std::vector<MatX> Js;
    const VecX r = g[f].error(v, &Js);
    const MatX& W = g[f].noiseModel().sqrtInformation();
    double scale = 1.0;
    if (g[f].robustKernel()) scale = std::sqrt(g[f].robustKernel()->weight((W * r).squaredNorm()));
    rd.segment(row, 6) = scale * W * r;
    for (std::size_t k = 0; k < g[f].keys().size(); ++k) {
      const auto col = sys.columnOf(g[f].keys()[k]);
      if (col >= 0) Jd.block(row, col, 6, 6) = scale * W * Js[k];
    }
    row += 6;
  }
  const MatX J = MatX(sys.jacobian().eigen());
  CHECK((J - Jd).norm() < 1e-12 * Jd.norm());
  CHECK((sys.residual() - rd).norm() < 1e-12 * rd.norm());
  const MatX H = MatX(sys.hessianUpper().eigen());
  const MatX Hd = Jd.transpose() * Jd;
  CHECK((MatX(H.triangularView<Eigen::Upper>()) - MatX(Hd.triangularView<Eigen::Upper>())).norm() <
        1e-11 * Hd.norm());
  CHECK(MatX(H.triangularView<Eigen::StrictlyLower>()).norm() == 0.0);
  const VecX x = VecX::LinSpaced(sys.numColumns(), -1.0, 1.0);
  CHECK((sys.multiplyJacobian(x) - Jd * x).norm() < 1e-12 * (Jd * x).norm());
  CHECK((sys.gradient() - Jd.transpose() * rd).norm() < 1e-11 * (Jd.transpose() * rd).norm());
  CHECK(sys.columnOf(key('f', 0)) == -1);
  CHECK(sys.keyOfColumn(13) == key('x', 2));
}
