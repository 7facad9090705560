// `fgcal calibrate` as a library call: a dataset folder or a robot bag in,
// calibration.yaml, a URDF snippet and a human summary out. Reads rig.yaml,
// joints.csv and the images (or the bag's joint states, images and
// camera_info, detecting the images as they are read); interpolates the joints
// at each image stamp; detects the board in every image on all cores; builds
// and solves the factor graph (solveCalibration); writes the results
// atomically, then the HTML report (report.hpp). The stages are in
// src/commands/calibrate/calibrate_stages.hpp.
#pragma once

#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fgcal/apps/calibrate_options.hpp"
#include "fgcal/apps/calibration_problem.hpp"
#include "fgcal/apps/corner_calibration.hpp"
#include "fgcal/apps/evaluate.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/robot_outputs.hpp"

namespace fgcal::apps {

struct ReportData;

/// The intermediate results a caller asked for (CalibrateOptions::trace);
/// each is empty when not asked for, or when the run stopped before it.
struct CalibrateTrace {
  /// The estimation problem that was solved: detections with their forward
  /// kinematics and the settings (benchmarks re-solve it under other settings).
  std::optional<CalibrationProblemInput> problem;
  /// What the corner graph needs (corner_calibration.hpp): every
  /// observation's corners and each camera's model as rig.yaml gives it, with
  /// the prior of its intrinsics (rig.yaml's, or the defaults).
  std::optional<CornerProblemInput> corners;
  /// What the report draws (report.hpp).
  std::shared_ptr<ReportData> report_data;
};

/// Wall-clock seconds of the stages (benchmarks). detection and solve are
/// spans of the run; decode, kinematics and optimizer are parts of them.
struct CalibrateTimings {
  double load = 0.0;        ///< rig.yaml, joints.csv, the URDF, listing the images (a bag: its index)
  double detection = 0.0;   ///< reading, decoding and detecting every image, PnP, joints at each image
  double decode = 0.0;      ///< image decoding summed over the detection threads (CPU side)
  double kinematics = 0.0;  ///< joint interpolation and forward kinematics (inside detection)
  double solve = 0.0;       ///< the graph built, solved and gated, the marginals
  double optimizer = 0.0;   ///< time in the optimizer (inside solve)
  double output = 0.0;      ///< reprojection, summary and the written files
  double total = 0.0;       ///< from the start to the written files (the report not included)
  double report = 0.0;      ///< the HTML report; 0 when none was written
};

/// An image the chi-square gate rejected as inconsistent with the others.
struct RejectedImage {
  std::string image;   ///< its file, or its bag message ("BAG: topic T, message I (stamp S)")
  std::string reason;  ///< the gate's words, with its chi-square
};

struct CalibrateResult {
  /// What calibration.yaml holds: per camera its pose, covariance, images
  /// used and skipped (by reason) and reprojection RMS; the board mount; the
  /// method; run information.
  CalibrationOutput output;
  /// The estimator's full answer (calibration_problem.hpp): the instants, each
  /// solve's convergence, the rejected observations and their chi-square.
  CalibrationSolution solution;
  /// The rig as used: the selected cameras, intrinsics filled in from a bag's
  /// camera_info where rig.yaml leaves them to it.
  RigConfig rig;
  std::vector<RejectedImage> rejected;  ///< the gate's outliers, in observation order
  /// Damaged image messages or files, skipped and counted in images_skipped
  /// as "unreadable image": a raw Image whose data are short of its size, a
  /// CompressedImage or image file that does not decode. `image` names the
  /// topic and stamp (or the file); `reason` says what is wrong.
  std::vector<RejectedImage> damaged;
  std::vector<std::string> warnings;    ///< plain words: the data's and the estimator's
  std::string summary;                  ///< the human summary that was printed
  /// Errors against the dataset's ground_truth.yaml (a simulated dataset has
  /// one), and its path; nullopt and empty otherwise.
  std::optional<Evaluation> evaluation;
  std::string ground_truth_path;
  /// The files written; empty when not written.
  std::string yaml_path, urdf_path, report_path;
  std::vector<std::string> robot_output_paths;  ///< of CalibrateOptions::robot_outputs
  CalibrateTimings timings;
  CalibrateTrace trace;  ///< what CalibrateOptions::trace asked to keep
};

/// Runs the calibration; progress and the summary go to `log`. Throws
/// InputError (exit 2) for bad input and DataError (exit 1) when the data
/// cannot support a calibration (its message ends with the failure's
/// diagnosis when one is found); nothing is written then. A result whose
/// quality verdict is unusable is returned, but writes no calibration output,
/// only its report (`fgcal calibrate` exits 1). A report that cannot be
/// written costs a warning, never the calibration.
CalibrateResult runCalibrate(const CalibrateOptions& options, std::ostream& log);

}  // namespace fgcal::apps
