// SE(3): rigid transforms T = (R, t) with tangent vectors ordered [w v]
// (rotation first) and right perturbation T ⊕ xi = T * Exp(xi), as DESIGN.md
// fixes. Jacobian names read J_out_in.
#pragma once

#include <cassert>

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

// ---------------------------------------------------------------------------

namespace detail {
// Barfoot's Q(v, w) block of the SE(3) left Jacobian, written for our [w v]
// order: Jl(w, v) = [[Jl(w) 0] [Q(v, w) Jl(w)]]. Series below a threshold.
// sin_t and cos_t are sin and cos of |w|, read only above the series threshold.
// The coefficients of Q below, from their series when theta^2 <
// kSeriesTheta2 (theta, sin and cos are then not read), else from theta,
// sin theta and cos theta.
template <class T>
inline void se3QSeries(const T& t2, T& c1, T& c2, T& c3) {
  c1 = so3CSeries(t2);
  c2 = series4(t2, 1.0 / 24.0, -1.0 / 720.0, 1.0 / 40320.0, -1.0 / 3628800.0, 1.0 / 479001600.0);
  c3 = series4(t2, -1.0 / 60.0, 1.0 / 1260.0, -1.0 / 60480.0, 1.0 / 4989600.0, -1.0 / 622702080.0);
}
inline void se3QCoefficients(double t2, double t, double sin_t, double cos_t, double& c1, double& c2, double& c3) {
  if (t2 < kSeriesTheta2) {
    se3QSeries(t2, c1, c2, c3);
  } else {
    const double s = sin_t, c = cos_t;
    const double inv_t = 1.0 / t, inv_t2 = inv_t * inv_t, inv_t4 = inv_t2 * inv_t2;
    c1 = (t - s) * inv_t2 * inv_t;
    c2 = (t2 / 2.0 + c - 1.0) * inv_t4;
    c3 = (1.0 - t2 / 2.0 - c) * inv_t4 - 3.0 * (t - s - t2 * t / 6.0) * inv_t4 * inv_t;
  }
}
// Q(w, v) of the SE(3) Jacobians, Jl(xi) = [[Jl(w) 0] [Q Jl(w)]], given |w|^2 = t2
// and, when t2 >= kSeriesTheta2, t = |w| with sin t and cos t.
inline Mat3 se3Q(const Vec3& w, const Vec3& v, double t2, double t, double sin_t, double cos_t) {
  double c1, c2, c3;
  se3QCoefficients(t2, t, sin_t, cos_t, c1, c2, c3);
  // Q = V/2 + c1 (WV + VW + WVW) + c2 (WWV + VWW - 3 WVW) - c3/2 (WVWW + WWVW),
  // W = w^, V = v^. With hat(a) hat(b) = b a^T - (a.b) I, s = w.v and
  // u = w x v, the products reduce to outer products: WVW = -s W,
  // WWV + VWW - 3 WVW = u w^T - w u^T + s W, WVWW + WWVW = -2 s W^2, so
  //   Q = V/2 + c1 (v w^T + w v^T) + c2 (u w^T - w u^T) + (c2 - c1) s W
  //       + c3 s w w^T - (2 c1 s + c3 s t2) I.
  // Its antisymmetric part is hat(m): u w^T - w u^T = hat(w x u) and
  // w x u = s w - t2 v, so m = (1/2 - c2 t2) v + (2 c2 - c1) s w. The rest is
  // symmetric: c1 (v w^T + w v^T) + c3 s w w^T - (2 c1 s + c3 s t2) I.
  const double s = w.dot(v);
  const Vec3 m = (0.5 - c2 * t2) * v + ((2.0 * c2 - c1) * s) * w;
  const double a = c3 * s, k = 2.0 * c1 * s + a * t2;
  const auto sym = [&](int i, int j) { return c1 * (v[i] * w[j] + w[i] * v[j]) + a * w[i] * w[j]; };
  Mat3 Q;
  Q(0, 0) = sym(0, 0) - k, Q(1, 1) = sym(1, 1) - k, Q(2, 2) = sym(2, 2) - k;
  Q(1, 0) = Q(0, 1) = sym(1, 0);
  Q(2, 0) = Q(0, 2) = sym(2, 0);
  Q(2, 1) = Q(1, 2) = sym(2, 1);
  addHat(Q, m);
  return Q;
}
inline Mat3 se3Q(const Vec3& w, const Vec3& v) {
  const double t2 = w.squaredNorm();
  if (t2 < kSeriesTheta2) return se3Q(w, v, t2, 0.0, 0.0, 1.0);
  const double t = std::sqrt(t2);
  return se3Q(w, v, t2, t, std::sin(t), std::cos(t));
}
}  // namespace detail

inline SE3 SE3::fromMatrix(const Mat4& T, double tol) {
  if (!T.allFinite()) throw std::invalid_argument("transform holds NaN or inf");
  if ((T.bottomRows<1>() - Eigen::RowVector4d(0, 0, 0, 1)).norm() > tol)
    throw std::invalid_argument("last row of a homogeneous transform must be [0, 0, 0, 1]");
  return SE3(SO3::fromMatrix(T.topLeftCorner<3, 3>(), tol), Vec3(T.topRightCorner<3, 1>()));
}

