#include "fgcal/core/optimizer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/internal/schur_solver.hpp"
#include "fgcal/core/internal/sparse_cholesky.hpp"
#include "fgcal/core/internal/streamed_schur.hpp"

namespace fgcal {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

int threadsOf(const OptimizerOptions& opt) {
  return opt.threads > 0 ? opt.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

bool isConvergence(Termination t) {
  return t == Termination::RelativeCostDecrease || t == Termination::AbsoluteCost || t == Termination::SmallStep ||
         t == Termination::SmallGradient;
}

}  // namespace

std::string toString(Termination t) {
  switch (t) {
    case Termination::RelativeCostDecrease: return "relative cost decrease below tolerance";
    case Termination::AbsoluteCost: return "cost below absolute tolerance";
    case Termination::SmallStep: return "step below tolerance";
    case Termination::SmallGradient: return "gradient below tolerance";
    case Termination::MaxIterations: return "maximum number of iterations reached";
    case Termination::NoDecrease: return "no step decreases the cost";
    case Termination::NotPositiveDefinite: return "normal equations not positive definite";
    case Termination::JacobianCheckFailed: return "a factor's Jacobian differs from central differences";
    case Termination::NonFiniteCost: return "cost is not finite";
  }
  return "unknown";
}

namespace {

void checkOptions(const OptimizerOptions& opt) {
  if (opt.threads < 0)
    throw std::invalid_argument("OptimizerOptions::threads must be >= 0 (0: every core), got " +
                                std::to_string(opt.threads));
  if (!(opt.min_diagonal >= 0.0) || !(opt.min_diagonal <= opt.max_diagonal))
    throw std::invalid_argument("OptimizerOptions::min_diagonal (" + std::to_string(opt.min_diagonal) +
                                ") must be >= 0 and <= max_diagonal (" + std::to_string(opt.max_diagonal) + ")");
  // LM raises lambda by factors of 2 and more after a failed step: from 0 it would stay 0.
  if (opt.algorithm == OptimizerOptions::Algorithm::LevenbergMarquardt &&
      (!(opt.initial_lambda > 0.0) || !std::isfinite(opt.initial_lambda)))
    throw std::invalid_argument("OptimizerOptions::initial_lambda must be finite and > 0 for Levenberg-Marquardt, "
                                "got " + std::to_string(opt.initial_lambda));
}

// Every factor's Jacobians (and the solver's fast path, where it takes one)
// against central differences; the report of the first few that differ.
std::optional<std::string> jacobianCheckFailures(const FactorGraph& graph, const Values& values, double tolerance) {
  std::ostringstream msg;
  int bad = 0;
  for (std::size_t f = 0; f < graph.size(); ++f)
    for (const auto& m : checkFactorJacobians(graph[f], values, 1e-6, tolerance))
      if (bad++ < 5) msg << "factor " << f << ": " << m.message << "\n";
  if (!bad) return std::nullopt;
  msg << bad << " Jacobian block(s) in all differ from central differences";
  return msg.str();
}

// The failure of a solve: its message, and the variable whose column broke
// down (recorded in res.degenerate_keys), if any.
template <class KeyOfColumn>
std::string degenerateMessage(const SolverStatus& st, KeyOfColumn&& keyOfColumn, OptimizerResult& res) {
  std::ostringstream msg;
  msg << st.message;
  if (st.failed_column >= 0) {
    const Key k = keyOfColumn(st.failed_column);
    res.degenerate_keys.push_back(k);
    msg << ": variable " << keyToString(k) << " is not constrained by the factors (gauge freedom or degenerate data)";
  }
  return msg.str();
}

// One run of optimize(): the linear system at the current estimate, its
// solver, and the damping. Each iteration solves for a step, moves the
// estimate and evaluates there; gaussNewtonStep and levenbergMarquardtStep
// decide what to keep.
class Run {
 public:
  Run(const FactorGraph& graph, const OptimizerOptions& opt, OptimizerResult& res)
      : opt_(opt), res_(res), lambda_(opt.initial_lambda), sys_(graph, res.values, opt.fixed_keys, systemOptions(opt)) {
    using LS = OptimizerOptions::LinearSolver;
    use_schur_ = sys_.numEliminatedBlocks() > 0 &&
                 (opt.linear_solver == LS::SchurComplement ||
                  (opt.linear_solver == LS::Auto &&
                   sys_.numEliminatedColumns() >= 0.75 * static_cast<double>(sys_.numColumns())));
    // The Schur solver damps the diagonal as it reads H; for CHOLMOD H itself
    // is damped, its diagonal kept here to undo that.
    diag_.resize(use_schur_ ? 0 : static_cast<std::size_t>(sys_.numColumns()));
  }

