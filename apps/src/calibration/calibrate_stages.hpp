// runCalibrate's stages (calibrate.hpp), each a function taking and returning
// small structs, in the order they run:
//   load      the folder dataset (loadInputs)
//   setup     the robot chain, encoder sigmas and board detector (setUpRobot)
//   detect    every image decoded, detected and its pose estimated on all
//             cores (detectFolder)
//   align     joint positions at each image stamp (alignJoints)
//   build     the board observations with forward kinematics (buildProblem)
//   solve     the factor graph solved and gated, reprojection (solveAndGate
//             in calibrate.cpp)
//   output    calibration.yaml, the URDF snippet (writeOutputs), the summary
//   report    the HTML report
// Everything from align on sees only Inputs + Detections, whatever the source.
#pragma once

#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <vector>

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
  std::string source;       ///< the dataset folder (absolute)
  std::string rig_path;     ///< rig.yaml as named in messages
  std::string joints_name;  ///< joints.csv's path, or "BAG: topic /joint_states"
  RigConfig rig;            ///< only the selected cameras
  JointLog joints;          ///< folder: joints.csv; bag: filled by detectBag
  std::vector<ImageEntry> images;  ///< folder: the files; bag: filled by detectBag (path = message label)
  std::vector<std::string> warnings;
  std::string ground_truth;  ///< the folder's ground_truth.yaml when it has one
};
Inputs loadInputs(const CalibrateOptions& opt);

struct RobotSetup {
  kinematics::RobotModel robot;
  kinematics::KinematicChain chain;
  VecX sigma_q;
  std::unique_ptr<vision::CharucoDetector> detector;
};
RobotSetup setUpRobot(const Inputs& in);

/// The chain's columns in the joint log (InputError naming the log when one
/// is missing); a warning for the log's joints the URDF does not know.
std::vector<int> jointColumns(const Inputs& in, const RobotSetup& setup, std::vector<std::string>* warnings);

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
