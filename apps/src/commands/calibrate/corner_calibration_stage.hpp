// The solve stage of `fgcal calibrate --method corners` (calibrate_stages.hpp
// has the others): the PnP graph for the start, then the corner graph on
// every detected corner of the images with a board pose; its outliers marked
// on the images, its estimated intrinsics into the cameras' models (for the
// reprojection and the report) and into calibration.yaml.
#pragma once

#include <string>
#include <vector>

#include "commands/calibrate/calibrate_stages.hpp"
#include "fgcal/apps/corner_calibration.hpp"

namespace fgcal::apps::stages {

/// solveAndGate's settings and PnP solve as the start (when the PnP graph
/// fails, a warning, and the corner graph starts from the detections), then
/// solveCornerCalibration. The images the PnP gate marked are judged again
/// by the corner graph's gates. With estimated intrinsics, `models` take
/// them. Warnings go to `warnings`; the corner graph's extras to `corners`.
CalibrationSolution solveCornersAndGate(Inputs& in, const CalibrateOptions& opt, BuiltProblem& built,
                                        std::vector<vision::CameraModel>& models, CornerSolution* corners,
                                        std::vector<std::string>* warnings);

/// The corner graph's input for `built`: the cameras from rig.yaml and
/// `models` (with their intrinsics priors when `estimate_intrinsics`; the
/// defaults' warnings into `warnings`) and every observation's corners.
CornerProblemInput cornerInput(const Inputs& in, const BuiltProblem& built,
                               const std::vector<vision::CameraModel>& models, bool estimate_intrinsics,
                               std::vector<std::string>* warnings);

/// calibration.yaml's intrinsics of every camera from the corner solution
/// (nothing when they were not estimated).
void addEstimatedIntrinsics(const CornerSolution& corners, CalibrationOutput& out);

}  // namespace fgcal::apps::stages
