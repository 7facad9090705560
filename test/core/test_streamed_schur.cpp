// The streamed Schur complement (no H stored) against the stored one and the
// dense solve: its step, predicted decrease and gradient, with damping,
// robust kernels, fixed variables, eliminated blocks of 3 and 6 dof and both
// the factors' fast paths and their Jacobians; whole optimizations, on one
// thread and two; the variable it names when a block is not positive
// definite, and the graphs it refuses.
#include <algorithm>
#include <cmath>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/internal/streamed_schur.hpp"
#include "fgcal/core/optimizer.hpp"
#include "linear_problems.hpp"

using namespace fgcal;
using namespace fgcal::test;

namespace {

// The largest difference, over the free variables, between values moved by
// two steps (each in its own solver's columns).
double stepDifference(const Values& at, const LinearSystem& sys, const VecX& x, const StreamedSchur& streamed,
                      const VecX& h) {
  Values a = at, b = at;
  sys.retract(a, x);
  streamed.retract(b, h);
  double worst = 0.0;
  VecX d(12);
  for (std::size_t i = 0; i < at.size(); ++i) {
    const Variable& va = a.variableAt(i);
    va.localCoordinates(b.variableAt(i), d.data());
    worst = std::max(worst, d.head(va.dim()).cwiseAbs().maxCoeff());
  }
  return worst;
}

// Checks the streamed step at damping lambda against the dense solve of the
// stored system's (H + lambda diag H) h = -g, its predicted decrease, its
// gradient and its cost.
void checkAgainstDense(const FactorGraph& graph, const Values& values, const std::vector<Key>& fixed, double lambda,
                       int threads = 1) {
  LinearSystem sys(graph, values, fixed, /*order_for_schur=*/true);
  const double cost = sys.linearize(values);
  const VecX g = sys.gradient();
  VecX D(sys.numColumns());
  for (LinearSystem::Index j = 0; j < sys.numColumns(); ++j)
    D[j] = sys.hessianValues()[static_cast<std::size_t>(sys.hessianDiagonalPosition(j))];
  const VecX x = dampAndSolveDense(sys, 1.0 + lambda);  // H_jj in [1e-6, 1e32]: no clamping here
  const double predicted_dense = 0.5 * (lambda * x.dot(D.asDiagonal() * x) - g.dot(x));

  StreamedSchur streamed(graph, values, fixed, threads);
  CHECK(streamed.numColumns() == sys.numColumns());
  CHECK(streamed.numEliminatedBlocks() == sys.numEliminatedBlocks());
  REQUIRE(streamed.reduce(values, {lambda, 1e-6, 1e32}).ok());
  CHECK(streamed.maxGradient() == Approx(g.cwiseAbs().maxCoeff()).epsilon(1e-9));
  VecX h;
  double predicted = 0.0, seconds = 0.0;
  REQUIRE(streamed.solve(values, h, predicted, seconds).ok());
  CHECK(stepDifference(values, sys, x, streamed, h) <= 1e-8 * (1.0 + x.cwiseAbs().maxCoeff()));
  CHECK(h.norm() == Approx(x.norm()).epsilon(1e-8));
  CHECK(predicted == Approx(predicted_dense).epsilon(1e-8));
  CHECK(predicted > 0.0);
  CHECK(streamed.cost(values) == Approx(cost).epsilon(1e-12));
}

// A point's first coordinate, measured 0: information along one axis only.
class FirstCoordinate final : public TypedFactor<1, Vec3> {
 public:
  explicit FirstCoordinate(Key p) : TypedFactor({p}, NoiseModel::isotropic(1, 0.01)) {}
  Residual evaluateTyped(const Vec3& p, Jacobian<Vec3>* J) const override {
    if (J) *J = Eigen::RowVector3d(1.0, 0.0, 0.0);
    return Residual(p.x());
  }
};

}  // namespace

TEST_CASE("the streamed Schur step equals the dense solve on a calibration-shaped system, damped or not") {
  const ArrowProblem p = makeArrowProblem(4, 61, 7);
  for (double lambda : {0.0, 1e-4, 0.5}) {
    INFO("lambda " << lambda);
    checkAgainstDense(p.graph, p.values, {}, lambda);
  }
}

TEST_CASE("the streamed Schur step equals the dense solve with 3- and 6-dof blocks, through Jacobians and fast paths") {
  for (bool own_blocks : {false, true}) {
    INFO((own_blocks ? "the factor's own normal-equation blocks" : "the factor's Jacobians"));
    const ArrowProblem p = makeMixedProblem(3, 30, 41, own_blocks);
    checkAgainstDense(p.graph, p.values, {}, 1e-3);
  }
}

TEST_CASE("the streamed Schur step holds fixed variables and reweights robust factors as the stored system does") {
  ArrowProblem p = makeArrowProblem(3, 40, 13);
  // An outlier, far on Huber's linear part, so the weights matter.
  p.graph.emplace<PriorFactorSE3>(key('b', 5), p.values.at<SE3>(key('b', 5)).plus(Vec6::Constant(0.5)),
                                  NoiseModel::isotropic(6, 0.02), huber(1.345));
  checkAgainstDense(p.graph, p.values, {key('c', 0)}, 1e-2);
  checkAgainstDense(p.graph, p.values, {key('m', 0), key('b', 3)}, 0.0);
}

