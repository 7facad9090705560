// `fgcal calibrate --urdf-out`: the robot's own URDF with each calibrated
// camera's pose written back into ONE fixed joint origin of its existing chain
// (base -> ... -> camera body -> optical frame), so the description needs no
// pasted snippet and keeps no duplicate frames.
//
// Which joint (rig.yaml per camera: `frame`, optional `urdf_joint`): by
// default the joint into the camera body when the frame's own joint is a pure
// rotation (the usual *_optical_joint, xyz 0), else the frame's own joint. The
// joint must be fixed, every joint between the base link and the frame must be
// fixed (the pose must not depend on a joint value: a pan-tilt head is
// refused), and it must not lie on the chain of another calibrated camera.
//
// How: the file's TEXT is edited, one <origin .../> per camera, so comments,
// formatting and every other element stay byte for byte; the result is parsed
// again (urdfdom) and every camera's chain recomputed with fgcal's own walker,
// which must give the calibrated pose to 1e-9 (applyUrdfUpdate).
//
// URDF rpy is fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "fgcal/core/se3.hpp"

namespace fgcal::apps {

/// One camera to write back: its name, the URDF link of its optical frame
/// (what T_base_cam means), the joint to update (empty: the default rule), and
/// where rig.yaml gave them (for messages, e.g. "cameras[cam1]").
struct UrdfCameraFrame {
  std::string camera;
  std::string frame;
  std::string urdf_joint;
  std::string field;
};

/// The joint chosen for one camera and the fixed transforms around it:
/// T_base_frame = T_base_parent * T_parent_child(new origin) * T_child_frame.
struct UrdfJointEdit {
  std::string camera, frame, joint;
  bool default_joint = false;  ///< chosen by the default rule, not named in rig.yaml
  SE3 T_base_parent;           ///< base link -> the joint's parent link (fixed joints only)
  SE3 T_child_frame;           ///< the joint's child link -> the camera frame
  SE3 T_parent_child_before;   ///< the origin in the input URDF
};

struct UrdfUpdatePlan {
  std::string urdf_path;  ///< for messages
  std::string urdf_text;  ///< the input, byte for byte
  std::string base_link;
  std::vector<UrdfJointEdit> edits;
};

/// Resolves and checks every camera's joint before any calibration work.
/// Throws InputError naming `rig_path` and the camera's field for: a frame that
/// is not a link (listing the closest link names), the base link itself as
/// frame, a urdf_joint that is not a joint or not above the frame on the chain
/// from the base, a movable joint between the base and the frame (named), and
/// a joint that lies on the chain of another listed camera. URDF errors
/// (kinematics::UrdfError) name the URDF.
UrdfUpdatePlan planUrdfUpdate(const std::string& urdf_text, const std::string& urdf_path,
                              const std::string& base_link, const std::vector<UrdfCameraFrame>& cameras,
                              const std::string& rig_path);

struct UrdfUpdateResult {
  std::string text;  ///< the updated URDF
  /// The check: every camera's chain in `text` (re-parsed) against its
  /// calibrated pose: largest translation (m) and rotation (rad) difference.
  double max_translation_error_m = 0.0;
  double max_rotation_error_rad = 0.0;
  int cameras_checked = 0;
};

/// Check tolerance of applyUrdfUpdate (metres and radians).
inline constexpr double kUrdfCheckTolerance = 1e-9;

/// Writes the new origins for `T_base_cam` (camera name -> calibrated pose;
/// every camera of the plan must be there) into the plan's text, then checks
/// the result: re-parsed with urdfdom, each camera's chain through
/// kinematics::RobotModel must equal its pose to kUrdfCheckTolerance, and every
/// other joint must be unchanged. Throws std::runtime_error when that check
/// fails (a bug, never bad input): nothing is returned to be written then.
UrdfUpdateResult applyUrdfUpdate(const UrdfUpdatePlan& plan, const std::map<std::string, SE3>& T_base_cam);

/// The text edit alone: `urdf_text` with the <origin> of the top-level
/// <joint name="joint"> set to T_parent_joint (xyz and rpy replaced in place,
/// other attributes and quoting kept; an <origin/> inserted when absent).
/// Comments, CDATA and <joint> elements nested in other elements (e.g.
/// <transmission>) are never touched. Numbers in the shortest form that reads
/// back to the same double (at most 17 significant digits). Throws
/// std::invalid_argument when the joint is not found or the XML around it is
/// malformed.
std::string setJointOrigin(const std::string& urdf_text, const std::string& joint, const SE3& T_parent_joint);

/// Levenshtein distance, for "did you mean" lists.
int editDistance(const std::string& a, const std::string& b);
/// Up to `count` of `candidates` most similar to `name`, closest first: the
/// one ranking of every "closest names" list (links, joints, topics,
/// cameras). Case-insensitive; a name containing the other first, then the
/// Levenshtein distance divided by the longer name's length.
std::vector<std::string> closestNames(const std::string& name, const std::vector<std::string>& candidates,
                                      std::size_t count = 3);

}  // namespace fgcal::apps
