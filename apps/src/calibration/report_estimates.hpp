// The report's table of what was estimated beyond the poses (the results
// table has those) with its 1-sigma, and the sweeps of the estimated time
// offsets (fgcal/apps/report.hpp), from a run.
#pragma once

#include <vector>

#include "commands/calibrate/calibrate_stages.hpp"
#include "fgcal/apps/report.hpp"

namespace fgcal::apps::stages {

/// Time offsets, joint offsets and intrinsics, in that order, as
/// calibration.yaml holds them; notes on what is not observed. The camera
/// poses and the mount are not repeated: the results table shows them.
std::vector<ReportEstimate> estimateRows(const CalibrateResult& res);

/// For each camera whose time offset was estimated, the reprojection RMS of
/// its used images' corners against the offset swept around its estimate.
std::vector<ReportTimeOffsetSweep> timeOffsetSweeps(const RunView& run);

}  // namespace fgcal::apps::stages
