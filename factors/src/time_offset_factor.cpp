#include "fgcal/factors/time_offset_factor.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace fgcal {

namespace {

std::vector<Key> wrappedKeys(const Factor::Ptr& inner, std::size_t board, const TimeOffsetFactor::Variables& v) {
  if (!inner) throw std::invalid_argument("TimeOffsetFactor: no image factor to wrap");
  const std::vector<Key>& k = inner->keys();
  if (board >= k.size())
    throw std::invalid_argument("TimeOffsetFactor: board position " + std::to_string(board) + " of a factor with " +
                                std::to_string(k.size()) + " key(s)");
  if (k.size() > TimeOffsetFactor::kMaxImageKeys)
    throw std::invalid_argument("TimeOffsetFactor: the image factor has " + std::to_string(k.size()) +
                                " keys; at most " + std::to_string(TimeOffsetFactor::kMaxImageKeys) + " are supported");
  std::vector<Key> keys = k;
  keys.push_back(v.mount);
  for (const std::optional<Key>& o : {v.time_offset, v.readout, v.joint_offsets})
    if (o) keys.push_back(*o);
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

TimeOffsetFactor::TimeOffsetFactor(Factor::Ptr image_factor, std::size_t board_position, const Variables& variables,
                                   std::shared_ptr<const kinematics::KinematicChain> chain,
                                   std::shared_ptr<const JointTrajectory> trajectory, Timing timing,
                                   RobustKernel::Ptr robust)
    : Factor(wrappedKeys(image_factor, board_position, variables),
             image_factor ? image_factor->noiseModelPtr() : nullptr, std::move(robust)),
      inner_(std::move(image_factor)),
      board_(board_position),
      chain_(std::move(chain)),
      trajectory_(std::move(trajectory)),
      timing_(timing) {
  if (!chain_ || !trajectory_) throw std::invalid_argument("TimeOffsetFactor: no kinematic chain or trajectory");
  if (trajectory_->numJoints() != chain_->numJoints())
    throw std::invalid_argument("TimeOffsetFactor: a trajectory of " + std::to_string(trajectory_->numJoints()) +
                                " joints for a chain of " + std::to_string(chain_->numJoints()));
  if (!(timing_.row >= 0.0 && timing_.row <= 1.0))
    throw std::invalid_argument("TimeOffsetFactor: a row fraction of " + std::to_string(timing_.row) +
                                "; expected one in [0, 1]");
  if (!std::isfinite(timing_.time_offset) || !std::isfinite(timing_.readout) || !std::isfinite(timing_.instant) ||
      !std::isfinite(timing_.image))
    throw std::invalid_argument("TimeOffsetFactor: a timing that is not finite");
  int next = static_cast<int>(inner_->keys().size()) + 1;
  if (variables.time_offset) time_offset_ = next++;
  if (variables.readout) readout_ = next++;
  if (variables.joint_offsets) joint_offsets_ = next++;
  trajectory_->evaluate(timing_.instant, &q_instant_, nullptr);
}

TimeOffsetFactor::TimeOffsetFactor(Factor::Ptr image_factor, std::size_t board_position, Key mount, Key time_offset,
                                   std::optional<Key> joint_offsets,
                                   std::shared_ptr<const kinematics::KinematicChain> chain,
                                   std::shared_ptr<const JointTrajectory> trajectory, Timing timing,
                                   RobustKernel::Ptr robust)
    : TimeOffsetFactor(std::move(image_factor), board_position, Variables{mount, time_offset, std::nullopt, joint_offsets},
                       std::move(chain), std::move(trajectory), timing, std::move(robust)) {}

SE3 TimeOffsetFactor::boardAtExposure(const SE3& L, const SE3& M, double time_offset, const VecX& o) const {
  return boardAtExposure(L, M, time_offset, timing_.readout, o);
}

SE3 TimeOffsetFactor::boardAtExposure(const SE3& L, const SE3& M, double time_offset, double readout,
                                      const VecX& o) const {
  VecX q_b;
  trajectory_->evaluate(timing_.image + time_offset + timing_.row * readout, &q_b, nullptr);
  if (o.size() == 0) return L * chain_->forward(q_instant_, M, nullptr).between(chain_->forward(q_b, M, nullptr));
  return L * chain_->forward(q_instant_ + o, M, nullptr).between(chain_->forward(q_b + o, M, nullptr));
}

void TimeOffsetFactor::evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const {
  const std::size_t n_inner = inner_->keys().size();
  const SE3& L = valueOf<SE3>(vars[board_]);
  const SE3& M = valueOf<SE3>(vars[n_inner]);
  const double delta = time_offset_ >= 0 ? valueOf<VecX>(vars[time_offset_])[0] : timing_.time_offset;
  const double readout = readout_ >= 0 ? valueOf<VecX>(vars[readout_])[0] : timing_.readout;
  const VecX* o = joint_offsets_ >= 0 ? &valueOf<VecX>(vars[joint_offsets_]) : nullptr;

  double* const J_L = jacobians ? jacobians[board_] : nullptr;
  double* const J_M = jacobians ? jacobians[n_inner] : nullptr;
  double* const J_d = jacobians && time_offset_ >= 0 ? jacobians[time_offset_] : nullptr;
  double* const J_R = jacobians && readout_ >= 0 ? jacobians[readout_] : nullptr;
  double* const J_o = jacobians && o ? jacobians[joint_offsets_] : nullptr;
  const bool need_P = J_L || J_M || J_d || J_R || J_o;
  const bool need_velocity = J_d || J_R;

  // Per-thread buffers: a graph has a factor per corner, and these are
  // evaluated many times per iteration (factors are evaluated concurrently,
  // never reentrantly).
  thread_local struct {
    VecX q_a, q_b, qdot_b;
    kinematics::KinematicChain::Jacobian Ja, Jb;  // at the board: FK(q + d) M = FK(q) M Exp(J d)
    MatX J_r_P;
  } buf;

  // The joints at the exposure and at the instant (with the offsets when estimated).
  trajectory_->evaluate(timing_.image + delta + timing_.row * readout, &buf.q_b, need_velocity ? &buf.qdot_b : nullptr);
  buf.q_a = q_instant_;
  if (o) {
    buf.q_a += *o;
    buf.q_b += *o;
  }
  const SE3 Fa = chain_->forward(buf.q_a, M, J_o ? &buf.Ja : nullptr);
  const SE3 Fb = chain_->forward(buf.q_b, M, (need_velocity || J_o) ? &buf.Jb : nullptr);
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
  if (need_velocity) {
    // The board's body velocity at the exposure: d/ddelta, and r of it per unit of readout.
    const Vec6 V = buf.Jb * buf.qdot_b;
    if (J_d) Eigen::Map<MatX>(J_d, d, 1).noalias() = J_r_P * V;
    if (J_R) Eigen::Map<MatX>(J_R, d, 1).noalias() = J_r_P * (timing_.row * V);
  }
  if (J_o) {
    Eigen::Map<MatX> out(J_o, d, buf.Jb.cols());
    out.noalias() = J_r_P * buf.Jb;
    out.noalias() -= (J_r_P * Ad_Dinv) * buf.Ja;
  }
}

std::string TimeOffsetFactor::describe() const { return "time offset on (" + inner_->describe() + ")"; }

}  // namespace fgcal
