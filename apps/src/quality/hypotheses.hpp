// The diagnoses (docs/outputs.md, "quality"): for what the family tests
// flag, the alternatives that would explain it, each judged by the
// chi-square it removes against the chi-square distribution of what a
// correct input would remove by chance:
//   - inputs refitted (the PnP graph rebuilt over changed measurements and
//     solved again): the board's scale, a camera's depth scale (its focal
//     length), a joint's sign, two joints swapped;
//   - score tests on the residuals at the solution, no refit: a camera's
//     time offset (residuals along the board's velocity), joint zero offsets
//     (residuals along the leg's Jacobian), each camera's corners against
//     its own PnP poses (intrinsics, distortion, pixel_sigma);
//   - what no alternative explains: the family's variance factor, with the
//     sigma that would fit (encoder_sigma, pixel_sigma).
#pragma once

#include <cstddef>
#include <vector>

#include "quality/assess.hpp"

namespace fgcal::apps::quality {

/// What the family tests flagged.
struct Diagnosis {
  std::vector<std::size_t> flagged_cameras;  ///< whose images' family is beyond its tail
  bool kinematics_flagged = false;
};

/// Adds the diagnoses' findings to q.
void diagnose(const Context& ctx, const Families& fam, const Diagnosis& dx, Quality& q);

/// The factor by which each camera's covariance is to be multiplied so that
/// it covers what the model did not explain: the largest variance factor
/// (chi-square / dof) of the families flagged for it, 1 when none is.
std::vector<double> covarianceInflation(const Families& fam, const Diagnosis& dx, std::size_t cameras);

}  // namespace fgcal::apps::quality
