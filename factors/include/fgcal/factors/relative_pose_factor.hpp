// Relative pose between two SE(3) variables: measured Z ~ A^-1 B,
// r = Log(Z^-1 A^-1 B). In the calibration, A = T_base_cam, B = T_base_marker
// and Z = T_cam_marker from PnP (the paper's fiducial factor).
#pragma once

#include "fgcal/core/factor.hpp"

namespace fgcal {

class RelativePoseFactor final : public TypedFactor<6, SE3, SE3> {
 public:
  /// keys: A and B.
  RelativePoseFactor(Key a, Key b, const SE3& measured, NoiseModel::Ptr noise, RobustKernel::Ptr robust = nullptr);

  Residual evaluateTyped(const SE3& A, const SE3& B, Jacobian<SE3>* J_r_A, Jacobian<SE3>* J_r_B) const override {
    const SE3 D = A.between(B);  // A^-1 B
    const SE3 E = measured_inverse_.compose(D);
    Mat6 Jlog;
    const bool need = J_r_A || J_r_B;
    const Vec6 r = E.log(need ? &Jlog : nullptr);
    // d/dB: D Exp(d) -> E Exp(d); d/dA: D <- Exp(-d) D = D Exp(-Ad(D^-1) d).
    if (J_r_B) *J_r_B = Jlog;
    if (J_r_A) *J_r_A = SE3::minusLogJacobianTimesInverseAdjoint(Jlog, D);
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