  // The cost at the start, with H and g there.
  double initialCost() {
    const auto t0 = Clock::now();
    const double cost = sys_.linearize(res_.values);
    res_.linearize_seconds += since(t0);
    return cost;
  }
  CscMatrix::Index numColumns() const { return sys_.numColumns(); }
  // max |g| at the estimate (H and g are those of the estimate).
  double maxGradient(IterationReport&) {
    const VecX& g = sys_.gradient();
    return g.size() == 0 ? 0.0 : g.cwiseAbs().maxCoeff();
  }

  // The solver for H's structure (made only on the path that uses it:
  // CHOLMOD's start-up is not free); its symbolic analysis.
  SolverStatus analyze(int threads) {
    if (use_schur_) {
      schur_ = std::make_unique<SchurSolver>(sys_, threads);
      res_.linear_solver = "Schur complement (" + std::to_string(sys_.numEliminatedBlocks()) +
                           " blocks eliminated, " + std::to_string(schur_->reducedSize()) + " reduced columns, " +
                           (schur_->reducedIsDense() ? "dense" : "sparse") + ")";
      return {};
    }
    chol_ = std::make_unique<SparseCholesky>();
    const SolverStatus st = chol_->analyze(sys_.hessianUpper());
    res_.linear_solver = "sparse Cholesky (" + chol_->ordering() + ")";
    return st;
  }

  // Keeps H's diagonal (CHOLMOD path) before the damped solves of an iteration.
  void keepDiagonal() {
    const std::vector<double>& Hv = sys_.hessianValues();
    for (std::size_t j = 0; j < diag_.size(); ++j) diag_[j] = Hv[diagonalAt(j)];
  }
  void restoreDiagonal() {
    std::vector<double>& Hv = sys_.hessianValues();
    for (std::size_t j = 0; j < diag_.size(); ++j) Hv[diagonalAt(j)] = diag_[j];
  }

  // (H + lambda D) h = -g, D = diag(clamp(H_jj)); lambda 0: Gauss-Newton.
  // Also the decrease the linear model 0.5 |r + J h|^2 predicts: since
  // (H + lambda D) h = -g, it is 0.5 h^T (lambda D h - g), O(n) instead of a
  // pass over J.
  SolverStatus solve(double lambda, IterationReport& rep, double& predicted) {
    if (lambda > 0.0) {
      std::vector<double>& Hv = sys_.hessianValues();
      for (std::size_t j = 0; j < diag_.size(); ++j) Hv[diagonalAt(j)] = diag_[j] + lambda * clamped(diag_[j]);
    }
    const VecX& g = sys_.gradient();
    const auto t0 = Clock::now();
    // Solved as -(H + lambda D)^-1 g: the same bits (negation is exact),
    // without a copy of -g (48 MB at N = 10^6).
    double damping_term = 0.0;  // h^T D h
    SolverStatus st;
    if (use_schur_) {
      st = schur_->solve(g, step_, {lambda, opt_.min_diagonal, opt_.max_diagonal},
                         lambda > 0.0 ? &damping_term : nullptr);
    } else {
      st = chol_->factorize(sys_.hessianUpper());
      if (st.ok()) st = chol_->solve(g, step_);
    }
    rep.solve_seconds += since(t0);
    if (!st.ok()) return st;
    step_ = -step_;
    rep.step_norm = step_.norm();
    if (lambda > 0.0 && !use_schur_)
      for (std::size_t j = 0; j < diag_.size(); ++j) damping_term += clamped(diag_[j]) * step_[j] * step_[j];
    predicted = 0.5 * (lambda * damping_term - g.dot(step_));
    return st;
  }

