// IntrinsicsPriorFactor: r = K - K0, d r / d K = I.
#include "fgcal/factors/intrinsics_prior_factor.hpp"

#include <algorithm>
#include <string>

#include "fgcal/factors/corner_factor.hpp"

namespace fgcal {

namespace {
NoiseModel::Ptr priorNoise(const VecX& prior, const VecX& sigmas) {
  const auto n = prior.size();
  if (n != 4 && n != 8 && n != 9)
    throw std::invalid_argument("IntrinsicsPriorFactor: expected 4, 8 or 9 intrinsics, got " + std::to_string(n));
  if (sigmas.size() != n)
    throw std::invalid_argument("IntrinsicsPriorFactor: " + std::to_string(sigmas.size()) + " sigmas for " +
                                std::to_string(n) + " intrinsics");
  return NoiseModel::diagonal(sigmas);  // rejects sigmas that are not finite and > 0
}
}  // namespace

IntrinsicsPriorFactor::IntrinsicsPriorFactor(Key intrinsics, const VecX& prior, const VecX& sigmas)
    : Factor({intrinsics}, priorNoise(prior, sigmas)), prior_(prior) {}

void IntrinsicsPriorFactor::evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const {
  const int n = dim();
  const double* K = CornerFactor::intrinsicsData(vars[0], n);
  for (int i = 0; i < n; ++i) residual[i] = K[i] - prior_[i];
  if (jacobians && jacobians[0]) {
    double* J = jacobians[0];
    std::fill(J, J + n * n, 0.0);
    for (int i = 0; i < n; ++i) J[i + i * n] = 1.0;
  }
}

}  // namespace fgcal
