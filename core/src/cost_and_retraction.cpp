// The cost alone (residuals, in linearize()'s order and pairs, so that on one
// thread both give the same bits) and the retraction of the free variables.
#include "fgcal/core/internal/linear_system.hpp"

#include <algorithm>
#include <stdexcept>

#include "normal_equation_blocks.hpp"
#include "parallel.hpp"

namespace fgcal {

using detail::squaredNorm;

double LinearSystem::cost(const Values& values) const {
  if (values.size() != num_values_)
    throw std::invalid_argument("cost: the values hold " + std::to_string(values.size()) +
                                " variables, the structure was built for " + std::to_string(num_values_));
  const std::size_t nf = graph_.size();
  // Residuals only: a factor costs less than in linearize, and there is no H to sum.
  const int T = detail::threadsFor(options_.threads, nf, 4096);
  std::vector<double> costs(static_cast<std::size_t>(T), 0.0);
  detail::parallelRun(T, [&](int t) {
    std::vector<const Variable*> vars(max_keys_), vars_b(max_keys_);
    VecX r(std::max(max_dim_, 1)), r_b(std::max(max_dim_, 1));
    // In linearize()'s order, with its pairs and its squared norm (one thread: the same bits).
    const auto add = [&](const Factor& factor, const VecX& res, double& sum) {
      sum += factor.costOfWhitened(squaredNorm(res.data(), factor.dim()));
    };
    const auto alone = [&](std::size_t f, double& sum) {
      const Factor& factor = graph_[f];
      gatherVariables(f, values, vars.data());
      if (const internal::NormalEquations* path = fast_path_.empty() ? nullptr : fast_path_[f]) {
        path->whitened(factor, vars.data(), r.data(), nullptr, nullptr);
      } else {
        factor.evaluate(vars.data(), r.data(), nullptr);
        factor.noiseModel().whitenResidual(r.data());
      }
      add(factor, r, sum);
    };
    const auto [p0, p1] = detail::chunkRange(nf, T, t);
    double total = 0.0;
    walkSchedule(
        p0, p1, [&](std::size_t pos) { alone(factorAt(pos), total); },
        [&](std::size_t pos) {
          const std::size_t f = factorAt(pos), fb = factorAt(pos + 1);
          gatherVariables(f, values, vars.data());
          gatherVariables(fb, values, vars_b.data());
          fast_path_[f]->whitenedPair(graph_[f], graph_[fb], vars.data(), vars_b.data(), r.data(), nullptr, nullptr,
                                      r_b.data(), nullptr, nullptr);
          add(graph_[f], r, total);
          add(graph_[fb], r_b, total);
        });
    costs[static_cast<std::size_t>(t)] = total;
  });
  double total = 0.0;
  for (double c : costs) total += c;
  return total;
}

void LinearSystem::retract(Values& values, const VecX& delta) const {
  const int T = detail::threadsFor(options_.threads, num_values_, 16384);
  detail::parallelRun(T, [&](int t) {
    const auto [v0, v1] = detail::chunkRange(num_values_, T, t);
    for (std::size_t vi = v0; vi < v1; ++vi)
      if (var_col0_[vi] >= 0) values.variableAt(vi).retract(delta.data() + var_col0_[vi]);
  });
}

}  // namespace fgcal
