// `fgcal simulate` as a library call: writes a complete synthetic
// dataset in the format of docs/formats.md — rig.yaml, joints.csv, robot.urdf, one image
// folder per camera and ground_truth.yaml — for a legged robot with a ChArUco
// board on one foot, set up like the paper's HyQ experiment: a stereo-head left
// camera and a lower-resolution RGB-D camera at the front of the base, the leg
// moved passively and smoothly in front of both.
//
// What is simulated, and how (details in apps/src/commands/simulate/):
// - the cameras are placed from the robot itself: the marker link's reachable
//   workspace is sampled, and the cameras sit at the front of the base looking
//   forward and down at where the raised foot goes (any URDF, e.g. ANYmal C or
//   Unitree A1, not only our default robot);
// - the true board mount faces the cameras in a typical raised-leg pose; the
//   rig.yaml prior is the truth moved by mount_error_m / mount_error_rad;
// - the leg visits joint configurations in which the board is in view, close
//   enough and facing the cameras, chosen for orientation diversity, joined by
//   minimum-jerk segments; other joints stand still;
// - joints at 500 Hz with encoder noise; cam0 (and extra cameras) at 30 Hz on
//   the joint clock, cam1 at 15 Hz hardware-synced with every other cam0 frame
//   (+200 us); images rendered with vision::BoardRenderer with blur, intensity
//   noise and corner (vertex) jitter of exactly pixel_noise px;
// - optionally what real legs and cameras add: gear backlash between motor
//   (encoder) and joint, encoder steps, a rolling shutter per camera and an
//   exposure time that blurs the moving board.
// Same options (seed included) give byte-identical files.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "fgcal/core/se3.hpp"

