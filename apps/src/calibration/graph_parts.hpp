// Pieces of the calibration graphs: what an instant is, the camera sets, the
// kinematic noise, the mount prior, the chi-square of a factor and the
// observability warnings, shared by the PnP graph (calibration_problem.cpp)
// and the corner graph (corner_calibration.cpp).
#pragma once

#include <cstddef>
#include <vector>

#include "fgcal/apps/calibration_problem.hpp"
#include "fgcal/core/factor.hpp"

namespace fgcal::apps::detail {

/// Groups of observation indices that share one board pose: sorted by stamp,
/// within the tolerance of the group's first stamp, one image per camera
/// (`share` false: every observation alone, F1).
std::vector<std::vector<std::size_t>> groupInstants(const std::vector<BoardObservation>& obs,
                                                    const std::vector<std::size_t>& selected, double tolerance_ns,
                                                    bool share);

/// The noise of the kinematic factor of an instant whose first image is `o`:
/// encoder noise through the leg Jacobian, at the marker of the mount prior,
/// plus the input's floors.
NoiseModel::Ptr kinematicNoise(const BoardObservation& o, const CalibrationProblemInput& in);
/// That noise's covariance, for those who need the matrix, not the model.
Mat6 kinematicCovariance(const BoardObservation& o, const CalibrationProblemInput& in);

/// The mount prior's noise: sigma_rad on rotation, sigma_m on translation.
NoiseModel::Ptr mountPriorNoise(double sigma_m, double sigma_rad);

/// The sets of cameras solved together: all of them (F2), or each alone (F1).
std::vector<std::vector<std::size_t>> cameraSets(const CalibrationProblemInput& in);

/// |W r|^2 of a factor, without its robust kernel: what the gates judge.
double chiSquare(const Factor& f, const Values& v);

/// Each camera's start: its guess (camera_guesses), or from its own
/// detections: every detection proposes T_base_cam = T_base_link * mount *
/// T_cam_marker^-1, and the proposal most others agree with, refined by the
/// mean of those that agree, is taken. DataError for a camera with fewer
/// than 3 detections.
std::vector<SE3> initialCameraPoses(const CalibrationProblemInput& in);

/// The cross-covariances of the cameras `cams` of one solve from the joint
/// covariance of their poses (6 x 6 blocks in `cams` order, first), into
/// sol.camera_cross_covariances.
void addCrossCovariances(const std::vector<std::size_t>& cams, const MatX& joint, CalibrationSolution& sol);

/// A finding of the solve into sol.findings, its message into sol.warnings.
void addFinding(CalibrationSolution& sol, std::string check, Severity severity, std::vector<std::string> fields,
                std::string message);

/// The findings on the estimated offsets: each warning of sol.offsets as an
/// offset_observability note, and joints whose backlash the log cannot show
/// (they never move both ways) as a backlash_not_reversing check naming them.
void addOffsetFindings(const CalibrationProblemInput& problem, CalibrationSolution& sol);

/// The findings on the solve (few_instants, convergence) of a camera set's
/// final solve of `instants` instants; `cams` names the set for F1.
void addSolveFindings(CalibrationSolution& sol, std::size_t instants, bool single_camera, const std::string& cams,
                      const OptimizerResult& r);

/// The plain-words warnings on what the data observe, into sol.warnings: the
/// mount (how much the board turned; sets mount_information_eigenvalues),
/// cameras without a shared instant, the outlier rate. Reads sol's
/// mount_covariance, used, rejected and instant_estimates.
/// Per camera: its images in the problem (`total`) and those the gate
/// rejected (`rejected`).
struct GatedImages {
  std::vector<std::size_t> total, rejected;
};
GatedImages gatedImages(const CalibrationProblemInput& in, const CalibrationSolution& sol);

void addObservabilityWarnings(const CalibrationProblemInput& in, bool mount_fixed, CalibrationSolution& sol);

}  // namespace fgcal::apps::detail
