// The columns of a linear system: which variables are free (named by a
// factor and not held fixed), the first column and tangent size of each, in
// the values' order or, for the Schur complement, with an elimination set
// first; the lookups between keys and columns, and the retraction of the
// free variables by a step given in these columns. It knows the factors only
// through their slots (which variables each names), and nothing of H's
// pattern or of evaluation.
#pragma once

#include <cstddef>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "fgcal/core/key.hpp"
#include "fgcal/core/types.hpp"
#include "fgcal/core/values.hpp"
#include "fgcal/core/internal/sparse_matrix.hpp"

namespace fgcal {

struct FactorSlots;

class ColumnOrdering {
 public:
  using Index = CscMatrix::Index;

  ColumnOrdering() = default;
  /// The variables of `values` that some factor of `slots` names and `fixed`
  /// does not list get columns, in value order. With order_for_schur, an
  /// independent set of them (no factor joins two, e.g. a calibration's board
  /// poses; elimination_set.hpp) comes first, so that H = [[A B] [B^T C]] with
  /// A block diagonal.
  ColumnOrdering(const Values& values, const FactorSlots& slots, const std::vector<Key>& fixed, bool order_for_schur);

  Index numColumns() const { return num_cols_; }
  std::size_t numVariables() const { return col0_.size(); }
  /// Variable vi's (a position in Values) first column, -1 when held constant.
  Index col0(std::size_t vi) const { return col0_[vi]; }
  /// Variable vi's tangent size (free or not).
  int dof(std::size_t vi) const { return dof_[vi]; }
  /// The free variables' positions in Values, in column order (one block of
  /// columns each).
  const std::vector<std::size_t>& order() const { return order_; }
  /// With order_for_schur: how many leading blocks (and columns) form the eliminable set.
  std::size_t numEliminatedBlocks() const { return num_eliminated_blocks_; }
  Index numEliminatedColumns() const { return num_eliminated_cols_; }

  /// The key owning column `col` (for messages).
  Key keyOfColumn(Index col) const;
  /// First column of a key, or -1 when the key is held constant. The key
  /// index behind it is formed on the first call (thread-safe).
  Index columnOf(Key k) const;
  /// Tangent dimension of a free key (0 when held constant).
  int dofOf(Key k) const;
  /// values <- values ⊕ delta on every free variable, on up to `threads` threads.
  void retract(Values& values, const VecX& delta, int threads) const;

 private:
  // The free variables' value indices in column order; in_set[vi] marks the
  // elimination set (order_for_schur), which comes first.
  std::vector<std::size_t> orderColumns(const FactorSlots& slots, const std::vector<char>& is_free,
                                        std::vector<char>& in_set, bool order_for_schur) const;
  // The block (in column order) of a free key, or -1.
  std::ptrdiff_t blockOf(Key k) const;

  std::vector<Index> col0_;           // per value index, -1 if constant
  std::vector<int> dof_;              // per value index
  std::vector<std::size_t> order_;    // value indices in column order
  std::vector<Key> col_key_;          // per free variable, in column order
  std::size_t num_eliminated_blocks_ = 0;
  Index num_eliminated_cols_ = 0;
  Index num_cols_ = 0;
  // (key, block) sorted by key, for columnOf / dofOf; formed on first use.
  mutable std::vector<std::pair<Key, std::size_t>> key_block_;
  std::unique_ptr<std::once_flag> key_block_once_ = std::make_unique<std::once_flag>();  // null once moved from
};

}  // namespace fgcal
