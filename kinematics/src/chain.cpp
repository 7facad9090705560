// Chain construction (collapsing fixed joints, inverting joints walked upward)
// and the allocation-free forward and backward passes.
#include "fgcal/kinematics/chain.hpp"

#include <cmath>
#include <sstream>

#include "fgcal/kinematics/errors.hpp"

namespace fgcal::kinematics {

namespace {

std::string sourceLabel(const std::string& source) {
  return source.empty() ? std::string("robot model") : "URDF '" + source + "'";
}

// Rotation by angle about a unit axis, with K = hat(axis), K2 = K^2 precomputed.
inline Mat3 rodrigues(const Mat3& K, const Mat3& K2, double angle) {
  const double s = std::sin(angle), c = std::cos(angle);
  Mat3 R = s * K + (1.0 - c) * K2;
  R.diagonal().array() += 1.0;
  return R;
}

// The two other axes of e_k in cyclic order: Rot_k maps e_a -> c e_a + s e_b.
constexpr int kA[3] = {1, 2, 0};
constexpr int kB[3] = {2, 0, 1};

// R <- R * Rot_k(angle), given c = cos(angle), s = sin(angle).
inline void rotateRight(Mat3& R, int k, double c, double s) {
  const Vec3 ca = R.col(kA[k]), cb = R.col(kB[k]);
  R.col(kA[k]) = c * ca + s * cb;
  R.col(kB[k]) = c * cb - s * ca;
}

// X <- Rot_k(angle) * X for a 3x3 matrix or a 3-vector.
template <class Derived>
inline void rotateLeft(Eigen::MatrixBase<Derived>& X, int k, double c, double s) {
  const auto ra = X.row(kA[k]).eval();
  const auto rb = X.row(kB[k]).eval();
  X.row(kA[k]) = c * ra - s * rb;
  X.row(kB[k]) = s * ra + c * rb;
}

}  // namespace

KinematicChain::KinematicChain(std::string base_link, std::string tip_link, const std::vector<PathStep>& path,
                               std::string source)
    : base_link_(std::move(base_link)), tip_link_(std::move(tip_link)), source_(std::move(source)) {
  num_path_joints_ = static_cast<int>(path.size());
  // C accumulates the constant transform since the last movable joint.
  SE3 C;
  for (const PathStep& step : path) {
    const JointInfo& j = step.joint;
    if (j.type == JointType::Floating || j.type == JointType::Planar) {
      std::ostringstream s;
      s << sourceLabel(source_) << ": joint '" << j.name << "' (" << toString(j.type) << ", between links '"
        << j.parent_link << "' and '" << j.child_link << "') lies on the chain from '" << base_link_ << "' to '"
        << tip_link_ << "'; the chain walker follows only revolute, continuous, prismatic and fixed joints";
      throw UrdfError(s.str());
    }
    if (!j.T_parent_joint.matrix().allFinite()) {
      throw UrdfError(sourceLabel(source_) + ": joint '" + j.name + "' has a non-finite <origin>; expected finite xyz and rpy");
    }
    if (j.type == JointType::Fixed) {
      // Walking a fixed joint upward uses the inverse of its origin.
      C = step.upward ? C * j.T_parent_joint.inverse() : C * j.T_parent_joint;
      continue;
    }
    const double n = j.axis.norm();
    if (!(n > 1e-9) || !std::isfinite(n)) {
      std::ostringstream s;
      s << sourceLabel(source_) << ": joint '" << j.name << "' (" << toString(j.type) << ") has axis ("
        << j.axis.transpose() << "); expected a non-zero, finite <axis xyz>";
      throw UrdfError(s.str());
    }
    // Downward: T_parent_child = O * M(q), so C_{i-1} = C * O and M follows.
    // Upward:   T_child_parent = M(q)^-1 * O^-1 = M_{-axis}(q) * O^-1, so the
    //           motion comes first with the axis negated and O^-1 starts the
    //           next constant.
    Step s;
    const SE3 before = step.upward ? C : C * j.T_parent_joint;
    s.R_before = before.rotation();
    s.t_before = before.translation();
    s.axis = (step.upward ? -1.0 : 1.0) * j.axis / n;
    s.K = hat(s.axis);
    s.K2 = s.K * s.K;
    s.prismatic = j.type == JointType::Prismatic;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(s.axis[k]) == 1.0 && s.axis.squaredNorm() == 1.0) {
        s.unit_axis = k;
        s.unit_sign = s.axis[k];
      }
    }
    steps_.push_back(s);
    C = step.upward ? j.T_parent_joint.inverse() : SE3();

    ChainJoint cj;
    cj.name = j.name;
    cj.type = j.type;
    cj.limits = j.limits;
    cj.upward = step.upward;
    joints_.push_back(cj);
    joint_names_.push_back(j.name);
  }
  R_tail_ = C.rotation();
  t_tail_ = C.translation();
}