namespace fgcal::apps {

struct SimulationOptions {
  /// Dataset folder; created when missing. It must be empty (or hold nothing
  /// but an earlier simulation's files when `overwrite` is set).
  std::string out_dir;
  /// Robot description; empty = fgcal's default robot. Either way the URDF is
  /// written into the dataset as robot.urdf, so the dataset is self-contained.
  std::string urdf_path;
  std::string base_link = "base_link";
  std::string marker_link = "lf_foot";
  /// 1..4: cam0 stereo-head left camera (multisense_left), cam1 RGB-D colour
  /// camera (xtion_rgb), cam2 stereo-head right camera, cam3 a wide head camera.
  int cameras = 2;
  /// Number of cam0 images (30 Hz), i.e. image instants of the fastest camera.
  int frames = 300;
  unsigned seed = 1;
  /// Corner noise std in pixels (vertex jitter); written as pixel_sigma (at
  /// least 0.05 px, the renderer's own corner noise, when 0).
  double pixel_noise = 0.5;
  /// Std of the joint readings (rad or m); written as encoder_sigma (at least
  /// 1e-5 when 0, rig.yaml needs a positive value).
  double encoder_noise = 0.002;
  /// Error of the rig.yaml mount prior w.r.t. the true mount (norms; random
  /// directions from the seed).
  double mount_error_m = 0.0;
  double mount_error_rad = 0.0;
  /// Lens distortion of every camera: radtan | equidistant | none.
  std::string distortion = "radtan";
  /// --fov-deg: horizontal field of view of every camera, degrees; 0 keeps
  /// each camera's own (cam0 82 deg). The focal lengths are set so that a ray
  /// at half this angle from the optical axis meets the image's side edges
  /// (through the distortion model; the principal point and fy / fx stay).
  /// 30..160 with equidistant (a fisheye: the diagonal may pass 90 deg only
  /// where the image corners stay in front of the camera), 30..120 with
  /// radtan or none; a distortion that folds inside the image is refused.
  double fov_deg = 0.0;
  /// Samples per pixel side when rendering (1..16).
  int supersampling = 3;
  /// Image size of every camera; 0 x 0 keeps each camera's own (cam0
  /// 1024x544, cam1 640x480, ...). When set, the focal length is scaled by
  /// min(width / own width, height / own height) and the principal point
  /// moves with the image centre, so each camera sees at least its own field
  /// of view (benchmarks at a given resolution).
  int image_width = 0, image_height = 0;
  /// false: write rig.yaml, joints.csv, robot.urdf and ground_truth.yaml but
  /// render no image. The images depend on the seed, cameras, frames, URDF,
  /// links, distortion, field of view, pixel noise, resolution,
  /// supersampling, camera delays, leg origin errors, backlash, readouts and
  /// exposure only, not on encoder_noise, encoder_resolution_rad,
  /// mount_error_*, joint_offsets_rad or intrinsics_error_*: a benchmark may
  /// pair one rendered dataset with the joints and priors of several such
  /// variants.
  bool render_images = true;
  /// Exposure of cam1 after the cam0 image it is synced with, microseconds
  /// (0..1000, below the 1 ms sync tolerance); 0 models perfectly
  /// synchronous cameras.
  double cam1_delay_us = 200.0;
  /// Replace the files of an earlier simulation in out_dir (rig.yaml,
  /// joints.csv, robot.urdf, ground_truth.yaml, the camera folders' images).
  bool overwrite = false;
  /// --camera-frames: when set, one URDF link per camera (its size must equal
  /// `cameras`), each the camera's optical frame (z forward, x right) and
  /// reached from base_link through fixed joints only. Camera i then sits at
  /// that link's pose moved by camera_frame_offset_m / _rad (random
  /// directions from the seed: the CAD pose is never exact), and rig.yaml
  /// names the link as the camera's `frame:`. Empty: cameras placed from the
  /// leg's workspace as described above.
  std::vector<std::string> camera_frames;
  double camera_frame_offset_m = 0.005;
  double camera_frame_offset_rad = 0.5 * M_PI / 180.0;
  /// --camera-delay-ms: camera name -> milliseconds. An image of that camera
  /// stamped t shows the board where the leg was at t + ms (joints.csv and
  /// the stamps are unchanged), so its true time offset is +ms (an image
  /// stamped t was exposed at t + offset); written as the camera's
  /// time_offset_ms in ground_truth.yaml (0 for the others). Negative values
  /// are allowed; every image's t + ms must lie inside joints.csv (a margin
  /// of 100 ms at each end, 99.8 ms after cam1's last image).
  std::map<std::string, double> camera_delay_ms;
  /// --joint-offsets: joint -> zero offset o (radians, metres for a
  /// prismatic joint), for movable joints of the chain base_link ->
  /// marker_link, |o| <= 0.5. joints.csv holds q_true - o (plus encoder
  /// noise), the images are rendered from q_true: forward kinematics at
  /// joints.csv + o gives the true pose. ground_truth.yaml lists every
  /// movable joint of that chain under joint_offsets (0 for the others).
  std::map<std::string, double> joint_offsets_rad;
  /// --intrinsics-error PCT,PX: rig.yaml holds fx and fy scaled by
  /// (1 +- PCT/100) and cx, cy moved by +- PX pixels, each sign drawn from the
  /// seed per camera; the images are rendered with the true intrinsics, which
  /// ground_truth.yaml holds. PCT in [0, 50], PX in [0, 100].
  double intrinsics_error_pct = 0.0;
  double intrinsics_error_px = 0.0;
  /// --leg-origin-error M,RAD: the real leg is not its URDF. The origin of
  /// every movable joint of the chain base_link -> marker_link is off by an
  /// error drawn from the seed, each axis normal with std M metres and RAD
  /// radians (KinematicChain::forwardCorrected's correction). robot.urdf is
  /// the nominal description, the images show the real leg; rig.yaml gets
  /// robot.kinematic_sigma: [M, RAD], ground_truth.yaml the corrections under
  /// kinematic_origins. M in [0, 0.02], RAD in [0, 0.05].
  double leg_origin_error_m = 0.0;
  double leg_origin_error_rad = 0.0;
  /// --backlash: gear backlash b of the movable joints of the chain
  /// base_link -> marker_link (radians, metres for a prismatic joint), in
  /// [0, 0.1]: backlash_rad for every one of them, joint_backlash_rad for
  /// single joints (winning over backlash_rad). The encoder sits on the motor
  /// side and the joint follows the motor through a dead zone of width b (a
  /// play operator): q_joint = clamp(q_joint before, q_motor - b/2,
  /// q_motor + b/2), started b/2 behind the joint's first move. The leg's
  /// smooth motion is the motor's: joints.csv holds it (minus any joint
  /// offset, plus noise), the images show q_joint, so a joint moving steadily
  /// lags its reading by b/2 and stands still for a turn of b after the motor
  /// reverses. ground_truth.yaml lists every movable joint of that chain under
  /// backlash: {JOINT: {rad}} (0 for the others) when any b is not 0.
  double backlash_rad = 0.0;
  std::map<std::string, double> joint_backlash_rad;
  /// --encoder-resolution: the step of every joint encoder (radians, metres
  /// for a prismatic joint), in [0, 0.1]: each joints.csv reading is rounded
  /// to the nearest multiple of it after the noise. 0 = continuous readings.
  /// ground_truth.yaml: encoder_resolution_rad, when not 0.
  double encoder_resolution_rad = 0.0;
  /// --readout-ms: camera name -> rolling-shutter readout R, milliseconds,
  /// from the start of the first row's exposure to that of the last row, in
  /// [0, the camera's frame period] (33.3 ms at 30 Hz, 66.7 ms for xtion_rgb
  /// at 15 Hz). The stamp of an image is the start of its first row's
  /// exposure; row v (0 at the top .. H - 1) starts at stamp + v / (H - 1) * R,
  /// and shows the board where the leg was then (plus any camera delay).
  /// Written only to ground_truth.yaml, as every camera's readout_ms (0 for
  /// the others) when any is not 0; rig.yaml stays global-shutter.
  std::map<std::string, double> readout_ms;
  /// --exposure-ms: exposure of every camera, milliseconds, in [0, 33.3]:
  /// each row integrates the board over [its start, its start + exposure]
  /// (7 equally weighted instants at the middles of 7 equal parts), so a
  /// moving board blurs. 0 = an instant. ground_truth.yaml: every camera's
  /// exposure_ms, when not 0.
  double exposure_ms = 0.0;
  /// Called after each image: camera name, images of that camera done, total.
  std::function<void(const std::string& camera, int done, int total)> progress;
};

struct SimulatedCameraSummary {
  std::string name;
  int images = 0;
  /// Images in which the whole board is inside the image, in front of the
  /// camera and facing it (by geometry, before detection).
  int board_in_view = 0;
  SE3 T_base_cam;  ///< the truth, as in ground_truth.yaml
};

struct SimulationSummary {
  int images_written = 0;  ///< all cameras
  int instants = 0;        ///< cam0 image instants (= frames)
  int joint_samples = 0;   ///< rows of joints.csv
  std::vector<std::string> cameras;  ///< camera names, rig.yaml order
  std::vector<SimulatedCameraSummary> per_camera;
  /// Fraction of cam1's instants (cam0's with one camera) at which every
  /// camera sees the whole board: the F2 share of the dataset.
  double fraction_all_in_view = 0.0;
  /// Largest rotation (deg) of the board between any two image instants, and
  /// the spread (std, deg) of its orientation about the base x, y, z axes.
  double board_rotation_range_deg = 0.0;
  Vec3 board_rotation_std_deg = Vec3::Zero();
  SE3 T_link_marker;  ///< the true mount
  double seconds = 0.0;  ///< wall time of simulateDataset
};

/// Writes the dataset. Throws InputError naming the option (e.g. "--cameras",
/// "--urdf", "--marker-link", "--camera-delay-ms", "--readout-ms") for a bad value, a URDF
/// that cannot be read or a link or joint it lacks, an unknown camera name,
/// or a non-empty out_dir, before anything is written; DataError when the
/// robot's leg cannot bring the board in front of the cameras.
SimulationSummary simulateDataset(const SimulationOptions& options);

/// The camera names of a simulation with `count` (1..4) cameras, rig.yaml
/// order: multisense_left, xtion_rgb, multisense_right, head_wide.
std::vector<std::string> simulatedCameraNames(int count);

/// Command-line values "NAME=VALUE", comma separated, from one or more texts
/// (the option may be repeated): name -> value. InputError naming `option`
/// for an item that is not NAME=number (finite), or a name given twice.
std::map<std::string, double> parseNamedValues(const std::vector<std::string>& texts, const std::string& option);
/// --backlash texts, comma separated, the option repeatable: an item RAD is
/// the backlash of every movable joint of the marker chain (*all_rad, 0 when
/// no such item), JOINT=RAD that joint's (*per_joint). InputError naming
/// --backlash for an item of neither form, RAD given twice or a joint twice.
void parseBacklash(const std::vector<std::string>& texts, double* all_rad, std::map<std::string, double>* per_joint);
/// Exactly `count` comma-separated finite numbers; InputError naming `option`
/// and the expected `form` (e.g. "PCT,PX") otherwise.
std::vector<double> parseNumberList(const std::string& text, const std::string& option, std::size_t count,
                                    const std::string& form);

}  // namespace fgcal::apps
