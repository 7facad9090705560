// Linearization of a factor graph around an estimate: the whitened,
// robust-reweighted Jacobian J assembled directly in compressed-column form,
// the whitened residual r, and the normal equations H = J^T J (the upper
// triangle, as CHOLMOD reads it) with g = J^T r. Both sparsity patterns are
// computed once, at construction, and reused at every iteration: factors
// write their blocks straight into precomputed slots.
//
// Internal to the library (the optimizer and marginals build on it; tests and
// benchmarks reach it through fgcal_core_internal). Its definitions are split
// by concern: linear_system.cpp (the structure), column_ordering.cpp,
// jacobian_pattern.cpp, hessian_pattern.cpp, pairing_schedule.cpp,
// factor_blocks.cpp (whitening, robust reweighting, the blocks of one
// factor), linearize.cpp (threads) and cost_and_retraction.cpp.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <typeinfo>
#include <utility>
#include <vector>

#include "fgcal/core/factor_graph.hpp"
#include "fgcal/core/internal/linear_system_options.hpp"
#include "fgcal/core/internal/normal_equations.hpp"
#include "fgcal/core/internal/sparse_matrix.hpp"

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
  const std::vector<BlockColumn>& blocks() const { return blocks_; }
  const std::vector<BlockNeighbour>& blockNeighbours() const { return block_neighbours_; }
  /// With order_for_schur: how many leading blocks (and columns) form the eliminable set.
  std::size_t numEliminatedBlocks() const { return num_eliminated_blocks_; }
  Index numEliminatedColumns() const { return num_eliminated_cols_; }

  /// Evaluates every factor at `values` (which must hold the same keys, in the
  /// same order, as at construction); fills J and r, and the normal equations
  /// H (upper triangle) = J^T J and g = J^T r, accumulated from each factor's
  /// blocks while they are in cache. Returns the total cost 0.5 sum rho(|W r|^2).
  double linearize(const Values& values);
  /// H and g recomputed from J and r as they stand (e.g. after editing J).
  /// Needs store_jacobian (std::logic_error otherwise).
  void formNormalEquations();
  /// The total cost at `values`, without Jacobians.
  double cost(const Values& values) const;

  /// J and r as of the last linearize(); both are empty unless store_jacobian.
  const CscMatrix& jacobian() const { return J_; }
  const VecX& residual() const { return r_; }
  /// Threads the last linearize() used (1 on graphs too small to share).
  int lastLinearizeThreads() const { return last_threads_; }
  /// H's upper triangle in compressed columns. Its row indices are filled on
  /// the first call (not thread-safe against a concurrent first call).
  const CscMatrix& hessianUpper() const {
    fillHessianRowIndices();
    return H_;
  }
  CscMatrix& hessianUpper() {
    fillHessianRowIndices();
    h_values_zero_ = false;
    return H_;
  }
  /// H's values and column pointers alone, for block solvers that never read
  /// its row indices.
  std::vector<double>& hessianValues() {
    h_values_zero_ = false;
    return H_.values;
  }
  const std::vector<double>& hessianValues() const { return H_.values; }
  const std::vector<Index>& hessianColumnPointers() const { return H_.colptr; }
  const VecX& gradient() const { return g_; }
  /// Position of H(j, j) in hessianUpper().values: the last entry of column j.
  Index hessianDiagonalPosition(Index j) const { return H_.colptr[j + 1] - 1; }

  Index numColumns() const { return num_cols_; }
  Index numRows() const { return num_rows_; }
  /// The key owning column `col` (for messages).
  Key keyOfColumn(Index col) const;
  /// First column of a key, or -1 when the key is held constant. The key
  /// index behind it is formed on the first call (thread-safe).
  Index columnOf(Key k) const;
  /// Tangent dimension of a free key (0 when held constant).
  int dofOf(Key k) const;
  /// values <- values ⊕ delta on every free variable.
  void retract(Values& values, const VecX& delta) const;
  /// J x (needs store_jacobian).
  VecX multiplyJacobian(const VecX& x) const;

 private:
  struct Slot {                // one (factor, key) pair: 16 bytes
    std::uint32_t value_index;  // position in Values
    int dof;
    Index col0;                 // first column, or -1 when constant
  };
  struct SlotInJ {  // where a free slot's block sits in J_.values (store_jacobian only)
    Index start;    // column 0 of the block
    Index stride;   // distance between the block's columns
  };
  struct HBlock {                // one contribution J_p^T J_q of a factor to H
    std::uint32_t slot_p : 31;   // slot_p has the smaller column
    std::uint32_t assign : 1;    // the first contribution to its block, in schedule_ order
    std::uint32_t slot_q;
    Index h_start;               // offset of row0_p within each column of q in H_
  };

  // The structure (linear_system.cpp), the column order (column_ordering.cpp),
  // the patterns of J and H (jacobian_pattern.cpp, hessian_pattern.cpp).
  void build(const Values& values, const std::vector<Key>& fixed);
  class FastPathFinder;
  void buildSlots(const Values& values, FastPathFinder& finder, std::vector<char>& touched);
  void assignColumns(const Values& values, const std::vector<char>& is_free);
  // The free variables' value indices in column order; in_set[vi] marks the
  // elimination set (order_for_schur), which comes first.
  std::vector<std::size_t> orderColumns(const std::vector<char>& is_free, std::vector<char>& in_set) const;
  void buildJacobianPattern(const FactorGraph& graph);
  void buildHessianPattern();  // in these steps:
  struct NeighbourPairs;
  NeighbourPairs neighbourPairs() const;
  void layOutHessian(const NeighbourPairs& np);
  void buildBlockStructure(const NeighbourPairs& np);
  void assignHessianBlocks(const NeighbourPairs& np);
  void fillHessianRowIndices() const;
  // The block (in column order) of a free key, or -1.
  std::ptrdiff_t blockOf(Key k) const;
  // One factor's contribution (factor_blocks.cpp).
  // Evaluates factor f, whitens and reweights it, writes r (and J when stored)
  // and adds its blocks to the normal equations in H_values / g.
  // `pos` is its place in schedule_.
  double evaluateFactor(std::size_t pos, const Values& values, double* scratch_J, double* H_values, double* g);
  // Its generic path's steps: whitening (and J's copy), then H and g.
  double whitenFactor(std::size_t f, double* r, double* const* jp);
  void addNormalEquations(std::size_t pos, int d, const double* r, double* const* jp, double* H_values,
                          double* g) const;
  // The factors at pos and pos + 1, a pair: their costs added to `cost` in that order.
  void evaluatePair(std::size_t pos, const Values& values, double* scratch, double* H_values, double* g,
                    double& cost);
  // The blocks of the factor's fast path added into H and g; its cost.
  double linearizeFromFactorBlocks(std::size_t pos, const internal::NormalEquations& path,
                                   const Variable* const* vars, double* scratch, double* H_values, double* g);
  // The variables of factor f's keys, in key order, into out[0 .. keys).
  // Inlined into each caller (linearization and cost, per factor).
