// When the calibration cannot be solved at all (every image of a camera
// rejected as inconsistent with the others, a marker chain that does not
// move): the input that, changed, makes the kinematics and the images agree.
// No solution exists to test against, so each alternative is judged by how
// many images then agree on their camera's pose: every image proposes
// T_base_cam = T_base_link * mount * T_cam_marker^-1, and with the right
// inputs nearly all proposals of a camera agree (the initializer's rule:
// within 5 cm and 3 deg of the proposal most others agree with).
#pragma once

#include <string>
#include <vector>

#include "fgcal/apps/calibration_problem.hpp"
#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/quality.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal/vision/camera_model.hpp"

namespace fgcal::apps::quality {

struct FailureContext {
  const CalibrationProblemInput& problem;
  const RigConfig& rig;
  const kinematics::RobotModel& robot;
  const kinematics::KinematicChain& chain;
  const VecX& sigma_q;
  const JointLog& joints;  ///< the chain's joints as logged
  /// Every joint the log holds (to try other marker links); null when only
  /// the chain's are at hand.
  const JointLog* all_joints = nullptr;
  /// How joint columns are named in fields (assess.hpp, Context::joints_input).
  std::string joints_input = "joints.csv";
  const std::vector<vision::CameraModel>* models = nullptr;  ///< per camera, for the corners' scatter
  /// The mount T_link_marker the images' agreement is judged with: a solved
  /// one when the solve kept a minority of a camera's images; null: the
  /// problem's prior (rig.yaml's).
  const SE3* mount = nullptr;

  const SE3& judgedMount() const { return mount ? *mount : problem.mount_prior; }
};

/// The fraction of images, over all cameras, whose camera-pose proposal
/// T_base_link * mount * T_cam_marker^-1 agrees with their camera's
/// consensus, with each image's T_base_link as given; with `scale`, each
/// PnP distance divided by it (camera < 0), or only `camera`'s depths, as
/// quality::scaled() changes them.
double agreement(const CalibrationProblemInput& problem, const std::vector<SE3>& T_base_link, const SE3& mount,
                 double scale = 1.0, int camera = -1);

/// Findings (severity unusable) naming the input whose change makes the
/// images agree: joints beyond the URDF's limits (in degrees), a joint's
/// sign, two joints swapped, another marker link, the board's size, one
/// camera's focal length, or rig.yaml's lens models given to the wrong
/// cameras (two swapped, or one camera with another's); else, corners that
/// miss their own PnP poses in every camera (the board's layout) or in one
/// (its intrinsics). Empty when nothing brings at least half of the images
/// that disagree as given (at least a tenth) into agreement.
std::vector<Finding> diagnoseFailure(const FailureContext& ctx);

}  // namespace fgcal::apps::quality
