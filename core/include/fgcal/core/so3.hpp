// SO(3): rotations, with exp/log stable near 0 and near pi, and the Jacobians
// of every operation under the right perturbation R ⊕ w = R * Exp(w).
// Jacobian names read J_out_in: J_result_a is d(result)/d(a) in tangent space.
#pragma once

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "fgcal/core/types.hpp"

namespace fgcal {

inline Mat3 hat(const Vec3& w) {
  Mat3 m;
  m << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return m;
}

inline Vec3 vee(const Mat3& m) { return Vec3(m(2, 1), m(0, 2), m(1, 0)); }

class SO3 {
 public:
  static constexpr int DoF = 3;

  SO3() : R_(Mat3::Identity()) {}
  /// Takes a rotation matrix as it is; see fromMatrix for a checked version.
  explicit SO3(const Mat3& R) : R_(R) {}
  explicit SO3(const Eigen::Quaterniond& q) : R_(q.normalized().toRotationMatrix()) {}

  /// Checked construction: throws std::invalid_argument when R is not a rotation
  /// within tol (orthonormality and determinant +1); re-orthonormalizes otherwise.
  static SO3 fromMatrix(const Mat3& R, double tol = 1e-6) {
    if (!R.allFinite()) throw std::invalid_argument("rotation matrix holds NaN or inf");
    const double ortho = (R.transpose() * R - Mat3::Identity()).norm();
    if (ortho > tol || std::abs(R.determinant() - 1.0) > tol)
      throw std::invalid_argument("matrix is not a rotation (|R^T R - I| = " + std::to_string(ortho) +
                                  ", det = " + std::to_string(R.determinant()) + ")");
    return SO3(R).normalized();
  }

  static SO3 identity() { return SO3(); }

  /// Exp(w); J_R_w, when given, receives the right Jacobian Jr(w).
  static SO3 exp(const Vec3& w, Mat3* J_R_w = nullptr);
  /// Log(R) in (-pi, pi]; J_w_R, when given, receives Jr^-1(Log R).
  Vec3 log(Mat3* J_w_R = nullptr) const;

  static Mat3 rightJacobian(const Vec3& w);
  static Mat3 rightJacobianInverse(const Vec3& w);
  static Mat3 leftJacobian(const Vec3& w) { return rightJacobian(-w); }
  static Mat3 leftJacobianInverse(const Vec3& w) { return rightJacobianInverse(-w); }

  const Mat3& matrix() const { return R_; }
  Eigen::Quaterniond quaternion() const { return Eigen::Quaterniond(R_); }
  Mat3 adjoint() const { return R_; }

  SO3 inverse(Mat3* J_inv_R = nullptr) const {
    if (J_inv_R) *J_inv_R = -R_;
    return SO3(R_.transpose());
  }

  SO3 compose(const SO3& other, Mat3* J_out_this = nullptr, Mat3* J_out_other = nullptr) const {
    if (J_out_this) *J_out_this = other.R_.transpose();
    if (J_out_other) J_out_other->setIdentity();
    return SO3(R_ * other.R_);
  }
  SO3 operator*(const SO3& other) const { return SO3(R_ * other.R_); }

  /// this^-1 * other.
  SO3 between(const SO3& other, Mat3* J_out_this = nullptr, Mat3* J_out_other = nullptr) const {
    const Mat3 D = R_.transpose() * other.R_;
    if (J_out_this) *J_out_this = -D.transpose();
    if (J_out_other) J_out_other->setIdentity();
    return SO3(D);
  }

  Vec3 act(const Vec3& p, Mat3* J_out_R = nullptr, Mat3* J_out_p = nullptr) const {
    if (J_out_R) *J_out_R = -R_ * hat(p);
    if (J_out_p) *J_out_p = R_;
    return R_ * p;
  }
  Vec3 operator*(const Vec3& p) const { return R_ * p; }

  SO3 plus(const Vec3& w) const { return SO3(R_ * exp(w).R_); }
  /// The w with this ⊕ w = other.
  Vec3 minus(const SO3& other) const { return between(other).log(); }

