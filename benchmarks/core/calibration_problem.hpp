// A seeded generator of the calibration-shaped problem: M cameras
// on a 1 m robot body, N board poses in the workspace in front of them, a
// prior on every board pose (kinematics) and a relative-pose measurement for
// every (camera, board pose) pair seen (PnP). One CalibrationProblem feeds
// both fgcal and Ceres, so both start from the same point and see the same
// measurements and covariances.
#pragma once

#include <cstdint>
#include <vector>

#include "fgcal/core/factor_graph.hpp"
#include "fgcal/core/se3.hpp"
#include "fgcal/core/values.hpp"

namespace fgcal::bench {

struct CalibrationProblemOptions {
  int cameras = 2;
  int frames = 1000;
  double see_probability = 0.6;  // each camera sees each board pose with it; at least one camera always does
  std::uint64_t seed = 1;
};

/// A measured pose with the upper-triangular square root W of its information
/// (W^T W = Sigma^-1), in the [w v] tangent of the right perturbation.
struct PoseMeasurement {
  SE3 measured;
  Mat6 sqrt_information;
};

struct Observation {
  int camera;
  int frame;
  PoseMeasurement z;  // T_cam_marker
};

struct CalibrationProblem {
  int cameras = 0, frames = 0;
  std::vector<SE3> true_cameras, true_boards;        // T_base_cam, T_base_marker
  std::vector<SE3> initial_cameras, initial_boards;  // the start of every solver
  std::vector<PoseMeasurement> board_priors;         // one per frame, on T_base_marker
  std::vector<Observation> observations;             // sorted by frame

  std::size_t numFactors() const { return board_priors.size() + observations.size(); }
};

CalibrationProblem makeCalibrationProblem(const CalibrationProblemOptions& options);

inline Key cameraKey(int i) { return key('c', static_cast<std::uint64_t>(i)); }
inline Key boardKey(int j) { return key('b', static_cast<std::uint64_t>(j)); }

/// The fgcal graph (PriorFactorSE3 per board, RelativePoseFactor per
/// observation, full-covariance noise models) and the initial values
/// (cameras first, then boards).
void buildFgcalProblem(const CalibrationProblem& problem, FactorGraph& graph, Values& initial);

}  // namespace fgcal::bench
