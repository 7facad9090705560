// `fgcal calibrate` as a library call: a dataset folder or a robot bag in,
// calibration.yaml, a URDF snippet and a human summary out. Reads rig.yaml,
// joints.csv and the images (or the bag's joint states, images and
// camera_info, detecting the images as they are read); interpolates the joints
// at each image stamp; detects the board in every image on all cores; builds
// and solves the factor graph (solveCalibration); writes the results
// atomically, then the HTML report (report.hpp). The stages are in
// src/calibration/calibrate_stages.hpp.
#pragma once

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "fgcal/apps/calibration_problem.hpp"
#include "fgcal/apps/corner_calibration.hpp"
#include "fgcal/apps/evaluate.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/robot_outputs.hpp"

namespace fgcal::apps {

struct ReportData;

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

  /// For programs that look further than the result; each is filled when set
  /// (never owned):
  /// - the estimation problem that was solved (detections with their forward
  ///   kinematics and the settings above), for benchmarks that re-solve it
  ///   under other settings;
  CalibrationProblemInput* problem_out = nullptr;
  /// - with it, what the corner graph needs (corner_calibration.hpp): every
  ///   observation's corners and each camera's model as rig.yaml gives it,
  ///   with the prior of its intrinsics (rig.yaml's, or the defaults);
  CornerProblemInput* corners_out = nullptr;
  /// - what the report draws (also when no report is written; tests).
  ReportData* report_data_out = nullptr;
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
