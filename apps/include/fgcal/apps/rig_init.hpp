// `fgcal init`: writes a starter rig.yaml for a robot, with comments, from what
// the user already has: the URDF, the board's description, and the cameras'
// intrinsics from camera_info (the messages of a bag, or files in ROS, Kalibr or
// OpenCV format, read by importIntrinsics). It finds each camera's `frame` in
// the URDF, the topics when a bag is given, and prints the board link's chain
// so the user can check that the right leg moves the board. The text is
// validated by the rig.yaml reader before anything is written; any bad input
// is an InputError (exit 2) and leaves no file.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include "fgcal/apps/rig_config.hpp"

namespace fgcal::kinematics {
class RobotModel;
}

namespace fgcal::apps {

/// Defaults written into a starter rig.yaml, each with a comment saying what
/// to change (docs/formats.md).
inline constexpr double kInitMountSigmaM = 0.005;    ///< a hand-measured mount: 5 mm
inline constexpr double kInitMountSigmaRad = 0.05;   ///< and about 3 degrees
inline constexpr double kInitEncoderSigma = 0.001;   ///< rad, typical leg encoders
/// robot.kinematic_sigma as init writes it, [m, rad] per axis of each joint
/// origin: a CAD URDF's usual machining and assembly tolerance.
inline constexpr double kInitKinematicSigmaM = 0.001;
inline constexpr double kInitKinematicSigmaRad = 0.002;
inline constexpr double kInitPixelSigma = 0.5;       ///< px, ChArUco corners after refinement

struct InitOptions {
  std::string urdf;         ///< robot description (required)
  std::string base_link;    ///< required
  std::string marker_link;  ///< the link the board is fixed to (required)
  /// "SQUARES_XxSQUARES_Y:SQUARE_SIZE:MARKER_SIZE:DICTIONARY", e.g. "5x7:0.04:0.03:DICT_4X4_50".
  std::string board;
  /// A ROS 1 .bag, ROS 2 bag folder or .mcap file: cameras from its
  /// CameraInfo topics. Exclusive with camera_infos.
  std::string bag;
  /// "NAME:FILE" (the camera NAME from FILE: the file's camera of that name,
  /// or its only camera renamed NAME) or "FILE" (every camera of the file
  /// under the file's own names).
  std::vector<std::string> camera_infos;
  std::string output;      ///< rig.yaml to write; its folder must exist
  bool overwrite = false;  ///< replace an existing output file
};

/// One camera of the starter file and where its values came from.
struct InitCamera {
  CameraConfig camera;  ///< intrinsics, distortion, resolution, pixel_sigma
  std::string source;   ///< "FILE (ROS camera_info file)" or "BAG, topic /cam0/camera_info"
  /// --camera-info: the file, written as rig.yaml's `intrinsics_file` (the
  /// values then stay with their source; `camera` shows them as comments).
  /// Empty for a bag: its intrinsics are written as numbers.
  std::string intrinsics_file;
  std::string frame;    ///< URDF link of the optical frame; empty when not found
  /// Why `frame` is what it is (how it was matched), or why it is left out and
  /// which links come closest: written as a comment.
  std::string frame_note;
  /// The name the frame was looked for by: the camera_info frame_id, or the camera's name.
  std::string frame_hint;
  /// When `frame` is empty: the URDF's optical frames, best first
  /// (opticalFrameCandidates), and the one written as a commented `# frame:`
  /// line, chosen on a branch of its own so that --urdf-out can update every
  /// camera; empty when the URDF has none.
  std::vector<std::string> frame_candidates;
  std::string frame_candidates_note;  ///< how they are ranked
  std::string suggested_frame;
  /// The joint --urdf-out updates for `frame` (or the suggestion) by default,
  /// written as a commented `# urdf_joint:` line; empty when none can be
  /// chosen, and then `urdf_joint_note` says what to edit first.
  std::string urdf_joint;
  std::string urdf_joint_note;
  std::string topic;              ///< image topic (bag only), empty when none
  std::string topic_note;         ///< other image topics of the camera, etc.
  std::string camera_info_topic;  ///< bag only
};

/// What init found before writing: the cameras, the chain and the text.
struct InitPlan {
  TargetConfig target;
  std::vector<InitCamera> cameras;
  std::string joint_states_topic;       ///< bag only
  std::string joint_states_note;        ///< e.g. other JointState topics
  std::vector<std::string> chain_lines; ///< "base", "  -- LF_HAA (revolute) --> LF_HIP", ...
  std::vector<std::string> chain_joints;  ///< movable joints base -> marker link (joints.csv columns)
  std::string rig_yaml;                 ///< the text to write
  std::vector<std::string> warnings;    ///< the reader's findings on that text, and init's own
};

/// Parses --board; InputError naming --board and the expected form.
TargetConfig parseBoardSpec(const std::string& spec);

/// closestNames (urdf_update.hpp) with init's default count.
std::vector<std::string> nearestNames(const std::string& name, const std::vector<std::string>& candidates,
                                      std::size_t count = 5);

/// A URDF link that may be a camera's optical frame, and why it was taken.
struct OpticalFrameCandidate {
  std::string link;
  bool named_optical = false;     ///< its name has "optical" in it (`*_optical_frame`, ...)
  bool optical_rotation = false;  ///< turned from its parent as optical frames are: z along the parent's x, x right, y down
  double distance_m = -1.0;       ///< from the camera's CAD link; -1 when there is none
};

/// The links of `model` that look like a camera's optical frame by what they
/// are, not by how they are spelled: named `*optical*` or turned from their
/// parent link into the optical convention. `camera_hint` is the camera's
/// frame_id or name; when a link is named like it without the optical suffix
/// ("front_cam_optical_frame" -> "front_cam", "front_cam_link"), that is the
/// camera's CAD pose and candidates are ranked by their distance from it.
/// Otherwise links with both marks come first, then the named, then the
/// turned, in the URDF's order.
std::vector<OpticalFrameCandidate> opticalFrameCandidates(const kinematics::RobotModel& model,
                                                          const std::string& base_link,
                                                          const std::string& camera_hint);

/// Reads every input, checks it and builds the text; writes nothing.
InitPlan planInit(const InitOptions& options);

/// planInit, then writes the file atomically and prints the chain, the
/// cameras and what to edit next to `out`. Returns the plan.
InitPlan runInit(const InitOptions& options, std::ostream& out);

}  // namespace fgcal::apps
