// rig.yaml (docs/formats.md) as plain structs, its reader with
// validation and its writer (used by the simulator). Every field of the file
// has a member of the same name; the reader throws InputError naming the file,
// the field path (e.g. "cameras[cam1].intrinsics"), the line and what was
// expected. yaml-cpp stays out of this header.
//
// Required: every field of robot and target, and of each camera except
// T_base_cam_guess (optional) and distortion_coeffs (optional only for
// distortion_model none). Optional with a documented default:
// sync_tolerance_ms = 1.0 ms (kDefaultSyncToleranceMs), joint_states_topic =
// /joint_states (kDefaultJointStatesTopic), robot.joint_offset_sigma =
// 0.05 rad (kDefaultJointOffsetSigma, used only when joint offsets are
// estimated). Unknown keys are accepted for
// forward compatibility and reported in RigConfig::warnings.
//
// Bag input (docs/formats.md): per camera `topic`,
// `camera_info_topic` and `intrinsics_file`. A camera's intrinsics (the group
// intrinsics, distortion_model, distortion_coeffs, resolution) come from the
// first of these that it has:
//   1. `intrinsics` in rig.yaml (then the whole group is read from rig.yaml;
//      an `intrinsics_file` beside it is ignored with a warning);
//   2. `intrinsics_file` (Kalibr camchain, ROS camera_info or OpenCV YAML,
//      loaded at parse time through intrinsics_import.hpp; the rest of the
//      group must then be absent from rig.yaml);
//   3. `camera_info_topic`: not known until the bag is read, which
//      CameraConfig::intrinsics_from_bag says explicitly.
// A camera with none of the three is an error naming cameras[i].intrinsics.
// Relative paths (urdf, intrinsics_file) are relative to rig.yaml's folder.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fgcal/apps/errors.hpp"
#include "fgcal/core/se3.hpp"

namespace fgcal::apps {

struct RobotConfig {
  /// Absolute, normalized path of the URDF (rig.yaml gives it relative to the
  /// dataset folder, or absolute).
  std::string urdf;
  std::string base_link;
  /// The link the board is fixed to.
  std::string marker_link;
  /// Board frame in marker_link: the prior (e.g. CAD) of the mount.
  SE3 T_link_marker;
  /// Prior std of the mount, metres and radians; both 0 holds it fixed
  /// (isMountFixed()), otherwise both > 0.
  double mount_sigma_m = 0.0;
  double mount_sigma_rad = 0.0;
  /// Encoder noise std (radians or metres) for every joint when rig.yaml gives
  /// a number; 0 when it gives the map form, which then fills encoder_sigmas
  /// (joint name -> sigma, all > 0). Exactly one of the two forms is set.
  double encoder_sigma = 0.0;
  std::map<std::string, double> encoder_sigmas;
  /// Optional: the prior std (radians, metres for prismatic joints) of the
  /// joint zero offsets that `--estimate joint-offsets` estimates, for every
  /// joint (joint_offset_sigma) or per joint (joint_offset_sigmas, all > 0),
  /// like encoder_sigma. Neither set (0 and empty) when rig.yaml does not give
  /// it: kDefaultJointOffsetSigma then.
  double joint_offset_sigma = 0.0;
  std::map<std::string, double> joint_offset_sigmas;
  /// Optional: the URDF's tolerance, the 1-sigma error [metres, radians] of
  /// each joint origin of the marker chain (robot.kinematic_sigma), for every
  /// movable joint (kinematic_sigma) or per joint (kinematic_sigmas, joints
  /// not listed taken as exact). Neither set ([0, 0] and empty) when rig.yaml
  /// does not give it: the URDF is then taken as exact, which is true of
  /// simulated data only.
  std::array<double, 2> kinematic_sigma{0.0, 0.0};
  /// Optional: the prior std (radians, metres for prismatic joints) of the
  /// gear backlash that `--estimate backlash` estimates, for every joint
  /// (backlash_sigma) or per joint (backlash_sigmas), like joint_offset_sigma.
  /// Neither set: kDefaultBacklashSigma.
  double backlash_sigma = 0.0;
  std::map<std::string, double> backlash_sigmas;
  std::map<std::string, std::array<double, 2>> kinematic_sigmas;

