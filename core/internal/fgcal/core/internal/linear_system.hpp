// Linearization of a factor graph around an estimate: the whitened,
// robust-reweighted Jacobian J assembled directly in compressed-column form,
// the whitened residual r, and the normal equations H = J^T J (the upper
// triangle, as CHOLMOD reads it) with g = J^T r. Both sparsity patterns are
// computed once, at construction, and reused at every iteration: factors
// write their blocks straight into precomputed slots.
//
// Internal to the library (the optimizer and marginals build on it; tests and
// benchmarks reach it through fgcal_core_internal). A composition of three
// types with one role each, which it builds in turn and forwards to:
// - ColumnOrdering (column_ordering.hpp, column_ordering.cpp): which
//   variables are free, their columns, key <-> column lookups, retract;
// - SystemPattern (system_pattern.hpp; factor_slots.cpp, jacobian_pattern.cpp,
//   hessian_pattern.cpp): the slots (factor, key), the patterns of J and H,
//   H's block structure and where each factor's blocks land;
// - FactorEvaluator (factor_evaluator.hpp; pairing_schedule.cpp for the fast
//   paths and pairs, factor_blocks.cpp for one factor's whitening, robust
//   reweighting and blocks, linearize.cpp for the threads, cost.cpp,
//   stored_jacobian.cpp for H and g from a stored J): the numbers J, r, H, g.
// linear_system.cpp wires them together.
#pragma once

#include <vector>

#include "fgcal/core/factor_graph.hpp"
#include "fgcal/core/internal/column_ordering.hpp"
#include "fgcal/core/internal/factor_evaluator.hpp"
#include "fgcal/core/internal/linear_system_options.hpp"
#include "fgcal/core/internal/sparse_matrix.hpp"
#include "fgcal/core/internal/system_pattern.hpp"

namespace fgcal {

class LinearSystem {
 public:
  using Index = CscMatrix::Index;

  /// Builds the structure. Variables listed in `fixed`, and variables no factor
  /// touches, are held constant. With order_for_schur, an independent set of
  /// variables (no factor joins two of them, e.g. a calibration's board poses)
  /// gets the first columns, so that H = [[A B] [B^T C]] with A block diagonal.
  /// Throws std::invalid_argument when a factor names a key absent from
  /// `values` or names one key twice.
  LinearSystem(const FactorGraph& graph, const Values& values, const std::vector<Key>& fixed = {},
               bool order_for_schur = false);
  LinearSystem(const FactorGraph& graph, const Values& values, const std::vector<Key>& fixed,
               const LinearSystemOptions& options);
  // The evaluator points at the pattern beside it: neither copied nor moved.
  LinearSystem(const LinearSystem&) = delete;
  LinearSystem& operator=(const LinearSystem&) = delete;

  /// The block structure of H (SystemPattern::BlockColumn): one BlockColumn
  /// per free variable in column order, each listing its neighbours with
  /// smaller columns.
  using BlockColumn = SystemPattern::BlockColumn;
  using BlockNeighbour = SystemPattern::BlockNeighbour;
  const std::vector<BlockColumn>& blocks() const { return pattern_.blocks(); }
  const std::vector<BlockNeighbour>& blockNeighbours() const { return pattern_.blockNeighbours(); }
  /// With order_for_schur: how many leading blocks (and columns) form the eliminable set.
  std::size_t numEliminatedBlocks() const { return ordering_.numEliminatedBlocks(); }
  Index numEliminatedColumns() const { return ordering_.numEliminatedColumns(); }

  /// Evaluates every factor at `values` (which must hold the same keys, in the
  /// same order, as at construction); fills J and r, and the normal equations
  /// H (upper triangle) = J^T J and g = J^T r, accumulated from each factor's
  /// blocks while they are in cache. Returns the total cost 0.5 sum rho(|W r|^2).
  double linearize(const Values& values) { return evaluator_.linearize(values); }
  /// H and g recomputed from J and r as they stand (e.g. after editing J).
  /// Needs store_jacobian (std::logic_error otherwise).
  void formNormalEquations() { evaluator_.formNormalEquations(); }
  /// The total cost at `values`, without Jacobians.
  double cost(const Values& values) const { return evaluator_.cost(values); }

  /// J and r as of the last linearize(); both are empty unless store_jacobian.
  const CscMatrix& jacobian() const { return evaluator_.jacobian(); }
  const VecX& residual() const { return evaluator_.residual(); }
  /// Threads the last linearize() used (1 on graphs too small to share).
  int lastLinearizeThreads() const { return evaluator_.lastLinearizeThreads(); }
  /// H's upper triangle in compressed columns. Its row indices are filled on
  /// the first call (not thread-safe against a concurrent first call).
  const CscMatrix& hessianUpper() const { return evaluator_.hessianUpper(); }
  CscMatrix& hessianUpper() { return evaluator_.hessianUpper(); }
  /// H's values and column pointers alone, for block solvers that never read
  /// its row indices.
  std::vector<double>& hessianValues() { return evaluator_.hessianValues(); }
  const std::vector<double>& hessianValues() const { return evaluator_.hessianValues(); }
  const std::vector<Index>& hessianColumnPointers() const { return evaluator_.hessianColumnPointers(); }
  const VecX& gradient() const { return evaluator_.gradient(); }
  /// Position of H(j, j) in hessianUpper().values: the last entry of column j.
  Index hessianDiagonalPosition(Index j) const { return evaluator_.hessianDiagonalPosition(j); }

  Index numColumns() const { return ordering_.numColumns(); }
  Index numRows() const { return pattern_.numRows(); }
  /// The key owning column `col` (for messages).
  Key keyOfColumn(Index col) const { return ordering_.keyOfColumn(col); }
  /// First column of a key, or -1 when the key is held constant. The key
  /// index behind it is formed on the first call (thread-safe).
  Index columnOf(Key k) const { return ordering_.columnOf(k); }
  /// Tangent dimension of a free key (0 when held constant).
  int dofOf(Key k) const { return ordering_.dofOf(k); }
  /// values <- values ⊕ delta on every free variable.
  void retract(Values& values, const VecX& delta) const { ordering_.retract(values, delta, options_.threads); }
  /// J x (needs store_jacobian).
  VecX multiplyJacobian(const VecX& x) const { return evaluator_.multiplyJacobian(x); }

 private:
  LinearSystemOptions options_;
  ColumnOrdering ordering_;
  SystemPattern pattern_;
  FactorEvaluator evaluator_;
};

}  // namespace fgcal
