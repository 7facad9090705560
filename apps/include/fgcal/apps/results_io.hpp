// The outputs of `fgcal calibrate` (docs/outputs.md):
// calibration.yaml (formatCalibrationYaml / loadCalibrationYaml), the URDF
// snippet a user pastes into a robot description, ground_truth.yaml (written by
// `fgcal simulate`, read by `fgcal evaluate`), human-facing 1-sigma values, and
// the atomic file write every output goes through ("never a partly written
// output").
//
// Conventions: 4x4 matrices row-major as nested lists; covariances 6x6
// row-major in [wx wy wz vx vy vz] order for the right perturbation
// T ⊕ xi = T Exp(xi) of the pose they belong to. Numbers are written in the
// shortest decimal form that reads back to the same double (up to 17
// significant digits), always with a '.' so YAML readers that follow YAML 1.1
// (PyYAML) see floats.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fgcal/apps/quality.hpp"
#include "fgcal/core/se3.hpp"

namespace fgcal::apps {

struct CameraResult {
  std::string name;
  SE3 T_base_cam;
  Mat6 covariance = Mat6::Zero();  ///< [w v], right perturbation of T_base_cam
  int images_used = 0;
  double rms_reprojection_px = 0.0;
  std::map<std::string, int> images_skipped;  ///< reason -> count
  /// Estimated intrinsics (`--estimate intrinsics`), else all empty:
  /// [fx fy cx cy] and the distortion coefficients (the camera's
  /// distortion_model as in rig.yaml), each with its 1-sigma.
  std::vector<double> intrinsics, intrinsics_sigma, distortion_coeffs, distortion_coeffs_sigma;
  /// When time offsets were estimated: an image stamped t was exposed at
  /// t + time_offset_ms (docs/outputs.md), with its marginal 1-sigma.
  std::optional<double> time_offset_ms, time_offset_sigma_ms;
  /// A rolling shutter: the readout (first row's exposure start to the last
  /// row's), rig.yaml's when known and not estimated (sigma absent), else
  /// estimated with its 1-sigma (`--estimate rolling-shutter`); whether the
  /// data observe it (false: the prior's centre and sigma are written).
  std::optional<double> readout_ms, readout_sigma_ms;
  bool readout_observed = true;
  /// With robot.kinematic_sigma: how much of sigma_mm_deg the URDF's
  /// tolerance adds, per component sqrt(sigma^2 - sigma_exact^2) where
  /// sigma_exact holds the leg's origins at their estimates.
  std::optional<Vec6> sigma_from_urdf_mm_deg;
};

/// The pose of camera b in camera a with its own covariance ([w v], right
/// perturbation of T_a_b), from the cameras' joint covariance: it does not
/// carry what they share (the URDF's tolerance, the leg's common error).
struct RelativePoseResult {
  std::string a, b;
  SE3 T_a_b;
  Mat6 covariance = Mat6::Zero();
};

/// T_a_b = T_base_a^-1 T_base_b and its covariance from the cameras'
/// covariances and cov(xi_a, xi_b) (`cross`; zero for cameras solved apart).
RelativePoseResult relativePose(const CameraResult& a, const CameraResult& b, const Mat6& cross);

/// One movable joint's origin correction (robot.kinematic_sigma): the
/// transform before the joint is the URDF's times Exp(correction), [w v].
struct OriginResult {
  std::string joint;
  Vec6 correction = Vec6::Zero();
  Vec6 sigma = Vec6::Zero();  ///< marginal 1-sigma
  /// Per component: whether the data observe it (else it rests on the prior).
  std::array<bool, 6> observed{};
};

/// One joint's estimated zero offset: the joint stood at its reading + offset_rad.
struct JointOffsetResult {
  std::string joint;
  double offset_rad = 0.0;
  double sigma_rad = 0.0;  ///< marginal 1-sigma
  /// false: the data do not observe it; offset_rad and sigma_rad are then the
  /// prior's (0 and its sigma), not a measurement.
  bool observed = true;
};

struct MountResult {
  SE3 T_link_marker;
  Mat6 covariance = Mat6::Zero();  ///< zero when the mount was held fixed
  bool estimated = false;
};

struct CalibrationOutput {
  std::vector<CameraResult> cameras;  ///< written in this order
  MountResult mount;
  /// When joint zero offsets were estimated: every movable joint of the
  /// marker chain, chain order (written as `joint_offsets:`).
  std::vector<JointOffsetResult> joint_offsets;
  /// When backlash was estimated: every movable joint of the marker chain,
  /// chain order, offset_rad holding the play (written as `backlash: {JOINT:
  /// {rad, sigma_rad, observed}}`).
  std::vector<JointOffsetResult> backlash;
  /// With robot.kinematic_sigma: every movable joint of the marker chain,
  /// chain order (written as `kinematic_origins:`).
  std::vector<OriginResult> kinematic_origins;
  /// Every pair of cameras in file order (a before b), written as
  /// `T_a_b: {T_a_b, covariance, sigma_mm_deg}`. A pair not listed is
  /// written with the cameras taken as independent.
  std::vector<RelativePoseResult> relative_poses;
  /// "pnp" or "corners" (--method); whether the cameras were solved jointly
  /// (F2) or each alone (F1) is info's `solve`.
  std::string method;
  /// What was estimated beyond the poses and the mount, `--estimate`'s names
  /// (time-offset, joint-offsets, intrinsics); written as `estimated: [...]`.
  std::vector<std::string> estimated;
  /// The result's verdict on itself and its findings (quality.hpp), written
  /// first, as `quality:`.
  Quality quality;
  /// Free-form key/value pairs written under `info:` (dataset, fgcal version,
  /// date, final cost, iterations, ...), in this order.
  std::vector<std::pair<std::string, std::string>> info;
};

/// 1-sigma of a pose with covariance `cov` ([w v], right perturbation):
/// [x y z] in mm (base-frame position: R Sigma_vv R^T) and [roll pitch yaw] in
/// degrees (Sigma_ww mapped through d rpy / d w). Near pitch = ±90° roll and yaw
/// are undefined and their sigmas grow without bound.
Vec6 sigmaMmDeg(const SE3& T, const Mat6& cov);

/// Jacobian of [roll pitch yaw](R Exp(w)) with respect to w at w = 0.
Mat3 rpyJacobian(const SO3& R);

/// calibration.yaml text: `quality: {verdict, findings}`, `cameras: NAME: {T_base_cam, covariance,
/// sigma_mm_deg, xyz_rpy, images_used, rms_reprojection_px, images_skipped}`,
/// then `T_<a>_<b>` for every pair a before b (in cameras order), then
/// `mount: {T_link_marker, covariance, sigma_mm_deg, estimated}`, when
/// estimated `joint_offsets: {JOINT: {offset_rad, sigma_rad, observed}}` (and
/// per camera `time_offset_ms`, `time_offset_sigma_ms`), `method`, `estimated`
/// and `info`.
std::string formatCalibrationYaml(const CalibrationOutput& out);

/// Reads calibration.yaml back (fgcal evaluate). Derived fields (sigma_mm_deg,
/// xyz_rpy, T_a_b) are not read. Throws InputError naming the file and field.
CalibrationOutput loadCalibrationYaml(const std::string& path);
CalibrationOutput parseCalibrationYaml(const std::string& yaml_text, const std::string& source_name);

/// One `<link name="NAME"/>` and one fixed `<joint name="NAME_joint">` from
/// `base_link` per camera, with <origin xyz rpy> of T_base_cam, to paste into
/// the robot's URDF.
std::string formatUrdfSnippet(const CalibrationOutput& out, const std::string& base_link);

struct GroundTruth {
  std::map<std::string, SE3> T_base_cam;  ///< camera name -> true pose
  std::optional<SE3> T_link_marker;       ///< true board mount, when known
  // What `fgcal calibrate --estimate` may estimate besides the poses; each
  // map holds the cameras (joints) whose truth is known, and is empty for a
  // ground truth written before these keys existed.
  /// Camera -> true time offset, ms: an image stamped t was exposed at t + offset.
  std::map<std::string, double> time_offset_ms;
  /// Camera -> true [fx, fy, cx, cy] (pixels) and distortion coefficients.
  std::map<std::string, std::vector<double>> intrinsics;
  std::map<std::string, std::vector<double>> distortion_coeffs;
  /// Joint -> true zero offset o (rad; m for a prismatic joint): forward
  /// kinematics at q + o, q as joints.csv holds it, gives the true pose.
  std::map<std::string, double> joint_offsets_rad;
  /// Joint -> true origin correction [w v] (the URDF's origin times
  /// Exp(correction) is the real leg), when the leg differs from its URDF.
  std::map<std::string, Vec6> kinematic_origins;
  /// Joint -> true gear backlash (rad; m for a prismatic joint): the dead
  /// zone between the motor, whose angle joints.csv holds, and the joint.
  std::map<std::string, double> backlash_rad;
  /// Camera -> true rolling-shutter readout (first row's exposure start to
  /// the last row's) and exposure time, ms.
  std::map<std::string, double> readout_ms;
  std::map<std::string, double> exposure_ms;
  /// The joint encoders' step (rad), when the readings were quantised.
  std::optional<double> encoder_resolution_rad;
};

/// ground_truth.yaml: `cameras: NAME: {T_base_cam: 4x4, time_offset_ms,
/// intrinsics, distortion_coeffs, readout_ms, exposure_ms}`, when known `mount:
/// T_link_marker: 4x4`, `joint_offsets: {JOINT: {offset_rad}}`, `backlash:
/// {JOINT: {rad}}` and `encoder_resolution_rad` — the same keys as calibration.yaml,
/// so either file can be read by loadGroundTruth (every key but T_base_cam is
/// optional).
std::string formatGroundTruthYaml(const GroundTruth& truth);
GroundTruth loadGroundTruth(const std::string& path);
GroundTruth parseGroundTruth(const std::string& yaml_text, const std::string& source_name);

/// Writes `content` to PATH.tmp.<pid> in the same folder, fsyncs it, renames
/// it onto `path` and fsyncs the folder: readers see the old file or the whole
/// new one, never a part. On any failure the temporary file is removed, an
/// existing `path` is left untouched, and InputError names the path (a missing
/// folder is named as such). `durable` = false skips the two fsyncs: still
/// whole-or-nothing for readers, but not guaranteed on disk after a power cut
/// (for many files whose set is marked complete by one durable file, e.g. a
/// simulated dataset's images before its rig.yaml).
enum class Durability { Synced, Unsynced };
void writeFileAtomically(const std::string& path, const std::string& content,
                         Durability durable = Durability::Synced);
/// Several files (path, content) that belong together, e.g. calibration.yaml
/// and its URDF snippet: every path is checked and every file written to its
/// temporary before the first rename, so a bad path, a full disk or a write
/// error leaves all of them as they were (InputError naming the one that
/// failed). Only a failing rename after an earlier one succeeded can split
/// the set, and the message then names the files already replaced.
void writeFilesAtomically(const std::vector<std::pair<std::string, std::string>>& files,
                          Durability durable = Durability::Synced);

/// Reads a whole text file; InputError naming it when missing or unreadable.
/// `what` describes it in the message (e.g. "rig.yaml of the dataset").
std::string readTextFile(const std::string& path, const std::string& what = "file");

}  // namespace fgcal::apps
