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
//   solve     the factor graph solved and gated, reprojection (solveAndGate
//             in calibrate.cpp)
//   output    calibration.yaml, the URDF snippet (writeOutputs), the summary
//   report    the HTML report
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

}  // namespace fgcal::apps::stages
