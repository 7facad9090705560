// The Schur complement without H: the normal equations of a graph whose
// eliminated variables are many (a calibration's board poses) and whose
// reduced system is small (its cameras and mount), solved without storing
// anything per eliminated variable. Each eliminated variable's factors are
// evaluated together, its block damped and reduced into the dense reduced
// system at once; once that is solved, they are evaluated again for the
// variable's step. Memory is that of the factors and the values; the price is
// a second evaluation of the factors per solve (and both evaluations again
// for each rejected Levenberg-Marquardt step, which SchurSolver answers from
// the stored H).
//
// Internal to the library: the optimizer's LinearSolver::StreamedSchurComplement.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "fgcal/core/factor_graph.hpp"
#include "fgcal/core/internal/normal_equations.hpp"
#include "fgcal/core/internal/sparse_cholesky.hpp"
#include "fgcal/core/internal/sparse_matrix.hpp"

namespace fgcal {

namespace detail {
class DenseCholesky;
}

class StreamedSchur {
 public:
  using Index = CscMatrix::Index;
  struct Damping {
    double lambda = 0.0;  // H_jj + lambda clamp(H_jj, min_diagonal, max_diagonal)
    double min_diagonal = 1e-6;
    double max_diagonal = 1e32;
  };

  /// The structure: the free variables (touched by a factor, not in `fixed`),
  /// the elimination set (elimination_set.hpp) and each eliminated
  /// variable's factors. Throws std::invalid_argument when a factor names a
  /// key absent from `values` or one key twice, or when the reduced system
  /// would have more than OptimizerOptions::kStreamedMaxReducedColumns columns
  /// (it is factored densely). `threads` >= 1.
  StreamedSchur(const FactorGraph& graph, const Values& values, const std::vector<Key>& fixed, int threads);
  ~StreamedSchur();
  StreamedSchur(const StreamedSchur&) = delete;
  StreamedSchur& operator=(const StreamedSchur&) = delete;

  std::size_t numEliminatedBlocks() const { return elim_value_.size(); }
  Index numColumns() const { return num_cols_; }
  Index reducedColumns() const { return num_cols_ - reduced_col0_; }

  /// Evaluates every factor at `values` and reduces (H + lambda D) h = -g to
  /// the reduced variables; D = clamp(diag H). NotPositiveDefinite, with the
  /// column, when an eliminated block is (maxGradient() is then still that of
  /// all of g). `values` must hold the keys of construction, in the same order.
  SolverStatus reduce(const Values& values, const Damping& damping);
  /// max |g| at the last reduce().
  double maxGradient() const { return max_gradient_; }
  /// The damping of the last reduce().
  double lambda() const { return damping_.lambda; }
  /// After reduce() at the same `values`: the step h = -(H + lambda D)^-1 g
  /// (columns: the eliminated variables in value order, then the reduced
  /// ones), and the decrease 0.5 h^T (lambda D h - g) that the linear model
  /// predicts. `factor_seconds` receives the time spent evaluating factors.
  SolverStatus solve(const Values& values, VecX& step, double& predicted, double& factor_seconds);
  /// The total cost 0.5 sum rho(|W r|^2) at `values`, without Jacobians.
  double cost(const Values& values) const;
  /// values <- values ⊕ step on every free variable.
  void retract(Values& values, const VecX& step) const;
  /// The key owning column `col`.
  Key keyOfColumn(Index col) const;

 private:
  struct Scratch;
  // The structure, built once by the constructor in these steps.
  void indexFactorSlots(const Values& values, std::vector<char>& touched);
  std::vector<std::uint32_t> orderColumns(const std::vector<char>& in_set, const std::vector<char>& is_free);
  void groupFactors(const std::vector<char>& in_set, const std::vector<char>& is_free,
                    const std::vector<std::uint32_t>& elim_index);
  void layOutReducedSystem();
  // Factor f's whitened, robust-reweighted gradient parts g[i] and pair
  // blocks H[k] (pairs i <= j in the order (0,0), (0,1), ..., (1,1), ...) into
  // the scratch; returns its cost.
  double factorBlocks(std::size_t f, const Values& values, Scratch& s) const;
  // Eliminated variable e's block A (undamped), its couplings B to the
  // reduced variables its factors touch (s.touched), g_e; with `reduced`,
  // also the factors' reduced-reduced blocks and gradient into S and g_r.
  void gatherBlock(std::size_t e, const Values& values, Scratch& s, bool reduced) const;
  // Eliminated variable e's gathered block folded into the scratch's S and
  // rhs (damped by damping_); a block that is not positive definite sets its status.
  void eliminateBlock(std::size_t e, Scratch& s) const;
  // The reduced-only factors' blocks into S and g_r.
  void addReducedFactor(std::size_t f, const Values& values, Scratch& s) const;

  const FactorGraph& graph_;
  int threads_ = 1;
  std::size_t num_values_ = 0;
  std::vector<std::size_t> slot_begin_;   // factor f's keys: [slot_begin_[f], slot_begin_[f + 1])
  std::vector<std::uint32_t> slot_value_;  // the value index of each (factor, key)
  std::vector<const internal::NormalEquations*> fast_path_;  // per factor, or null
  std::vector<Index> var_col0_;  // per value index; -1 when held constant
  std::vector<int> var_dof_;
  std::vector<std::uint32_t> elim_value_;         // eliminated variables, in column order
  std::vector<std::size_t> elim_factor_begin_;    // their factors: [begin[e], begin[e + 1]) of elim_factors_
  std::vector<std::uint32_t> elim_factors_;
  std::vector<std::uint32_t> reduced_factors_;    // factors on reduced variables only
  std::vector<std::uint32_t> reduced_value_;      // reduced variables, in column order
  std::vector<Key> keys_of_free_;                 // the eliminated, then the reduced variables' keys
  Index num_cols_ = 0, reduced_col0_ = 0;
  int max_keys_ = 0, max_dof_ = 0, max_dim_ = 0;

  Damping damping_;
  CscMatrix S_;  // the reduced system's upper triangle, every entry present (dense)
  VecX rhs_;     // -g_r + B^T A^-1 g_e
  VecX g_r_;     // the reduced variables' gradient
  VecX reduced_diag_;  // H's undamped diagonal on the reduced columns
  double max_gradient_ = 0.0;
  std::unique_ptr<detail::DenseCholesky> dense_;
};

}  // namespace fgcal
