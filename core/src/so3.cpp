// SO(3)'s exp, log and Jacobians, from the series and closed forms of
// lie_series.hpp.
#include "fgcal/core/so3.hpp"

#include "fgcal/core/internal/lie_series.hpp"

namespace fgcal {

SO3 SO3::exp(const Vec3& w, Mat3* J_R_w) {
  // R = I + a W + b W^2, Jr = I - b W + c W^2.
  const double theta2 = w.squaredNorm();
  double a, b, c;
  detail::so3Coefficients(theta2, a, b, c);
  if (J_R_w) *J_R_w = detail::so3Polynomial(1.0 - c * theta2, -b, c, w);
  return SO3(detail::so3Polynomial(1.0 - b * theta2, a, b, w));
}

Vec3 SO3::log(Mat3* J_w_R) const {
  const Vec3 w = detail::so3LogHalfAngle(R_).w;
  if (J_w_R) *J_w_R = rightJacobianInverse(w);
  return w;
}

Mat3 SO3::rightJacobian(const Vec3& w) {
  const double theta2 = w.squaredNorm();
  double a, b, c;
  detail::so3Coefficients(theta2, a, b, c);
  return detail::so3Polynomial(1.0 - c * theta2, -b, c, w);  // I - b W + c W^2
}

Mat3 SO3::rightJacobianInverse(const Vec3& w) {
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

}  // namespace fgcal
