// The calibration report: what a user looks at after calibrating to decide
// whether to trust the result. One self-contained HTML page (inline CSS and
// SVG plots drawn by our own helper, no JavaScript, no network resource) and
// PNG images beside it:
// - a stamp: the fgcal version, the date (UTC), rig.yaml and the dataset;
// - warnings in plain words (solveCalibration's and the run's);
// - the results: the table of poses (pose, 1-sigma, images, reprojection
//   RMS; errors and NEES when the dataset has a ground_truth.yaml), then what
//   --estimate added (time offsets, joint offsets, intrinsics) with its
//   1-sigma and, for a time offset, the reprojection RMS against the offset
//   swept around its estimate;
// - the rig from above, from the side and from the front: base frame, the
//   robot's links (the URDF's tree at its zero pose), camera frustums at their
//   estimated poses and, for a camera with a `frame:`, at its URDF pose, the
//   board positions seen, coloured by camera;
// - the convergence of every solve (cost per iteration);
// - per camera: where the detected corners fell in the image over the run
//   (coverage, drawn on the image frame), reprojection residuals (scatter,
//   histogram), fiducial and kinematic chi-square over time, the images
//   rejected and why, and a few images with detected (green) and predicted
//   (red) corners drawn over them.
//
// The report draws a ReportData, which the calibration pipeline builds
// (CalibrateTrace::report_data hands it to a caller).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "fgcal/apps/evaluate.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/core/se3.hpp"

