// Offset estimates into calibration.yaml and the summary (offset_estimation.hpp).
#include "fgcal/apps/offset_estimation.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace fgcal::apps {

// A joint standing still, its readings' noise turning the fit to and fro,
// crosses no play: only stretches longer than the noise count.
VecX backlashSpeedScales(const JointLogTrajectory& trajectory, const JointLog& log, const VecX& encoder_sigma) {
  const Eigen::Index n = trajectory.numJoints();
  std::vector<VecX> q(log.stamps_ns.size()), v(log.stamps_ns.size());
  VecX sq = VecX::Zero(n);
  for (std::size_t i = 0; i < log.stamps_ns.size(); ++i) {
    trajectory.evaluate(trajectory.seconds(log.stamps_ns[i]), &q[i], &v[i]);
    sq += v[i].cwiseAbs2();
  }
  VecX scale = kBacklashSpeedFraction * (sq / std::max<double>(1.0, static_cast<double>(v.size()))).cwiseSqrt();
  for (Eigen::Index k = 0; k < n; ++k) {
    const double travel = kBacklashReversalTravel * encoder_sigma[k];
    bool forward = false, backward = false;
    std::size_t start = 0;
    for (std::size_t i = 1; i <= v.size(); ++i) {
      if (i < v.size() && (v[i][k] > 0.0) == (v[start][k] > 0.0)) continue;
      if (std::abs(q[i - 1][k] - q[start][k]) > travel) (v[start][k] > 0.0 ? forward : backward) = true;
      start = i;
    }
    if (!forward || !backward) scale[k] = 0.0;
  }
  return scale;
}

Eigen::VectorXd backlashLag(const JointLogTrajectory& trajectory, const Eigen::VectorXd& scale, std::int64_t stamp_ns) {
  VecX q, q_dot;
  trajectory.evaluate(trajectory.seconds(stamp_ns), &q, &q_dot);
  Eigen::VectorXd lag = Eigen::VectorXd::Zero(scale.size());
  for (Eigen::Index k = 0; k < lag.size(); ++k)
    if (scale[k] > 0.0) lag[k] = -0.5 * std::tanh(q_dot[k] / scale[k]);
  return lag;
}

Eigen::VectorXd OffsetModel::backlashLag(std::int64_t stamp_ns) const {
  if (!backlash || !trajectory) return Eigen::VectorXd::Zero(backlash_speed_scale.size());
  return apps::backlashLag(*trajectory, backlash_speed_scale, stamp_ns);
}

double OffsetModel::rowFraction(std::size_t camera, double v) const {
  if (camera >= rows.size() || rows[camera] < 2) return 0.0;
  return std::clamp(v / static_cast<double>(rows[camera] - 1), 0.0, 1.0);
}

void addOffsetResults(const OffsetEstimates& est, CalibrationOutput* out) {
  for (const TimeOffsetEstimate& t : est.time_offsets)
    for (CameraResult& c : out->cameras)
      if (c.name == t.camera) {
        c.time_offset_ms = t.observed ? t.offset_s * 1e3 : 0.0;
        c.time_offset_sigma_ms = t.observed ? t.sigma_s * 1e3 : kTimeOffsetPriorSigmaS * 1e3;
      }
  for (const ReadoutEstimate& r : est.readouts)
    for (CameraResult& c : out->cameras)
      if (c.name == r.camera) {
        c.readout_ms = (r.observed ? r.readout_s : r.prior_s) * 1e3;
        c.readout_sigma_ms = (r.observed ? r.sigma_s : kReadoutPriorSigmaS) * 1e3;
        c.readout_observed = r.observed;
      }
  out->joint_offsets.clear();
  for (const JointOffsetEstimate& j : est.joint_offsets)
    out->joint_offsets.push_back(
        {j.joint, j.observed ? j.offset_rad : 0.0, j.observed ? j.sigma_rad : j.prior_sigma_rad, j.observed});
  out->backlash.clear();
  for (const JointOffsetEstimate& j : est.backlash)
    out->backlash.push_back(
        {j.joint, j.observed ? j.offset_rad : 0.0, j.observed ? j.sigma_rad : j.prior_sigma_rad, j.observed});
  out->kinematic_origins.clear();
  for (const OriginEstimate& o : est.origins) out->kinematic_origins.push_back({o.joint, o.correction, o.sigma, o.observed});
  for (const UrdfShare& u : est.urdf_shares)
    for (CameraResult& c : out->cameras)
      if (c.name == u.camera) {
        const Vec6 full = sigmaMmDeg(c.T_base_cam, c.covariance);
        const Vec6 exact = sigmaMmDeg(c.T_base_cam, u.covariance_urdf_exact);
        c.sigma_from_urdf_mm_deg = (full.cwiseAbs2() - exact.cwiseAbs2()).cwiseMax(0.0).cwiseSqrt();
      }
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
  for (const ReadoutEstimate& r : est.readouts) {
    s << "  rolling-shutter readout " << r.camera << ": ";
    if (r.observed)
      s << std::setprecision(3) << r.readout_s * 1e3 << " ms, 1-sigma " << r.sigma_s * 1e3
        << " ms (row v exposed at t + offset + v / (rows - 1) x readout)\n";
    else
      s << "not observed (see the warning)\n";
  }
  if (!est.origins.empty()) {
    s << "  URDF tolerance (robot.kinematic_sigma): the data observe " << est.origin_directions_observed << " of "
      << 6 * est.origins.size() << " origin-correction directions; the rest stay in the cameras' covariance\n";
    for (const OriginEstimate& o : est.origins) {
      s << "  origin " << o.joint << ": rotation [" << std::setprecision(2);
      for (int k = 0; k < 3; ++k) s << (k ? " " : "") << o.correction[k] * 1e3 << (o.observed[static_cast<std::size_t>(k)] ? "" : "*");
      s << "] mrad, translation [";
      for (int k = 3; k < 6; ++k) s << (k > 3 ? " " : "") << o.correction[k] * 1e3 << (o.observed[static_cast<std::size_t>(k)] ? "" : "*");
      s << "] mm (* rests on the prior)\n";
    }
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
  for (const JointOffsetEstimate& b : est.backlash) {
    s << "  backlash " << b.joint << ": ";
    if (b.observed)
      s << std::setprecision(3) << b.offset_rad * 1e3 << " mrad, 1-sigma " << b.sigma_rad * 1e3
        << " mrad (the joint lags its encoder by half of it against the motion)\n";
    else
      s << "not observed (see the warning)\n";
  }
  return s.str();
}

}  // namespace fgcal::apps