  // Moves the estimate by the step and evaluates there: the cost alone when
  // the model promises less than the stopping rule asks (the step is then
  // most likely the last), else a whole linearization (which the next
  // iteration uses when the step is accepted, the usual case).
  double tryStep(double cost, double predicted, IterationReport& rep, bool& cost_only) {
    sys_.retract(res_.values, step_);
    cost_only = predicted < opt_.relative_cost_tolerance * cost;
    const auto t0 = Clock::now();
    const double new_cost = cost_only ? sys_.cost(res_.values) : sys_.linearize(res_.values);
    rep.linearize_seconds += since(t0);
    return new_cost;
  }
  void undoStep() { sys_.retract(res_.values, -step_); }
  void relinearize(IterationReport& rep) {
    const auto t0 = Clock::now();
    sys_.linearize(res_.values);
    rep.linearize_seconds += since(t0);
  }

  // The failure of a solve: the variable whose column broke down, if any.
  std::string degenerate(const SolverStatus& st) {
    restoreDiagonal();
    return degenerateMessage(st, [&](CscMatrix::Index c) { return sys_.keyOfColumn(c); }, res_);
  }

  const OptimizerOptions& opt_;
  OptimizerResult& res_;
  double lambda_, nu_ = 2.0;

 private:
  static LinearSystemOptions systemOptions(const OptimizerOptions& opt) {
    LinearSystemOptions lso;
    lso.order_for_schur = opt.linear_solver != OptimizerOptions::LinearSolver::SparseCholesky;
    lso.store_jacobian = false;  // the solvers need only H and g
    lso.threads = threadsOf(opt);
    return lso;
  }
  std::size_t diagonalAt(std::size_t j) const {
    return static_cast<std::size_t>(sys_.hessianDiagonalPosition(static_cast<CscMatrix::Index>(j)));
  }
  double clamped(double d) const { return std::clamp(d, opt_.min_diagonal, opt_.max_diagonal); }

  LinearSystem sys_;
  bool use_schur_ = false;
  std::unique_ptr<SparseCholesky> chol_;
  std::unique_ptr<SchurSolver> schur_;
  std::vector<double> diag_;
  VecX step_;  // lives across iterations (no fresh temporary of the system's size per solve)
};

// The same run over StreamedSchur (LinearSolver::StreamedSchurComplement):
// nothing of H is stored, so each solve evaluates the factors at the
// estimate, reducing them with the damping of that solve, and again for the
// eliminated variables' steps; a trial point is evaluated for its cost only.
class StreamedRun {
 public:
  StreamedRun(const FactorGraph& graph, const OptimizerOptions& opt, OptimizerResult& res)
      : opt_(opt), res_(res), lambda_(opt.initial_lambda), schur_(graph, res.values, opt.fixed_keys, threadsOf(opt)) {}

  double initialCost() {
    const auto t0 = Clock::now();
    const double cost = schur_.cost(res_.values);
    res_.linearize_seconds += since(t0);
    return cost;
  }
  CscMatrix::Index numColumns() const { return schur_.numColumns(); }
  SolverStatus analyze(int) {
    res_.linear_solver = "streamed Schur complement (" + std::to_string(schur_.numEliminatedBlocks()) +
                         " blocks eliminated, " + std::to_string(schur_.reducedColumns()) + " reduced columns, dense)";
    return {};
  }
  // max |g| at the estimate, from the reduction the next solve uses (its
  // damping is the one lambda_ holds now); a failed reduction still gives
  // it, and the solve then reports the failure.
  double maxGradient(IterationReport& rep) {
    reduceAt(nextLambda(), rep);
    return schur_.maxGradient();
  }
  void keepDiagonal() {}

  SolverStatus solve(double lambda, IterationReport& rep, double& predicted) {
    if (!reduced_ || lambda != schur_.lambda()) reduceAt(lambda, rep);
    if (!status_.ok()) {
      reduced_ = false;
      return status_;
    }
    const auto t0 = Clock::now();
    double factor_seconds = 0.0;
    const SolverStatus st = schur_.solve(res_.values, step_, predicted, factor_seconds);
    rep.linearize_seconds += factor_seconds;
    rep.solve_seconds += since(t0) - factor_seconds;
    if (!st.ok()) return st;
    rep.step_norm = step_.norm();
    return st;
  }
  // The cost alone at the trial point: H is never formed ahead of a solve.
  double tryStep(double, double, IterationReport& rep, bool& cost_only) {
    schur_.retract(res_.values, step_);
    reduced_ = false;
    cost_only = true;
    const auto t0 = Clock::now();
    const double new_cost = schur_.cost(res_.values);
    rep.linearize_seconds += since(t0);
    return new_cost;
  }
  void undoStep() {
    schur_.retract(res_.values, -step_);
    reduced_ = false;
  }
  void relinearize(IterationReport&) {}  // the next solve evaluates the factors anyway
  std::string degenerate(const SolverStatus& st) {
    return degenerateMessage(st, [&](CscMatrix::Index c) { return schur_.keyOfColumn(c); }, res_);
  }

