// The kinematics factor: the board pose L = T_base_marker at one instant is
// tied to the forward kinematics T_base_link(q) measured there and to the
// board mount M = T_link_marker (a variable with its own prior, or held fixed):
//   r = Log((T_base_link(q) * M)^-1 * L).
// Its noise is the encoder noise propagated through the leg Jacobian,
// expressed at the marker (see markerCovariance).
#pragma once

#include "fgcal/core/factor.hpp"

namespace fgcal {

class KinematicFactor final : public TypedFactor<6, SE3, SE3> {
 public:
  /// keys: the board pose L and the mount M.
  KinematicFactor(Key board, Key mount, const SE3& T_base_link, NoiseModel::Ptr noise,
                  RobustKernel::Ptr robust = nullptr);

  Residual evaluateTyped(const SE3& L, const SE3& M, Jacobian<SE3>* J_r_L, Jacobian<SE3>* J_r_M) const override {
    const SE3 D = M.between(T_link_base_.compose(L));  // M^-1 T_link_base L
    Mat6 Jlog;
    const bool need = J_r_L || J_r_M;
    const Vec6 r = D.log(need ? &Jlog : nullptr);
    if (J_r_L) *J_r_L = Jlog;
    if (J_r_M) *J_r_M = SE3::minusLogJacobianTimesInverseAdjoint(Jlog, D);  // D Exp(-Ad(D^-1) d)
    return r;
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
  // The solver linearizes this factor by a faster path than evaluateTyped
  // (the same numbers, to rounding); the constructor hands it over.
  static void registerFastPath();

  SE3 T_link_base_;
};

}  // namespace fgcal
