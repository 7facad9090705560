// The order of H's columns: value order without the Schur complement; with
// it, an independent set of small variables first (no factor joins two of
// them), so that H's leading block is block diagonal. Fixed variables and
// variables no factor touches get no columns.
#include <random>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "linear_problems.hpp"

using namespace fgcal;
using namespace fgcal::test;

TEST_CASE("the Schur order puts an independent set of small variables first, the rest after") {
  ArrowProblem p = makeArrowProblem(3, 12, 5);
  p.values.insert(key('u', 0), SE3());  // touched by no factor
  LinearSystem plain(p.graph, p.values, {key('c', 1)}, /*order_for_schur=*/false);
  LinearSystem schur(p.graph, p.values, {key('c', 1)}, /*order_for_schur=*/true);
  // Value order: cameras, mount, then the boards, as inserted; c1 fixed, u0 untouched.
  CHECK(plain.numEliminatedBlocks() == 0);
  CHECK(plain.columnOf(key('c', 0)) == 0);
  CHECK(plain.columnOf(key('c', 2)) == 6);
  CHECK(plain.columnOf(key('c', 1)) == -1);
  CHECK(plain.columnOf(key('u', 0)) == -1);
  CHECK(plain.numColumns() == 6 * (3 - 1 + 1 + 12));
  // Schur order: every board pose (each tied to cameras and the mount only),
  // in value order, then the cameras and the mount.
  REQUIRE(schur.numEliminatedBlocks() == 12);
  CHECK(schur.numEliminatedColumns() == 72);
  for (int b = 0; b < 12; ++b) CHECK(schur.columnOf(key('b', b)) == 6 * b);
  CHECK(schur.columnOf(key('c', 0)) >= schur.numEliminatedColumns());
  CHECK(schur.columnOf(key('m', 0)) >= schur.numEliminatedColumns());
  CHECK(schur.columnOf(key('c', 1)) == -1);
  // No two eliminated blocks are neighbours in H: its leading block is block diagonal.
  for (std::size_t b = 0; b < schur.numEliminatedBlocks(); ++b) {
    const auto& bc = schur.blocks()[b];
    for (std::size_t k = bc.neighbour_begin; k < bc.neighbour_end; ++k)
      CHECK(schur.blockNeighbours()[k].block >= schur.numEliminatedBlocks());
  }
  CHECK(schur.keyOfColumn(schur.columnOf(key('b', 7)) + 5) == key('b', 7));
}

TEST_CASE("two variables a factor joins are never both in the elimination set") {
  // A chain x0 - x1 - x2 - x3 of relative poses: an independent set takes
  // at most every other pose.
  FactorGraph g;
  Values v;
  for (int i = 0; i < 4; ++i) v.insert(key('x', i), SE3::exp(Vec6::Constant(0.1 * i)));
  g.emplace<PriorFactorSE3>(key('x', 0), SE3(), NoiseModel::isotropic(6, 1.0));
  for (int i = 0; i + 1 < 4; ++i)
    g.emplace<RelativePoseFactor>(key('x', i), key('x', i + 1), SE3(), NoiseModel::isotropic(6, 1.0));
  LinearSystem sys(g, v, {}, /*order_for_schur=*/true);
  REQUIRE(sys.numEliminatedBlocks() == 2);
  std::vector<bool> eliminated(4);
  for (int i = 0; i < 4; ++i) eliminated[i] = sys.columnOf(key('x', i)) < sys.numEliminatedColumns();
  for (int i = 0; i + 1 < 4; ++i) CHECK_FALSE((eliminated[i] && eliminated[i + 1]));
}
