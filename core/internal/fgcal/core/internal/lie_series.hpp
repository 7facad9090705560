// The series and closed forms behind SO(3) and SE(3)'s exp, log and
// Jacobians, shared by so3.cpp, se3.cpp and the library's SE(3) factors'
// fast paths (factors/internal/fgcal/factors/internal/whitened_log.hpp),
// which form the log and its Jacobian blocks without the public classes'
// copies. Templates on the scalar where the fast paths run them on two-lane
// packets.
#pragma once

#include <cassert>
#include <cmath>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "fgcal/core/types.hpp"

namespace fgcal::detail {
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

}  // namespace fgcal::detail
