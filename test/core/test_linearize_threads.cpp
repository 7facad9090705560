// Linearization on several threads: the same H, g and cost as on one, and
// an exception on a worker reaching the caller.
#include <random>

#include "fgcal/core/internal/schur_solver.hpp"
#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "linear_problems.hpp"

using namespace fgcal;
using namespace fgcal::test;

TEST_CASE("threaded linearization and Schur elimination equal the single-threaded ones") {
  // Large enough that two threads are really used (checked below).
  const ArrowProblem p = makeArrowProblem(3, 5000, 5);
  LinearSystemOptions one, two;
  one.order_for_schur = two.order_for_schur = true;
  two.threads = 2;
  two.store_jacobian = false;
  LinearSystem s1(p.graph, p.values, {}, one), s2(p.graph, p.values, {}, two);
  const double c1 = s1.linearize(p.values), c2 = s2.linearize(p.values);
  REQUIRE(s1.lastLinearizeThreads() == 1);
  REQUIRE(s2.lastLinearizeThreads() == 2);  // else this would compare one thread with one
  CHECK(c2 == Approx(c1).epsilon(1e-13));
  // The cost alone (the optimizer's last step), on one and on two threads.
  CHECK(s1.cost(p.values) == Approx(c1).epsilon(1e-13));
  CHECK(s2.cost(p.values) == Approx(c1).epsilon(1e-13));
  CHECK_THROWS_AS(s2.cost(Values()), std::invalid_argument);
  CHECK(relativeMaxDifference(s2.hessianUpper().values, s1.hessianUpper().values) <= 1e-12);
  CHECK((s1.gradient() - s2.gradient()).norm() <= 1e-12 * s1.gradient().norm());

  // Without a stored J, what needs it says so instead of reading garbage.
  CHECK(s1.jacobian().nonZeros() > 0);
  CHECK(s2.jacobian().nonZeros() == 0);
  CHECK_THROWS_AS(s2.multiplyJacobian(VecX::Zero(s2.numColumns())), std::logic_error);
  CHECK_THROWS_AS(s2.formNormalEquations(), std::logic_error);

  SchurSolver e1(s1), e2(s2, 2);
  VecX x1, x2;
  REQUIRE(e1.solve(-s1.gradient(), x1).ok());
  REQUIRE(e2.solve(-s2.gradient(), x2).ok());
  CHECK((x1 - x2).norm() <= 1e-9 * (1.0 + x1.norm()));

  // The optimizer with two threads reaches the same estimate.
  OptimizerOptions o1, o2;
  o2.threads = 2;
  const OptimizerResult r1 = optimize(p.graph, p.values, o1), r2 = optimize(p.graph, p.values, o2);
  REQUIRE(r1.converged);
  REQUIRE(r2.converged);
  CHECK(r2.final_cost == Approx(r1.final_cost).epsilon(1e-9));
  for (Key k : {key('c', 0), key('c', 2), key('m', 0), key('b', 4999)})
    CHECK(r1.values.at<SE3>(k).minus(r2.values.at<SE3>(k)).norm() < 1e-8);
}

TEST_CASE("an exception thrown while evaluating on a worker thread reaches the caller") {
  struct Throwing final : TypedFactor<6, SE3> {
    using TypedFactor::TypedFactor;
    Residual evaluateTyped(const SE3& x, Jacobian<SE3>* J) const override {
      if (x.translation().x() > 1e6) throw std::runtime_error("bad factor");
      if (J) J->setIdentity();
      return x.log();
    }
  };
  FactorGraph g;
  Values v;
  for (int i = 0; i < 10000; ++i) {
    v.insert(key('x', i), SE3());
    g.emplace<Throwing>(std::vector<Key>{key('x', i)}, NoiseModel::isotropic(6, 1.0));
  }
  v.insertOrAssign(key('x', 9999), SE3(SO3(), Vec3(2e6, 0, 0)));  // on the second thread's half
  LinearSystemOptions two;
  two.threads = 2;
  LinearSystem sys(g, v, {}, two);
  CHECK_THROWS_WITH(sys.linearize(v), "bad factor");
  CHECK(sys.lastLinearizeThreads() == 2);
  CHECK_THROWS_WITH(sys.cost(v), "bad factor");
  two.threads = 0;
  CHECK_THROWS_AS(LinearSystem(g, v, {}, two), std::invalid_argument);
}
