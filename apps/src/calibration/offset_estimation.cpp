// Offset estimates into calibration.yaml and the summary (offset_estimation.hpp).
#include "fgcal/apps/offset_estimation.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace fgcal::apps {

void addOffsetResults(const OffsetEstimates& est, CalibrationOutput* out) {
  for (const TimeOffsetEstimate& t : est.time_offsets)
    for (CameraResult& c : out->cameras)
      if (c.name == t.camera) {
        c.time_offset_ms = t.observed ? t.offset_s * 1e3 : 0.0;
        c.time_offset_sigma_ms = t.observed ? t.sigma_s * 1e3 : kTimeOffsetPriorSigmaS * 1e3;
      }
  out->joint_offsets.clear();
  for (const JointOffsetEstimate& j : est.joint_offsets)
    out->joint_offsets.push_back(
        {j.joint, j.observed ? j.offset_rad : 0.0, j.observed ? j.sigma_rad : j.prior_sigma_rad, j.observed});
}

std::string formatOffsetSummary(const OffsetEstimates& est) {
  std::ostringstream s;
  s << std::fixed;
  for (const TimeOffsetEstimate& t : est.time_offsets) {
    s << "  time offset " << t.camera << ": ";
    if (t.observed)
      s << std::showpos << std::setprecision(3) << t.offset_s * 1e3 << std::noshowpos << " ms, 1-sigma "
        << t.sigma_s * 1e3 << " ms (an image stamped t was exposed at t + offset)\n";
    else
      s << "not observed (see the warning)\n";
  }
  for (const JointOffsetEstimate& j : est.joint_offsets) {
    s << "  joint offset " << j.joint << ": ";
    if (j.observed) {
      s << std::showpos << std::setprecision(3) << j.offset_rad * 1e3 << std::noshowpos << " mrad, 1-sigma "
        << j.sigma_rad * 1e3 << " mrad\n";
    } else {
      s << "not observed (prior 0 +- " << std::setprecision(1) << j.prior_sigma_rad * 1e3
        << " mrad); a true offset moves, per mrad:";
      for (std::size_t a = 0; a < j.absorbed.size(); ++a)
        s << (a ? "; " : " ") << j.absorbed[a].estimate << " " << std::setprecision(3) << j.absorbed[a].mm_per_mrad
          << " mm, " << std::setprecision(4) << j.absorbed[a].deg_per_mrad << " deg";
      s << "\n";
    }
  }
  return s.str();
}

}  // namespace fgcal::apps
