// `fgcal evaluate`: errors of a calibration against ground truth, per camera and
// for the board mount, as in Table I of Reinke et al. (absolute per-axis
// errors), plus the total translation and rotation errors and the NEES that
// says whether the reported covariance is honest (about 6 on average for a
// consistent 6-DoF estimate). When calibration.yaml holds more estimated
// quantities (`fgcal calibrate --estimate`: time offsets, joint offsets,
// intrinsics), each is compared with its truth, in its unit and in sigmas.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fgcal/apps/errors.hpp"
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

/// An estimate and its 1-sigma, as calibration.yaml writes them.
struct EstimateWithSigma {
  double value = 0.0;
  double sigma = 0.0;  ///< >= 0; +inf allowed
};

/// calibration.yaml's estimated quantities of one camera (docs/outputs.md);
/// each empty when it was not estimated.
struct EstimatedCamera {
  std::optional<EstimateWithSigma> time_offset_ms;   ///< time_offset_ms, time_offset_sigma_ms
  /// readout_ms, readout_sigma_ms: an estimated rolling-shutter readout (a
  /// readout without sigma is rig.yaml's, held, and is not read); not scored
  /// when readout_observed is false.
  std::optional<EstimateWithSigma> readout_ms;
  bool readout_observed = true;
  std::vector<EstimateWithSigma> intrinsics;         ///< fx, fy, cx, cy (px) with intrinsics_sigma
  std::vector<EstimateWithSigma> distortion_coeffs;  ///< with distortion_coeffs_sigma
};

struct EstimatedJointOffset {
  EstimateWithSigma offset_rad;  ///< offset_rad, sigma_rad
  /// false: the data does not observe this offset (calibrate warned); the
  /// value is the prior's, not a result, and is not scored.
  bool observed = true;
};

/// What calibration.yaml holds besides the poses: `method`, `estimated`, the
/// per-camera time offsets and intrinsics, `joint_offsets` and `backlash`.
struct EstimatedQuantities {
  std::string method;                  ///< "" when the file has none
  std::vector<std::string> estimated;  ///< subset of time-offset, joint-offsets, intrinsics, backlash, rolling-shutter
  std::map<std::string, EstimatedCamera> cameras;  ///< only cameras with an estimated quantity
  std::map<std::string, EstimatedJointOffset> joint_offsets;
  /// Joint -> its gear play (offset_rad holding calibration.yaml's `rad`).
  std::map<std::string, EstimatedJointOffset> backlash;
};

/// Reads those keys of calibration.yaml. Throws InputError naming the file
/// and field: a value without its sigma, a negative or NaN sigma, a list of
/// the wrong length, an unknown name in `estimated`, or a quantity that
/// `estimated` lists and the file lacks.
EstimatedQuantities parseEstimatedQuantities(const std::string& yaml_text, const std::string& source_name);

/// One estimated number against its truth.
struct ScalarError {
  double estimate = 0.0, truth = 0.0, sigma = 0.0;
  double error = 0.0;   ///< estimate - truth
  double sigmas = 0.0;  ///< error / sigma; NaN when sigma is 0 or infinite
};

struct Evaluation {
  std::map<std::string, PoseError> cameras;
  std::optional<PoseError> mount;  ///< when the truth holds the mount
  /// Why the mount is not scored, when `mount` is empty (the table prints
  /// "mount: not scored (<this>)").
  std::string mount_not_scored;
  std::string method;              ///< calibration.yaml's `method`, when read
  /// Camera -> time offset error, ms.
  std::map<std::string, ScalarError> time_offsets_ms;
  /// Camera -> rolling-shutter readout error, ms (observed ones only), and the
  /// cameras whose readout calibration.yaml marks not observed.
  std::map<std::string, ScalarError> readouts_ms;
  std::vector<std::string> readouts_not_observed;
  /// Camera -> errors of fx, fy, cx, cy (px), and of each distortion coefficient.
  std::map<std::string, std::vector<ScalarError>> intrinsics;
  std::map<std::string, std::vector<ScalarError>> distortion_coeffs;
  /// Joint -> offset error, rad (observed offsets only).
  std::map<std::string, ScalarError> joint_offsets_rad;
  /// Joints whose offset calibration.yaml marks `observed: false`: not scored.
  std::map<std::string, EstimatedJointOffset> joint_offsets_not_observed;
  /// Joint -> backlash error, rad (observed ones only), and those not observed.
  std::map<std::string, ScalarError> backlash_rad;
  std::map<std::string, EstimatedJointOffset> backlash_not_observed;
  /// Estimated quantities the ground truth has no value for, e.g.
  /// "cam0.time_offset_ms", "joint_offsets.LF_HFE": listed, not scored.
  std::vector<std::string> without_truth;
};

/// Throws InputError when the cameras of `result` and `truth` differ, naming
/// the ones missing on each side.
Evaluation evaluate(const CalibrationOutput& result, const GroundTruth& truth);
/// The same, and every estimated quantity against its truth. InputError when
/// a camera's distortion coefficients and its truth differ in number.
Evaluation evaluate(const CalibrationOutput& result, const EstimatedQuantities& estimates, const GroundTruth& truth);
/// `fgcal evaluate CALIBRATION GROUND_TRUTH`: both files read (InputError
/// naming the file and field) and evaluated. When CALIBRATION is not a
/// calibration result but GROUND_TRUTH is one (the arguments swapped), the
/// InputError says that the order is result, then truth.
Evaluation evaluateFiles(const std::string& calibration_path, const std::string& truth_path);

/// The InputError for `fgcal evaluate TRUTH RESULT` when `truth_path` reads
/// as a calibration result or a Kalibr camchain; nullopt otherwise (then the
/// caller reports its own error).
std::optional<InputError> swappedEvaluateArguments(const std::string& calibration_path,
                                                   const std::string& truth_path);

/// A fixed-width table, one row per camera (and the mount), for a terminal;
/// then, when estimated, tables of the time offsets (ms), joint offsets
/// (mrad) and intrinsics (px; distortion coefficients unitless), each with
/// estimate, truth, error, sigma and error / sigma, and how many of the
/// scored quantities lie within 3 sigma.
std::string formatEvaluationTable(const Evaluation& eval);

}  // namespace fgcal::apps
