// The evaluation of a graph's factors into its linear system: each factor
// through its type's fast path (alone, or paired with a like factor in one
// call) or through evaluate() and its Jacobian, whitened by its noise model,
// robust-reweighted (IRLS), and accumulated into H (upper triangle) and g
// while its blocks are in cache, on one thread or several; the cost alone;
// J and r kept when stored. It owns these numbers and the order in which the
// factors are evaluated (the schedule); where each block lands it reads from
// the SystemPattern it was built on.
#pragma once

#include <cstddef>
#include <cstdint>
#include <typeinfo>
#include <vector>

#include "fgcal/core/factor_graph.hpp"
#include "fgcal/core/internal/linear_system_options.hpp"
#include "fgcal/core/internal/normal_equations.hpp"
#include "fgcal/core/internal/sparse_matrix.hpp"
#include "fgcal/core/internal/system_pattern.hpp"

namespace fgcal {

class FactorEvaluator {
 public:
  using Index = CscMatrix::Index;

  /// Each factor's fast path and its partner in a pair, seen factor by factor
  /// while the pattern's slots are built (pairing_schedule.cpp).
  class FastPathFinder final : public FactorVisitor {
   public:
    FastPathFinder(std::size_t num_factors, const LinearSystemOptions& options);
    void see(std::size_t f, const Factor& factor) override;
    // The factors in evaluation order: the graph's, except that a factor
    // whose fast path pairs has its partner next, flagged kPairedWithNext.
    std::vector<std::uint32_t> schedule() const;

   private:
    friend class FactorEvaluator;
    struct TypeMet {
      const std::type_info* type;
      const internal::NormalEquations* path;
      std::size_t waiting;  // the last unpaired factor of the type; num_factors_ when none waits
    };
    std::size_t num_factors_;
    bool fast_, pair_;
    // partner_[f]: the factor paired with f (kNoPartner: none); empty when nothing pairs.
    std::vector<std::uint32_t> partner_;
    std::vector<const internal::NormalEquations*> fast_path_;
    std::vector<TypeMet> types_met_;
  };

  FactorEvaluator() = default;
  /// Evaluates `graph`'s factors in `schedule`'s order (finder.schedule())
  /// into `jacobian` (with options.store_jacobian) and `hessian` as `pattern`
  /// laid them out; `pattern` must outlive this object and stay in place.
  FactorEvaluator(const FactorGraph& graph, const LinearSystemOptions& options, const SystemPattern& pattern,
                  FastPathFinder&& finder, std::vector<std::uint32_t> schedule, CscMatrix jacobian, CscMatrix hessian);

  /// See LinearSystem: J, r, H and g at `values`, and the total cost.
  double linearize(const Values& values);
  /// H and g from J and r as they stand (store_jacobian only).
  void formNormalEquations();
  /// The total cost at `values`, without Jacobians.
  double cost(const Values& values) const;
  /// J x (store_jacobian only).
  VecX multiplyJacobian(const VecX& x) const;

  const CscMatrix& jacobian() const { return J_; }
  const VecX& residual() const { return r_; }
  int lastLinearizeThreads() const { return last_threads_; }
  const CscMatrix& hessianUpper() const {
    fillHessianRowIndices();
    return H_;
  }
  CscMatrix& hessianUpper() {
    fillHessianRowIndices();
    h_values_zero_ = false;
    return H_;
  }
  std::vector<double>& hessianValues() {
    h_values_zero_ = false;
    return H_.values;
  }
  const std::vector<double>& hessianValues() const { return H_.values; }
  const std::vector<Index>& hessianColumnPointers() const { return H_.colptr; }
  const VecX& gradient() const { return g_; }
  Index hessianDiagonalPosition(Index j) const { return H_.colptr[j + 1] - 1; }

 private:
  using Slot = SystemPattern::Slot;
  using SlotInJ = SystemPattern::SlotInJ;
  using HBlock = SystemPattern::HBlock;
  const FactorGraph& graph() const { return *graph_; }
  void fillHessianRowIndices() const {
    if (h_rowind_ready_) return;
    pattern_->fillHessianRowIndices(H_);
    h_rowind_ready_ = true;
  }
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
    const std::vector<std::size_t>& slot_begin = pattern_->slotBegin();
    const std::vector<Slot>& slots = pattern_->slots();
    for (std::size_t s = slot_begin[f]; s < slot_begin[f + 1]; ++s)
      out[s - slot_begin[f]] = &values.variableAt(slots[s].value_index);
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
  // Where factor f writes its whitened residual: its rows of r with a stored J,
  // else the end of the thread's scratch.
  double* residualOut(std::size_t f, double* scratch) {
    return store_jacobian_ ? r_.data() + pattern_->factorRows()[f] : scratch + residual_at_;
  }

  // The schedule's entries: a factor index, and this flag on the first of a pair.
  static constexpr std::uint32_t kPairedWithNext = 1u << 31;
  static_assert((kPairedWithNext & SystemPattern::kFactorBits) == 0, "the flag is not part of a factor index");
  // Fast paths (and pairs) are taken for factors of at most kFastKeys keys
  // (pointers to their blocks on the stack).
  static constexpr std::size_t kFastKeys = 16, kFastPairs = kFastKeys * (kFastKeys + 1) / 2;
  // A factor's partner is at most this many places later; kNoPartner: none.
  static constexpr std::size_t kPairWindow = 64;
  static constexpr std::uint32_t kNoPartner = ~std::uint32_t{0};

  const FactorGraph* graph_ = nullptr;
  const SystemPattern* pattern_ = nullptr;
  bool store_jacobian_ = true;
  int threads_ = 1;
  // The factors in evaluation order (FastPathFinder::schedule): blocks of H
  // are first written in this order.
  std::vector<std::uint32_t> schedule_;
  // Per factor, its type's fast path, found once while the structure is
  // built; null for a factor linearized through evaluate() (and for every
  // factor with a stored J, which the fast paths do not form).
  std::vector<const internal::NormalEquations*> fast_path_;

  CscMatrix J_;
  mutable CscMatrix H_;           // mutable: its row indices are filled lazily
  mutable bool h_rowind_ready_ = false;
  bool h_values_zero_ = true;   // H_.values all zero as laid out: the first linearize() need not clear them
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
