// The sparsity of a linear system, computed once and reused at every
// linearization: the slots (one per factor and key it names), the patterns of
// the whitened Jacobian J and of H's upper triangle (which it lays out in the
// matrices the evaluator fills), H's block structure for the block solvers,
// and where each factor's contributions land in H (the first contribution to
// a block assigns it, the others add). It knows nothing of values or of how
// factors are evaluated.
//
// Built in two steps: FactorSlots (each factor's variables; ColumnOrdering
// reads them to give the free variables their columns), then SystemPattern,
// which takes the slots over and places their columns.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "fgcal/core/factor_graph.hpp"
#include "fgcal/core/internal/sparse_matrix.hpp"

namespace fgcal {

class ColumnOrdering;

/// Told of each factor, in the graph's order, while FactorSlots are built
/// (the factor is then in cache): another pass over the factors rides on it.
class FactorVisitor {
 public:
  virtual void see(std::size_t f, const Factor& factor) = 0;

 protected:
  ~FactorVisitor() = default;
};

/// The structure builders' errors for a factor's key (std::invalid_argument
/// naming the factor and the key): k has no value in Values, or factor f names
/// it a second time.
[[noreturn]] void throwKeyWithoutValue(std::size_t f, const Factor& factor, Key k);
[[noreturn]] void throwKeyNamedTwice(std::size_t f, Key k);

/// Each factor's variables: one slot per (factor, key).
struct FactorSlots {
  using Index = CscMatrix::Index;
  struct Slot {                 // one (factor, key) pair: 16 bytes
    std::uint32_t value_index;  // position in Values
    int dof;
    Index col0;                 // first column, or -1 when constant (or not yet placed)
  };

  /// Throws std::invalid_argument when a factor names a key absent from
  /// `values` or names one key twice. Rows of r are counted per factor only
  /// with store_jacobian (factor_row).
  FactorSlots(const FactorGraph& graph, const Values& values, bool store_jacobian, FactorVisitor& visitor);

  std::vector<std::size_t> begin;  // slots of factor f: [begin[f], begin[f+1])
  std::vector<Slot> slots;
  std::vector<Index> factor_row;   // first residual row of each factor (store_jacobian only)
  std::vector<int> dofs;           // per value index: its tangent size, read once
  std::vector<char> touched;       // per value index: named by some factor
  Index num_rows = 0;
  int max_dim = 0, max_dof = 0;
};

class SystemPattern {
 public:
  using Index = CscMatrix::Index;
  using Slot = FactorSlots::Slot;
  struct SlotInJ {  // where a free slot's block sits in J's values (store_jacobian only)
    Index start;    // column 0 of the block
    Index stride;   // distance between the block's columns
  };
  struct HBlock {                // one contribution J_p^T J_q of a factor to H
    std::uint32_t slot_p : 31;   // slot_p has the smaller column
    std::uint32_t assign : 1;    // the first contribution to its block, in the evaluation order
    std::uint32_t slot_q;
    Index h_start;               // offset of row0_p within each column of q in H
  };
  /// The block structure of H: one BlockColumn per free variable in column
  /// order, each listing its neighbours with smaller columns. Entry (a0 + r,
  /// b0 + c) of an off-diagonal block sits at H.values[H.colptr[b0 + c] +
  /// offset + r]; entry (r <= c) of a diagonal block at
  /// H.values[H.colptr[b0 + c] + neighbour_rows + r].
  struct BlockColumn {
    Index col0;
    int dof;
    std::size_t neighbour_begin, neighbour_end;
    Index neighbour_rows;
  };
  struct BlockNeighbour {
    std::size_t block;
    Index offset;
  };
  /// An evaluation order holds factor indices in these bits of each entry
  /// (a factor index is below 2^31: FactorSlots refuses 2^31 slots); the
  /// bit above them is the evaluator's.
  static constexpr std::uint32_t kFactorBits = (1u << 31) - 1;

  SystemPattern() = default;
  /// Takes `slots` over and places their columns (`ordering`). Lays out J in
  /// `jacobian` when given (column pointers, row indices, zero values) and H's
  /// upper triangle in `hessian` (column pointers and zero values; its row
  /// indices wait for fillHessianRowIndices), and finds where each factor's
  /// blocks land in them, the factors taken in the order of `schedule`
  /// (entry & kFactorBits).
  SystemPattern(const FactorGraph& graph, FactorSlots slots, const ColumnOrdering& ordering,
                const std::vector<std::uint32_t>& schedule, CscMatrix* jacobian, CscMatrix& hessian);

  std::size_t numVariables() const { return num_values_; }
  Index numRows() const { return num_rows_; }
  /// Factor f's slots: [slotBegin()[f], slotBegin()[f + 1]) of slots().
  const std::vector<std::size_t>& slotBegin() const { return slot_begin_; }
  const std::vector<Slot>& slots() const { return slots_; }
  /// With a stored J: each factor's first row, each slot's block in J.
  const std::vector<Index>& factorRows() const { return factor_row_; }
  const std::vector<SlotInJ>& slotsInJ() const { return slot_in_j_; }
  /// The contributions to H of the factor at place pos of the evaluation
  /// order: hblocks()[hblockBegin()[pos] .. hblockBegin()[pos + 1]).
  const std::vector<HBlock>& hblocks() const { return hblocks_; }
  const std::vector<std::size_t>& hblockBegin() const { return hblock_begin_; }
  const std::vector<BlockColumn>& blocks() const { return blocks_; }
  const std::vector<BlockNeighbour>& blockNeighbours() const { return block_neighbours_; }
  /// The largest residual, tangent size and number of keys of one factor.
  int maxDim() const { return max_dim_; }
  int maxDof() const { return max_dof_; }
  std::size_t maxKeys() const { return max_keys_; }
  /// H's row indices, from the block structure, into `hessian` as laid out.
  void fillHessianRowIndices(CscMatrix& hessian) const;

 private:
  void buildJacobianPattern(const FactorGraph& graph, const ColumnOrdering& ordering, CscMatrix& J);
  struct NeighbourPairs;  // H's pattern, in these steps:
  NeighbourPairs neighbourPairs(const ColumnOrdering& ordering) const;
  void layOutHessian(const NeighbourPairs& np, const ColumnOrdering& ordering, CscMatrix& H) const;
  void buildBlockStructure(const NeighbourPairs& np, const ColumnOrdering& ordering);
  void assignHessianBlocks(const NeighbourPairs& np, const ColumnOrdering& ordering,
                           const std::vector<std::uint32_t>& schedule);

  std::size_t num_values_ = 0;
  Index num_rows_ = 0;
  int max_dim_ = 0, max_dof_ = 0;
  std::size_t max_keys_ = 0;
  std::vector<Index> factor_row_;       // store_jacobian only
  std::vector<std::size_t> slot_begin_;
  std::vector<Slot> slots_;
  std::vector<SlotInJ> slot_in_j_;      // parallel to slots_, with store_jacobian
  std::vector<HBlock> hblocks_;
  std::vector<std::size_t> hblock_begin_;  // per place in the evaluation order
  std::vector<BlockColumn> blocks_;
  std::vector<BlockNeighbour> block_neighbours_;
};

}  // namespace fgcal
