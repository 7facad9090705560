// Priors: on an SE(3) variable, r = Log(Z^-1 X), [w v] order, with the
// inverse right Jacobian of Log so the Jacobian is exact away from r = 0 too;
// on a vector variable, r = x - z.
#pragma once

#include "fgcal/core/factor.hpp"

namespace fgcal {

class PriorFactorSE3 final : public TypedFactor<6, SE3> {
 public:
  PriorFactorSE3(Key k, const SE3& measured, NoiseModel::Ptr noise, RobustKernel::Ptr robust = nullptr);

  Residual evaluateTyped(const SE3& X, Jacobian<SE3>* J_r_X) const override {
    const SE3 E = measured_inverse_.compose(X);
    Mat6 J_r_E;
    const Vec6 r = E.log(J_r_X ? &J_r_E : nullptr);
    if (J_r_X) *J_r_X = J_r_E;  // d(Z^-1 X Exp(d)) = E Exp(d): Jr^-1 of the residual
    return r;
  }
  SE3 measured() const { return measured_inverse_.inverse(); }

 private:
  // The solver linearizes this factor by a faster path than evaluateTyped
  // (the same numbers, to rounding); the constructor hands it over.
  static void registerFastPath();

  SE3 measured_inverse_;
};

}  // namespace fgcal

namespace fgcal {

/// Prior on a vector variable (VecX of any size): r = x - z, e.g. on the
/// calibration's extra parameters (joint zero offsets, time offsets).
class PriorFactorVector final : public TypedFactor<Eigen::Dynamic, VecX> {
 public:
  /// Throws std::invalid_argument when the noise model's dimension differs from measured's size.
  PriorFactorVector(Key k, VecX measured, NoiseModel::Ptr noise, RobustKernel::Ptr robust = nullptr);

  Residual evaluateTyped(const VecX& x, Jacobian<VecX>* J_r_x) const override {
    if (J_r_x) J_r_x->setIdentity(dim(), dim());
    return x - measured_;
  }
  const VecX& measured() const { return measured_; }

 private:
  VecX measured_;
};

}  // namespace fgcal
