#include "fgcal/core/optimizer.hpp"

#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "fgcal/core/internal/linear_system.hpp"
#include "fgcal/core/internal/schur_solver.hpp"
#include "fgcal/core/internal/sparse_cholesky.hpp"

namespace fgcal {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

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

  if (opt.check_jacobians) {
    std::ostringstream msg;
    int bad = 0;
    for (std::size_t f = 0; f < graph.size(); ++f)
      for (const auto& m : checkFactorJacobians(graph[f], initial, 1e-6, opt.jacobian_check_tolerance)) {
        if (bad++ < 5) msg << "factor " << f << ": " << m.message << "\n";
      }
    if (bad) {
      msg << bad << " Jacobian block(s) in all differ from central differences";
      return finish(Termination::JacobianCheckFailed, msg.str());
    }
  }

  using LS = OptimizerOptions::LinearSolver;
  LinearSystemOptions lso;
  lso.order_for_schur = opt.linear_solver != LS::SparseCholesky;
  lso.store_jacobian = false;  // the solvers need only H and g
  lso.threads = opt.threads > 0 ? opt.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  LinearSystem sys(graph, initial, opt.fixed_keys, lso);
  const bool use_schur =
      sys.numEliminatedBlocks() > 0 &&
      (opt.linear_solver == LS::SchurComplement ||
       (opt.linear_solver == LS::Auto && sys.numEliminatedColumns() >= 0.75 * static_cast<double>(sys.numColumns())));
  std::unique_ptr<SparseCholesky> chol;  // made only on the path that uses it (CHOLMOD's start-up is not free)
  std::unique_ptr<SchurSolver> schur;
  const bool lm = opt.algorithm == OptimizerOptions::Algorithm::LevenbergMarquardt;

  auto t0 = Clock::now();
  double cost = sys.linearize(res.values);
  res.linearize_seconds += since(t0);
  res.initial_cost = res.final_cost = cost;
  if (!std::isfinite(cost)) return finish(Termination::NonFiniteCost, "initial cost is not finite");
  if (sys.numColumns() == 0) return finish(Termination::SmallStep, "no free variables");

  t0 = Clock::now();
  SolverStatus st;
  if (use_schur) {
    schur = std::make_unique<SchurSolver>(sys, lso.threads);
    res.linear_solver = "Schur complement (" + std::to_string(sys.numEliminatedBlocks()) + " blocks eliminated, " +
                        std::to_string(schur->reducedSize()) + " reduced columns, " +
                        (schur->reducedIsDense() ? "dense" : "sparse") + ")";
  } else {
    chol = std::make_unique<SparseCholesky>();
    st = chol->analyze(sys.hessianUpper());
    res.linear_solver = "sparse Cholesky (" + chol->ordering() + ")";
  }
  res.analyze_seconds = since(t0);
  if (!st.ok()) return finish(Termination::NotPositiveDefinite, st.message);

  // Whether an accepted step ends the solve, and how: one rule, read before
  // deciding to linearize at the step and again after accepting it.
  auto stopAfterStep = [&](double old_cost, double new_cost, double step_norm) -> std::optional<Termination> {
    if (new_cost < opt.absolute_cost_tolerance) return Termination::AbsoluteCost;
    if (old_cost - new_cost < opt.relative_cost_tolerance * old_cost) return Termination::RelativeCostDecrease;
    if (step_norm < opt.step_tolerance) return Termination::SmallStep;
    return std::nullopt;
  };

  double lambda = opt.initial_lambda, nu = 2.0;
  // The Schur solver damps the diagonal as it reads H; for CHOLMOD H itself
  // is damped, its diagonal kept here to undo that.
  std::vector<double> diag(use_schur ? 0 : static_cast<std::size_t>(sys.numColumns()));
  // The step lives across iterations (no fresh temporary of the system's size per solve).
  VecX step;

