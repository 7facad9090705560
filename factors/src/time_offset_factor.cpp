#include "fgcal/factors/time_offset_factor.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>

namespace fgcal {

namespace {

std::vector<Key> wrappedKeys(const Factor::Ptr& inner, std::size_t board, Key mount, Key time_offset,
                             std::optional<Key> joint_offsets) {
  if (!inner) throw std::invalid_argument("TimeOffsetFactor: no image factor to wrap");
  const std::vector<Key>& k = inner->keys();
  if (board >= k.size())
    throw std::invalid_argument("TimeOffsetFactor: board position " + std::to_string(board) + " of a factor with " +
                                std::to_string(k.size()) + " key(s)");
  if (k.size() > TimeOffsetFactor::kMaxImageKeys)
    throw std::invalid_argument("TimeOffsetFactor: the image factor has " + std::to_string(k.size()) +
                                " keys; at most " + std::to_string(TimeOffsetFactor::kMaxImageKeys) + " are supported");
  std::vector<Key> keys = k;
  keys.push_back(mount);
  keys.push_back(time_offset);
  if (joint_offsets) keys.push_back(*joint_offsets);
  for (std::size_t a = k.size(); a < keys.size(); ++a)
    if (std::count(keys.begin(), keys.end(), keys[a]) != 1)
      throw std::invalid_argument("TimeOffsetFactor: key " + keyToString(keys[a]) +
                                  " appears twice (the image factor may not have the mount or offset keys)");
  return keys;
}

template <class T>
const T& valueOf(const Variable* v) {
  return static_cast<const TypedVariable<T>*>(v)->value();
}

}  // namespace

TimeOffsetFactor::TimeOffsetFactor(Factor::Ptr image_factor, std::size_t board_position, Key mount, Key time_offset,
                                   std::optional<Key> joint_offsets,
                                   std::shared_ptr<const kinematics::KinematicChain> chain,
                                   std::shared_ptr<const JointTrajectory> trajectory, Timing timing,
                                   RobustKernel::Ptr robust)
    : Factor(wrappedKeys(image_factor, board_position, mount, time_offset, joint_offsets),
             image_factor ? image_factor->noiseModelPtr() : nullptr, std::move(robust)),
      inner_(std::move(image_factor)),
      board_(board_position),
      has_offsets_(joint_offsets.has_value()),
      chain_(std::move(chain)),
      trajectory_(std::move(trajectory)),
      timing_(timing) {
  if (!chain_ || !trajectory_) throw std::invalid_argument("TimeOffsetFactor: no kinematic chain or trajectory");
  if (trajectory_->numJoints() != chain_->numJoints())
    throw std::invalid_argument("TimeOffsetFactor: a trajectory of " + std::to_string(trajectory_->numJoints()) +
                                " joints for a chain of " + std::to_string(chain_->numJoints()));
  trajectory_->evaluate(timing_.instant, &q_instant_, nullptr);
}

SE3 TimeOffsetFactor::boardAtExposure(const SE3& L, const SE3& M, double time_offset, const VecX& o) const {
  VecX q_b;
  trajectory_->evaluate(timing_.image + time_offset, &q_b, nullptr);
  if (o.size() == 0) return L * chain_->forward(q_instant_, M, nullptr).between(chain_->forward(q_b, M, nullptr));
  return L * chain_->forward(q_instant_ + o, M, nullptr).between(chain_->forward(q_b + o, M, nullptr));
}

void TimeOffsetFactor::evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const {
  const std::size_t n_inner = inner_->keys().size();
  const SE3& L = valueOf<SE3>(vars[board_]);
  const SE3& M = valueOf<SE3>(vars[n_inner]);
  const double delta = valueOf<VecX>(vars[n_inner + 1])[0];
  const VecX* o = has_offsets_ ? &valueOf<VecX>(vars[n_inner + 2]) : nullptr;

  double* const J_L = jacobians ? jacobians[board_] : nullptr;
  double* const J_M = jacobians ? jacobians[n_inner] : nullptr;
  double* const J_d = jacobians ? jacobians[n_inner + 1] : nullptr;
  double* const J_o = jacobians && o ? jacobians[n_inner + 2] : nullptr;
  const bool need_P = J_L || J_M || J_d || J_o;

  // Per-thread buffers: a graph has a factor per corner, and these are
  // evaluated many times per iteration (factors are evaluated concurrently,
  // never reentrantly).
  thread_local struct {
    VecX q_a, q_b, qdot_b;
    kinematics::KinematicChain::Jacobian Ja, Jb;  // at the board: FK(q + d) M = FK(q) M Exp(J d)
    MatX J_r_P;
  } buf;

  // The joints at the exposure and at the instant (with the offsets when estimated).
  trajectory_->evaluate(timing_.image + delta, &buf.q_b, J_d ? &buf.qdot_b : nullptr);
  buf.q_a = q_instant_;
  if (o) {
    buf.q_a += *o;
    buf.q_b += *o;
  }
  const SE3 Fa = chain_->forward(buf.q_a, M, J_o ? &buf.Ja : nullptr);
  const SE3 Fb = chain_->forward(buf.q_b, M, (J_d || J_o) ? &buf.Jb : nullptr);
  const SE3 D = Fa.between(Fb);
  const TypedVariable<SE3> P(L.compose(D));

  // The wrapped factor on P: its own keys' Jacobians go straight to the
  // caller, the board's into J_r_P for the chain rule.
  std::array<const Variable*, kMaxImageKeys> inner_vars{};
  std::array<double*, kMaxImageKeys> inner_jac{};
  std::copy(vars, vars + n_inner, inner_vars.begin());
  inner_vars[board_] = &P;
  const int d = dim();
  MatX& J_r_P = buf.J_r_P;
  if (jacobians) {
    std::copy(jacobians, jacobians + n_inner, inner_jac.begin());
    if (need_P) J_r_P.resize(d, 6);
    inner_jac[board_] = need_P ? J_r_P.data() : nullptr;
  }
  inner_->evaluate(inner_vars.data(), residual, jacobians ? inner_jac.data() : nullptr);
  if (!need_P) return;

  const Mat6 Ad_Dinv = D.inverse().adjoint();
  if (J_L) Eigen::Map<MatX>(J_L, d, 6).noalias() = J_r_P * Ad_Dinv;
  if (J_M) Eigen::Map<MatX>(J_M, d, 6).noalias() = J_r_P * (Mat6::Identity() - Ad_Dinv);
  if (J_d) Eigen::Map<MatX>(J_d, d, 1).noalias() = J_r_P * (buf.Jb * buf.qdot_b);
  if (J_o) {
    Eigen::Map<MatX> out(J_o, d, buf.Jb.cols());
    out.noalias() = J_r_P * buf.Jb;
    out.noalias() -= (J_r_P * Ad_Dinv) * buf.Ja;
  }
}

std::string TimeOffsetFactor::describe() const { return "time offset on (" + inner_->describe() + ")"; }

}  // namespace fgcal