  bool hasKinematicSigma() const { return kinematic_sigma[0] > 0.0 || !kinematic_sigmas.empty(); }
  bool isMountFixed() const { return mount_sigma_m == 0.0 && mount_sigma_rad == 0.0; }
};

struct TargetConfig {
  std::string type = "charuco";  ///< the only board type supported
  int squares_x = 0;             ///< >= 2
  int squares_y = 0;             ///< >= 2
  double square_size = 0.0;      ///< metres, > 0
  double marker_size = 0.0;      ///< metres, 0 < marker_size < square_size
  /// OpenCV predefined dictionary name, e.g. DICT_4X4_50; checked by vision/.
  std::string dictionary;
};

struct CameraConfig {
  /// Also the image folder's name: letters, digits, '_', '-', '.', not
  /// starting with '.'.
  std::string name;
  /// Bag input: the sensor_msgs/Image or CompressedImage topic of this camera;
  /// empty when rig.yaml does not give one (a folder dataset needs none).
  std::string topic;
  /// Bag input: the sensor_msgs/CameraInfo topic; empty when not given.
  std::string camera_info_topic;
  /// Absolute, normalized path of the intrinsics file the intrinsics group was
  /// loaded from; empty when they came from rig.yaml (or are still to come
  /// from the bag). writeRigConfig writes this path instead of the numbers.
  std::string intrinsics_file;
  /// True when the intrinsics group (intrinsics, distortion_model,
  /// distortion_coeffs, resolution) is NOT known yet: rig.yaml gives neither
  /// `intrinsics` nor `intrinsics_file`, only camera_info_topic, so the bag's
  /// CameraInfo must fill them (and set this to false) before any use. While it
  /// is true those members hold no values (zeros, "none") and must not be
  /// used; a folder dataset with such a camera is refused by loadDataset.
  bool intrinsics_from_bag = false;
  /// 1-based line of this camera's entry in rig.yaml (0 when unknown), for
  /// messages about fields checked after parsing (e.g. a missing topic).
  int yaml_line = 0;
  std::string camera_model = "pinhole";  ///< Kalibr's name; only pinhole supported
  std::string distortion_model = "none";  ///< radtan | equidistant | none
  std::array<double, 4> intrinsics{};     ///< fx, fy (> 0), cx, cy (finite), pixels
  /// radtan [k1 k2 p1 p2], equidistant [k1 k2 k3 k4], none [].
  std::vector<double> distortion_coeffs;
  std::array<int, 2> resolution{};  ///< width, height, > 0
  double pixel_sigma = 0.0;         ///< corner noise std, pixels, > 0
  /// Rolling shutter: the time from the first row's exposure start to the
  /// last row's, ms (a datasheet's readout or line time x rows); 0 (absent)
  /// for a global shutter. >= 0 and finite.
  double readout_ms = 0.0;
  /// The prior std of the intrinsics when they are estimated (`fgcal
  /// calibrate --estimate intrinsics`): [fx, fy, cx, cy] in pixels, each
  /// finite and > 0; empty when rig.yaml does not give it (the documented
  /// default of kDefaultIntrinsicsSigmaFraction then applies, with a warning).
  std::vector<double> intrinsics_sigma;
  /// The same for the distortion coefficients, one per coefficient of
  /// distortion_model, each finite and > 0; empty when not given (default
  /// defaultDistortionSigma, with a warning).
  std::vector<double> distortion_coeffs_sigma;
  /// When absent, the first detections initialize the camera pose.
  std::optional<SE3> T_base_cam_guess;

