// `fgcal calibrate --method corners`: the solve stage (corner_calibration_stage.hpp).
#include "commands/calibrate/corner_calibration_stage.hpp"

#include <cmath>

#include "fgcal/apps/errors.hpp"

namespace fgcal::apps::stages {

namespace {

/// Every observation's corners, from the problem's detected corners.
std::vector<ImageCorners> observationCorners(const CalibrationProblemInput& problem) {
  std::vector<ImageCorners> out(problem.observations.size());
  for (std::size_t k = 0; k < out.size(); ++k) {
    const BoardObservation& o = problem.observations[k];
    out[k].pixels.reserve(o.corners_count);
    out[k].board_points.reserve(o.corners_count);
    problem.corners.appendCorrespondences(o.corners_begin, o.corners_count, out[k].board_points, out[k].pixels);
  }
  return out;
}

}  // namespace

CalibrationSolution solveCornersAndGate(Inputs& in, const CalibrateOptions& opt, BuiltProblem& built,
                                        std::vector<vision::CameraModel>& models, CornerSolution* corners,
                                        std::vector<std::string>* warnings) {
  CalibrationSolution pnp;
  try {
    pnp = solveAndGate(in, opt, built);
  } catch (const DataError& e) {
    // Intrinsics far enough off make the images' poses disagree beyond the
    // PnP gate; the corners, with the intrinsics estimated, need no PnP start.
    warnings->push_back(std::string("the PnP graph, the corner graph's start, failed (") + e.what() +
                        "); the corner graph started from each camera's detections and the kinematics");
  }
  for (ImageRecord& r : in.images)  // the corner graph's gates judge every image again
    if (r.status == ImageStatus::Outlier) {
      r.status = ImageStatus::Used;
      r.detail = Interned::kNone;
    }
  const CornerProblemInput input = cornerInput(in, built, models, opt.estimate.intrinsics, warnings);
  *corners = solveCornerCalibration(built.problem, input, pnp);
  CalibrationSolution& sol = corners->solution;
  for (const RejectedObservation& rj : sol.rejected) {
    ImageRecord& r = in.images[built.obs_image[rj.observation]];
    r.status = ImageStatus::Outlier;
    r.detail = in.details.add(rj.reason);
  }
  // The report shows every solve: the PnP start first.
  for (std::size_t s = 0; s < pnp.solves.size(); ++s) {
    sol.solves.insert(sol.solves.begin() + static_cast<std::ptrdiff_t>(s), pnp.solves[s]);
    sol.solve_labels.insert(sol.solve_labels.begin() + static_cast<std::ptrdiff_t>(s),
                            "PnP start: " + pnp.solve_labels[s]);
  }
  if (opt.estimate.intrinsics)
    for (std::size_t c = 0; c < models.size(); ++c) models[c] = models[c].withIntrinsics(corners->intrinsics[c].value);
  return sol;
}

CornerProblemInput cornerInput(const Inputs& in, const BuiltProblem& built,
                               const std::vector<vision::CameraModel>& models, bool estimate_intrinsics,
                               std::vector<std::string>* warnings) {
  CornerProblemInput input;
  input.cameras = cornerCameras(in.rig, models, estimate_intrinsics, warnings);
  input.corners = observationCorners(built.problem);
  input.estimate_intrinsics = estimate_intrinsics;
  return input;
}

void addEstimatedIntrinsics(const CornerSolution& corners, CalibrationOutput& out) {
  for (std::size_t c = 0; c < corners.intrinsics.size() && c < out.cameras.size(); ++c) {
    const IntrinsicsEstimate& e = corners.intrinsics[c];
    CameraResult& cr = out.cameras[c];
    cr.intrinsics.clear();
    cr.intrinsics_sigma.clear();
    cr.distortion_coeffs.clear();
    cr.distortion_coeffs_sigma.clear();
    for (Eigen::Index i = 0; i < e.value.size(); ++i) {
      const double sigma = std::sqrt(std::max(0.0, e.covariance(i, i)));
      (i < 4 ? cr.intrinsics : cr.distortion_coeffs).push_back(e.value[i]);
      (i < 4 ? cr.intrinsics_sigma : cr.distortion_coeffs_sigma).push_back(sigma);
    }
  }
}

}  // namespace fgcal::apps::stages
