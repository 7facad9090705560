// H's pattern and where each factor's blocks land: a relinearization
// rewrites every entry, whatever H held (the first contribution assigns).
#include <random>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "linear_problems.hpp"

using namespace fgcal;
using namespace fgcal::test;

namespace {
// Linearizes at `values`, scribbles over H, linearizes at `moved` and
// compares H and g with J^T J and J^T r summed from a stored J into a cleared
// H (formNormalEquations) at `moved`.
void checkRelinearizationOverScribbledH(const FactorGraph& graph, const Values& values, const Values& moved,
                                        const std::vector<Key>& fixed, LinearSystemOptions o) {
  LinearSystem sys(graph, values, fixed, o);
  sys.linearize(values);
  for (double& h : sys.hessianValues()) h = 1e3 * h + 7.0;
  sys.linearize(moved);
  LinearSystemOptions with_j = o;
  with_j.store_jacobian = true;
  with_j.threads = 1;
  LinearSystem ref(graph, moved, fixed, with_j);
  ref.linearize(moved);
  ref.formNormalEquations();
  CHECK(relativeMaxDifference(sys.hessianValues(), ref.hessianValues()) <= 1e-12);
  CHECK((sys.gradient() - ref.gradient()).norm() <= 1e-12 * ref.gradient().norm());
}
Values movedBy(const Values& v, double d) {
  Values out = v;
  for (Key k : v.keys()) {
    if (v.variable(k).type() == typeid(SE3))
      out.insertOrAssign(k, v.at<SE3>(k).plus(Vec6::Constant(d)));
    else
      out.insertOrAssign(k, Vec3(v.at<Vec3>(k) + Vec3::Constant(d)));
  }
  return out;
}
}  // namespace

TEST_CASE("a second linearization rewrites every entry of H, whatever H held") {
  // On one thread each block of H is assigned by its first contribution and
  // added to by the others, without clearing H; on two threads H is cleared
  // and summed. Blocks with one contribution and with several (a repeated
  // factor, a prior beside relative poses), factors with their own blocks
  // and through J (the points), a robust kernel, a fixed variable, both
  // column orders, with and without a stored J.
  ArrowProblem p = makeArrowProblem(3, 9, 43);
  p.graph.emplace<RelativePoseFactor>(key('c', 1), key('b', 4), SE3::exp(Vec6::Constant(0.05)),
                                      NoiseModel::isotropic(6, 0.02));  // a second factor on one pair
  p.graph.emplace<RelativePoseFactor>(key('c', 2), key('b', 5), SE3::exp(Vec6::Constant(0.4)),
                                      NoiseModel::isotropic(6, 0.02), huber(0.1));
  ArrowProblem mixed = makeMixedProblem(3, 12, 47);
  mixed.graph.emplace<PriorFactorSE3>(key('c', 1), SE3::exp(Vec6::Constant(0.3)), NoiseModel::isotropic(6, 0.1),
                                      cauchy(0.2));
  for (bool schur_order : {false, true})
    for (bool store_j : {false, true}) {
      INFO("schur order " << schur_order << ", stored J " << store_j);
      LinearSystemOptions o;
      o.order_for_schur = schur_order;
      o.store_jacobian = store_j;
      checkRelinearizationOverScribbledH(p.graph, p.values, movedBy(p.values, 0.03), {}, o);
      checkRelinearizationOverScribbledH(mixed.graph, mixed.values, movedBy(mixed.values, 0.02), {key('c', 2)}, o);
    }
  // Two threads (enough factors that both are used).
  const ArrowProblem big = makeArrowProblem(3, 5000, 11);
  LinearSystemOptions two;
  two.order_for_schur = true;
  two.store_jacobian = false;
  two.threads = 2;
  LinearSystem probe(big.graph, big.values, {}, two);
  probe.linearize(big.values);
  REQUIRE(probe.lastLinearizeThreads() == 2);
  checkRelinearizationOverScribbledH(big.graph, big.values, movedBy(big.values, 0.01), {}, two);
}
