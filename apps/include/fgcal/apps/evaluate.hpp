// `fgcal evaluate`: errors of a calibration against ground truth, per camera and
// for the board mount, as in Table I of Reinke et al. (absolute per-axis
// errors), plus the total translation and rotation errors and the NEES that
// says whether the reported covariance is honest (about 6 on average for a
// consistent 6-DoF estimate).
#pragma once

#include <map>
#include <optional>
#include <string>

#include "fgcal/apps/results_io.hpp"

namespace fgcal::apps {

struct PoseError {
  /// |estimate - truth| of the position in the base (parent) frame, mm.
  double x_mm = 0, y_mm = 0, z_mm = 0;
  /// |roll/pitch/yaw difference| wrapped to [-180, 180) before the absolute value, degrees.
  double roll_deg = 0, pitch_deg = 0, yaw_deg = 0;
  double translation_mm = 0;  ///< |t_est - t_true|
  double rotation_deg = 0;    ///< |Log(R_true^T R_est)|
  /// e^T Sigma^-1 e, e = T_est.minus(T_true) in [w v], Sigma the estimate's
  /// covariance; NaN when Sigma is not positive definite (e.g. a fixed mount).
  double nees = 0;
};

/// Error of one pose estimate with covariance `cov` against `truth`.
PoseError poseError(const SE3& estimate, const Mat6& cov, const SE3& truth);

struct Evaluation {
  std::map<std::string, PoseError> cameras;
  std::optional<PoseError> mount;  ///< when the truth holds the mount
};

/// Throws InputError when the cameras of `result` and `truth` differ, naming
/// the ones missing on each side.
Evaluation evaluate(const CalibrationOutput& result, const GroundTruth& truth);

/// A fixed-width table, one row per camera (and the mount), for a terminal.
std::string formatEvaluationTable(const Evaluation& eval);

}  // namespace fgcal::apps
