// The calibration problem as a Ceres problem, with exactly fgcal's residuals
// and tangent-space Jacobians: each SE(3) pose is a 7-double block
// [qx qy qz qw tx ty tz] on a manifold whose Plus is T * Exp(delta) with
// fgcal's [w v] tangent and whose PlusJacobian is [I6; 0]; the cost functions
// return the analytic tangent Jacobian (whitened by the same W) in the first 6
// columns of the ambient Jacobian and zeros in the last. Ceres' Jacobian in
// tangent space, J_ambient * PlusJacobian, is then fgcal's Jacobian.
#pragma once

#ifdef FGCAL_HAVE_CERES

#include <memory>
#include <vector>

#include <ceres/ceres.h>

#include "calibration_problem.hpp"

namespace fgcal::bench {

void poseToParams(const SE3& T, double* x);
SE3 paramsToPose(const double* x);

class SE3Manifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 7; }
  int TangentSize() const override { return 6; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

/// The Ceres problem and the parameter storage it points into.
struct CeresCalibrationProblem {
  std::vector<double> params;  // 7 per camera, then 7 per board
  SE3Manifold manifold;
  std::unique_ptr<ceres::Problem> problem;

  double* camera(int i) { return params.data() + 7 * static_cast<std::size_t>(i); }
  double* board(int j, int cameras) { return params.data() + 7 * static_cast<std::size_t>(cameras + j); }
};

/// Same start (initial_cameras, initial_boards), same factors in the same order as buildFgcalProblem.
void buildCeresProblem(const CalibrationProblem& p, CeresCalibrationProblem& out);

/// Largest differences between the Ceres cost functions (residual, tangent
/// Jacobians) and fgcal's factors at the initial values of `p`, over its first
/// `max_factors` factors: the proof that both solvers see the same problem.
struct EvaluationMismatch {
  double residual = 0.0, jacobian = 0.0;
};
EvaluationMismatch compareWithFgcal(const CalibrationProblem& p, std::size_t max_factors);

}  // namespace fgcal::bench

#endif  // FGCAL_HAVE_CERES
