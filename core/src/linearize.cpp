// FactorEvaluator's buffers, and linearize(): every factor's contribution to
// H and g, on one thread or several (each with its own H and g, summed at the
// end).
#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

#include "fgcal/core/internal/factor_evaluator.hpp"
#include "parallel.hpp"

namespace fgcal {

FactorEvaluator::FactorEvaluator(const FactorGraph& graph, const LinearSystemOptions& options,
                                 const SystemPattern& pattern, FastPathFinder&& finder,
                                 std::vector<std::uint32_t> schedule, CscMatrix jacobian, CscMatrix hessian)
    : graph_(&graph),
      pattern_(&pattern),
      store_jacobian_(options.store_jacobian),
      threads_(options.threads),
      schedule_(std::move(schedule)),
      fast_path_(std::move(finder.fast_path_)),
      J_(std::move(jacobian)),
      H_(std::move(hessian)) {
  if (store_jacobian_) r_.setZero(pattern.numRows());  // else each factor's r goes to the scratch
  g_.setZero(H_.cols);
  // Room for a factor's Jacobian blocks, or for its gradient parts and pair
  // blocks (linearizeFromFactorBlocks), whichever is larger.
  const std::size_t nk = std::max<std::size_t>(pattern.maxKeys(), 1), dof = static_cast<std::size_t>(pattern.maxDof());
  const std::size_t max_dim = static_cast<std::size_t>(pattern.maxDim());
  residual_at_ = std::max(max_dim * dof * nk, nk * dof + nk * (nk + 1) / 2 * dof * dof);
  scratch_half_ = residual_at_ + max_dim;
  scratch_.resize(2 * scratch_half_);
}

double FactorEvaluator::linearize(const Values& values) {
  const std::size_t num_values = pattern_->numVariables();
  if (values.size() != num_values)
    throw std::invalid_argument("linearize: the values hold " + std::to_string(values.size()) +
                                " variables, the structure was built for " + std::to_string(num_values));
  const std::size_t nf = graph().size();
  // Enough factors per thread to pay for starting it and for summing its copy
  // of H (a factor costs about a microsecond, an entry of H about a nanosecond).
  const int T = detail::threadsFor(threads_, nf, std::max<std::size_t>(2048, H_.values.size() / 512));
  last_threads_ = T;
  if (thread_buffers_.size() < static_cast<std::size_t>(T - 1)) thread_buffers_.resize(static_cast<std::size_t>(T - 1));
  std::vector<double> costs(static_cast<std::size_t>(T), 0.0);
  // On one thread every block of H is first written by the factor that
  // contributes to it first, which assigns: H is not cleared beforehand (a
  // pass over all of H per linearization). Threads add into cleared copies.
  assign_first_ = T == 1;
  detail::parallelRun(T, [&](int t) {
    double* H = H_.values.data();
    double* g = nullptr;
    double* scratch = scratch_.data();
    if (t == 0) {
      if (!h_values_zero_ && !assign_first_) std::fill(H_.values.begin(), H_.values.end(), 0.0);
      g_.setZero(H_.cols);
      g = g_.data();
    } else {
      ThreadBuffers& b = thread_buffers_[static_cast<std::size_t>(t - 1)];
      b.H.assign(H_.values.size(), 0.0);
      b.g.setZero(H_.cols);
      b.scratch.resize(scratch_.size());
      H = b.H.data();
      g = b.g.data();
      scratch = b.scratch.data();
    }
    // The schedule's places in this thread's range; a pair split by the range's end goes singly.
    const auto [p0, p1] = detail::chunkRange(nf, T, t);
    double cost = 0.0;
    walkSchedule(
        p0, p1, [&](std::size_t pos) { cost += evaluateFactor(pos, values, scratch, H, g); },
        [&](std::size_t pos) { evaluatePair(pos, values, scratch, H, g, cost); });
    costs[static_cast<std::size_t>(t)] = cost;
  });
  // Sum the threads' normal equations, each thread a range of entries.
  detail::parallelRun(T, [&](int t) {
    const auto [i0, i1] = detail::chunkRange(H_.values.size(), T, t);
    for (int u = 1; u < T; ++u) {
      const double* src = thread_buffers_[static_cast<std::size_t>(u - 1)].H.data();
      for (std::size_t i = i0; i < i1; ++i) H_.values[i] += src[i];
    }
    const auto [c0, c1] = detail::chunkRange(static_cast<std::size_t>(H_.cols), T, t);
    for (int u = 1; u < T; ++u) {
      const double* src = thread_buffers_[static_cast<std::size_t>(u - 1)].g.data();
      for (std::size_t c = c0; c < c1; ++c) g_[static_cast<Eigen::Index>(c)] += src[c];
    }
  });
  h_values_zero_ = false;
  double cost = 0.0;
  for (double c : costs) cost += c;
  return cost;
}

}  // namespace fgcal
