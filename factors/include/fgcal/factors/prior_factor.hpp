// Prior on an SE(3) variable: r = Log(Z^-1 X), [w v] order, with the inverse
// right Jacobian of Log so the Jacobian is exact away from r = 0 too.
#pragma once

#include <typeinfo>

#include "fgcal/core/factor.hpp"
#include "fgcal/factors/detail/whitened_log.hpp"

namespace fgcal {

class PriorFactorSE3 final : public TypedFactor<6, SE3> {
 public:
  PriorFactorSE3(Key k, const SE3& measured, NoiseModel::Ptr noise, RobustKernel::Ptr robust = nullptr)
      : TypedFactor({k}, std::move(noise), std::move(robust)), measured_inverse_(measured.inverse()) {}

  Residual evaluateTyped(const SE3& X, Jacobian<SE3>* J_r_X) const override {
    const SE3 E = measured_inverse_.compose(X);
    Mat6 J_r_E;
    const Vec6 r = E.log(J_r_X ? &J_r_E : nullptr);
    if (J_r_X) *J_r_X = J_r_E;  // d(Z^-1 X Exp(d)) = E Exp(d): Jr^-1 of the residual
    return r;
  }
  /// H = U^T U and g = U^T W r with U = W Jr^-1, without the generic path's copies.
  bool whitenedNormalEquations(const Variable* const* vars, double* r, double* const* g,
                               double* const* H) const override {
    const SE3& X = static_cast<const TypedVariable<SE3>*>(vars[0])->value();
    detail::whitenedLogBlock(noiseModel(), measured_inverse_.compose(X), r, g ? g[0] : nullptr,
                             g ? H[0] : nullptr);
    return true;
  }
  /// Two priors at once (detail::whitenedLogBlockPair).
  /// (The class is final: a typeid comparison, cheaper than a dynamic_cast, is the same test.)
  bool pairsWith(const Factor& other) const override { return typeid(other) == typeid(PriorFactorSE3); }
  bool whitenedNormalEquationsPair(const Factor& other, const Variable* const* vars, const Variable* const* other_vars,
                                   double* r, double* const* g, double* const* H, double* other_r,
                                   double* const* other_g, double* const* other_H) const override {
    const auto& o = static_cast<const PriorFactorSE3&>(other);
    const SE3& X = static_cast<const TypedVariable<SE3>*>(vars[0])->value();
    const SE3& Y = static_cast<const TypedVariable<SE3>*>(other_vars[0])->value();
    detail::whitenedLogBlockPair(noiseModel(), measured_inverse_.compose(X), o.noiseModel(),
                                 o.measured_inverse_.compose(Y), r, g ? g[0] : nullptr, g ? H[0] : nullptr, other_r,
                                 other_g ? other_g[0] : nullptr, other_g ? other_H[0] : nullptr);
    return true;
  }
  SE3 measured() const { return measured_inverse_.inverse(); }

 private:
  SE3 measured_inverse_;
};

}  // namespace fgcal
