// The kinematics factor: the board pose L = T_base_marker at one instant is
// tied to the forward kinematics T_base_link(q) measured there and to the
// board mount M = T_link_marker (a variable with its own prior, or held fixed):
//   r = Log((T_base_link(q) * M)^-1 * L).
// Its noise is the encoder noise propagated through the leg Jacobian,
// expressed at the marker (see markerCovariance).
#pragma once

#include "fgcal/core/factor.hpp"
#include "fgcal/factors/detail/whitened_log.hpp"

namespace fgcal {

class KinematicFactor final : public TypedFactor<6, SE3, SE3> {
 public:
  /// keys: the board pose L and the mount M.
  KinematicFactor(Key board, Key mount, const SE3& T_base_link, NoiseModel::Ptr noise,
                  RobustKernel::Ptr robust = nullptr)
      : TypedFactor({board, mount}, std::move(noise), std::move(robust)), T_link_base_(T_base_link.inverse()) {}

  Residual evaluateTyped(const SE3& L, const SE3& M, Jacobian<SE3>* J_r_L, Jacobian<SE3>* J_r_M) const override {
    const SE3 D = M.between(T_link_base_.compose(L));  // M^-1 T_link_base L
    Mat6 Jlog;
    const bool need = J_r_L || J_r_M;
    const Vec6 r = D.log(need ? &Jlog : nullptr);
    if (J_r_L) *J_r_L = Jlog;
    if (J_r_M) *J_r_M = SE3::minusLogJacobianTimesInverseAdjoint(Jlog, D);  // D Exp(-Ad(D^-1) d)
    return r;
  }

  /// H and g straight from the board side's block (J_L = Jr^-1 of the
  /// residual) and, for the mount (D = M^-1 (T_base_link L), J_M = -J_L
  /// Ad(D^-1)), from that block through Ad, as RelativePoseFactor does.
  bool whitenedNormalEquations(const Variable* const* vars, double* r, double* const* g,
                               double* const* H) const override {
    const SE3& L = static_cast<const TypedVariable<SE3>*>(vars[0])->value();
    const SE3& M = static_cast<const TypedVariable<SE3>*>(vars[1])->value();
    const SE3 D = M.between(T_link_base_.compose(L));
    if (!detail::whitenedLogBlock(noiseModel(), D, r, g ? g[0] : nullptr, g ? H[0] : nullptr)) return true;
    Mat6 H_ML;  // the mount's rows, the board's columns; the factor's pair (0, 1) is its transpose
    detail::inverseAdjointSide(D, H[0], g[0], H[2], H_ML.data(), g[1]);
    Eigen::Map<Mat6> H_LM(H[1]);
    H_LM = H_ML.transpose();
    return true;
  }

  SE3 linkPose() const { return T_link_base_.inverse(); }

  /// The covariance of the residual from the covariance of T_base_link's right
  /// perturbation (J Sigma_q J^T from the kinematics): a perturbation
  /// T_base_link Exp(d) moves the marker by Exp(Ad(M^-1) d).
  static Mat6 markerCovariance(const Mat6& link_covariance, const SE3& T_link_marker) {
    const Mat6 A = T_link_marker.inverse().adjoint();
    return A * link_covariance * A.transpose();
  }

 private:
  SE3 T_link_base_;
};

}  // namespace fgcal
