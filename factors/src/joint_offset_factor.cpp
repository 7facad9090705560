#include "fgcal/factors/joint_offset_factor.hpp"

#include <stdexcept>
#include <string>

namespace fgcal {

namespace {

/// The checks both chain factors make of what they were given.
void checkChainFactor(const char* factor, const kinematics::KinematicChain* chain, const VecX& q) {
  if (!chain) throw std::invalid_argument(std::string(factor) + ": no kinematic chain");
  if (q.size() != chain->numJoints())
    throw std::invalid_argument(std::string(factor) + ": " + std::to_string(q.size()) +
                                " joint positions for a chain of " + std::to_string(chain->numJoints()) +
                                " movable joints");
}

}  // namespace

JointOffsetKinematicFactor::JointOffsetKinematicFactor(Key board, Key mount, Key offsets,
                                                       std::shared_ptr<const kinematics::KinematicChain> chain, VecX q,
                                                       NoiseModel::Ptr noise, RobustKernel::Ptr robust)
    : TypedFactor({board, mount, offsets}, std::move(noise), std::move(robust)),
      chain_(std::move(chain)),
      q_(std::move(q)) {
  checkChainFactor("JointOffsetKinematicFactor", chain_.get(), q_);
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

namespace {

std::vector<Key> chainKeys(Key board, Key mount, const ChainCorrections& c) {
  std::vector<Key> k{board, mount};
  for (const std::optional<Key>& key : {c.origins, c.offsets, c.backlash})
    if (key) k.push_back(*key);
  return k;
}

const VecX& vecAt(const Variable* const* vars, int i) { return static_cast<const TypedVariable<VecX>*>(vars[i])->value(); }

}  // namespace

ChainKinematicFactor::ChainKinematicFactor(Key board, Key mount, ChainCorrections corrections,
                                           std::shared_ptr<const kinematics::KinematicChain> chain, VecX q,
                                           NoiseModel::Ptr noise, RobustKernel::Ptr robust)
    : Factor(chainKeys(board, mount, corrections), std::move(noise), std::move(robust)),
      chain_(std::move(chain)),
      q_(std::move(q)),
      corrections_(std::move(corrections)) {
  checkChainFactor("ChainKinematicFactor", chain_.get(), q_);
  if (dim() != 6)
    throw std::invalid_argument("ChainKinematicFactor: a noise model of dimension " + std::to_string(dim()) +
                                " (6 expected)");
  int next = 2;
  if (corrections_.origins) origins_ = next++;
  if (corrections_.offsets) offsets_ = next++;
  if (corrections_.backlash) {
    backlash_ = next++;
    if (corrections_.backlash_lag.size() != q_.size())
      throw std::invalid_argument("ChainKinematicFactor: " + std::to_string(corrections_.backlash_lag.size()) +
                                  " backlash coefficients for a chain of " + std::to_string(q_.size()) +
                                  " movable joints");
  }
}

void ChainKinematicFactor::evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const {
  const SE3& L = static_cast<const TypedVariable<SE3>*>(vars[0])->value();
  const SE3& M = static_cast<const TypedVariable<SE3>*>(vars[1])->value();
  auto wanted = [&](int i) { return jacobians && i >= 0 && jacobians[i]; };
  const bool need_u = wanted(origins_), need_o = wanted(offsets_), need_b = wanted(backlash_);
  VecX q = q_;
  if (offsets_ >= 0) q += vecAt(vars, offsets_);
  if (backlash_ >= 0) q += corrections_.backlash_lag.cwiseProduct(vecAt(vars, backlash_));
  kinematics::KinematicChain::Jacobian J_q;
  kinematics::KinematicChain::OriginJacobian J_u;
  kinematics::KinematicChain::Jacobian* jq = need_o || need_b ? &J_q : nullptr;
  const SE3 F = origins_ >= 0 ? chain_->forwardCorrected(q, vecAt(vars, origins_), M, jq, need_u ? &J_u : nullptr)
                              : chain_->forward(q, M, jq);
  const SE3 D = F.between(L);
  Mat6 Jlog;
  const bool need = jacobians && (jacobians[0] || jacobians[1] || need_u || need_o || need_b);
  Eigen::Map<Vec6> r(residual);
  r = D.log(need ? &Jlog : nullptr);
  if (!need) return;
  if (jacobians[0]) Eigen::Map<Mat6>{jacobians[0]} = Jlog;
  const Mat6 J_r_F = SE3::minusLogJacobianTimesInverseAdjoint(Jlog, D);  // F Exp(xi) gives D Exp(-Ad(D^-1) xi)
  if (jacobians[1]) Eigen::Map<Mat6>{jacobians[1]} = J_r_F;
  if (need_u) Eigen::Map<MatX>{jacobians[origins_], 6, J_u.cols()} = J_r_F * J_u;
  if (need_o) Eigen::Map<MatX>{jacobians[offsets_], 6, J_q.cols()}.noalias() = J_r_F * J_q;
  if (need_b)  // d r / d b = (d r / d o) diag(lag), column by column
    Eigen::Map<MatX>{jacobians[backlash_], 6, J_q.cols()}.noalias() =
        J_r_F * (J_q * corrections_.backlash_lag.asDiagonal());
}

}  // namespace fgcal
