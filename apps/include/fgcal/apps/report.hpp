// The calibration report: what a user looks at after calibrating to decide
// whether to trust the result. One self-contained HTML page (inline CSS and
// SVG plots drawn by our own helper, no JavaScript, no network resource) and
// PNG images beside it:
// - warnings in plain words (solveCalibration's and the run's);
// - the results table (pose, 1-sigma, images, reprojection RMS; errors and
//   NEES when the dataset has a ground_truth.yaml);
// - the rig from above and from the side: base frame, camera frustums at
//   their estimated poses, the board positions seen, coloured by camera;
// - the convergence of every solve (cost per iteration);
// - per camera: reprojection residuals (scatter, histogram), fiducial and
//   kinematic chi-square over time, the images rejected and why, and a few
//   images with detected (green) and predicted (red) corners drawn over them.
#pragma once

#include <cstddef>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "fgcal/apps/calibrate.hpp"

namespace fgcal::apps {

struct ReportOptions {
  /// Overlay images per camera: best, median and worst reprojection RMS
  /// (fewer when the camera used fewer images), plus its worst outlier.
  int images_per_camera = 3;
  /// Called when every file is in the temporary folder, just before it is
  /// renamed into place (tests inject a failure here).
  std::function<void(const std::string& temporary_folder)> before_commit;
  /// Loads the images the overlays are drawn on, all in one call (keys:
  /// indices into CalibrateResult::images); an image it leaves out costs its
  /// picture only. When unset, each ImageOutcome::path is read as a file. A
  /// bag's images are messages, not files: calibrate passes a loader that
  /// reads them from the bag in one pass.
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
std::string writeReport(const CalibrateResult& result, const std::string& dir, const ReportOptions& options = {});

/// The HTML page alone (image files are named, not written): for tests.
std::string formatReportHtml(const CalibrateResult& result, const ReportOptions& options = {});

/// The `id` of every <svg> plot formatReportHtml emits for `result`.
std::vector<std::string> reportPlotIds(const CalibrateResult& result);

}  // namespace fgcal::apps
