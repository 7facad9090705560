// runCalibrate's stages (calibrate.hpp), each a function taking and returning
// small structs, in the order they run:
//   load      the folder's rig.yaml and image list, or the bag's rig and
//             topics (loadInputs)
//   setup     the robot chain, encoder sigmas and board detector (setUpRobot)
//   detect    every image decoded and detected on all cores as it is read,
//             only its compact record and corners kept: the folder's files
//             (detectFolder, after its joints.csv is read: readFolderJoints),
//             or the bag's messages, which also collects its joint states and
//             camera_info (detectBag)
//   build     per image with a board: its pose by PnP, the joints at its
//             stamp and the forward kinematics: the estimation problem
//             (buildProblem)
//   solve     the problem's settings, the factor graph solved and gated
//             (solveAndGate), every corner reprojected (reproject)
//   output    the results and summary (calibrate_results.cpp),
//             calibration.yaml, the URDF snippet, the robot outputs
//   report    what the report draws (buildReportData), then the HTML report
// A folder and a bag give the same Inputs; everything from build on does not
// know which it was.
//
// Memory: what is kept per image is an ImageRecord (about 48 bytes), its
// corners in the problem's DetectedCorners (10 bytes a corner) and, when it
// has a board pose, its BoardObservation; the joint log keeps only the
// chain's joints and only the samples around the images' stamps.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "bag/bag_source.hpp"
#include "bag/detection_pool.hpp"
#include "fgcal/apps/calibrate.hpp"
#include "fgcal/apps/report.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal/vision/camera_model.hpp"
#include "fgcal/vision/charuco_detector.hpp"

namespace fgcal::apps::stages {

/// Why an image is not used; skipKey gives the words, the keys of
/// CameraResult::images_skipped.
enum class ImageStatus : std::uint8_t {
  Used,
  WrongSize,
  Unreadable,
  NoBoard,
  TooFewCorners,
  Collinear,
  NotDetected,
  PoseFailed,
  OutsideJointSpan,
  InvalidJoints,
  Outlier,
};
/// "" for Used, else e.g. "no board", "outside joint span", "outlier".
const char* skipKey(ImageStatus s);

/// Strings that many images share (detection messages, the joint span),
/// stored once.
class Interned {
 public:
  static constexpr std::uint32_t kNone = 0xffffffffu;
  std::uint32_t add(const std::string& s);
  /// "" for kNone.
  const std::string& operator[](std::uint32_t i) const;

 private:
  std::vector<std::string> strings_;
  std::unordered_map<std::string, std::uint32_t> index_;
};

/// One image of the run: what the stages after detection keep of it.
struct ImageRecord {
  std::int64_t stamp_ns = 0;
  /// Where it is: a folder's file (Inputs::file_names), or a bag's message
  /// (its index among its topic's messages).
  std::uint64_t locator = 0;
  double rms_px = 0.0;                     ///< final reprojection RMS when used
  std::uint32_t detail = Interned::kNone;  ///< why it is not used, in words (Inputs::details)
  std::int32_t observation = -1;           ///< index into the problem's observations; -1: none
  std::uint32_t corners_begin = 0;         ///< its detected corners in the problem's DetectedCorners
  std::uint16_t corners_count = 0;
  std::uint16_t camera = 0;  ///< index into Inputs::rig.cameras
  std::uint16_t width = 0, height = 0;  ///< as decoded; 0 when it could not be
  ImageStatus status = ImageStatus::Used;
};

/// What the load stage found, and what the stages after it add.
struct Inputs {
  bool from_bag = false;
  std::string source;       ///< the dataset folder (absolute) or the bag as given
  std::string rig_path;     ///< rig.yaml as named in messages
  std::string joints_name;  ///< joints.csv's path, or "BAG: topic /joint_states"
  RigConfig rig;            ///< only the selected cameras
  /// The chain's joints (in its order) at the samples around the images'
  /// stamps: folder: readFolderJoints; bag: detectBag.
  JointLog joints;
  /// Every image, sorted by stamp, then by the camera's place in rig.yaml.
  std::vector<ImageRecord> images;
  Interned file_names;  ///< folder: image file names, or their part after the stamp (imageName)
  Interned details;     ///< ImageRecord::detail
  std::vector<std::string> warnings;
  std::string ground_truth;  ///< the folder's ground_truth.yaml when it has one
  std::unique_ptr<logs::BagReader> bag;  ///< open until detectBag has read it; readBagImages reopens it
  std::string bag_path;                  ///< the bag's file (or folder), for messages, also once it is closed
  BagPlan plan;

