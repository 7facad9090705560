// Building a LinearSystem's structure: the errors a graph can raise.
#include <random>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "linear_problems.hpp"

using namespace fgcal;
using namespace fgcal::test;

TEST_CASE("linearization rejects a factor on a variable without a value") {
  Values v;
  v.insert(key('x', 0), SE3());
  FactorGraph g;
  g.emplace<RelativePoseFactor>(key('x', 0), key('x', 9), SE3(), NoiseModel::isotropic(6, 1.0));
  CHECK_THROWS_WITH(LinearSystem(g, v), Catch::Contains("x9"));
}
