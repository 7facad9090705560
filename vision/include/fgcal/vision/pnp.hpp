// Board pose T_cam_marker from ChArUco corners: an initial planar PnP
// (OpenCV IPPE on undistorted normalized points, so every distortion model
// works), then Levenberg-Marquardt on the full reprojection error through
// our own CameraModel with the analytic Jacobian. The covariance is the
// paper's vertex-jitter model, sigma_px^2 (J^T J)^-1, with J the Jacobian of
// all projected corners with respect to the pose in docs/design.md's convention:
// tangent [w v], right perturbation T_cam_marker * Exp(xi).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "fgcal/core/se3.hpp"
#include "fgcal/vision/camera_model.hpp"
#include "fgcal/vision/charuco_detector.hpp"

namespace fgcal::vision {

struct PnpOptions {
  /// Corner noise std in pixels (rig.yaml `pixel_sigma`), used for the covariance.
  double pixel_sigma = 0.5;
  /// Which corner sigma scales the covariance sigma^2 (J^T J)^-1: the stated
  /// pixel_sigma; this solve's residual estimate s^2 = RSS / (2n - 6); or the
  /// larger of the two (never less uncertain than the corners' own scatter).
  enum class SigmaSource { PixelSigma, Residuals, Larger };
  SigmaSource sigma_source = SigmaSource::PixelSigma;
  int max_iterations = 50;
};

struct PoseEstimate {
  SE3 T_cam_marker;
  Mat6 covariance = Mat6::Zero();  ///< [w v], right perturbation of T_cam_marker
  Mat6 JtJ = Mat6::Zero();         ///< J^T J of the reprojection Jacobian (pixels per [w v])
  double sigma_px = 0.0;           ///< sigma used in covariance
  double residual_sigma_px = 0.0;  ///< sqrt(RSS / (2n - 6)); 0 when n <= 3
  double rms_px = 0.0;             ///< sqrt(RSS / n): RMS reprojection error per corner
  std::vector<Vec2> residuals;     ///< project(T * P_i) - uv_i
  int iterations = 0;
  bool converged = false;
};

/// Pixel residuals of the corners and, when J is given, their Jacobian
/// (2n x 6, rows [u_i v_i]) with respect to the pose, [w v] right perturbation.
/// Returns false when a point is not in front of the camera.
bool reprojection(const CameraModel& camera, const SE3& T_cam_marker,
                  const std::vector<Vec3>& object_points, const std::vector<Vec2>& pixels,
                  Eigen::VectorXd* residuals, Eigen::Matrix<double, Eigen::Dynamic, 6>* J);

/// Pose from matched board points / pixels (>= 4, not collinear). Throws
/// VisionError when too few points are given or no initial pose is found.
PoseEstimate estimatePose(const CameraModel& camera, const std::vector<Vec3>& object_points,
                          const std::vector<Vec2>& pixels, const PnpOptions& options = {});

/// Pose from a detection; throws VisionError (with the detection's message)
/// when the detection is not Ok.
PoseEstimate estimatePose(const CameraModel& camera, const CharucoDetection& detection,
                          const PnpOptions& options = {});

/// Levenberg-Marquardt refinement from a given initial pose (no initial PnP).
PoseEstimate refinePose(const CameraModel& camera, const SE3& initial,
                        const std::vector<Vec3>& object_points, const std::vector<Vec2>& pixels,
                        const PnpOptions& options = {});

}  // namespace fgcal::vision