Vec3 KinematicChain::originTranslation(int i) const {
  if (i < 0 || i >= numJoints())
    throw KinematicsError("originTranslation: joint index " + std::to_string(i) + " outside the chain's " +
                          std::to_string(numJoints()) + " movable joints");
  const Step& s = steps_[static_cast<std::size_t>(i)];
  return s.R_before.transpose() * s.t_before;
}

std::vector<JointType> KinematicChain::jointTypes() const {
  std::vector<JointType> out;
  out.reserve(joints_.size());
  for (const auto& j : joints_) out.push_back(j.type);
  return out;
}

std::vector<JointLimits> KinematicChain::jointLimits() const {
  std::vector<JointLimits> out;
  out.reserve(joints_.size());
  for (const auto& j : joints_) out.push_back(j.limits);
  return out;
}

int KinematicChain::indexOf(const std::string& joint_name) const {
  for (std::size_t i = 0; i < joint_names_.size(); ++i)
    if (joint_names_[i] == joint_name) return static_cast<int>(i);
  return -1;
}

void KinematicChain::checkSize(const Eigen::Ref<const VecX>& q, const char* what) const {
  if (q.size() != numJoints()) {
    std::ostringstream s;
    s << "chain '" << base_link_ << "' -> '" << tip_link_ << "' has " << numJoints() << " movable joints, but "
      << what << " has " << q.size() << " values";
    throw KinematicsError(s.str());
  }
}

SE3 KinematicChain::forward(const Eigen::Ref<const VecX>& q) const {
  checkSize(q, "the joint vector");
  // Forward pass: T = C_0, then T <- T M_i C_i.
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  for (std::size_t i = 0; i < steps_.size(); ++i) {
    const Step& s = steps_[i];
    t += R * s.t_before;
    R = (R * s.R_before).eval();
    const double qi = q[static_cast<Eigen::Index>(i)];
    if (s.prismatic) {
      t += R * (qi * s.axis);
    } else if (s.unit_axis >= 0) {
      rotateRight(R, s.unit_axis, std::cos(qi), s.unit_sign * std::sin(qi));
    } else {
      R = (R * rodrigues(s.K, s.K2, qi)).eval();
    }
  }
  t += R * t_tail_;
  R = (R * R_tail_).eval();
  return SE3(R, t);
}

SE3 KinematicChain::backward(const Eigen::Ref<const VecX>& q, const SE3* T_tip_marker, Jacobian* J,
                             const Eigen::Ref<const VecX>* sigma, Mat6* Sigma, const Eigen::Ref<const VecX>* u,
                             OriginJacobian* J_u) const {
  // B is everything after motion i: T = A_i Exp(q_i xi_i) B_i, hence
  // T(q + dq e_i) = T Exp(dq Ad(B_i^-1) xi_i) and column i is Ad(B_i^-1) xi_i:
  // for xi = [w; v], Ad(B^-1) xi = [R_B^T w; R_B^T (w x t_B + v)].
  Mat3 R = R_tail_;
  Vec3 t = t_tail_;
  if (T_tip_marker) {
    t += R * T_tip_marker->translation();
    R = (R * T_tip_marker->rotation()).eval();
  }
  if (Sigma) Sigma->setZero();
  for (std::size_t k = steps_.size(); k-- > 0;) {
    const Step& s = steps_[k];
    const auto i = static_cast<Eigen::Index>(k);
    Vec6 col;
    if (s.prismatic) {
      col.head<3>().setZero();
      col.tail<3>().noalias() = R.transpose() * s.axis;
      t += q[i] * s.axis;  // B <- M_i B
    } else {
      col.head<3>().noalias() = R.transpose() * s.axis;
      col.tail<3>().noalias() = R.transpose() * s.axis.cross(t);
      if (s.unit_axis >= 0) {
        const double c = std::cos(q[i]), sn = s.unit_sign * std::sin(q[i]);
        rotateLeft(t, s.unit_axis, c, sn);
        rotateLeft(R, s.unit_axis, c, sn);
      } else {
        const Mat3 M = rodrigues(s.K, s.K2, q[i]);
        t = (M * t).eval();
        R = (M * R).eval();
      }
    }
    if (J) J->col(i) = col;
    if (Sigma) {
      const double var = (*sigma)[i] * (*sigma)[i];
      Sigma->noalias() += (var * col) * col.transpose();
    }
    if (u || J_u) {
      // T = A C_{i-1} Exp(u_i) B: a change du of u_i moves the marker by
      // Ad(B^-1) Jr(u_i) du.
      const Vec6 ui = u ? Vec6((*u).segment<6>(6 * i)) : Vec6::Zero();
      if (J_u) {
        const Mat6 A = SE3(R, t).inverse().adjoint();
        J_u->middleCols<6>(6 * i) = u ? Mat6(A * SE3::rightJacobian(ui)) : A;
      }
      if (u) {  // B <- Exp(u_i) B
        const SE3 E = SE3::exp(ui);
        t = (E.rotation() * t + E.translation()).eval();
        R = (E.rotation() * R).eval();
      }
    }
    // B <- C_{i-1} B
    t = (s.R_before * t + s.t_before).eval();
    R = (s.R_before * R).eval();
  }
  return SE3(R, t);
}