namespace fgcal::apps {

/// A chi-square at a time (seconds from the dataset's first image).
struct TimedChi2 {
  double t = 0.0;
  double chi2 = 0.0;
};

/// An image shown with its detected and predicted corners.
struct ReportOverlay {
  std::string tag;    ///< best, median, worst (of the reprojection RMS of the images used), rejected
  std::string image;  ///< its file, or its bag message
  /// Which image of the run it is (ReportOptions::load_images gets these).
  std::size_t image_index = 0;
  double rms_px = 0.0;         ///< reprojection RMS (used images)
  double fiducial_chi2 = 0.0;  ///< of its fiducial factor (rejected images)
  std::vector<Eigen::Vector2d> detected_px;
  std::vector<Eigen::Vector2d> predicted_px;  ///< same order; NaN where not projectable
};

/// An image that was not used, and why.
struct ReportRejection {
  std::string image;
  std::string reason;  ///< a key of CameraResult::images_skipped
  std::string detail;
};

struct ReportCamera {
  /// Pose, covariance, images used and skipped (by reason) and RMS, as in calibration.yaml.
  CameraResult result;
  std::optional<PoseError> error;  ///< against ground truth, when known
  std::array<double, 4> intrinsics{};  ///< fx, fy, cx, cy: the frustum
  /// rig.yaml's `frame:` (the URDF link of its optical frame) and that link's
  /// pose in the base frame at the URDF's zero pose; unset without a frame.
  std::string frame;
  std::optional<SE3> T_base_cam_urdf;
  std::array<int, 2> resolution{};
  std::size_t images = 0;  ///< images of this camera read
  std::vector<Eigen::Vector2d> residuals_px;  ///< predicted - detected, every corner of the images used
  /// Where in the image the corners fell over the run (the coverage picture):
  /// every detected corner of the images used, and of the images with a board
  /// pose that were not used (the gate's outliers), in pixels.
  std::vector<Eigen::Vector2d> corners_used_px, corners_rejected_px;
  std::vector<TimedChi2> fiducial_used, fiducial_rejected;  ///< per image with a board pose
  std::vector<TimedChi2> kinematic;  ///< per image used: its instant's kinematic chi-square
  /// Images not used, outliers first, at most kMaxRejectedRows (the counts by
  /// reason are in result.images_skipped).
  std::vector<ReportRejection> rejected;
  std::vector<ReportOverlay> overlays;
  static constexpr std::size_t kMaxRejectedRows = 30;
};

/// A link of the robot at the URDF's zero pose (every joint at 0), in the
/// base frame: the rig views draw the kinematic tree as a line from each
/// link's origin to its parent's.
struct ReportLink {
  std::string name;
  Vec3 origin_base = Vec3::Zero();
  int parent = -1;  ///< index in ReportData::links; -1 for the root
};

/// The board at one instant of the final solve(s).
struct ReportBoard {
  Vec3 centre_base;  ///< the board's centre in the base frame
  int camera = -1;   ///< the one camera that saw it; -1 when several did
};

/// One solve: how it converged.
struct ReportSolve {
  std::string label;  ///< e.g. "robust (cam0, cam1)", "final (cam0, cam1)"
  double initial_cost = 0.0, final_cost = 0.0;
  int iterations = 0;
  std::string termination;    ///< the optimizer's message, or its termination in words
  std::string linear_solver;
  std::vector<int> iteration;  ///< the iterations reported, as the optimizer numbered them
  std::vector<double> cost;    ///< the cost after each of them
};

/// One quantity --estimate added, for the results' second table.
struct ReportEstimate {
  std::string group;  ///< "time offset", "joint offset", "intrinsics"
  std::string name;   ///< which: a camera, a joint, "fx", ...
  std::string value;  ///< with its unit
  std::string sigma;  ///< 1-sigma with its unit
  std::string note;   ///< e.g. why a quantity is not observed, and what that means
};

/// A camera's time offset swept around its estimate: the reprojection RMS of
/// its corners through kinematics + calibration at each offset.
struct ReportTimeOffsetSweep {
  std::string camera;
  std::vector<double> delta_ms, rms_px;
  double estimate_ms = 0.0, sigma_ms = 0.0;
};

struct ReportData {
  /// The stamp, as calibration.yaml's info block has it (docs/outputs.md):
  /// which fgcal wrote the result, when, from which rig.yaml.
  std::string fgcal_version;  ///< e.g. "fgcal 0.1.0 (git 5e14d11)"
  std::string date_utc;       ///< e.g. "2026-03-01T12:34:56Z"
  std::string rig;            ///< rig.yaml's path
  std::string dataset;  ///< the folder (images are shown relative to it) or the bag
  bool from_bag = false;
  std::string method;   ///< "pnp" or "corners" (--method)
  std::string solve;    ///< calibration.yaml's info `solve`: "F1 (each camera alone)" or "F2 (cameras jointly)"
  /// The gate of an image's fiducial chi-square (6 dof) drawn over the
  /// residuals: images above it were rejected (calibration_problem.hpp).
  double fiducial_gate = 0.0;
  std::string base_link, marker_link;
  int instants = 0;
  std::size_t images = 0;       ///< images read, every camera
  std::size_t images_used = 0;
  /// The result's verdict and findings (quality.hpp): the page opens with them.
  Quality quality;
  std::vector<std::string> warnings;  ///< shown apart when not already a finding's message
  /// Damaged image messages (or files) that were skipped: which (topic and
  /// stamp) and why, every camera, in input order.
  std::vector<ReportRejection> damaged;
  std::string summary;  ///< as printed
  std::vector<ReportCamera> cameras;
  MountResult mount;
  std::optional<PoseError> mount_error;
  bool has_truth = false;
  std::string ground_truth_path;
  std::vector<ReportBoard> boards;
  /// Every link of the URDF, parents first; empty when the robot is unknown.
  std::vector<ReportLink> links;
  std::vector<ReportSolve> solves;  ///< in the order they ran; the last is the final one
  /// What --estimate added (time offsets, joint offsets, intrinsics) with its
  /// 1-sigma; the camera poses and the mount are in `cameras` and `mount`.
  std::vector<ReportEstimate> estimates;
  std::vector<ReportTimeOffsetSweep> time_offset_sweeps;  ///< one per camera whose time offset was estimated
};

struct ReportOptions {
  /// Called when every file is in the temporary folder, just before it is
  /// renamed into place (tests inject a failure here).
  std::function<void(const std::string& temporary_folder)> before_commit;
  /// Loads the images the overlays are drawn on, all in one call (keys:
  /// ReportOverlay::image_index); an image it leaves out costs its picture
  /// only. When unset, each ReportOverlay::image is read as a file. A bag's
  /// images are messages, not files: calibrate passes a loader that reads
  /// them from the bag in one pass.
  std::function<std::map<std::size_t, cv::Mat>(const std::vector<std::size_t>& images)> load_images;
};

/// Throws InputError when `dir` cannot hold a report: its parent folder is
/// missing, it is a file, or it is a folder that is not an earlier fgcal
/// report (never replaced). calibrate checks this before any work.
void checkReportFolder(const std::string& dir);

/// Writes the report into folder `dir` (index.html, images/) and returns the
/// path of index.html. Atomic: everything is written into a temporary folder
/// beside `dir`, then renamed into place; on any error the temporary folder
/// is removed, an earlier report in `dir` is left as it was, and the error is
/// rethrown. An existing `dir` is replaced only when it is empty or an earlier
/// fgcal report; anything else throws InputError.
std::string writeReport(const ReportData& data, const std::string& dir, const ReportOptions& options = {});

/// The HTML page alone (image files are named, not written): for tests.
std::string formatReportHtml(const ReportData& data);

/// The `id` of every <svg> plot formatReportHtml emits for `data`.
std::vector<std::string> reportPlotIds(const ReportData& data);

}  // namespace fgcal::apps
