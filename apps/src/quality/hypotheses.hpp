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
#include <string>
#include <vector>

#include "quality/assess.hpp"

namespace fgcal::apps::quality {

/// What the family tests flagged.
struct Diagnosis {
  std::vector<std::size_t> flagged_cameras;  ///< whose images' family is beyond its tail
  bool kinematics_flagged = false;
};

/// The first of q's first `earlier` findings at check level or above that
/// names an input as the cause of what the data show (an alternative, a
/// delay, an offset, the mount, ...), other than the inputs in `fields`: a
/// finding on the same input corroborates (the camera's scale its
/// intrinsics). Empty when there is none.
std::string namedCause(const Quality& q, std::size_t earlier, const std::vector<std::string>& fields);

/// Adds a finding of a test that assumes the rest of the model holds: as a
/// note when one of the `earlier` findings (those made before the test ran)
/// named another input (namedCause), since it may follow from that one (a
/// mount left at the identity pulls the solution, and the leg's lengths
/// then seem off too); else as made.
void addAssumingTheRest(Quality& q, Finding f, std::size_t earlier);

/// Adds the diagnoses' findings to q.
void diagnose(const Context& ctx, const Families& fam, const Diagnosis& dx, Quality& q);

/// The factor by which each camera's covariance is to be multiplied so that
/// it covers what the model did not explain: the largest variance factor
/// (chi-square / dof) of the families flagged for it, 1 when none is.
std::vector<double> covarianceInflation(const Families& fam, const Diagnosis& dx, std::size_t cameras);

}  // namespace fgcal::apps::quality
