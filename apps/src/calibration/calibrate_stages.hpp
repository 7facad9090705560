// runCalibrate's stages (calibrate.hpp), each a function taking and returning
// small structs, in the order they run:
//   load      the folder dataset, or the bag's rig and topics (loadInputs)
//   setup     the robot chain, encoder sigmas and board detector (setUpRobot)
//   detect    every image decoded, detected and its pose estimated on all
//             cores: the folder's files (detectFolder), or the bag's messages
//             detected as they are read, which also collects its joint states
//             and camera_info, then PnP with the final intrinsics (detectBag)
//   align     joint positions at each image stamp (alignJoints)
//   build     the board observations with forward kinematics (buildProblem)
//   solve     the problem's settings, the factor graph solved and gated
//             (solveAndGate), every corner reprojected (reproject)
//   output    the results and summary (calibrate_results.cpp),
//             calibration.yaml, the URDF snippet, the robot outputs
//   report    what the report draws (buildReportData), then the HTML report
// A folder and a bag give the same Inputs + Detections; everything from align
// on does not know which it was.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "../bag/bag_source.hpp"
#include "fgcal/apps/calibrate.hpp"
#include "fgcal/apps/dataset.hpp"
#include "fgcal/apps/report.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal/vision/batch_detection.hpp"
#include "fgcal/vision/camera_model.hpp"
#include "fgcal/vision/charuco_detector.hpp"

namespace fgcal::apps::stages {

/// What the load stage found.
struct Inputs {
  bool from_bag = false;
  std::string source;       ///< the dataset folder (absolute) or the bag as given
  std::string rig_path;     ///< rig.yaml as named in messages
  std::string joints_name;  ///< joints.csv's path, or "BAG: topic /joint_states"
  RigConfig rig;            ///< only the selected cameras
  JointLog joints;          ///< folder: joints.csv; bag: filled by detectBag
  std::vector<ImageEntry> images;  ///< folder: the files; bag: filled by detectBag (path = message label)
  std::vector<std::string> warnings;
  std::string ground_truth;  ///< the folder's ground_truth.yaml when it has one
  std::unique_ptr<logs::BagReader> bag;  ///< open, not read yet
  BagPlan plan;
  std::vector<std::uint64_t> message_index;  ///< bag: per image, its index among its topic's messages
};
/// A bag when logs::looksLikeBag(opt.dataset), else a dataset folder.
Inputs loadInputs(const CalibrateOptions& opt);
Inputs loadBagInputs(const CalibrateOptions& opt);

struct RobotSetup {
  kinematics::RobotModel robot;
  kinematics::KinematicChain chain;
  VecX sigma_q;
  std::unique_ptr<vision::CharucoDetector> detector;
};
RobotSetup setUpRobot(const Inputs& in);

/// The chain's columns in the joint log (InputError naming the log when one
/// is missing); a warning in in.warnings for the log's joints the URDF does
/// not know.
std::vector<int> jointColumns(Inputs& in, const RobotSetup& setup);

/// One vision::CameraModel per camera of the rig (InputError naming rig.yaml).
std::vector<vision::CameraModel> cameraModels(const Inputs& in);

/// Per image of Inputs::images (same order), its detection and pose.
struct Detections {
  std::vector<vision::FrameResult> frames;
  std::vector<std::string> wrong_size;  ///< non-empty: "WxH, rig.yaml says ..."
  double decode_seconds = 0.0;          ///< summed over the threads
};
Detections detectFolder(const Inputs& in, const RobotSetup& setup, const std::vector<vision::CameraModel>& models,
                        const CalibrateOptions& opt, std::ostream& log);
/// Reads the bag once: fills in.joints, in.images (sorted like a folder's;
/// of two images of one camera with the same stamp the one recorded later is
/// kept) and the intrinsics left to camera_info, detecting while reading;
/// then `models` from the final intrinsics, and PnP.
Detections detectBag(Inputs& in, const RobotSetup& setup, const CalibrateOptions& opt, std::ostream& log,
                     std::vector<vision::CameraModel>* models);

/// Reads the named images (indices into in.images) back from the bag, as
/// 8-bit grey, in one pass that stops when all are found (for the report).
std::map<std::size_t, cv::Mat> readBagImages(Inputs& in, const std::vector<std::size_t>& images);

/// Per image, the chain's joint positions at its stamp, or why not.
struct AlignedJoints {
  std::vector<std::optional<Eigen::VectorXd>> q;
  std::vector<std::string> why;
};
AlignedJoints alignJoints(const Inputs& in, const std::vector<int>& columns);

/// What happened to one image.
struct ImageOutcome {
  std::string camera;
  std::string path;
  std::int64_t stamp_ns = 0;
  std::string skipped;  ///< empty when used; else the reason (a key of CameraResult::images_skipped)
  std::string detail;   ///< the message behind it
  double rms_px = 0.0;  ///< final reprojection RMS (kinematics + calibration) when used
  int observation = -1;  ///< index into the problem's observations; -1: no board pose
};

/// The observations and each image's outcome; obs_image maps an observation
/// to its image.
struct BuiltProblem {
  CalibrationProblemInput problem;
  std::vector<ImageOutcome> images;
  std::vector<std::size_t> obs_image;
};
BuiltProblem buildProblem(const Inputs& in, const RobotSetup& setup, const Detections& det,
                          const AlignedJoints& joints);
/// DataError (or InputError when every image has the wrong size) for a
/// camera with fewer than 3 usable images, the reasons counted.
void checkCoverage(const Inputs& in, const BuiltProblem& built, const CalibrateOptions& opt);

/// The problem's settings from rig.yaml and the options; solveCalibration;
/// the gated images marked as outliers.
CalibrationSolution solveAndGate(const Inputs& in, const CalibrateOptions& opt, BuiltProblem& built);

/// Every detected corner projected through kinematics + calibration: per
/// camera the squared error and count over its used images, each used
/// image's RMS (into built.images), and, when asked, the residuals
/// (predicted - detected) of every corner of the used images, per camera.
struct Reprojection {
  std::vector<double> squared;
  std::vector<long> corners;
  std::vector<std::vector<Eigen::Vector2d>> residuals;
};
Reprojection reproject(const Detections& det, const std::vector<vision::CameraModel>& models,
                       const CalibrationSolution& sol, bool keep_residuals, BuiltProblem& built);

/// The corners of observation k predicted by kinematics + calibration, in
/// its detection's order (NaN where not projectable).
std::vector<Eigen::Vector2d> predictedCorners(const Detections& det, const std::vector<vision::CameraModel>& models,
                                              const CalibrationSolution& sol, const BuiltProblem& built,
                                              std::size_t k);

/// The results (calibrate_results.cpp): calibration.yaml's content, the
/// gate's outliers in image order, the errors against the dataset's
/// ground_truth.yaml when it has one (into res), the summary a user reads.
CalibrationOutput assembleOutput(const Inputs& in, const BuiltProblem& built, const Reprojection& rp,
                                 const CalibrateOptions& opt, const CalibrationSolution& sol);
std::vector<RejectedImage> rejectedImages(const BuiltProblem& built);
void evaluateAgainstTruth(const std::string& ground_truth, CalibrateResult& res);
std::string formatSummary(const CalibrateResult& res);

/// What the run had when the report is drawn.
struct RunView {
  const Inputs& in;
  const Detections& det;
  const BuiltProblem& built;
  const std::vector<vision::CameraModel>& models;
  const CalibrateResult& res;
};
/// What the report draws (report.hpp); the residuals are moved out of `rp`.
ReportData buildReportData(const RunView& run, Reprojection& rp);

}  // namespace fgcal::apps::stages
