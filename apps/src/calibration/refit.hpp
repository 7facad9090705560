// The PnP graph of a finished solve rebuilt over changed measurements, for
// the quality checks' alternative hypotheses (src/quality/hypotheses.cpp):
// "had the board been this size", "had this joint's sign been the other".
#pragma once

#include "fgcal/apps/calibration_problem.hpp"

namespace fgcal::apps::detail {

/// The final graph of `sol` (its cameras, its observations used, plain least
/// squares, no gate) over `in`'s measurements, solved from sol's camera
/// estimates: every factor's |W r|^2 at its optimum, the mount prior's
/// included. `in` must have sol's observations, in the same order; their
/// poses, covariances and kinematics may differ. DataError as solveCalibration.
double refitChiSquare(const CalibrationProblemInput& in, const CalibrationSolution& sol);

}  // namespace fgcal::apps::detail
