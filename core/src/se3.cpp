// SE(3)'s exp, log and Jacobians, from the series and closed forms of
// lie_series.hpp.
#include "fgcal/core/se3.hpp"

#include "fgcal/core/internal/lie_series.hpp"

namespace fgcal {

SE3 SE3::exp(const Vec6& xi, Mat6* J_T_xi) {
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

Vec6 SE3::log(Mat6* J_xi_T) const {
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

Mat6 SE3::rightJacobian(const Vec6& xi) {
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

Mat6 SE3::rightJacobianInverse(const Vec6& xi) {
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
