// The report's table of every estimated quantity with its 1-sigma, and the
// sweeps of the estimated time offsets (fgcal/apps/report.hpp), from a run.
#pragma once

#include <vector>

#include "calibrate_stages.hpp"
#include "fgcal/apps/report.hpp"

namespace fgcal::apps::stages {

/// Camera poses, the mount, time offsets, joint offsets and intrinsics, in
/// that order, as calibration.yaml holds them; notes on what is not observed.
std::vector<ReportEstimate> estimateRows(const CalibrateResult& res);

/// For each camera whose time offset was estimated, the reprojection RMS of
/// its used images' corners against the offset swept around its estimate.
std::vector<ReportTimeOffsetSweep> timeOffsetSweeps(const RunView& run);

}  // namespace fgcal::apps::stages