#if defined(__GNUC__)
  __attribute__((always_inline))
#endif
  void gatherVariables(std::size_t f, const Values& values, const Variable** out) const {
    for (std::size_t s = slot_begin_[f]; s < slot_begin_[f + 1]; ++s)
      out[s - slot_begin_[f]] = &values.variableAt(slots_[s].value_index);
  }
  // Where factor f's gradient parts (gp) and pair blocks (hp) go in `scratch`.
  void factorBlockPointers(std::size_t f, double* scratch, double** gp, double** hp) const;
  // The cost of the factor at `pos` from its whitened residual r, and its
  // blocks gp, hp (robust-reweighted) added into H and g.
  double accumulateFactorBlocks(std::size_t pos, double* r, const double* const* gp, const double* const* hp,
                                double* H_values, double* g) const;
  std::size_t factorAt(std::size_t pos) const { return schedule_[pos] & ~kPairedWithNext; }
  bool pairedWithNext(std::size_t pos) const { return (schedule_[pos] & kPairedWithNext) != 0; }
  // single(pos) for each place of [p0, p1), pair(pos) instead for the first
  // of a pair (then pos + 1 is the second); a pair split by p1 goes singly.
  // linearize() and cost() both walk the schedule through it (on one thread
  // they must meet the same pairs, for the same bits).
  template <class Single, class Pair>
  void walkSchedule(std::size_t p0, std::size_t p1, Single&& single, Pair&& pair) const {
    for (std::size_t pos = p0; pos < p1; ++pos) {
      if (pairedWithNext(pos) && pos + 1 < p1)
        pair(pos++);
      else
        single(pos);
    }
  }
  // Each factor's fast path and its partner, seen factor by factor while the
  // structure is built (pairing_schedule.cpp).
  class FastPathFinder {
   public:
    explicit FastPathFinder(LinearSystem& system);
    void see(std::size_t f, const Factor& factor);
    // partners()[f]: the factor paired with f (kNoPartner: none); empty when nothing pairs.
    const std::vector<std::uint32_t>& partners() const { return partner_; }

   private:
    struct TypeMet {
      const std::type_info* type;
      const internal::NormalEquations* path;
      std::size_t waiting;  // the last unpaired factor of the type; num_factors_ when none waits
    };
    LinearSystem& system_;
    std::size_t num_factors_;
    bool fast_, pair_;
    std::vector<std::uint32_t> partner_;
    std::vector<TypeMet> types_met_;
  };
  void buildSchedule(const std::vector<std::uint32_t>& partner);
  // Where factor f writes its whitened residual: its rows of r with a stored J,
  // else the end of the thread's scratch.
  double* residualOut(std::size_t f, double* scratch) {
    return options_.store_jacobian ? r_.data() + factor_row_[f] : scratch + residual_at_;
  }

  const FactorGraph& graph_;
  LinearSystemOptions options_;
  std::vector<Index> factor_row_;       // first residual row of each factor (store_jacobian only)
  std::vector<std::size_t> slot_begin_; // slots of factor f: [slot_begin_[f], slot_begin_[f+1])
  std::vector<Slot> slots_;
  std::vector<SlotInJ> slot_in_j_;  // parallel to slots_, with store_jacobian
  std::vector<HBlock> hblocks_;
  std::vector<std::size_t> hblock_begin_;  // per place in schedule_
  // The factors in evaluation order: the graph's, except that a factor whose
  // fast path pairs has the next factor of its type within kPairWindow places
  // next, flagged kPairedWithNext. Blocks of H are first written in this order.
  static constexpr std::uint32_t kPairedWithNext = 1u << 31;
  // Fast paths (and pairs) are taken for factors of at most kFastKeys keys
  // (pointers to their blocks on the stack).
  static constexpr std::size_t kFastKeys = 16, kFastPairs = kFastKeys * (kFastKeys + 1) / 2;
  // A factor's partner is at most this many places later; kNoPartner: none.
  static constexpr std::size_t kPairWindow = 64;
  static constexpr std::uint32_t kNoPartner = ~std::uint32_t{0};
  std::vector<std::uint32_t> schedule_;
  // Per factor, its type's fast path, found once while the structure is
  // built; null for a factor linearized through evaluate() (and for every
  // factor with a stored J, which the fast paths do not form).
  std::vector<const internal::NormalEquations*> fast_path_;
  std::vector<Index> var_col0_;            // per value index, -1 if constant
  std::vector<int> var_dof_;
  std::vector<Key> col_key_;               // per free variable (in column order, as blocks_)
  std::vector<std::size_t> col_order_;  // value indices in column order
  std::vector<BlockColumn> blocks_;
  std::vector<BlockNeighbour> block_neighbours_;
  std::size_t num_eliminated_blocks_ = 0;
  Index num_eliminated_cols_ = 0;
  // (key, block) sorted by key, for columnOf / dofOf; formed on first use.
  mutable std::vector<std::pair<Key, std::size_t>> key_block_;
  std::unique_ptr<std::once_flag> key_block_once_ = std::make_unique<std::once_flag>();  // null once moved from
  Index num_rows_ = 0, num_cols_ = 0;
  std::size_t num_values_ = 0;
  int max_dim_ = 0, max_dof_ = 0;
  std::size_t max_keys_ = 0;  // the most keys of one factor

  CscMatrix J_;
  mutable CscMatrix H_;           // mutable: its row indices are filled lazily
  mutable bool h_rowind_ready_ = false;
  bool h_values_zero_ = false;  // H_.values all zero as built: the first linearize() need not clear them
  bool assign_first_ = false;   // this linearize(): blocks' first contributions assign (one thread)
  VecX r_, g_;
  // A factor's blocks, then its residual (residual_at_); twice, for a pair.
  std::vector<double> scratch_;
  std::size_t residual_at_ = 0;
  std::size_t scratch_half_ = 0;  // one factor's part of the scratch; the pair's second factor uses the next
  // Per extra thread: its scratch, H values and g (summed into H_, g_).
  struct ThreadBuffers {
    std::vector<double> scratch, H;
    VecX g;
  };
  std::vector<ThreadBuffers> thread_buffers_;
  int last_threads_ = 1;
};

}  // namespace fgcal
