#include <algorithm>
#include "calibration/report_estimates.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "calibration/offset_graph.hpp"

namespace fgcal::apps::stages {

namespace {

std::string fixed(double v, int precision, bool sign = false) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << (sign ? std::showpos : std::noshowpos) << v;
  return s.str();
}

std::string absorbedNote(const JointOffsetEstimate& j) {
  std::ostringstream s;
  s << "not observed (the data's information " << std::setprecision(3) << j.eigenvalue
    << " mrad^-2): the prior's value, not a measurement; a true offset of this joint moves, per mrad:";
  for (const Absorption& a : j.absorbed)
    s << " " << a.estimate << " " << fixed(a.mm_per_mrad, 3) << " mm, " << fixed(a.deg_per_mrad, 4) << " deg;";
  std::string out = s.str();
  out.back() = '.';
  return out;
}

}  // namespace

std::vector<ReportEstimate> estimateRows(const CalibrateResult& res) {
  const CalibrationOutput& out = res.output;
  std::vector<ReportEstimate> rows;
  for (const CameraResult& c : out.cameras) {
    if (!c.time_offset_ms) continue;
    ReportEstimate e{"time offset", c.name, fixed(*c.time_offset_ms, 3, true) + " ms",
                     fixed(c.time_offset_sigma_ms.value_or(0.0), 3) + " ms",
                     "an image stamped t was exposed at t + offset"};
    for (const TimeOffsetEstimate& t : res.solution.offsets.time_offsets)
      if (t.camera == c.name && !t.observed)
        e.note = "not observed (the data's information " + fixed(t.information, 4) +
                 " ms^-2): the prior's value, not a measurement";
    rows.push_back(e);
  }
  for (const CameraResult& c : out.cameras) {
    if (!c.readout_ms) continue;
    ReportEstimate e{"rolling-shutter readout", c.name, fixed(*c.readout_ms, 3) + " ms",
                     c.readout_sigma_ms ? fixed(*c.readout_sigma_ms, 3) + " ms" : "held",
                     "row v of an image stamped t was exposed at t + offset + v / (rows - 1) x readout"};
    if (!c.readout_sigma_ms) e.note = "rig.yaml's readout_ms, held (not estimated)";
    else if (!c.readout_observed) e.note = "not observed by the data: the prior's value, not a measurement";
    rows.push_back(e);
  }
  for (std::size_t k = 0; k < out.joint_offsets.size(); ++k) {
    const JointOffsetResult& j = out.joint_offsets[k];
    ReportEstimate e{"joint offset", j.joint, fixed(j.offset_rad * 1e3, 3, true) + " mrad",
                     fixed(j.sigma_rad * 1e3, 3) + " mrad", "the joint stood at its reading + offset"};
    if (!j.observed && k < res.solution.offsets.joint_offsets.size())
      e.note = absorbedNote(res.solution.offsets.joint_offsets[k]);
    rows.push_back(e);
  }
  for (std::size_t k = 0; k < out.backlash.size(); ++k) {
    const JointOffsetResult& b = out.backlash[k];
    ReportEstimate e{"backlash", b.joint, fixed(b.offset_rad * 1e3, 3) + " mrad", fixed(b.sigma_rad * 1e3, 3) + " mrad",
                     "the joint lags its reading by half of it against its motion"};
    const OffsetEstimates& est = res.solution.offsets;
    if (std::find(est.backlash_not_reversing.begin(), est.backlash_not_reversing.end(), b.joint) !=
        est.backlash_not_reversing.end())
      e.note = "not estimated: the joint never moves both ways in the joint log";
    else if (!b.observed && k < est.backlash.size())
      e.note = absorbedNote(est.backlash[k]);
    rows.push_back(e);
  }
  static const char* kNames[] = {"fx", "fy", "cx", "cy"};
  for (const CameraResult& c : out.cameras) {
    for (std::size_t i = 0; i < c.intrinsics.size() && i < 4 && i < c.intrinsics_sigma.size(); ++i)
      rows.push_back({"intrinsics", c.name + " " + kNames[i], fixed(c.intrinsics[i], 3) + " px",
                      fixed(c.intrinsics_sigma[i], 3) + " px", ""});
    for (std::size_t i = 0; i < c.distortion_coeffs.size() && i < c.distortion_coeffs_sigma.size(); ++i)
      rows.push_back({"intrinsics", c.name + " distortion_coeffs[" + std::to_string(i) + "]",
                      fixed(c.distortion_coeffs[i], 6), fixed(c.distortion_coeffs_sigma[i], 6), ""});
  }
  return rows;
}

std::vector<ReportTimeOffsetSweep> timeOffsetSweeps(const RunView& run) {
  std::vector<ReportTimeOffsetSweep> out;
  const CalibrationProblemInput& p = run.built.problem;
  if (!p.offsets.time_offsets) return out;
  for (std::size_t c = 0; c < p.camera_names.size(); ++c) {
    std::vector<std::size_t> observations;
    for (std::size_t k = 0; k < p.observations.size(); ++k)
      if (p.observations[k].camera == static_cast<int>(c) && run.res.solution.used[k]) observations.push_back(k);
    if (auto sw = offsets::sweepTimeOffset(p, run.res.solution, c, observations, run.models[c])) out.push_back(*sw);
  }
  return out;
}

}  // namespace fgcal::apps::stages
