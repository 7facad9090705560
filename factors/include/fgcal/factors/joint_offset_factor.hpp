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

// The kinematics factor with the chain's corrections: the robot is not
// exactly its URDF, its encoders do not read exactly the joint. Each is
// optional, a variable of the graph:
// - u, the joints' origins (VecX, 6 per movable joint, [w v] in chain order).
//   Before each movable joint the chain applies a constant transform (the
//   joint's URDF <origin>, with any fixed joints since the previous one); u_i
//   moves and turns it: C_i becomes C_i Exp(u_i)
//   (KinematicChain::forwardCorrected). Its prior is the URDF's tolerance.
// - o, the joints' zero offsets (VecX, one per movable joint), as
//   JointOffsetKinematicFactor.
// - b, the joints' backlash (VecX, one per movable joint): a gear's play lets
//   the joint lag its motor-side encoder by half the play against the
//   direction of motion, and after a reversal stand still while the motor
//   crosses the play. The factor is given, per joint, the coefficient lag_k
//   of b_k at its instant, in [-0.5, 0.5] (the caller's model: fgcal's is a
//   play operator run over the joint log, fgcal/apps/offset_estimation.hpp;
//   0 for a joint whose backlash is not estimated), held fixed: the factor is
//   linear in b.
//
//   r = Log((FK(q + o + lag .* b; u) M)^-1 L)
//
// Jacobians (right perturbations, [w v]; D = (FK(...) M)^-1 L):
//   d r / d L = Jr^-1(r),  d r / d M = -Jr^-1(r) Ad(D^-1)
//   d r / d u = -Jr^-1(r) Ad(D^-1) G_M,   d r / d o = -Jr^-1(r) Ad(D^-1) J_M
//   d r / d b = (d r / d o) diag(lag)
// where G_M and J_M are the chain's Jacobians in u and q, at the board.
//
// What images cannot tell: a correction of the first joint's transform moves
// every board pose rigidly, as poses of whatever observes the boards (the
// cameras) can; its prior then stays in their marginals, which is what a pose
// measured through an imperfect leg is worth. Relative poses of two such
// observers, solved together, do not carry it. A joint's backlash is seen
// only if the joint moves both ways; moving one way, it is a zero offset.
struct ChainCorrections {
  std::optional<Key> origins;   ///< u: VecX of 6 chain->numJoints()
  std::optional<Key> offsets;   ///< o: VecX of chain->numJoints()
  std::optional<Key> backlash;  ///< b: VecX of chain->numJoints()
  /// With backlash: per joint, the true angle's change per unit of backlash
  /// at this instant (chain order).
  VecX backlash_lag;
};

class ChainKinematicFactor final : public Factor {
 public:
  /// keys: the board pose L (T_base_marker), the mount M (T_tip_marker), then
  /// those of `corrections` that are set, in the order u, o, b; q: the
  /// encoder readings, chain order. Throws std::invalid_argument for a
  /// missing chain, a q or backlash_lag of the wrong size or a noise model
  /// that is not 6-dimensional.
  ChainKinematicFactor(Key board, Key mount, ChainCorrections corrections,
                       std::shared_ptr<const kinematics::KinematicChain> chain, VecX q, NoiseModel::Ptr noise,
                       RobustKernel::Ptr robust = nullptr);

  void evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const override;

  const VecX& jointPositions() const { return q_; }
  const kinematics::KinematicChain& chain() const { return *chain_; }
  const ChainCorrections& corrections() const { return corrections_; }

 private:
  std::shared_ptr<const kinematics::KinematicChain> chain_;
  VecX q_;
  ChainCorrections corrections_;
  int origins_ = -1, offsets_ = -1, backlash_ = -1;  // positions among the keys, -1 when absent
};

}  // namespace fgcal