  for (int it = 1; it <= opt.max_iterations; ++it) {
    const auto t_iter = Clock::now();
    IterationReport rep;
    rep.iteration = it;
    const VecX& g = sys.gradient();
    if (g.size() == 0 || g.cwiseAbs().maxCoeff() < opt.gradient_tolerance) {
      res.final_cost = cost;
      return finish(Termination::SmallGradient);
    }

    // CHOLMOD: damp the diagonal in place, remembering it to undo.
    std::vector<double>& Hv = sys.hessianValues();
    auto at = [&](std::size_t j) { return sys.hessianDiagonalPosition(static_cast<CscMatrix::Index>(j)); };
    for (std::size_t j = 0; j < diag.size(); ++j) diag[j] = Hv[at(j)];
    bool accepted = false;
    double new_cost = cost;
    for (int attempt = 0; attempt < 20 && !accepted; ++attempt) {
      if (lm)
        for (std::size_t j = 0; j < diag.size(); ++j)
          Hv[at(j)] = diag[j] + lambda * std::clamp(diag[j], opt.min_diagonal, opt.max_diagonal);
      t0 = Clock::now();
      // (H + lambda D) h = -g solved as -(H + lambda D)^-1 g: the same bits
      // (negation is exact), without a copy of -g (48 MB at N = 10^6).
      double damping_term = 0.0;  // h^T D h
      if (use_schur) {
        st = schur->solve(g, step, {lm ? lambda : 0.0, opt.min_diagonal, opt.max_diagonal},
                          lm ? &damping_term : nullptr);
      } else {
        st = chol->factorize(sys.hessianUpper());
        if (st.ok()) st = chol->solve(g, step);
      }
      if (st.ok()) step = -step;
      rep.solve_seconds += since(t0);
      if (!st.ok()) {
        if (lm && st.code == SolverStatus::Code::NotPositiveDefinite && attempt < 19) {
          lambda *= nu;
          nu *= 2.0;
          continue;
        }
        for (std::size_t j = 0; j < diag.size(); ++j) Hv[at(j)] = diag[j];
        if (st.failed_column >= 0) res.degenerate_keys.push_back(sys.keyOfColumn(st.failed_column));
        std::ostringstream msg;
        msg << st.message;
        if (st.failed_column >= 0)
          msg << ": variable " << keyToString(sys.keyOfColumn(st.failed_column))
              << " is not constrained by the factors (gauge freedom or degenerate data)";
        res.final_cost = cost;
        res.reports.push_back(rep);
        res.iterations = it;
        return finish(Termination::NotPositiveDefinite, msg.str());
      }
      rep.step_norm = step.norm();
      // Decrease predicted by the linear model 0.5 |r + J h|^2: since
      // (H + lambda D) h = -g, it is 0.5 h^T (lambda D h - g), O(n) instead of a pass over J.
      if (lm && !use_schur)
        for (std::size_t j = 0; j < diag.size(); ++j)
          damping_term += std::clamp(diag[j], opt.min_diagonal, opt.max_diagonal) * step[j] * step[j];
      const double predicted = 0.5 * (lambda * damping_term - g.dot(step));
      // Linearize at the trial point right away: when the step is accepted
      // (the usual case) its H and g are the next iteration's, so each
      // iteration evaluates the factors once, not twice. When the model
      // promises less than the stopping rule asks, the step is most likely
      // the last: its cost alone decides, and the Jacobians are computed only
      // if the iteration goes on after all.
      sys.retract(res.values, step);  // undone below when rejected
      t0 = Clock::now();
      const bool cost_only = predicted < opt.relative_cost_tolerance * cost;
      new_cost = cost_only ? sys.cost(res.values) : sys.linearize(res.values);
      rep.linearize_seconds += since(t0);
      const double actual = cost - new_cost;
      rep.lambda = lm ? lambda : 0.0;
      if (std::isfinite(new_cost) && actual > 0.0 && (!lm || predicted > 0.0)) {
        accepted = true;
        if (lm) {
          const double rho = actual / predicted;
          lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
          nu = 2.0;
        }
        // The last iteration or a stopping step needs no H and g at the new estimate.
        const bool last = it == opt.max_iterations || stopAfterStep(cost, new_cost, rep.step_norm).has_value();
        if (cost_only && !last) {
          t0 = Clock::now();
          sys.linearize(res.values);  // the next iteration needs H and g here
          rep.linearize_seconds += since(t0);
        }
      } else if (lm) {
        sys.retract(res.values, -step);
        lambda *= nu;
        nu *= 2.0;
        if (rep.step_norm < opt.step_tolerance) break;
        if (!cost_only) {
          t0 = Clock::now();
          sys.linearize(res.values);  // H and g of the estimate again, for the next trial
          rep.linearize_seconds += since(t0);
        }
      } else {
        sys.retract(res.values, -step);
        break;  // Gauss-Newton: no damping to fall back on
      }
    }
    // An accepted trial that goes on left its own (undamped) H; on the
    // CHOLMOD path one that stops may leave the damped H of the previous
    // point, which nothing reads after it (the Schur path never damps H); a
    // give-up returns below.
    rep.accepted = accepted;
    rep.total_seconds = since(t_iter);
    res.linearize_seconds += rep.linearize_seconds;
    res.solve_seconds += rep.solve_seconds;
    res.iterations = it;
    if (!accepted) {
      rep.cost = cost;
      res.reports.push_back(rep);
      if (opt.callback) opt.callback(rep);
      res.final_cost = cost;
      // A rejected tiny step at the optimum is convergence, not failure.
      if (rep.step_norm < opt.step_tolerance) return finish(Termination::SmallStep);
      if (std::abs(cost - new_cost) <= opt.relative_cost_tolerance * cost || !std::isfinite(new_cost))
        return finish(std::isfinite(new_cost) ? Termination::RelativeCostDecrease : Termination::NonFiniteCost);
      return finish(Termination::NoDecrease);
    }
    rep.cost = new_cost;
    rep.cost_change = cost - new_cost;
    res.reports.push_back(rep);
    if (opt.callback) opt.callback(rep);
    const double old_cost = cost;
    cost = res.final_cost = new_cost;

    if (const auto stop = stopAfterStep(old_cost, new_cost, rep.step_norm)) return finish(*stop);
  }
  return finish(Termination::MaxIterations);
}

}  // namespace fgcal
