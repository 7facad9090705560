// The kinematics factor with joint zero offsets: the encoders read q, the
// joints stood at q + o, where o (one entry per movable joint of the chain,
// in chain order) is a variable of the graph. The board pose L at one instant
// is tied to the forward kinematics re-evaluated at q + o and to the mount M:
//
//   r = Log((FK(q + o) M)^-1 L)          (KinematicFactor's residual, at q + o)
//
// Jacobians (right perturbations, [w v]; D = (FK(q + o) M)^-1 L):
//   d r / d L = Jr^-1(r)
//   d r / d M = -Jr^-1(r) Ad(D^-1)
//   d r / d o = -Jr^-1(r) Ad(D^-1) J_M(q + o)
// where J_M = Ad(M^-1) J is the chain's Jacobian expressed at the board
// (KinematicChain::forward with T_tip_marker = M): FK(q + o + d) M =
// FK(q + o) M Exp(J_M d).
//
// Not every offset is observable from images and kinematics: on a leg, the
// offset of the joint nearest the base turns every board pose rigidly about
// that joint's axis, which the camera poses absorb, and the offset of the
// joint nearest the board folds into the mount. Give o a prior
// (PriorFactorVector) and judge from its marginal information which entries
// the data determine.
#pragma once

#include <memory>
#include <optional>

#include "fgcal/core/factor.hpp"
#include "fgcal/kinematics/chain.hpp"

namespace fgcal {

class JointOffsetKinematicFactor final : public TypedFactor<6, SE3, SE3, VecX> {
 public:
  /// keys: the board pose L, the mount M and the offsets o (VecX of
  /// chain->numJoints()); q: the encoder readings at this instant, chain
  /// order. Throws std::invalid_argument when q's size is not the chain's.
  JointOffsetKinematicFactor(Key board, Key mount, Key offsets, std::shared_ptr<const kinematics::KinematicChain> chain,
                             VecX q, NoiseModel::Ptr noise, RobustKernel::Ptr robust = nullptr);

  Residual evaluateTyped(const SE3& L, const SE3& M, const VecX& o, Jacobian<SE3>* J_r_L, Jacobian<SE3>* J_r_M,
                         Jacobian<VecX>* J_r_o) const override;

  const VecX& jointPositions() const { return q_; }
  const kinematics::KinematicChain& chain() const { return *chain_; }

 private:
  std::shared_ptr<const kinematics::KinematicChain> chain_;
  VecX q_;
};

// The kinematics factor with the leg's geometry estimated: the robot is not
// exactly its URDF. Before each movable joint the chain applies a constant
// transform (the joint's URDF <origin>, with any fixed joints since the
// previous one); u, a variable of the graph (VecX, 6 per movable joint, [w v]
// in chain order), moves and turns each of them: C_i becomes C_i Exp(u_i)
// (KinematicChain::forwardCorrected). Give u a prior (PriorFactorVector): the
// URDF's tolerance. Optionally with joint zero offsets o, as
// JointOffsetKinematicFactor:
//
//   r = Log((FK(q + o; u) M)^-1 L)
//
// Jacobians (right perturbations, [w v]; D = (FK(q + o; u) M)^-1 L):
//   d r / d L = Jr^-1(r),  d r / d M = -Jr^-1(r) Ad(D^-1)
//   d r / d u = -Jr^-1(r) Ad(D^-1) G_M,   d r / d o = -Jr^-1(r) Ad(D^-1) J_M
// where G_M and J_M are the chain's Jacobians in u and q, at the board.
//
// What images cannot tell: a correction of the first joint's transform moves
// every board pose rigidly, as poses of whatever observes the boards (the
// cameras) can; its prior then stays in their marginals, which is what a pose
// measured through an imperfect leg is worth. Relative poses of two such
// observers, solved together, do not carry it.
class OriginKinematicFactor final : public Factor {
 public:
  /// keys: the board pose L (T_base_marker), the mount M (T_tip_marker), the
  /// origin corrections u (VecX of 6 chain->numJoints()) and, when given, the
  /// joint offsets o (VecX of chain->numJoints()); q: the encoder readings,
  /// chain order. Throws
  /// std::invalid_argument for a missing chain, a q of the wrong size or a
  /// noise model that is not 6-dimensional.
  OriginKinematicFactor(Key board, Key mount, Key origins, std::optional<Key> offsets,
                        std::shared_ptr<const kinematics::KinematicChain> chain, VecX q, NoiseModel::Ptr noise,
                        RobustKernel::Ptr robust = nullptr);

  void evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const override;

  const VecX& jointPositions() const { return q_; }
  const kinematics::KinematicChain& chain() const { return *chain_; }
  /// Whether o is among the keys (the fourth).
  bool hasJointOffsets() const { return keys().size() == 4; }

 private:
  std::shared_ptr<const kinematics::KinematicChain> chain_;
  VecX q_;
};

}  // namespace fgcal
