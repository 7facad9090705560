// Corner-level estimation (`fgcal calibrate --method corners`): the graph of
// calibration_problem.hpp with each image's PnP pose factor replaced by one
// reprojection factor per detected ChArUco corner (factors/corner_factor.hpp),
// through each camera's model. Its noise is the detector's pixel sigma, or
// the image's own corner scatter about its best pose when that is larger
// (the rule of the PnP covariance; the image's far-off corners left out of
// it, and the stated sigma alone when the intrinsics are estimated).
// The PnP pose of an image summarizes its corners by a Gaussian in 6 numbers;
// the corners themselves keep what that summary loses (a half-seen board,
// the fisheye edge, the depth-rotation coupling of a small board), and let
// the intrinsics be estimated too (a PnP pose cannot tell a focal length
// error from a distance error).
//
// Variables: every camera pose, one board pose per instant (images within
// the sync tolerance share it, as for F2; each alone for F1), the mount with
// its prior, and, with estimate_intrinsics, each camera's intrinsics vector
// [fx fy cx cy, distortion] with its prior. Factors: the kinematic factor of
// each instant (encoder noise through the leg Jacobian, as for PnP), one
// corner factor per corner, the mount and intrinsics priors.
//
// It starts from the PnP solution (solveCalibration). Outliers: a robust
// solve (Huber on every corner), then gates, then plain least squares on
// what passed, gated again until nothing more is rejected:
//   - a corner whose |W r|^2 exceeds kCornerGate (chi-square(2) 99.999 %:
//     a recording has 10^5 corners, and a 99.9 % gate would drop a hundred
//     good ones and keep finding new ones near its edge after every solve)
//     is dropped alone (a corner refined onto the wrong edge);
//   - an image loses all its corners when more than half of them fail that
//     gate (a wrong board pose: an ID mix-up, a wrong stamp) or when the sum
//     over its remaining n corners exceeds the chi-square(2n) 99.99 % point
//     (every corner a little off in a way its own pose does not explain: a
//     late frame; a smeared image's own scatter is its noise), or when fewer
//     than 4 of its corners pass. Those images are the ones reported as
//     rejected.
// The final solve is plain least squares, so the marginal covariances of the
// cameras, the mount and the intrinsics are the Gaussian ones.
#pragma once

#include <string>
#include <vector>

#include "fgcal/apps/calibration_problem.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/vision/camera_model.hpp"

namespace fgcal::apps {

/// The corners of one image: pixels (pixel-centre convention) and the
/// matching points of the board frame.
struct ImageCorners {
  std::vector<Eigen::Vector2d> pixels;
  std::vector<Vec3> board_points;
};

/// A camera as the corner graph sees it.
struct CornerCamera {
  vision::CameraModel model;
  /// The detector's corner noise, pixels (> 0); an image whose corners
  /// scatter more about its best pose weighs by that scatter.
  double pixel_sigma = 0.5;
  /// With estimate_intrinsics: the prior std of the intrinsics vector
  /// [fx fy cx cy, distortion coefficients] (model.intrinsicsSize()
  /// entries, all finite and > 0).
  VecX intrinsics_sigma;
};

struct CornerProblemInput {
  std::vector<CornerCamera> cameras;  ///< one per CalibrationProblemInput::camera_names
  /// One per CalibrationProblemInput::observations, same order.
  std::vector<ImageCorners> corners;
  bool estimate_intrinsics = false;
};

/// The corner graph's cameras from rig.yaml (rig.cameras, the same order as
/// `models`): each model and pixel_sigma and, with `estimate_intrinsics`, the
/// prior std from intrinsics_sigma and distortion_coeffs_sigma, or where
/// rig.yaml lacks one the documented default (rig_config.hpp) with a warning
/// naming the camera and the field in `warnings`. InputError naming rig.yaml's
/// field when distortion_coeffs_sigma does not have one sigma per
/// coefficient of the camera's model (a model that came from a bag's
/// camera_info after rig.yaml was read).
std::vector<CornerCamera> cornerCameras(const RigConfig& rig, const std::vector<vision::CameraModel>& models,
                                        bool estimate_intrinsics, std::vector<std::string>* warnings);

/// One camera's estimated intrinsics.
struct IntrinsicsEstimate {
  VecX value;       ///< [fx fy cx cy, distortion coefficients]
  MatX covariance;  ///< marginal, same order
  VecX prior;       ///< the model's intrinsics the prior was centred on
  VecX prior_sigma;
  /// Eigenvalues (ascending) of the information the images add about the
  /// intrinsics, in units of the prior's (prior-whitened): below
  /// kWarnIntrinsicsInformation the images know less than the prior in that
  /// direction, which then rests on rig.yaml, and a warning names it.
  VecX data_information;
};

struct CornerSolution {
  /// Cameras, mount, rejected images (and why), instants, solves and
  /// warnings, as for PnP. fiducial_chi2 holds each image's sum of corner
  /// |W r|^2 over its corners kept (NaN: never solved).
  CalibrationSolution solution;
  /// Per camera, when the intrinsics were estimated (else empty).
  std::vector<IntrinsicsEstimate> intrinsics;
  /// Per observation, per corner: kept by the gates in the final solve.
  std::vector<std::vector<char>> corner_used;
  long corners_used = 0;
  /// Corners dropped alone (an image rejected whole counts in
  /// solution.rejected, not here).
  long corners_rejected = 0;
  /// Wall time of the phases besides the optimizer's (solution.solves has
  /// those): building the graphs, the gates, the marginal covariances.
  double build_seconds = 0.0, gate_seconds = 0.0, marginals_seconds = 0.0;
};

/// The chi-square(2) 99.999 % point (-2 ln 1e-5): the gate of one corner.
constexpr double kCornerGate = 23.0259;
/// More than this fraction of an image's corners beyond kCornerGate: the
/// image is rejected whole.
constexpr double kImageRejectFraction = 0.5;
/// See IntrinsicsEstimate::data_information.
constexpr double kWarnIntrinsicsInformation = 1.0;

/// Solves from `start` (solveCalibration's solution of `problem`) on one
/// thread (`threads` > 1: the optimizer evaluates factors on that many).
/// A `start` without cameras (the PnP graph failed, e.g. on intrinsics too
/// wrong for its images to agree) starts each camera from its own detections
/// as the PnP graph does (the pose most of them agree on) and every board
/// from the kinematics.
/// Throws DataError when the data cannot support a calibration (a camera
/// left with fewer than 3 images, a degenerate system) and
/// std::invalid_argument when `corners` does not match `problem` (sizes,
/// sigmas).
CornerSolution solveCornerCalibration(const CalibrationProblemInput& problem, const CornerProblemInput& corners,
                                      const CalibrationSolution& start, int threads = 1);

}  // namespace fgcal::apps
