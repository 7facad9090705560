// Offset estimates into calibration.yaml and the summary (offset_estimation.hpp).
#include "fgcal/apps/offset_estimation.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace fgcal::apps {

std::shared_ptr<const MotorPath> motorPath(std::shared_ptr<const JointLogTrajectory> trajectory, const JointLog& log) {
  auto path = std::make_shared<MotorPath>();
  const auto samples = static_cast<Eigen::Index>(log.stamps_ns.size());
  path->q.resize(samples, trajectory->numJoints());
  path->v.resize(samples, trajectory->numJoints());
  path->t.reserve(log.stamps_ns.size());
  VecX q, v;
  for (Eigen::Index i = 0; i < samples; ++i) {
    path->t.push_back(trajectory->seconds(log.stamps_ns[static_cast<std::size_t>(i)]));
    trajectory->evaluate(path->t.back(), &q, &v);
    path->q.row(i) = q.transpose();
    path->v.row(i) = v.transpose();
  }
  path->trajectory = std::move(trajectory);
  return path;
}

// A joint standing still, its readings' noise turning the fit to and fro,
// crosses no play: only stretches longer than the noise count.
std::vector<bool> backlashReversing(const MotorPath& path, const VecX& encoder_sigma) {
  const Eigen::Index n = path.q.cols(), samples = path.q.rows();
  std::vector<bool> out(static_cast<std::size_t>(n), false);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double travel = kBacklashReversalTravel * encoder_sigma[k];
    bool forward = false, backward = false;
    Eigen::Index start = 0;
    for (Eigen::Index i = 1; i <= samples; ++i) {
      if (i < samples && (path.v(i, k) > 0.0) == (path.v(start, k) > 0.0)) continue;
      if (std::abs(path.q(i - 1, k) - path.q(start, k)) > travel) (path.v(start, k) > 0.0 ? forward : backward) = true;
      start = i;
    }
    out[static_cast<std::size_t>(k)] = forward && backward;
  }
  return out;
}

BacklashLag::BacklashLag(std::shared_ptr<const MotorPath> path, const VecX& play)
    : path_(std::move(path)), play_(play) {
  const Eigen::MatrixXd& x = path_->q;
  y_ = x;
  for (Eigen::Index k = 0; k < x.cols(); ++k) {
    if (!(play_[k] > 0.0)) {
      play_[k] = 0.0;
      continue;
    }
    const double h = 0.5 * play_[k];
    // Started b/2 behind the first motion that takes up half the play (the
    // fit's noise at rest does not), at rest when the motor never moves that far.
    double y = x(0, k);
    for (Eigen::Index i = 1; i < x.rows(); ++i)
      if (std::abs(x(i, k) - x(0, k)) > h) {
        y += x(i, k) > x(0, k) ? -h : h;
        break;
      }
    for (Eigen::Index i = 0; i < x.rows(); ++i) y_(i, k) = y = std::clamp(y, x(i, k) - h, x(i, k) + h);
  }
}

VecX BacklashLag::at(std::int64_t stamp_ns) const {
  VecX lag = VecX::Zero(play_.size());
  if (!path_ || path_->t.empty()) return lag;
  const double t = path_->trajectory->seconds(stamp_ns);
  const auto i = static_cast<Eigen::Index>(std::max<std::ptrdiff_t>(
      0, std::upper_bound(path_->t.begin(), path_->t.end(), t) - path_->t.begin() - 1));
  VecX x;
  path_->trajectory->evaluate(t, &x, nullptr);
  for (Eigen::Index k = 0; k < lag.size(); ++k) {
    if (play_[k] <= 0.0) continue;
    const double h = 0.5 * play_[k];
    lag[k] = (std::clamp(y_(i, k), x[k] - h, x[k] + h) - x[k]) / play_[k];
  }
  return lag;
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
      static const char* const kComponent[6] = {"rotation x", "rotation y", "rotation z",
                                                "translation x", "translation y", "translation z"};
      for (int k = 0; k < 6; ++k) {
        const auto& moved = o.absorbed[static_cast<std::size_t>(k)];
        if (moved.empty()) continue;
        s << "    not observed, " << kComponent[k] << ": a true 1 " << (k < 3 ? "mrad" : "mm") << " moves";
        for (std::size_t a = 0; a < moved.size(); ++a)
          s << (a ? "; " : " ") << moved[a].estimate << " " << std::setprecision(3) << moved[a].mm_per_mrad << " mm, "
            << std::setprecision(4) << moved[a].deg_per_mrad << " deg";
        s << "\n";
      }
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
