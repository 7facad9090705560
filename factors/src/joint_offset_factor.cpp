#include "fgcal/factors/joint_offset_factor.hpp"

#include <stdexcept>
#include <string>

namespace fgcal {

JointOffsetKinematicFactor::JointOffsetKinematicFactor(Key board, Key mount, Key offsets,
                                                       std::shared_ptr<const kinematics::KinematicChain> chain, VecX q,
                                                       NoiseModel::Ptr noise, RobustKernel::Ptr robust)
    : TypedFactor({board, mount, offsets}, std::move(noise), std::move(robust)),
      chain_(std::move(chain)),
      q_(std::move(q)) {
  if (!chain_) throw std::invalid_argument("JointOffsetKinematicFactor: no kinematic chain");
  if (q_.size() != chain_->numJoints())
    throw std::invalid_argument("JointOffsetKinematicFactor: " + std::to_string(q_.size()) +
                                " joint positions for a chain of " + std::to_string(chain_->numJoints()) +
                                " movable joints");
}

JointOffsetKinematicFactor::Residual JointOffsetKinematicFactor::evaluateTyped(const SE3& L, const SE3& M,
                                                                               const VecX& o, Jacobian<SE3>* J_r_L,
                                                                               Jacobian<SE3>* J_r_M,
                                                                               Jacobian<VecX>* J_r_o) const {
  kinematics::KinematicChain::Jacobian J_M;  // d(FK M) / d q at the board, 6 x n
  const SE3 F = chain_->forward(q_ + o, M, J_r_o ? &J_M : nullptr);
  const SE3 D = F.between(L);
  Mat6 Jlog;
  const bool need = J_r_L || J_r_M || J_r_o;
  const Vec6 r = D.log(need ? &Jlog : nullptr);
  if (J_r_L) *J_r_L = Jlog;
  if (J_r_M || J_r_o) {
    // Both move F on the right: F Exp(xi) gives D Exp(-Ad(D^-1) xi).
    const Mat6 J_r_F = SE3::minusLogJacobianTimesInverseAdjoint(Jlog, D);
    if (J_r_M) *J_r_M = J_r_F;
    if (J_r_o) *J_r_o = J_r_F * J_M;
  }
  return r;
}

}  // namespace fgcal
