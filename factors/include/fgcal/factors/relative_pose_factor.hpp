// Relative pose between two SE(3) variables: measured Z ~ A^-1 B,
// r = Log(Z^-1 A^-1 B). In the calibration, A = T_base_cam, B = T_base_marker
// and Z = T_cam_marker from PnP (the paper's fiducial factor).
#pragma once

#include <typeinfo>

#include "fgcal/core/factor.hpp"
#include "fgcal/factors/detail/whitened_log.hpp"

namespace fgcal {

class RelativePoseFactor final : public TypedFactor<6, SE3, SE3> {
 public:
  RelativePoseFactor(Key a, Key b, const SE3& measured, NoiseModel::Ptr noise, RobustKernel::Ptr robust = nullptr)
      : TypedFactor({a, b}, std::move(noise), std::move(robust)), measured_inverse_(measured.inverse()) {}

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
  /// H and g straight from the 6x6 block of the B side: with U = W Jlog and
  /// Ad = Ad(D^-1) (D = A^-1 B), so that J_A = -U Ad,
  ///   H_BB = U^T U,  H_AB = -Ad^T H_BB,  H_AA = Ad^T H_BB Ad,
  ///   g_B = U^T W r,  g_A = -Ad^T g_B,
  /// without whitening J_A or forming J_A^T J_A and J_A^T J_B from it.
  bool whitenedNormalEquations(const Variable* const* vars, double* r, double* const* g,
                               double* const* H) const override {
    const SE3& A = static_cast<const TypedVariable<SE3>*>(vars[0])->value();
    const SE3& B = static_cast<const TypedVariable<SE3>*>(vars[1])->value();
    const SE3 D = A.between(B);
    if (!detail::whitenedLogBlock(noiseModel(), measured_inverse_.compose(D), r, g ? g[1] : nullptr,
                                  g ? H[2] : nullptr))
      return true;
    detail::inverseAdjointSide(D, H[2], g[1], H[0], H[1], g[0]);
    return true;
  }
  /// Two relative poses at once: the B sides' blocks by
  /// detail::whitenedLogBlockPair, the A sides' from them as above.
  bool pairsWith(const Factor& other) const override { return typeid(other) == typeid(RelativePoseFactor); }
  bool whitenedNormalEquationsPair(const Factor& other, const Variable* const* vars, const Variable* const* other_vars,
                                   double* r, double* const* g, double* const* H, double* other_r,
                                   double* const* other_g, double* const* other_H) const override {
    const auto& o = static_cast<const RelativePoseFactor&>(other);
    const auto pose = [](const Variable* v) -> const SE3& {
      return static_cast<const TypedVariable<SE3>*>(v)->value();
    };
    const SE3 D = pose(vars[0]).between(pose(vars[1]));
    const SE3 D_o = pose(other_vars[0]).between(pose(other_vars[1]));
    detail::whitenedLogBlockPair(noiseModel(), measured_inverse_.compose(D), o.noiseModel(),
                                 o.measured_inverse_.compose(D_o), r, g ? g[1] : nullptr, g ? H[2] : nullptr, other_r,
                                 other_g ? other_g[1] : nullptr, other_g ? other_H[2] : nullptr);
    if (g) {
      detail::inverseAdjointSide(D, H[2], g[1], H[0], H[1], g[0]);
      detail::inverseAdjointSide(D_o, other_H[2], other_g[1], other_H[0], other_H[1], other_g[0]);
    }
    return true;
  }
  SE3 measured() const { return measured_inverse_.inverse(); }

 private:
  SE3 measured_inverse_;
};

}  // namespace fgcal
