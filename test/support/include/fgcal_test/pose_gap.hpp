// How far apart two poses are: the distance between their origins and the
// angle of the rotation between them, in the units a test's tolerance is
// written in.
#pragma once

#include <cmath>

#include <Eigen/Cholesky>

#include "fgcal/core/se3.hpp"

namespace fgcal::test {

/// |t_a - t_b|, metres.
inline double translationGap(const SE3& a, const SE3& b) { return (a.translation() - b.translation()).norm(); }

/// The angle of R_a^-1 R_b, radians.
inline double rotationGap(const SE3& a, const SE3& b) { return a.so3().between(b.so3()).log().norm(); }

inline double translationGapMm(const SE3& a, const SE3& b) { return 1e3 * translationGap(a, b); }
inline double rotationGapDeg(const SE3& a, const SE3& b) { return rotationGap(a, b) * 180.0 / M_PI; }

/// The NEES of an estimate against the truth, its error xi = Log(truth^-1
/// estimate) ([w v], the right perturbation calibration.yaml's covariance is
/// written in) weighed by that covariance: chi-square(6) when it is honest.
inline double nees(const SE3& truth, const SE3& estimate, const Mat6& covariance) {
  const Vec6 e = truth.between(estimate).log();
  return e.dot(covariance.ldlt().solve(e));
}

}  // namespace fgcal::test
