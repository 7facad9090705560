// Shared by the SE(3) factors whose residual is r = Log(E): the whitened
// residual and, when asked, the normal-equation block of the side whose
// Jacobian is Jr^-1(r) itself.
#pragma once

#include "fgcal/core/factor.hpp"

namespace fgcal::detail {

/// r <- W Log(E). When g is not null, also U = W Jr^-1(r), H = U^T U (6x6,
/// column-major) and g = U^T W r. Returns false when only r was asked for.
inline bool whitenedLogBlock(const NoiseModel& noise, const SE3& E, double* r, double* g, double* H) {
  Mat6 U;
  Eigen::Map<Vec6> rw(r);
  rw = E.log(g ? &U : nullptr);
  noise.whitenResidual(r);
  if (!g) return false;
  noise.whitenJacobian(U.data(), 6, 6);
  Eigen::Map<Mat6>(H).noalias() = U.transpose() * U;
  Eigen::Map<Vec6>(g).noalias() = U.transpose() * rw;
  return true;
}

}  // namespace fgcal::detail
