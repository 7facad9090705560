// SE(3): rigid transforms T = (R, t) with tangent vectors ordered [w v]
// (rotation first) and right perturbation T ⊕ xi = T * Exp(xi), as docs/outputs.md ("Conventions")
// fixes. Jacobian names read J_out_in.
#pragma once

#include "fgcal/core/so3.hpp"

namespace fgcal {

class SE3 {
 public:
  static constexpr int DoF = 6;

  SE3() : R_(), t_(Vec3::Zero()) {}
  SE3(const SO3& R, const Vec3& t) : R_(R), t_(t) {}
  SE3(const Mat3& R, const Vec3& t) : R_(R), t_(t) {}
  /// Takes the top 3x4 of a homogeneous matrix as it is.
  explicit SE3(const Mat4& T) : R_(Mat3(T.topLeftCorner<3, 3>())), t_(T.topRightCorner<3, 1>()) {}

  /// Checked construction from a 4x4: throws std::invalid_argument when the
  /// rotation block is not a rotation or the last row is not [0 0 0 1].
  static SE3 fromMatrix(const Mat4& T, double tol = 1e-6);

  static SE3 identity() { return SE3(); }

  /// Exp([w v]); J_T_xi, when given, receives the right Jacobian Jr(xi).
  static SE3 exp(const Vec6& xi, Mat6* J_T_xi = nullptr);
  /// Log(T) as [w v]; J_xi_T, when given, receives Jr^-1(Log T).
  Vec6 log(Mat6* J_xi_T = nullptr) const;

  /// -J_log Ad(D^-1): for a residual r = Log(E) with E = C D and D = A^-1 B,
  /// the Jacobian of r with respect to a right perturbation of A, when J_log
  /// is log's Jacobian at E (E = D in the plainest case). Built from 3x3
  /// blocks: J_log has log's structure [[J 0] [K J]] and Ad(D^-1) =
  /// [[Rt 0] [-Rt t^  Rt]], so the product is [[-J Rt 0] [J Rt t^ - K Rt  -J Rt]].
  static Mat6 minusLogJacobianTimesInverseAdjoint(const Mat6& J_log, const SE3& D);

  static Mat6 rightJacobian(const Vec6& xi);
  static Mat6 rightJacobianInverse(const Vec6& xi);
  static Mat6 leftJacobian(const Vec6& xi) { return rightJacobian(-xi); }
  static Mat6 leftJacobianInverse(const Vec6& xi) { return rightJacobianInverse(-xi); }

  const SO3& so3() const { return R_; }
  const Mat3& rotation() const { return R_.matrix(); }
  const Vec3& translation() const { return t_; }
  Mat4 matrix() const {
    Mat4 T = Mat4::Identity();
    T.topLeftCorner<3, 3>() = R_.matrix();
    T.topRightCorner<3, 1>() = t_;
    return T;
  }

  /// Ad(T) with T Exp(xi) T^-1 = Exp(Ad(T) xi), in [w v] order: [[R 0] [t^R R]].
  Mat6 adjoint() const {
    Mat6 A;
    const Mat3& R = R_.matrix();
    A.topLeftCorner<3, 3>() = R;
    A.topRightCorner<3, 3>().setZero();
    A.bottomLeftCorner<3, 3>() = hat(t_) * R;
    A.bottomRightCorner<3, 3>() = R;
    return A;
  }

  SE3 inverse(Mat6* J_inv_T = nullptr) const {
    if (J_inv_T) *J_inv_T = -adjoint();
    const Mat3 Rt = R_.matrix().transpose();
    return SE3(Rt, -(Rt * t_));
  }

  SE3 compose(const SE3& other, Mat6* J_out_this = nullptr, Mat6* J_out_other = nullptr) const {
    if (J_out_this) *J_out_this = other.inverse().adjoint();
    if (J_out_other) J_out_other->setIdentity();
    return SE3(SO3(R_.matrix() * other.rotation()), R_.matrix() * other.t_ + t_);
  }
  SE3 operator*(const SE3& other) const { return compose(other); }

  /// this^-1 * other.
  SE3 between(const SE3& other, Mat6* J_out_this = nullptr, Mat6* J_out_other = nullptr) const {
    const Mat3 Rt = R_.matrix().transpose();
    const SE3 D(SO3(Rt * other.rotation()), Rt * (other.t_ - t_));
    if (J_out_this) *J_out_this = -D.inverse().adjoint();
    if (J_out_other) J_out_other->setIdentity();
    return D;
  }

  /// T * p = R p + t.
  Vec3 act(const Vec3& p, Mat36* J_out_T = nullptr, Mat3* J_out_p = nullptr) const {
    const Mat3& R = R_.matrix();
    if (J_out_T) {
      J_out_T->leftCols<3>() = -R * hat(p);
      J_out_T->rightCols<3>() = R;
    }
    if (J_out_p) *J_out_p = R;
    return R * p + t_;
  }
  Vec3 operator*(const Vec3& p) const { return R_.matrix() * p + t_; }

  SE3 plus(const Vec6& xi) const { return compose(exp(xi)); }
  /// The xi with this ⊕ xi = other.
  Vec6 minus(const SE3& other) const { return between(other).log(); }

  SE3 normalized() const { return SE3(R_.normalized(), t_); }

  /// [x y z roll pitch yaw], what a URDF <origin xyz rpy> wants.
  Eigen::Matrix<double, 6, 1> xyzRpy() const {
    Eigen::Matrix<double, 6, 1> out;
    out << t_, R_.rpy();
    return out;
  }
  static SE3 fromXyzRpy(const Vec3& xyz, const Vec3& rpy) {
    return SE3(SO3::fromRpy(rpy.x(), rpy.y(), rpy.z()), xyz);
  }

 private:
  SO3 R_;
  Vec3 t_;
};

// Inline: small, and free of the series (exp, log and the Jacobians are in src/).

inline SE3 SE3::fromMatrix(const Mat4& T, double tol) {
  if (!T.allFinite()) throw std::invalid_argument("transform holds NaN or inf");
  if ((T.bottomRows<1>() - Eigen::RowVector4d(0, 0, 0, 1)).norm() > tol)
    throw std::invalid_argument("last row of a homogeneous transform must be [0, 0, 0, 1]");
  return SE3(SO3::fromMatrix(T.topLeftCorner<3, 3>(), tol), Vec3(T.topRightCorner<3, 1>()));
}

inline Mat6 SE3::minusLogJacobianTimesInverseAdjoint(const Mat6& J_log, const SE3& D) {
  const Mat3 Rt = D.rotation().transpose();
  const Mat3 JRt = J_log.topLeftCorner<3, 3>() * Rt;
  Mat6 out;
  out.topLeftCorner<3, 3>() = -JRt;
  out.topRightCorner<3, 3>().setZero();
  out.bottomLeftCorner<3, 3>() = JRt * hat(D.translation()) - J_log.bottomLeftCorner<3, 3>() * Rt;
  out.bottomRightCorner<3, 3>() = -JRt;
  return out;
}

}  // namespace fgcal
