// The cost alone (residuals, in linearize()'s order and pairs, so that on one
// thread both give the same bits).
#include <algorithm>
#include <stdexcept>
#include <string>

#include "fgcal/core/internal/factor_evaluator.hpp"
#include "normal_equation_blocks.hpp"
#include "parallel.hpp"

namespace fgcal {

using detail::squaredNorm;

double FactorEvaluator::cost(const Values& values) const {
  const std::size_t num_values = pattern_->numVariables();
  if (values.size() != num_values)
    throw std::invalid_argument("cost: the values hold " + std::to_string(values.size()) +
                                " variables, the structure was built for " + std::to_string(num_values));
  const std::size_t nf = graph().size();
  // Residuals only: a factor costs less than in linearize, and there is no H to sum.
  const int T = detail::threadsFor(threads_, nf, 4096);
  std::vector<double> costs(static_cast<std::size_t>(T), 0.0);
  detail::parallelRun(T, [&](int t) {
    std::vector<const Variable*> vars(pattern_->maxKeys()), vars_b(pattern_->maxKeys());
    VecX r(std::max(pattern_->maxDim(), 1)), r_b(std::max(pattern_->maxDim(), 1));
    // In linearize()'s order, with its pairs and its squared norm (one thread: the same bits).
    const auto add = [&](const Factor& factor, const VecX& res, double& sum) {
      sum += factor.costOfWhitened(squaredNorm(res.data(), factor.dim()));
    };
    const auto alone = [&](std::size_t f, double& sum) {
      const Factor& factor = graph()[f];
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
          fast_path_[f]->whitenedPair(graph()[f], graph()[fb], vars.data(), vars_b.data(), r.data(), nullptr, nullptr,
                                      r_b.data(), nullptr, nullptr);
          add(graph()[f], r, total);
          add(graph()[fb], r_b, total);
        });
    costs[static_cast<std::size_t>(t)] = total;
  });
  double total = 0.0;
  for (double c : costs) total += c;
  return total;
}

}  // namespace fgcal