  SO3 normalized() const {
    Eigen::JacobiSVD<Mat3> svd(R_, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat3 R = svd.matrixU() * svd.matrixV().transpose();
    if (R.determinant() < 0) {
      Mat3 U = svd.matrixU();
      U.col(2) *= -1.0;
      R = U * svd.matrixV().transpose();
    }
    return SO3(R);
  }

  /// Roll, pitch, yaw (URDF convention: R = Rz(yaw) Ry(pitch) Rx(roll)).
  Vec3 rpy() const;
  static SO3 fromRpy(double roll, double pitch, double yaw);

 private:
  Mat3 R_;
};

// ---------------------------------------------------------------------------
// Implementation (inline: these sit in every solver's hot loop).

namespace detail {
// Below this theta^2 (|theta| < 0.1) the coefficient functions of theta come
// from their Taylor series through theta^8, whose first omitted term is below
// 1e-17 of the value there. The closed forms would cost a square root, sin,
// cos and divisions, and lose digits to cancellation at small angles
// ((t - sin t) / t^3 keeps about 10 of them at t = 0.01, 6 for Q's c3).
inline constexpr double kSeriesTheta2 = 1e-2;
// c0 + c1 x + c2 x^2 + c3 x^3 + c4 x^4, by Horner's rule.
// The series below are templates on the scalar: double, or Eigen::Array2d
// for two evaluations in the lanes of one register (the same operations).
// One operation per statement: as one nested expression, GCC leaves Eigen's
// assignment of it to an Array2d out of line (a call per series).
template <class T>
inline T series4(const T& x, double c0, double c1, double c2, double c3, double c4) {
  T s = x * c4;
  s += c3;
  s *= x;
  s += c2;
  s *= x;
  s += c1;
  s *= x;
  s += c0;
  return s;
}
// c(t) = (t - sin t)/t^3 below kSeriesTheta2: exp's third coefficient and
// the first of SE(3)'s Q.
template <class T>
inline T so3CSeries(const T& theta2) {
  return series4(theta2, 1.0 / 6.0, -1.0 / 120.0, 1.0 / 5040.0, -1.0 / 362880.0, 1.0 / 39916800.0);
}
// Coefficients a(t) = sin t / t, b(t) = (1 - cos t)/t^2, c(t) = (t - sin t)/t^3.
inline void so3Coefficients(double theta2, double& a, double& b, double& c) {
  if (theta2 < kSeriesTheta2) {
    a = series4(theta2, 1.0, -1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362880.0);
    b = series4(theta2, 0.5, -1.0 / 24.0, 1.0 / 720.0, -1.0 / 40320.0, 1.0 / 3628800.0);
    c = so3CSeries(theta2);
  } else {
    const double theta = std::sqrt(theta2);
    const double s = std::sin(theta), co = std::cos(theta);
    a = s / theta;
    b = (1.0 - co) / theta2;
    c = (theta - s) / (theta2 * theta);
  }
}
// d(t) = 1/t^2 - (1 + cos t) / (2 t sin t), of the inverse Jacobians
// Jr^-1(w) = I + W/2 + d W^2, below kSeriesTheta2.
template <class T>
inline T so3InverseCoefficientSeries(const T& theta2) {
  return series4(theta2, 1.0 / 12.0, 1.0 / 720.0, 1.0 / 30240.0, 1.0 / 1209600.0, 1.0 / 47900160.0);
}
// M += hat(a).
inline void addHat(Mat3& M, const Vec3& a) {
  M(0, 1) -= a.z(), M(1, 0) += a.z();
  M(0, 2) += a.y(), M(2, 0) -= a.y();
  M(1, 2) -= a.x(), M(2, 1) += a.x();
}
// alpha I + beta W + gamma w w^T, W = hat(w): the form of Exp, Jr, Jl and
// their inverses, since W^2 = w w^T - |w|^2 I (no 3x3 product).
inline Mat3 so3Polynomial(double alpha, double beta, double gamma, const Vec3& w) {
  Mat3 M;
  M.noalias() = gamma * (w * w.transpose());
  M.diagonal().array() += alpha;
  addHat(M, beta * w);
  return M;
}
}  // namespace detail

inline SO3 SO3::exp(const Vec3& w, Mat3* J_R_w) {
  // R = I + a W + b W^2, Jr = I - b W + c W^2.
  const double theta2 = w.squaredNorm();
  double a, b, c;
  detail::so3Coefficients(theta2, a, b, c);
  if (J_R_w) *J_R_w = detail::so3Polynomial(1.0 - c * theta2, -b, c, w);
  return SO3(detail::so3Polynomial(1.0 - b * theta2, a, b, w));
}

namespace detail {
// Log of a rotation matrix through its quaternion (qw, qv): theta = 2
// atan2(|qv|, qw) is accurate at every angle, including near 0 and near pi
// where acos of the trace is not. The quaternion is not normalized (that
// would put a square root and a division on the log's critical path): qw = s
// cos(theta/2) >= 0 and |qv| = s sin(theta/2) for some s > 0, and every
// formula uses ratios only. Besides w it gives theta^2, and either `series`
// (|w| < 0.1: callers take their coefficients from series in theta^2, and
// theta, sin and cos are not computed), or theta with its sine and cosine.
struct HalfAngleLog {
  Vec3 w;
  double theta2;
  bool series;
  double qw;                           // cos(theta/2), up to the scale
  double n;                            // |qv| (NaN when series)
  double theta, sin_theta, cos_theta;  // NaN when series
};
// k of w = k qv for a quaternion (qw, qv) at any positive scale with n2 =
// |qv|^2 < 0.0025 qw^2, given 1 / qw: k = (2 / qw) atan(r) / r with r =
// |qv| / qw, atan(r) / r as a series in r^2.
template <class T>
inline T so3LogSeriesScale(const T& inv_qw, const T& n2) {
  const T r2 = n2 * inv_qw * inv_qw;
  const T atan_r_over_r =
      series4(r2, 1.0, -1.0 / 3.0, 1.0 / 5.0, -1.0 / 7.0, 1.0 / 9.0) + r2 * r2 * r2 * r2 * r2 * (-1.0 / 11.0 + r2 / 13.0);
  return 2.0 * inv_qw * atan_r_over_r;
}
// The series path of so3LogHalfAngle for a quaternion (qw, qv) at any
// positive scale, with n2 = |qv|^2 < 0.0025 qw^2.
inline HalfAngleLog so3LogSeries(double qw, const Vec3& qv, double n2) {
  // r = tan(theta/2) = |qv| / qw; r^2 < 0.0025 is |theta| < 0.09992, inside
  // kSeriesTheta2. There 2 atan(r) / r is a series in r^2 (through r^12:
  // the next term is below 1e-19 of it), and w = (2 / qw) (atan(r) / r) qv
  // needs no square root.
  HalfAngleLog out;
  const double inv_qw = 1.0 / qw;
  const double k = so3LogSeriesScale(inv_qw, n2);
  out.w = k * qv;
  out.theta2 = k * k * n2;
  out.series = true;
  out.qw = qw;
  out.n = out.theta = out.sin_theta = out.cos_theta = std::numeric_limits<double>::quiet_NaN();
  return out;
}
inline HalfAngleLog so3LogHalfAngle(const Mat3& R) {
  HalfAngleLog out;
  // Small angles first, from R without a square root or a division: there
  // 1 + trace = 4 qw^2 and (R21 - R12, R02 - R20, R10 - R01) = 4 qw qv, the
  // quaternion scaled by 4 qw > 0. (Near pi, where qw -> 0, both vanish and
  // their ratio means nothing: the guard on the trace keeps the shortcut to
  // angles below 60 degrees; the series range is below 5.7 degrees.)
  const double tr1 = 1.0 + R(0, 0) + R(1, 1) + R(2, 2);
  if (tr1 > 3.0) {
    const Vec3 sqv(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
    const double sn2 = sqv.squaredNorm();
    if (sn2 < 0.0025 * tr1 * tr1) return so3LogSeries(tr1, sqv, sn2);
  }
  const Eigen::Quaterniond q(R);
  double qw = q.w();
  Vec3 qv = q.vec();
  if (qw < 0.0) {
    qw = -qw;
    qv = -qv;
  }
  const double n2 = qv.squaredNorm(), qw2 = qw * qw;
  if (n2 < 0.0025 * qw2) return so3LogSeries(qw, qv, n2);
  const double n = std::sqrt(n2);
  out.series = false;
  out.qw = qw;
  out.n = n;
  out.theta = 2.0 * std::atan2(n, qw);
  out.theta2 = out.theta * out.theta;
  out.w = (out.theta / n) * qv;
  const double inv_s2 = 1.0 / (qw2 + n2);  // the quaternion's scale, squared
  out.sin_theta = 2.0 * n * qw * inv_s2;
  out.cos_theta = (qw2 - n2) * inv_s2;
  return out;
}
// d of Jr^-1(w) = I + W/2 + d W^2 for a log formed by so3LogHalfAngle:
// from the series, or 1/t^2 - (1 + cos t) / (2 t sin t) = 1/t^2 - cot(t/2) / (2 t).
inline double so3InverseCoefficient(const HalfAngleLog& h) {
  return h.series ? so3InverseCoefficientSeries(h.theta2) : 1.0 / h.theta2 - h.qw / (2.0 * h.theta * h.n);
}
}  // namespace detail

inline Vec3 SO3::log(Mat3* J_w_R) const {
  const Vec3 w = detail::so3LogHalfAngle(R_).w;
  if (J_w_R) *J_w_R = rightJacobianInverse(w);
  return w;
}

inline Mat3 SO3::rightJacobian(const Vec3& w) {
  const double theta2 = w.squaredNorm();
  double a, b, c;
  detail::so3Coefficients(theta2, a, b, c);
  return detail::so3Polynomial(1.0 - c * theta2, -b, c, w);  // I - b W + c W^2
}

inline Mat3 SO3::rightJacobianInverse(const Vec3& w) {
  const double theta2 = w.squaredNorm();
  double d;
  if (theta2 < detail::kSeriesTheta2) {
    d = detail::so3InverseCoefficientSeries(theta2);
  } else {
    const double theta = std::sqrt(theta2);
    d = (1.0 / theta2) - (1.0 + std::cos(theta)) / (2.0 * theta * std::sin(theta));
  }
  return detail::so3Polynomial(1.0 - d * theta2, 0.5, d, w);  // I + W/2 + d W^2
}

inline Vec3 SO3::rpy() const {
  const Mat3& R = R_;
  const double c = std::hypot(R(0, 0), R(1, 0));  // |cos(pitch)|
  const double pitch = std::atan2(-R(2, 0), c);
  if (c <= 1e-12) {  // gimbal lock: only yaw - roll (or yaw + roll) is defined; put it all into yaw
    return Vec3(0.0, pitch, std::atan2(-R(0, 1), R(1, 1)));
  }
  // Near the lock yaw alone is ill-conditioned (R(1,0) and R(0,0) are both
  // tiny), and so is roll from R(2,1), R(2,2): independent errors of ~eps/c in
  // each would not cancel. Taking roll from Rz(yaw)^T R = Ry(pitch) Rx(roll),
  // whose rows 1 are [0 cos(roll) -sin(roll)] at any pitch, makes it absorb
  // yaw's error, so that Rz(yaw) Ry(pitch) Rx(roll) gives R back to ~eps.
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  const double roll = std::atan2(sy * R(0, 2) - cy * R(1, 2), cy * R(1, 1) - sy * R(0, 1));
  return Vec3(roll, pitch, yaw);
}

inline SO3 SO3::fromRpy(double roll, double pitch, double yaw) {
  const Eigen::AngleAxisd rx(roll, Vec3::UnitX()), ry(pitch, Vec3::UnitY()), rz(yaw, Vec3::UnitZ());
  return SO3((rz * ry * rx).toRotationMatrix());
}

}  // namespace fgcal
