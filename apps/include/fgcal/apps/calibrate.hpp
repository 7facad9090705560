// `fgcal calibrate` as a library call: a dataset folder in, calibration.yaml,
// a URDF snippet and a human summary out. Reads rig.yaml, joints.csv and the
// images; interpolates the joints at each image stamp; detects the board in
// every image on all cores; builds and solves the factor graph
// (solveCalibration); writes the results atomically.
#pragma once

#include <iosfwd>
#include <map>
#include <string>
#include <vector>

#include "fgcal/apps/calibration_problem.hpp"
#include "fgcal/apps/results_io.hpp"

namespace fgcal::apps {

struct CalibrateOptions {
  std::string dataset;
  std::string output = "calibration.yaml";  // the URDF snippet goes beside it (.urdf.xml)
  std::vector<std::string> cameras;         // empty: every camera of rig.yaml
  bool single_camera = false;               // F1
  bool fix_mount = false;
  int threads = 0;                          // 0: every core
  bool write_files = true;                  // false: compute and summarize only
};

/// What happened to one image.
struct ImageOutcome {
  std::string camera;
  std::string path;
  std::int64_t stamp_ns = 0;
  std::string skipped;  // empty when used; else the reason (a key of CameraResult::images_skipped)
  std::string detail;   // the message behind it
  double rms_px = 0.0;  // final reprojection RMS (kinematics + calibration) when used
};

struct CalibrateResult {
  CalibrationOutput output;
  CalibrationSolution solution;
  std::vector<ImageOutcome> images;
  std::vector<std::string> warnings;
  std::string summary;  // the human summary that was printed
  std::string yaml_path, urdf_path;
  double detection_seconds = 0.0, solve_seconds = 0.0, total_seconds = 0.0;
};

/// Runs the calibration; progress and the summary go to `log`. Throws
/// InputError (exit 2) for bad input and DataError (exit 1) when the data
/// cannot support a calibration; nothing is written then.
CalibrateResult runCalibrate(const CalibrateOptions& options, std::ostream& log);

}  // namespace fgcal::apps