  // Where the camera sits in the robot description (`fgcal calibrate
  // --urdf-out`, --tf-out). Both optional; urdf_joint needs frame.
  /// The URDF link of the camera's optical frame: the frame T_base_cam means.
  std::string frame;
  /// The fixed joint whose <origin> --urdf-out updates; empty: the default
  /// rule of urdf_update.hpp (the camera body's joint when the frame's own
  /// joint is a pure rotation, else the frame's own joint).
  std::string urdf_joint;
};

inline constexpr double kDefaultSyncToleranceMs = 1.0;
/// The prior std of estimated joint zero offsets when rig.yaml gives no
/// robot.joint_offset_sigma: 0.05 rad (about 3 deg), loose enough for an
/// encoder mounted one tooth off, tight enough to hold what the data cannot
/// observe at zero (such offsets are reported as not observed either way).
inline constexpr double kDefaultJointOffsetSigma = 0.05;
/// The prior std of estimated backlash when rig.yaml gives no
/// robot.backlash_sigma: 0.01 rad, a few times the play of a worn gearbox
/// (1 - 5 mrad at the joint), so the prior only holds a play the data do not
/// observe at zero.
inline constexpr double kDefaultBacklashSigma = 0.01;
/// Default prior std of estimated intrinsics without intrinsics_sigma: this
/// fraction of fx and fy, and of the image width and height for cx and cy
/// (2 %: 12 px on a 600 px focal length; an error of 1 % is half a sigma).
inline constexpr double kDefaultIntrinsicsSigmaFraction = 0.02;
/// Default prior std of estimated distortion coefficients without
/// distortion_coeffs_sigma: radtan [0.1, 0.1, 0.01, 0.01] (k1 k2 p1 p2),
/// equidistant [0.1, 0.1, 0.1, 0.1], none []: loose against the usual
/// magnitudes (k1 ~ 0.2, p ~ 1e-3), so that the images decide.
std::vector<double> defaultDistortionSigma(const std::string& distortion_model);
inline constexpr const char* kDefaultJointStatesTopic = "/joint_states";

struct RigConfig {
  RobotConfig robot;
  TargetConfig target;
  std::vector<CameraConfig> cameras;  ///< at least one, unique names, file order
  /// Images closer in time than this share one board pose (F2). Optional in
  /// rig.yaml; kDefaultSyncToleranceMs when absent. >= 0.
  double sync_tolerance_ms = kDefaultSyncToleranceMs;
  /// Bag input: the sensor_msgs/JointState topic. Optional in rig.yaml;
  /// kDefaultJointStatesTopic when absent.
  std::string joint_states_topic = kDefaultJointStatesTopic;
  /// The rig.yaml as named in messages (the path given to loadRigConfig, or
  /// parseRigConfig's source_name), for errors found after parsing.
  std::string source;
  /// Non-fatal findings while reading (unknown keys, principal point outside
  /// the image, ...), each naming the file and field.
  std::vector<std::string> warnings;

  /// The line of each field rig.yaml gives, by its path as every message
  /// spells it: "robot.base_link", "cameras[cam0].topic" (a camera by its
  /// name, never its position), "cameras[cam0]" for the camera itself.
  std::map<std::string, int> field_lines;

  /// Index of the camera with that name, or -1.
  int cameraIndex(const std::string& name) const;
  /// " (line N)" for `field`, else for the nearest enclosing field that has
  /// a line ("cameras[cam0].frame" -> "cameras[cam0]"); "" when none.
  std::string lineSuffix(const std::string& field) const;
};

/// The error of a value rig.yaml holds, found after reading it (against the
/// URDF, the bag, the images): rig.yaml's file, the field path, what was
/// expected and found (`detail`), and the field's line. The one format of
/// every rig.yaml error: "rig.yaml: cameras[cam0].topic: expected ... (line 12)".
InputError rigFieldError(const RigConfig& rig, const std::string& field, const std::string& detail);

/// The path of a camera's field in messages: "cameras[NAME].field" (or
/// "cameras[NAME]" when `field` is empty).
std::string cameraField(const std::string& camera, const std::string& field = "");

/// The closest of `candidates` to `name`, at most `count`, as a message
/// ends: "; closest <what>: a, b, c" ("" when there are no candidates).
std::string closestNote(const std::string& name, const std::vector<std::string>& candidates,
                        const std::string& what, std::size_t count = 5);

/// Valid values of the enumerated fields, for messages and other readers.
const std::vector<std::string>& supportedCameraModels();        // pinhole
const std::vector<std::string>& supportedDistortionModels();    // radtan equidistant none
/// Number of distortion coefficients a model takes, or -1 when unknown.
int distortionCoeffCount(const std::string& distortion_model);

/// Reads and validates rig.yaml; the URDF and intrinsics_file paths are
/// resolved against the file's folder. Throws InputError (file missing or
/// unreadable, YAML syntax error with line and column, missing field, wrong
/// type or value, an intrinsics_file missing or invalid).
RigConfig loadRigConfig(const std::string& path);

/// The same from text: `source_name` names it in messages, `base_dir` is the
/// folder relative URDF and intrinsics_file paths are resolved against.
RigConfig parseRigConfig(const std::string& yaml_text, const std::string& source_name,
                         const std::string& base_dir);

/// rig.yaml text for `rig` (numbers written to round-trip exactly, comments
/// naming units). With `relative_to` (usually the dataset folder), the URDF
/// and intrinsics_file paths are written relative to it; otherwise as stored.
/// A camera with intrinsics_file gets that path instead of the numbers; one
/// with intrinsics_from_bag gets neither (its camera_info_topic supplies
/// them). parseRigConfig of the result gives back `rig` (warnings, yaml_line
/// and source aside; an intrinsics_file must still exist to be read back).
std::string writeRigConfig(const RigConfig& rig, const std::string& relative_to = "");

}  // namespace fgcal::apps
