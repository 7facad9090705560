// The cost alone (the optimizer's residual-only evaluation) against the
// linearization's and the graph's, and the retraction of the free variables
// by a step in column order.
#include <random>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "linear_problems.hpp"

using namespace fgcal;
using namespace fgcal::test;

TEST_CASE("the cost alone equals the linearization's and the graph's, robust kernels included") {
  ArrowProblem p = makeArrowProblem(3, 30, 21);
  p.graph.emplace<RelativePoseFactor>(key('c', 1), key('b', 4), SE3::exp(Vec6::Constant(0.3)),
                                      NoiseModel::isotropic(6, 0.02), huber(0.1));
  for (bool store_j : {false, true}) {
    INFO("stored J " << store_j);
    LinearSystemOptions o;
    o.order_for_schur = true;
    o.store_jacobian = store_j;
    LinearSystem sys(p.graph, p.values, {}, o);
    const double linearized = sys.linearize(p.values);
    // One thread, the same order and pairs: the same bits (the optimizer
    // compares the two to accept a step).
    CHECK(sys.cost(p.values) == linearized);
    CHECK(linearized == Approx(p.graph.cost(p.values)).epsilon(1e-12));
  }
}

TEST_CASE("retract moves each free variable by its columns of the step and leaves fixed ones") {
  const ArrowProblem p = makeArrowProblem(2, 5, 31);
  LinearSystem sys(p.graph, p.values, {key('c', 1)}, /*order_for_schur=*/true);
  VecX step(sys.numColumns());
  for (Eigen::Index i = 0; i < step.size(); ++i) step[i] = 0.001 * static_cast<double>(i % 7 + 1);
  Values moved = p.values;
  sys.retract(moved, step);
  for (Key k : p.values.keys()) {
    const auto c0 = sys.columnOf(k);
    const Vec6 expected = c0 < 0 ? Vec6::Zero() : Vec6(step.segment<6>(c0));
    CHECK((p.values.at<SE3>(k).minus(moved.at<SE3>(k)) - expected).norm() < 1e-12);
  }
  CHECK(p.values.at<SE3>(key('c', 1)).matrix() == moved.at<SE3>(key('c', 1)).matrix());  // untouched, to the bit
  // A step back returns there.
  sys.retract(moved, -step);
  for (Key k : p.values.keys()) CHECK(p.values.at<SE3>(k).minus(moved.at<SE3>(k)).norm() < 1e-12);
}
