// Nonlinear least squares on a factor graph: Gauss-Newton or
// Levenberg-Marquardt with Nielsen's damping update, over the sparse normal
// equations and CHOLMOD. The symbolic analysis is done once; each iteration
// relinearizes, refills H in place and refactorizes numerically.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fgcal/core/factor_graph.hpp"
#include "fgcal/core/values.hpp"

namespace fgcal {

struct OptimizerOptions {
  enum class Algorithm { GaussNewton, LevenbergMarquardt };
  Algorithm algorithm = Algorithm::LevenbergMarquardt;
  /// SparseCholesky: CHOLMOD on the whole of H. SchurComplement: eliminate an
  /// independent set of small variables (e.g. board poses) first, CHOLMOD on
  /// the reduced system. Auto: Schur when that set covers >= 75 % of the columns.
  /// StreamedSchurComplement: the Schur complement without storing H, for
  /// graphs of many small eliminated variables and a small reduced system (at
  /// most kStreamedMaxReducedColumns columns, else optimize() throws
  /// std::invalid_argument): each eliminated variable's factors are evaluated
  /// together and reduced at once, and evaluated again for its step, so that
  /// memory is that of the factors and values alone. Each iteration evaluates
  /// the factors about twice as often (and both passes again for a rejected
  /// Levenberg-Marquardt step). Auto never picks it; BENCHMARKS.md has both
  /// solvers' times and memory.
  enum class LinearSolver { Auto, SparseCholesky, SchurComplement, StreamedSchurComplement };
  /// The largest reduced system StreamedSchurComplement takes (it factors it densely).
  static constexpr int kStreamedMaxReducedColumns = 512;
  LinearSolver linear_solver = LinearSolver::Auto;
  int max_iterations = 100;
  /// Stop when (cost_before - cost_after) < relative_cost_tolerance * cost_before.
  double relative_cost_tolerance = 1e-10;
  /// Stop when the cost itself falls below this.
  double absolute_cost_tolerance = 1e-14;
  /// Stop when |step| (Euclidean norm of the tangent step) falls below this.
  double step_tolerance = 1e-10;
  /// Stop when max |J^T r| falls below this.
  double gradient_tolerance = 1e-12;
  /// LM: the first damping lambda (relative to the diagonal of H, Marquardt
  /// scaling); finite and > 0, else optimize() throws std::invalid_argument.
  double initial_lambda = 1e-4;
  /// LM: the diagonal used for damping is clamped to [min_diagonal,
  /// max_diagonal]; 0 <= min_diagonal <= max_diagonal, else optimize() throws
  /// std::invalid_argument (for Gauss-Newton too).
  double min_diagonal = 1e-6;
  double max_diagonal = 1e32;
  /// Before solving, compare every factor's Jacobians with central differences
  /// (and stop with JacobianCheckFailed when one differs).
  bool check_jacobians = false;
  double jacobian_check_tolerance = 1e-5;
  /// Variables held at their initial value.
  std::vector<Key> fixed_keys;
  /// Threads for evaluating factors and eliminating blocks on large graphs
  /// (0: every core; negative is an error). Factors must then be safe to
  /// evaluate concurrently. Sums are then split by thread, so results differ
  /// from a single-threaded run in the last bits, and depend on the count.
  int threads = 1;
  /// Called after every iteration.
  std::function<void(const struct IterationReport&)> callback;
};

struct IterationReport {
  int iteration = 0;
  double cost = 0.0;         // after the iteration (the accepted estimate)
  double cost_change = 0.0;  // cost before - cost after (0 when rejected)
  double step_norm = 0.0;
  double lambda = 0.0;  // LM damping used (0 for Gauss-Newton)
  bool accepted = false;
  double linearize_seconds = 0.0;  // evaluation, J assembly and normal equations
  double solve_seconds = 0.0;      // numeric factorization and triangular solves
  double total_seconds = 0.0;
};

enum class Termination {
  RelativeCostDecrease,
  AbsoluteCost,
  SmallStep,
  SmallGradient,
  MaxIterations,
  NoDecrease,  // Gauss-Newton step increased the cost, or LM damping exhausted
  NotPositiveDefinite,
  JacobianCheckFailed,
  NonFiniteCost,
};
std::string toString(Termination t);

struct OptimizerResult {
  Values values;
  Termination termination = Termination::MaxIterations;
  /// True when it stopped on one of the convergence tests.
  bool converged = false;
  std::string message;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int iterations = 0;
  std::vector<IterationReport> reports;
  double linearize_seconds = 0.0;
  double analyze_seconds = 0.0;
  double solve_seconds = 0.0;
  double total_seconds = 0.0;
  /// "sparse Cholesky (ordering)", "Schur complement (N blocks eliminated, M reduced columns, dense|sparse)"
  /// or "streamed Schur complement (N blocks eliminated, M reduced columns, dense)".
  std::string linear_solver;
  /// Keys involved when the system was not positive definite.
  std::vector<Key> degenerate_keys;
};

/// Minimizes 0.5 sum rho(|W r|^2) starting from `initial`.
OptimizerResult optimize(const FactorGraph& graph, const Values& initial, const OptimizerOptions& options = {});

}  // namespace fgcal