inline SE3 SE3::exp(const Vec6& xi, Mat6* J_T_xi) {
  // R = I + a W + b W^2 and t = Jl(w) v = v + b w x v + c W^2 v from one set
  // of coefficients (SO3::exp and SO3::leftJacobian would each compute them),
  // with W^2 = w w^T - theta^2 I, so that W^2 x = w (w.x) - theta^2 x.
  const Vec3 w = xi.head<3>(), v = xi.tail<3>();
  const double theta2 = w.squaredNorm();
  double a, b, c;
  detail::so3Coefficients(theta2, a, b, c);
  const Mat3 R = detail::so3Polynomial(1.0 - b * theta2, a, b, w);  // as SO3::exp
  const Vec3 t = v + b * w.cross(v) + c * (w.dot(v) * w - theta2 * v);
  if (J_T_xi) *J_T_xi = rightJacobian(xi);
  return SE3(R, t);
}

namespace detail {
// Log(T) = [w rho] of T = (R, trans) and, when J and K are given (both or
// neither, distinct), the blocks of its inverse right Jacobian
// Jr^-1(xi) = [[J 0] [K J]]. One quaternion gives w and theta^2 (and, past
// the series range, theta, sin and cos); the Jacobian reuses them instead of
// calling sin, cos and atan2 again (this sits in every pose factor's
// evaluation).
inline void se3LogBlocks(const Mat3& R, const Vec3& trans, Vec6& xi, Mat3* J, Mat3* K) {
  assert((J == nullptr) == (K == nullptr) && (J == nullptr || J != K));
  const HalfAngleLog h = so3LogHalfAngle(R);
  const Vec3& w = h.w;
  const double t2 = h.theta2;
  // Jl^-1(w) = I - W/2 + d W^2, Jr^-1(w) = I + W/2 + d W^2 with
  // d = 1/t^2 - (1 + cos t) / (2 t sin t) = 1/t^2 - cot(t/2) / (2 t), and
  // W^2 = w w^T - t^2 I, so that W^2 x = w (w.x) - t^2 x.
  const double d = so3InverseCoefficient(h);
  xi.head<3>() = w;
  xi.tail<3>() = trans - 0.5 * w.cross(trans) + d * (w.dot(trans) * w - t2 * trans);
  if (!J) return;
  // Jr^-1(xi)'s lower-left block is -Jr^-1(w) Q(-w, -v) Jr^-1(w), as rightJacobianInverse.
  Mat3& Ji = *J;
  Ji = so3Polynomial(1.0 - d * t2, 0.5, d, w);  // Jr^-1(w) = I + W/2 + d W^2
  const Mat3 QJ = se3Q(-w, -xi.tail<3>(), t2, h.theta, h.sin_theta, h.cos_theta) * Ji;
  K->noalias() = -Ji * QJ;
}
}  // namespace detail

inline Vec6 SE3::log(Mat6* J_xi_T) const {
  Vec6 xi;
  if (!J_xi_T) {
    detail::se3LogBlocks(R_.matrix(), t_, xi, nullptr, nullptr);
    return xi;
  }
  Mat3 J, K;
  detail::se3LogBlocks(R_.matrix(), t_, xi, &J, &K);
  Mat6& out = *J_xi_T;
  out.topLeftCorner<3, 3>() = J;
  out.topRightCorner<3, 3>().setZero();
  out.bottomLeftCorner<3, 3>() = K;
  out.bottomRightCorner<3, 3>() = J;
  return xi;
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

inline Mat6 SE3::rightJacobian(const Vec6& xi) {
  // Jr(xi) = Jl(-xi).
  const Vec3 w = -xi.head<3>(), v = -xi.tail<3>();
  const Mat3 J = SO3::leftJacobian(w);
  Mat6 out;
  out.topLeftCorner<3, 3>() = J;
  out.topRightCorner<3, 3>().setZero();
  out.bottomLeftCorner<3, 3>() = detail::se3Q(w, v);
  out.bottomRightCorner<3, 3>() = J;
  return out;
}

inline Mat6 SE3::rightJacobianInverse(const Vec6& xi) {
  // Block inverse of [[J 0] [Q J]]: [[J^-1 0] [-J^-1 Q J^-1  J^-1]].
  const Vec3 w = -xi.head<3>(), v = -xi.tail<3>();
  const Mat3 Jinv = SO3::leftJacobianInverse(w);
  Mat6 out;
  out.topLeftCorner<3, 3>() = Jinv;
  out.topRightCorner<3, 3>().setZero();
  out.bottomLeftCorner<3, 3>() = -Jinv * detail::se3Q(w, v) * Jinv;
  out.bottomRightCorner<3, 3>() = Jinv;
  return out;
}

}  // namespace fgcal
