// `fgcal calibrate` as a library call: a dataset folder or a robot bag in,
// calibration.yaml, a URDF snippet and a human summary out. Reads rig.yaml,
// joints.csv and the images (or the bag's joint states, images and
// camera_info, detecting the images as they are read); interpolates the joints
// at each image stamp; detects the board in every image on all cores; builds
// and solves the factor graph (solveCalibration); writes the results
// atomically. The stages are in src/calibration/calibrate_stages.hpp.
#pragma once

#include <iosfwd>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fgcal/apps/calibration_problem.hpp"
#include "fgcal/apps/evaluate.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/robot_outputs.hpp"

namespace fgcal::apps {

struct CalibrateOptions {
  /// A dataset folder, or a bag: a ROS 1 .bag, a ROS 2 bag folder (.db3 or
  /// .mcap files) or an .mcap file (logs::looksLikeBag tells them apart).
  std::string dataset;
  /// rig.yaml: required for a bag (its cameras name their topics); for a
  /// folder, used instead of the folder's own rig.yaml when given.
  std::string rig;
  std::string output = "calibration.yaml";  // the URDF snippet goes beside it (.urdf.xml)
  std::vector<std::string> cameras;         // empty: every camera of rig.yaml
  bool single_camera = false;               // F1
  bool fix_mount = false;
  int threads = 0;                          // 0: every core
  /// Multiplies every image's PnP covariance (>= 1): see
  /// CalibrationProblemInput::fiducial_covariance_scale.
  double pnp_covariance_scale = kDefaultFiducialCovarianceScale;
  bool write_files = true;                  // false: compute and summarize only
  /// The HTML report (fgcal/apps/report.hpp): written when write_files and
  /// report are set, into report_dir, or when that is empty beside the output
  /// as <output stem>_report/index.html.
  bool report = true;
  std::string report_dir;
  /// --urdf-out, --kalibr-out, --tf-out: written with calibration.yaml, as one set.
  RobotOutputOptions robot_outputs;
};

/// What happened to one image.
struct ImageOutcome {
  std::string camera;
  std::string path;
  std::int64_t stamp_ns = 0;
  std::string skipped;  // empty when used; else the reason (a key of CameraResult::images_skipped)
  std::string detail;   // the message behind it
  double rms_px = 0.0;  // final reprojection RMS (kinematics + calibration) when used
  /// For reports: index into CalibrateResult::problem.observations (-1: no
  /// board pose), the detected corners and those predicted by kinematics +
  /// calibration (same order; NaN where not projectable). Filled only with
  /// CalibrateOptions::report (a report is drawn from them).
  int observation = -1;
  std::vector<Eigen::Vector2d> corners_px, predicted_px;
};

struct CalibrateResult {
  CalibrationOutput output;
  CalibrationSolution solution;
  std::vector<ImageOutcome> images;
  std::vector<std::string> warnings;
  std::string summary;  // the human summary that was printed
  std::string yaml_path, urdf_path;
  /// The files of CalibrateOptions::robot_outputs that were written.
  std::vector<std::string> robot_output_paths;
  double detection_seconds = 0.0, solve_seconds = 0.0, total_seconds = 0.0;
  /// The split of total_seconds (benchmarks): reading rig.yaml, joints.csv and
  /// the URDF and listing the images (load); image decoding summed over the
  /// detection threads (decode, CPU-side: about decode_seconds / threads of
  /// the detection wall time); joint interpolation and forward kinematics
  /// (kinematics, inside detection_seconds); time in the optimizer (optimizer,
  /// inside solve_seconds: the rest of solve_seconds builds the graph,
  /// initializes, gates and computes the marginals); reprojection, summary and
  /// files (output).
  double load_seconds = 0.0, decode_seconds = 0.0, kinematics_seconds = 0.0, optimizer_seconds = 0.0,
         output_seconds = 0.0;
  /// The estimation problem that was solved (detections with their forward
  /// kinematics): benchmarks re-solve it under other settings.
  CalibrationProblemInput problem;
  /// The rig.yaml that was read (cameras' intrinsics for the report).
  RigConfig rig;
  /// Errors against the dataset's ground_truth.yaml, when it has one.
  std::optional<Evaluation> evaluation;
  std::string ground_truth_path;
  std::string report_path;  // index.html of the report, when written
  double report_seconds = 0.0;
};

/// Runs the calibration; progress and the summary go to `log`. Throws
/// InputError (exit 2) for bad input and DataError (exit 1) when the data
/// cannot support a calibration; nothing is written then.
CalibrateResult runCalibrate(const CalibrateOptions& options, std::ostream& log);

}  // namespace fgcal::apps
