// The priors' construction and the solver's fast path for PriorFactorSE3.
#include "fgcal/factors/prior_factor.hpp"

#include "fgcal/core/internal/normal_equations.hpp"
#include "fgcal/factors/internal/whitened_log.hpp"

namespace fgcal {

PriorFactorVector::PriorFactorVector(Key k, VecX measured, NoiseModel::Ptr noise, RobustKernel::Ptr robust)
    : TypedFactor({k}, std::move(noise), std::move(robust)), measured_(std::move(measured)) {
  if (measured_.size() != dim())
    throw std::invalid_argument("a vector prior of size " + std::to_string(measured_.size()) +
                                " got a noise model of dimension " + std::to_string(dim()));
}

PriorFactorSE3::PriorFactorSE3(Key k, const SE3& measured, NoiseModel::Ptr noise, RobustKernel::Ptr robust)
    : TypedFactor({k}, std::move(noise), std::move(robust)), measured_inverse_(measured.inverse()) {
  registerFastPath();
}

void PriorFactorSE3::registerFastPath() {
  // H = U^T U and g = U^T W r with U = W Jr^-1, without the generic path's
  // copies; two priors at once in the lanes of two-lane packets.
  struct FastPath final : internal::NormalEquations {
    static const SE3& pose(const Variable* v) { return static_cast<const TypedVariable<SE3>*>(v)->value(); }
    void whitened(const Factor& factor, const Variable* const* vars, double* r, double* const* g,
                  double* const* H) const override {
      const auto& f = static_cast<const PriorFactorSE3&>(factor);
      detail::whitenedLogBlock(f.noiseModel(), f.measured_inverse_.compose(pose(vars[0])), r, g ? g[0] : nullptr,
                               g ? H[0] : nullptr);
    }
    bool pairs() const override { return true; }
    void whitenedPair(const Factor& a, const Factor& b, const Variable* const* vars_a, const Variable* const* vars_b,
                      double* r_a, double* const* g_a, double* const* H_a, double* r_b, double* const* g_b,
                      double* const* H_b) const override {
      const auto& fa = static_cast<const PriorFactorSE3&>(a);
      const auto& fb = static_cast<const PriorFactorSE3&>(b);
      detail::whitenedLogBlockPair(fa.noiseModel(), fa.measured_inverse_.compose(pose(vars_a[0])), fb.noiseModel(),
                                   fb.measured_inverse_.compose(pose(vars_b[0])), r_a, g_a ? g_a[0] : nullptr,
                                   g_a ? H_a[0] : nullptr, r_b, g_b ? g_b[0] : nullptr, g_b ? H_b[0] : nullptr);
    }
  };
  static const FastPath path;
  static const bool registered = (internal::registerNormalEquations(typeid(PriorFactorSE3), path), true);
  (void)registered;
}

}  // namespace fgcal