SE3 KinematicChain::forward(const Eigen::Ref<const VecX>& q, Jacobian* J_T_q) const {
  if (!J_T_q) return forward(q);
  checkSize(q, "the joint vector");
  if (J_T_q->cols() != numJoints()) J_T_q->resize(6, numJoints());
  return backward(q, nullptr, J_T_q, nullptr, nullptr);
}

SE3 KinematicChain::forward(const Eigen::Ref<const VecX>& q, const SE3& T_tip_marker, Jacobian* J_T_q) const {
  checkSize(q, "the joint vector");
  if (J_T_q && J_T_q->cols() != numJoints()) J_T_q->resize(6, numJoints());
  return backward(q, &T_tip_marker, J_T_q, nullptr, nullptr);
}

SE3 KinematicChain::forwardWithCovariance(const Eigen::Ref<const VecX>& q, const Eigen::Ref<const VecX>& sigma_q,
                                          Mat6* Sigma_T, const SE3& T_tip_marker, Jacobian* J_T_q) const {
  checkSize(q, "the joint vector");
  checkSize(sigma_q, "the sigma vector");
  if (J_T_q && J_T_q->cols() != numJoints()) J_T_q->resize(6, numJoints());
  return backward(q, &T_tip_marker, J_T_q, Sigma_T ? &sigma_q : nullptr, Sigma_T);
}

SE3 KinematicChain::forwardCorrected(const Eigen::Ref<const VecX>& q, const Eigen::Ref<const VecX>& u,
                                     const SE3& T_tip_marker, Jacobian* J_T_q, OriginJacobian* J_T_u) const {
  checkSize(q, "the joint vector");
  if (u.size() != 6 * numJoints()) {
    std::ostringstream s;
    s << "chain '" << base_link_ << "' -> '" << tip_link_ << "' has " << numJoints()
      << " movable joints (6 origin corrections each), but the correction vector has " << u.size() << " values";
    throw KinematicsError(s.str());
  }
  if (J_T_q && J_T_q->cols() != numJoints()) J_T_q->resize(6, numJoints());
  if (J_T_u && J_T_u->cols() != 6 * numJoints()) J_T_u->resize(6, 6 * numJoints());
  return backward(q, &T_tip_marker, J_T_q, nullptr, nullptr, &u, J_T_u);
}

Mat6 KinematicChain::covariance(const Eigen::Ref<const VecX>& q, const Eigen::Ref<const VecX>& sigma_q,
                                const SE3& T_tip_marker) const {
  Mat6 Sigma;
  forwardWithCovariance(q, sigma_q, &Sigma, T_tip_marker);
  return Sigma;
}

VecX KinematicChain::jointVector(const std::map<std::string, double>& values) const {
  VecX q(numJoints());
  for (int i = 0; i < numJoints(); ++i) {
    const auto it = values.find(joint_names_[static_cast<std::size_t>(i)]);
    if (it == values.end()) {
      throw KinematicsError("chain '" + base_link_ + "' -> '" + tip_link_ + "' needs a value for joint '" +
                            joint_names_[static_cast<std::size_t>(i)] + "', which is missing");
    }
    q[i] = it->second;
  }
  return q;
}

VecX KinematicChain::sigmaVector(double sigma) const {
  if (!(sigma >= 0.0) || !std::isfinite(sigma))
    throw KinematicsError("encoder sigma must be finite and >= 0, got " + std::to_string(sigma));
  return VecX::Constant(numJoints(), sigma);
}

VecX KinematicChain::sigmaVector(const std::map<std::string, double>& sigmas, std::optional<double> fallback) const {
  VecX out(numJoints());
  for (int i = 0; i < numJoints(); ++i) {
    const std::string& name = joint_names_[static_cast<std::size_t>(i)];
    const auto it = sigmas.find(name);
    double s = 0.0;
    if (it != sigmas.end()) {
      s = it->second;
    } else if (fallback) {
      s = *fallback;
    } else {
      throw KinematicsError("chain '" + base_link_ + "' -> '" + tip_link_ + "' needs an encoder sigma for joint '" +
                            name + "', which is missing (and no default sigma was given)");
    }
    if (!(s >= 0.0) || !std::isfinite(s))
      throw KinematicsError("encoder sigma of joint '" + name + "' must be finite and >= 0, got " + std::to_string(s));
    out[i] = s;
  }
  return out;
}

}  // namespace fgcal::kinematics