  /// The image's file (folder) or message ("BAG: topic T, message I (stamp S)"), for messages.
  std::string imageName(std::size_t i) const;
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

/// The folder's joints.csv into in.joints: the chain's joints only, at the
/// samples around the images' stamps (JointLogFilter), or at every sample
/// when `every_sample` (an estimated time offset reads the trajectory around
/// each exposure, not only at the stamp); a warning for the columns the URDF
/// does not know.
void readFolderJoints(Inputs& in, const RobotSetup& setup, bool every_sample);
/// The bag's joint table (the chain's joints) cut likewise; the same warning.
void reduceBagJoints(Inputs& in, const RobotSetup& setup, bool every_sample);

/// One vision::CameraModel per camera of the rig (InputError naming rig.yaml).
std::vector<vision::CameraModel> cameraModels(const Inputs& in);

/// The detect stage's result besides the records' status: the corners of
/// every image whose detection is Ok.
struct Detections {
  DetectedCorners corners;
  double decode_seconds = 0.0;  ///< summed over the threads
};
/// Keeps what later stages use of image i's detection: its size, its status
/// and message, its corners when Ok (appended to `det`). Not thread-safe.
void keepDetection(Inputs& in, std::size_t i, const StreamedDetection& s, Detections& det);
/// WrongSize for image i when it was decoded at another size than its
/// camera's; `says` names where that size came from ("rig.yaml says").
void checkSize(Inputs& in, std::size_t i, const std::string& says);
Detections detectFolder(Inputs& in, const RobotSetup& setup, const CalibrateOptions& opt, std::ostream& log);
/// Reads the bag once: fills in.joints, in.images (sorted like a folder's;
/// of two images of one camera with the same stamp the one recorded later is
/// kept) and the intrinsics left to camera_info, detecting while reading.
Detections detectBag(Inputs& in, const RobotSetup& setup, const CalibrateOptions& opt, std::ostream& log);

/// Reads the named images (indices into in.images) back from the bag, as
/// 8-bit grey, in one pass that stops when all are found (for the report).
std::map<std::size_t, cv::Mat> readBagImages(Inputs& in, const std::vector<std::size_t>& images);

/// The board observations, camera by camera in image order: per image with
/// an Ok detection its pose by PnP (PoseFailed when none), the joints at its
/// stamp (OutsideJointSpan, InvalidJoints) and the forward kinematics.
/// obs_image maps an observation to its image. The corners move into the problem.
struct BuiltProblem {
  CalibrationProblemInput problem;
  std::vector<std::size_t> obs_image;
};
BuiltProblem buildProblem(Inputs& in, const RobotSetup& setup, const std::vector<vision::CameraModel>& models,
                          Detections& det, int threads);
/// InputError naming rig.yaml's cameras[NAME].readout_ms when a camera's
/// readout is longer than its frame period (the median spacing of its
/// images' stamps, which only a throttled recording makes longer).
void checkReadouts(const Inputs& in);
/// DataError (or InputError when every image has the wrong size) for a
/// camera with fewer than 3 usable images, the reasons counted.
void checkCoverage(const Inputs& in, const BuiltProblem& built);

/// The problem's settings from rig.yaml and the options; solveCalibration;
/// the gated images marked as outliers.
CalibrationSolution solveAndGate(Inputs& in, const CalibrateOptions& opt, BuiltProblem& built);

/// Every detected corner projected through kinematics + calibration: per
/// camera the squared error and count over its used images, each used
/// image's RMS (into in.images), and, when asked, the residuals (predicted -
/// detected) of every corner of the used images, per camera.
struct Reprojection {
  std::vector<double> squared;
  std::vector<long> corners;
  std::vector<std::vector<Eigen::Vector2d>> residuals;
};
Reprojection reproject(const BuiltProblem& built, const std::vector<vision::CameraModel>& models,
                       const CalibrationSolution& sol, bool keep_residuals, Inputs& in);

/// The corners of observation k predicted by kinematics + calibration, in
/// its detection's order (NaN where not projectable).
std::vector<Eigen::Vector2d> predictedCorners(const CalibrationProblemInput& problem,
                                              const std::vector<vision::CameraModel>& models,
                                              const CalibrationSolution& sol, std::size_t k);

/// The results (calibrate_results.cpp): calibration.yaml's content, the
/// gate's outliers in image order, the errors against the dataset's
/// ground_truth.yaml when it has one (into res), the summary a user reads.
CalibrationOutput assembleOutput(const Inputs& in, const BuiltProblem& built, const Reprojection& rp,
                                 const CalibrateOptions& opt, const CalibrationSolution& sol);
/// The images skipped as unreadable (damaged messages, undecodable files), in input order.
std::vector<RejectedImage> damagedImages(const Inputs& in);
/// A camera most of whose images are damaged: a `damaged_messages` finding
/// (check; unusable when none is left) naming its topic (or its images' folder).
std::vector<Finding> damagedFindings(const Inputs& in);
std::vector<RejectedImage> rejectedImages(const Inputs& in);
void evaluateAgainstTruth(const std::string& ground_truth, CalibrateResult& res);
std::string formatSummary(const CalibrateResult& res);

/// What the run had when the report is drawn.
struct RunView {
  const Inputs& in;
  const BuiltProblem& built;
  const std::vector<vision::CameraModel>& models;
  const CalibrateResult& res;
  const kinematics::RobotModel& robot;
};
/// What the report draws (report.hpp); the residuals are moved out of `rp`.
ReportData buildReportData(const RunView& run, Reprojection& rp);
/// What the report of a run whose solve failed draws: the stamp, the input
/// and the failure's diagnosis (its unusable findings), so that it opens as a
/// failed calibration that says why.
ReportData failedReportData(const Inputs& in, const CalibrateOptions& opt, const std::vector<Finding>& findings);

/// Now, UTC, to the second: "2026-03-01T12:34:56Z".
std::string utcNow();
/// rig.yaml's path as the stamp gives it: absolute and normal when it can be.
std::string stampedRigPath(const Inputs& in);
/// The stamp's `solve`: "F1 (each camera alone)" or "F2 (cameras jointly)".
std::string solveLabel(const CalibrateOptions& opt);

/// Whether the gate rejected more than half of some camera's images: the
/// result then rests on a minority of them, which correct data do not give
/// (the gate rejects about one image in a thousand), and runCalibrate judges
/// it as it judges a failed solve (src/quality/failure.hpp).
bool mostImagesRejected(const CalibrationProblemInput& problem, const CalibrationSolution& sol);

}  // namespace fgcal::apps::stages