  const OptimizerOptions& opt_;
  OptimizerResult& res_;
  double lambda_, nu_ = 2.0;

 private:
  double nextLambda() const {
    return opt_.algorithm == OptimizerOptions::Algorithm::LevenbergMarquardt ? lambda_ : 0.0;
  }
  void reduceAt(double lambda, IterationReport& rep) {
    const auto t0 = Clock::now();
    status_ = schur_.reduce(res_.values, {lambda, opt_.min_diagonal, opt_.max_diagonal});
    rep.linearize_seconds += since(t0);
    reduced_ = true;
  }

  StreamedSchur schur_;
  SolverStatus status_;
  bool reduced_ = false;
  VecX step_;
};

// How an iteration ended: a step taken at new_cost, none, or a failed solve.
struct StepOutcome {
  bool accepted = false;
  double new_cost = 0.0;
  std::optional<std::string> failure;  // the solve's message (NotPositiveDefinite)
};

// Whether an accepted step ends the solve, and how: one rule, read before
// deciding to linearize at the step and again after accepting it.
std::optional<Termination> stopAfterStep(const OptimizerOptions& opt, double old_cost, double new_cost,
                                         double step_norm) {
  if (new_cost < opt.absolute_cost_tolerance) return Termination::AbsoluteCost;
  if (old_cost - new_cost < opt.relative_cost_tolerance * old_cost) return Termination::RelativeCostDecrease;
  if (step_norm < opt.step_tolerance) return Termination::SmallStep;
  return std::nullopt;
}

// Gauss-Newton: the undamped step, kept when it lowers the cost.
template <class R>
StepOutcome gaussNewtonStep(R& run, double cost, bool last_iteration, IterationReport& rep) {
  StepOutcome out{false, cost, std::nullopt};
  double predicted = 0.0;
  const SolverStatus st = run.solve(0.0, rep, predicted);
  if (!st.ok()) {
    out.failure = run.degenerate(st);
    return out;
  }
  bool cost_only = false;
  out.new_cost = run.tryStep(cost, predicted, rep, cost_only);
  if (!(std::isfinite(out.new_cost) && cost - out.new_cost > 0.0)) {
    run.undoStep();  // no damping to fall back on
    return out;
  }
  out.accepted = true;
  // The last iteration or a stopping step needs no H and g at the new estimate.
  const bool last = last_iteration || stopAfterStep(run.opt_, cost, out.new_cost, rep.step_norm).has_value();
  if (cost_only && !last) run.relinearize(rep);
  return out;
}

// Levenberg-Marquardt with Nielsen's update: damped steps until one lowers
// the cost as the model predicts (at most 20 tries), lambda raised after
// each failure and lowered by the gain ratio after a success.
template <class R>
StepOutcome levenbergMarquardtStep(R& run, double cost, bool last_iteration, IterationReport& rep) {
  StepOutcome out{false, cost, std::nullopt};
  for (int attempt = 0; attempt < 20; ++attempt) {
    double predicted = 0.0;
    const SolverStatus st = run.solve(run.lambda_, rep, predicted);
    if (!st.ok()) {
      if (st.code == SolverStatus::Code::NotPositiveDefinite && attempt < 19) {
        run.lambda_ *= run.nu_;
        run.nu_ *= 2.0;
        continue;
      }
      out.failure = run.degenerate(st);
      return out;
    }
    bool cost_only = false;
    out.new_cost = run.tryStep(cost, predicted, rep, cost_only);
    rep.lambda = run.lambda_;
    const double actual = cost - out.new_cost;
    if (std::isfinite(out.new_cost) && actual > 0.0 && predicted > 0.0) {
      out.accepted = true;
      run.lambda_ *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * (actual / predicted) - 1.0, 3));
      run.nu_ = 2.0;
      const bool last = last_iteration || stopAfterStep(run.opt_, cost, out.new_cost, rep.step_norm).has_value();
      if (cost_only && !last) run.relinearize(rep);  // the next iteration needs H and g here
      return out;
    }
    run.undoStep();
    run.lambda_ *= run.nu_;
    run.nu_ *= 2.0;
    if (rep.step_norm < run.opt_.step_tolerance) return out;
    if (!cost_only) run.relinearize(rep);  // H and g of the estimate again, for the next trial
  }
  return out;
}

