// What `fgcal calibrate` is asked to do, as a library call (calibrate.hpp):
// the input, the method, what is estimated beyond the poses, the outputs.
// The command line's spelling of each option is in
// apps/src/commands/calibrate/calibrate_command.cpp.
#pragma once

#include <string>
#include <vector>

#include "fgcal/apps/calibration_problem.hpp"
#include "fgcal/apps/robot_outputs.hpp"

namespace fgcal::apps {

/// How the images enter the graph (`--method`): a PnP pose per image (the
/// paper's method) or a factor per detected corner.
enum class Method { Pnp, Corners };
/// "pnp" or "corners".
std::string toString(Method m);
/// Parses "pnp" | "corners"; InputError naming `--method` and the valid names.
Method methodFromString(const std::string& name);

/// What is estimated beyond the camera poses and the mount (`--estimate`).
struct EstimateSet {
  bool time_offset = false;
  bool joint_offsets = false;
  bool intrinsics = false;
  bool backlash = false;
  bool rolling_shutter = false;
  bool any() const { return time_offset || joint_offsets || intrinsics || backlash || rolling_shutter; }
};
/// The valid names, in the order names() writes them: time-offset,
/// joint-offsets, intrinsics, backlash, rolling-shutter.
const std::vector<std::string>& estimateNames();
/// Parses a comma-separated subset of estimateNames() (empty: none; repeats
/// allowed); InputError naming `--estimate` and listing the valid names for
/// anything else.
EstimateSet parseEstimateSet(const std::string& list);
/// The chosen names in the order of estimateNames().
std::vector<std::string> names(const EstimateSet& set);

/// Which intermediate results runCalibrate keeps in CalibrateResult::trace
/// besides the result (calibrate.hpp says what each holds).
struct TraceRequest {
  bool problem = false;      ///< the PnP estimation problem that was solved
  bool corners = false;      ///< what the corner graph needs
  bool report_data = false;  ///< what the report draws, also when no report is written
};

struct CalibrateOptions {
  /// A dataset folder, or a bag: a ROS 1 .bag, a ROS 2 bag folder (.db3 or
  /// .mcap files) or an .mcap file (logs::looksLikeBag tells them apart).
  std::string dataset;
  /// rig.yaml: required for a bag (its cameras name their topics); for a
  /// folder, used instead of the folder's own rig.yaml when given.
  std::string rig;
  /// calibration.yaml; the URDF snippet goes beside it (<stem>.urdf.xml).
  /// Empty: nothing is written.
  std::string output = "calibration.yaml";
  std::vector<std::string> cameras;  ///< --cameras: a subset of rig.yaml's; empty: every camera
  bool single_camera = false;        ///< --single-camera: each camera solved alone (the paper's F1)
  bool fix_mount = false;            ///< --fix-mount: the board mount held at its rig.yaml value
  int threads = 0;                   ///< detection threads; 0: every core
  /// Multiplies every image's PnP covariance (>= 1): see
  /// CalibrationProblemInput::fiducial_covariance_scale.
  double pnp_covariance_scale = kDefaultFiducialCovarianceScale;
  bool write_files = true;  ///< false: compute and summarize only, write nothing
  /// The HTML report (report.hpp): written when write_files and report are
  /// set, into report_dir, or when that is empty beside the output as
  /// <output stem>_report/index.html.
  bool report = true;
  std::string report_dir;
  /// --urdf-out, --kalibr-out, --tf-out: written with calibration.yaml, as one set.
  RobotOutputOptions robot_outputs;
  /// --method: a PnP pose factor per image (the paper's) or a reprojection
  /// factor per detected corner (corner_calibration.hpp).
  Method method = Method::Pnp;
  /// --estimate: what is estimated beyond the camera poses and the mount:
  /// time offsets and joint zero offsets (offset_estimation.hpp; either
  /// method), intrinsics (Method::Corners only: InputError otherwise, a PnP
  /// pose cannot tell a focal length error from a distance error).
  EstimateSet estimate;

  /// What else CalibrateResult::trace keeps (tests, benchmarks, Python).
  TraceRequest trace;
};

}  // namespace fgcal::apps