TEST_CASE("optimizing with the streamed Schur complement reaches the stored one's optimum, LM and Gauss-Newton") {
  // 2,100 board poses: enough for the passes to split over two threads.
  const ArrowProblem p = makeArrowProblem(3, 2100, 5);
  for (auto algorithm : {OptimizerOptions::Algorithm::LevenbergMarquardt, OptimizerOptions::Algorithm::GaussNewton})
    for (int threads : {1, 2}) {
      INFO((algorithm == OptimizerOptions::Algorithm::GaussNewton ? "Gauss-Newton" : "LM") << ", threads "
                                                                                             << threads);
      OptimizerOptions a, b;
      a.algorithm = b.algorithm = algorithm;
      a.threads = b.threads = threads;
      a.linear_solver = OptimizerOptions::LinearSolver::SchurComplement;
      b.linear_solver = OptimizerOptions::LinearSolver::StreamedSchurComplement;
      a.fixed_keys = b.fixed_keys = {key('c', 1)};
      a.relative_cost_tolerance = b.relative_cost_tolerance = 1e-14;
      const OptimizerResult ra = optimize(p.graph, p.values, a), rb = optimize(p.graph, p.values, b);
      REQUIRE(ra.converged);
      REQUIRE(rb.converged);
      CHECK(rb.linear_solver.find("streamed Schur complement (2100 blocks eliminated, 18 reduced columns") == 0);
      CHECK(rb.final_cost == Approx(ra.final_cost).epsilon(1e-9));
      CHECK(rb.initial_cost == Approx(ra.initial_cost).epsilon(1e-12));
      CHECK(std::abs(rb.iterations - ra.iterations) <= 1);
      double worst = 0.0;
      for (Key k : p.values.keys()) worst = std::max(worst, ra.values.at<SE3>(k).minus(rb.values.at<SE3>(k)).norm());
      CHECK(worst < 1e-7);
      CHECK(rb.values.at<SE3>(key('c', 1)).matrix() == p.values.at<SE3>(key('c', 1)).matrix());
      // Every accepted iteration lowered the cost by what its report says.
      for (const IterationReport& rep : rb.reports)
        if (rep.accepted) CHECK(rep.cost_change > 0.0);
    }
}

TEST_CASE("the streamed Schur complement names the eliminated variable that the factors do not constrain") {
  // Point 4 is seen by one camera through one coordinate only: its 3x3 block has rank one.
  ArrowProblem p = makeMixedProblem(2, 6, 3);
  FactorGraph graph;
  for (const auto& f : p.graph) {
    const auto& keys = f->keys();
    if (std::find(keys.begin(), keys.end(), key('p', 4)) == keys.end()) graph.add(f);
  }
  graph.emplace<FirstCoordinate>(key('p', 4));
  OptimizerOptions opt;
  opt.algorithm = OptimizerOptions::Algorithm::GaussNewton;
  opt.linear_solver = OptimizerOptions::LinearSolver::StreamedSchurComplement;
  const OptimizerResult r = optimize(graph, p.values, opt);
  CHECK(r.termination == Termination::NotPositiveDefinite);
  REQUIRE(r.degenerate_keys.size() == 1);
  CHECK(r.degenerate_keys[0] == key('p', 4));
  CHECK(r.message.find("p4") != std::string::npos);
  // The stored Schur complement says the same.
  opt.linear_solver = OptimizerOptions::LinearSolver::SchurComplement;
  const OptimizerResult s = optimize(graph, p.values, opt);
  CHECK(s.termination == Termination::NotPositiveDefinite);
  CHECK(s.degenerate_keys == r.degenerate_keys);

  // At a stationary point the gradient test ends the solve before any
  // factorization, on both solvers, although the block is still singular.
  FactorGraph flat;
  flat.emplace<FirstCoordinate>(key('p', 0));
  Values at;
  at.insert(key('p', 0), Vec3(0.0, 1.0, 2.0));
  for (auto solver : {OptimizerOptions::LinearSolver::SchurComplement,
                      OptimizerOptions::LinearSolver::StreamedSchurComplement}) {
    opt.linear_solver = solver;
    const OptimizerResult f = optimize(flat, at, opt);
    CHECK(f.termination == Termination::SmallGradient);
    CHECK(f.converged);
  }
}

TEST_CASE("the streamed Schur complement refuses a reduced system too large to factor densely, and unknown keys") {
  // A chain of 200 poses: the elimination set takes every other one, and
  // leaves 100 x 6 = 600 reduced columns.
  FactorGraph chain;
  Values values;
  for (int i = 0; i < 200; ++i) {
    values.insert(key('x', i), SE3());
    if (i > 0) chain.emplace<RelativePoseFactor>(key('x', i - 1), key('x', i), SE3(), NoiseModel::isotropic(6, 0.1));
  }
  chain.emplace<PriorFactorSE3>(key('x', 0), SE3(), NoiseModel::isotropic(6, 0.1));
  OptimizerOptions opt;
  opt.linear_solver = OptimizerOptions::LinearSolver::StreamedSchurComplement;
  CHECK_THROWS_WITH(optimize(chain, values, opt), Catch::Contains("more than the 512 it factors densely"));
  // The stored Schur complement takes it.
  opt.linear_solver = OptimizerOptions::LinearSolver::SchurComplement;
  CHECK(optimize(chain, values, opt).converged);

  FactorGraph missing;
  missing.emplace<PriorFactorSE3>(key('y', 3), SE3(), NoiseModel::isotropic(6, 0.1));
  CHECK_THROWS_WITH(StreamedSchur(missing, values, {}, 1), Catch::Contains("y3, which has no initial value"));
}