// The iterations of optimize() on a run (Run or StreamedRun); `finish`
// records the termination.
template <class R, class Finish>
OptimizerResult iterate(R& run, const OptimizerOptions& opt, OptimizerResult& res, Finish&& finish) {
  double cost = run.initialCost();
  res.initial_cost = res.final_cost = cost;
  if (!std::isfinite(cost)) return finish(Termination::NonFiniteCost, "initial cost is not finite");
  if (run.numColumns() == 0) return finish(Termination::SmallStep, "no free variables");
  auto t0 = Clock::now();
  const SolverStatus st = run.analyze(threadsOf(opt));
  res.analyze_seconds = since(t0);
  if (!st.ok()) return finish(Termination::NotPositiveDefinite, st.message);

  const bool lm = opt.algorithm == OptimizerOptions::Algorithm::LevenbergMarquardt;
  for (int it = 1; it <= opt.max_iterations; ++it) {
    const auto t_iter = Clock::now();
    IterationReport rep;
    rep.iteration = it;
    if (run.maxGradient(rep) < opt.gradient_tolerance) {
      res.linearize_seconds += rep.linearize_seconds;
      res.final_cost = cost;
      return finish(Termination::SmallGradient);
    }
    run.keepDiagonal();
    const bool last = it == opt.max_iterations;
    const StepOutcome step = lm ? levenbergMarquardtStep(run, cost, last, rep) : gaussNewtonStep(run, cost, last, rep);
    res.iterations = it;
    if (step.failure) {
      res.final_cost = cost;
      res.reports.push_back(rep);
      return finish(Termination::NotPositiveDefinite, *step.failure);
    }
    // An accepted step that goes on left its own (undamped) H; on the
    // CHOLMOD path one that stops may leave the damped H of the previous
    // point, which nothing reads after it (the Schur path never damps H).
    rep.accepted = step.accepted;
    rep.total_seconds = since(t_iter);
    res.linearize_seconds += rep.linearize_seconds;
    res.solve_seconds += rep.solve_seconds;
    if (!step.accepted) {
      rep.cost = cost;
      res.reports.push_back(rep);
      if (opt.callback) opt.callback(rep);
      res.final_cost = cost;
      // A rejected tiny step at the optimum is convergence, not failure.
      if (rep.step_norm < opt.step_tolerance) return finish(Termination::SmallStep);
      if (std::abs(cost - step.new_cost) <= opt.relative_cost_tolerance * cost || !std::isfinite(step.new_cost))
        return finish(std::isfinite(step.new_cost) ? Termination::RelativeCostDecrease : Termination::NonFiniteCost);
      return finish(Termination::NoDecrease);
    }
    rep.cost = step.new_cost;
    rep.cost_change = cost - step.new_cost;
    res.reports.push_back(rep);
    if (opt.callback) opt.callback(rep);
    const double old_cost = cost;
    cost = res.final_cost = step.new_cost;
    if (const auto stop = stopAfterStep(opt, old_cost, step.new_cost, rep.step_norm)) return finish(*stop);
  }
  return finish(Termination::MaxIterations);
}

}  // namespace

OptimizerResult optimize(const FactorGraph& graph, const Values& initial, const OptimizerOptions& opt) {
  const auto t_start = Clock::now();
  OptimizerResult res;
  res.values = initial;
  auto finish = [&](Termination t, std::string msg = {}) {
    res.termination = t;
    res.converged = isConvergence(t);
    res.message = msg.empty() ? toString(t) : std::move(msg);
    res.total_seconds = since(t_start);
    return std::move(res);
  };
  checkOptions(opt);
  if (opt.check_jacobians)
    if (auto failures = jacobianCheckFailures(graph, initial, opt.jacobian_check_tolerance))
      return finish(Termination::JacobianCheckFailed, *failures);
  if (opt.linear_solver == OptimizerOptions::LinearSolver::StreamedSchurComplement) {
    StreamedRun run(graph, opt, res);
    return iterate(run, opt, res, finish);
  }
  Run run(graph, opt, res);
  return iterate(run, opt, res, finish);
}

}  // namespace fgcal
