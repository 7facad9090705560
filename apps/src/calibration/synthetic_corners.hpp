// A seeded corner-level calibration problem with known truth, without images:
// two (or more) cameras at the front of a 1 m body, a ChArUco board's
// corners on a foot moved through varied poses 0.4-0.9 m in front of them,
// projected through each camera's true model with Gaussian pixel noise; the
// PnP pose of every image from those corners (vision::estimatePose) and the
// forward kinematics with encoder noise through a 3-joint leg Jacobian. The
// corner graph's tests and its speed benchmark (benchmarks/apps) share it;
// images are rendered and detected by the simulator (fgcal simulate), which
// the end-to-end tests and bench_accuracy use.
#pragma once

#include <string>
#include <vector>

#include "fgcal/apps/corner_calibration.hpp"

namespace fgcal::apps::synthetic {

struct CornerProblemOptions {
  int cameras = 2;                 ///< 1..4
  int instants = 150;
  int squares_x = 5, squares_y = 7;  ///< the board: (x-1)(y-1) corners
  double square_size = 0.04;       ///< metres
  double pixel_sigma = 0.5;        ///< the stated corner noise std, pixels (rig.yaml's pixel_sigma)
  /// The std of the noise drawn on the corners; negative: pixel_sigma
  /// (0: exact corners, for checks that the truth is recovered).
  double pixel_noise = -1.0;
  double encoder_sigma = 0.002;    ///< radians
  /// none | radtan | equidistant (a wide-angle lens, 1280x1024, f = 300 px).
  std::string distortion = "radtan";
  /// Each camera sees each instant with this probability (all corners in
  /// the image are then kept).
  double see_probability = 0.8;
  /// The rig's intrinsics off the truth: fx, fy scaled by (1 +- pct/100), cx,
  /// cy moved by +- px (signs from the seed); images follow the truth.
  double intrinsics_error_pct = 0.0, intrinsics_error_px = 0.0;
  double mount_error_m = 0.0, mount_error_rad = 0.0;
  unsigned seed = 1;
};

struct CornerProblem {
  CalibrationProblemInput problem;   ///< PnP observations, kinematics, priors
  CornerProblemInput corners;        ///< the same images' corners, the rig's models
  std::vector<SE3> true_cameras;     ///< T_base_cam
  SE3 true_mount;                    ///< T_link_marker
  std::vector<VecX> true_intrinsics; ///< per camera, [fx fy cx cy, distortion]
};

/// Throws std::invalid_argument for options out of range.
CornerProblem makeCornerProblem(const CornerProblemOptions& options);

}  // namespace fgcal::apps::synthetic
