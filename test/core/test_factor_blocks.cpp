// One factor's contribution to H and g: through its type's fast path or
// through evaluate() and J, whitened and robust-reweighted, with blocks of
// 3 and 6 dof, plain and transposed.
#include <random>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "linear_problems.hpp"

using namespace fgcal;
using namespace fgcal::test;

TEST_CASE("H and g from the factors' own blocks equal those formed through J") {
  // Without a stored J the linearizer takes the factors' fast paths; with
  // one it forms J. Full, diagonal and isotropic noise, robust kernels,
  // a fixed variable, and pairs whose H block is the factor's transposed
  // (the second key's columns first), in both column orders. Measurements
  // are 0.3-0.9 rad off, so every residual is non-zero and Log is smooth.
  const auto pts = fgcal::test::se3TestPoints(37, 6);
  Values v;
  for (int i = 0; i < 5; ++i) v.insert(key('x', i), pts[i + 3]);
  v.insert(key('f', 0), pts[2]);
  auto off = [&](Key a, Key b, int i) {
    Vec6 d;
    d << 0.3, -0.5, 0.4 + 0.1 * i, 0.2, -0.1, 0.3;
    return v.at<SE3>(a).between(v.at<SE3>(b)).plus(d);
  };
  FactorGraph g;
  MatX A(6, 6);
  for (int i = 0; i < 36; ++i) A(i % 6, i / 6) = std::sin(1.0 + 7.0 * i);
  const MatX S = A * A.transpose() + MatX::Identity(6, 6);
  Vec6 sigmas;
  sigmas << 0.1, 0.2, 0.3, 0.4, 0.5, 0.6;
  Vec6 d0;
  d0 << 0.5, 0.1, -0.2, 0.3, 0.2, 0.1;
  g.emplace<PriorFactorSE3>(key('x', 0), v.at<SE3>(key('x', 0)).plus(d0), NoiseModel::fromCovariance(S));
  g.emplace<PriorFactorSE3>(key('x', 3), v.at<SE3>(key('x', 3)).plus(-d0), NoiseModel::diagonal(sigmas), cauchy(0.3));
  for (int i = 0; i + 1 < 5; ++i)
    g.emplace<RelativePoseFactor>(key('x', i + 1), key('x', i), off(key('x', i + 1), key('x', i), i),
                                  NoiseModel::fromCovariance(S));
  g.emplace<RelativePoseFactor>(key('x', 4), key('x', 0), off(key('x', 4), key('x', 0), 5), NoiseModel::isotropic(6, 0.2),
                                huber(0.5));
  g.emplace<RelativePoseFactor>(key('f', 0), key('x', 2), off(key('f', 0), key('x', 2), 6), NoiseModel::isotropic(6, 0.3));
  g.emplace<RelativePoseFactor>(key('x', 1), key('f', 0), off(key('x', 1), key('f', 0), 7), NoiseModel::diagonal(sigmas));
  for (bool schur_order : {false, true}) {
    LinearSystemOptions with_j, without_j;
    with_j.order_for_schur = without_j.order_for_schur = schur_order;
    without_j.store_jacobian = false;
    LinearSystem a(g, v, {key('f', 0)}, with_j), b(g, v, {key('f', 0)}, without_j);
    const double ca = a.linearize(v), cb = b.linearize(v);
    REQUIRE(std::isfinite(ca));
    REQUIRE(a.gradient().allFinite());
    CHECK(cb == Approx(ca).epsilon(1e-13));
    CHECK(b.cost(v) == Approx(ca).epsilon(1e-13));
    CHECK(a.residual().size() == a.numRows());
    CHECK(b.residual().size() == 0);  // r is kept with J only
    CHECK((a.gradient() - b.gradient()).norm() <= 1e-11 * a.gradient().norm());
    const MatX Ha = MatX(a.hessianUpper().eigen()), Hb = MatX(b.hessianUpper().eigen());
    CHECK((Ha - Hb).norm() <= 1e-11 * Ha.norm());
  }
}

TEST_CASE("factors' own blocks of 3 and 6 dof land in H and g as through J") {
  // The points' columns come first (eliminated), so every pose-point block
  // is the factor's transposed: the general-size scatter, plain and transposed,
  // and the 3x3 diagonal.
  const ArrowProblem p = makeMixedProblem(3, 20, 43, /*own_blocks=*/true);
  LinearSystemOptions with_j, without_j;
  with_j.order_for_schur = without_j.order_for_schur = true;
  without_j.store_jacobian = false;
  LinearSystem a(p.graph, p.values, {}, with_j), b(p.graph, p.values, {}, without_j);
  const double ca = a.linearize(p.values), cb = b.linearize(p.values);
  CHECK(cb == Approx(ca).epsilon(1e-13));
  CHECK((a.gradient() - b.gradient()).norm() <= 1e-11 * a.gradient().norm());
  const MatX Ha = MatX(a.hessianUpper().eigen()), Hb = MatX(b.hessianUpper().eigen());
  REQUIRE(Ha.norm() > 0.0);
  CHECK((Ha - Hb).norm() <= 1e-11 * Ha.norm());
}
