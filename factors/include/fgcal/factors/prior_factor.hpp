// Prior on an SE(3) variable: r = Log(Z^-1 X), [w v] order, with the inverse
// right Jacobian of Log so the Jacobian is exact away from r = 0 too.
#pragma once

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
  SE3 measured() const { return measured_inverse_.inverse(); }

 private:
  SE3 measured_inverse_;
};

}  // namespace fgcal
