// Pieces of calibration.yaml's reader (results_io.cpp) that the reader of
// its estimated quantities (estimated_quantities.cpp, for `fgcal evaluate`)
// shares, so that both read a block the same way.
#pragma once

#include <vector>

#include "fgcal/apps/results_io.hpp"
#include "io/yaml_read.hpp"

namespace fgcal::apps::detail {

/// joint_offsets: (--estimate joint-offsets) or backlash: (--estimate
/// backlash) when present: `field` maps joint -> {`value`, sigma_rad,
/// observed}; empty when the file has no `field`. InputError naming the
/// file and key otherwise.
std::vector<JointOffsetResult> readJointVector(const YNode& root, const char* field, const char* value,
                                               const char* what);

}  // namespace fgcal::apps::detail
