// The quality checks (assess.hpp): the factor families' chi-square against
// their redundancy, the mount prior's Mahalanobis distance, the joint log
// against the URDF's limits, each camera's corners against its own PnP
// poses; then the diagnoses of hypotheses.hpp for what is flagged.
#include "quality/assess.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "calibration/graph_parts.hpp"
#include "quality/chi_square.hpp"
#include "quality/hypotheses.hpp"
#include "quality/words.hpp"

namespace fgcal::apps::quality {

double FamilyStat::pHigh() const { return dof > 0.0 ? chiSquareSf(chi2, dof) : 1.0; }
double FamilyStat::pLow() const { return dof > 0.0 ? chiSquareCdf(chi2, dof) : 1.0; }

namespace {

/// The chi-square's upper tail as words: "p = 2e-05".
std::string pWords(double p) { return p < 1e-300 ? "p < 1e-300" : "p = " + num(p, 2); }

}  // namespace

Families familyStatistics(const Context& ctx) {
  const CalibrationProblemInput& in = ctx.problem;
  const CalibrationSolution& sol = ctx.sol;
  Families f;
  f.fiducial.resize(in.camera_names.size());
  const double scale = in.fiducial_covariance_scale;
  for (const InstantEstimate& ie : sol.instant_estimates) {
    if (ie.observations.empty()) continue;
    const BoardObservation& first = in.observations[ie.observations.front()];
    const Mat6 kin = detail::kinematicCovariance(first, in).inverse();
    Mat6 total = kin;
    std::vector<Mat6> fid;
    for (std::size_t i : ie.observations) {
      fid.push_back((scale * in.observations[i].covariance.matrix()).inverse());
      total += fid.back();
    }
    const Mat6 S = total.inverse();
    f.kinematic.chi2 += ie.kinematic_chi2;
    f.kinematic.dof += 6.0 - (kin * S).trace();
    ++f.kinematic.factors;
    for (std::size_t k = 0; k < ie.observations.size(); ++k) {
      const std::size_t i = ie.observations[k];
      FamilyStat& cam = f.fiducial[static_cast<std::size_t>(in.observations[i].camera)];
      const double chi2 = i < sol.fiducial_chi2.size() ? sol.fiducial_chi2[i] : std::nan("");
      if (!std::isfinite(chi2)) continue;
      cam.chi2 += chi2;
      // A PnP pose is 6 numbers; a corner graph's image is its 2n corner coordinates.
      const double m = ctx.method == Method::Corners ? 2.0 * in.observations[i].corners_count : 6.0;
      cam.dof += m - (fid[k] * S).trace();
      ++cam.factors;
    }
  }
  for (FamilyStat& c : f.fiducial) c.dof -= 6.0;  // the camera's pose
  if (sol.mount_estimated) {
    Vec6 prior_var;
    prior_var << Vec3::Constant(in.mount_sigma_rad * in.mount_sigma_rad), Vec3::Constant(in.mount_sigma_m * in.mount_sigma_m);
    const double held_by_prior = (sol.mount_covariance.diagonal().array() / prior_var.array()).sum();
    f.kinematic.dof -= 6.0 - held_by_prior;
  }
  // Estimated offsets take their parameters from the families they serve.
  const OffsetEstimates& off = sol.offsets;
  for (const auto& t : off.time_offsets)
    for (std::size_t c = 0; c < in.camera_names.size(); ++c)
      if (in.camera_names[c] == t.camera) f.fiducial[c].dof -= 1.0;
  for (const auto& r : off.readouts)
    for (std::size_t c = 0; c < in.camera_names.size(); ++c)
      if (in.camera_names[c] == r.camera && r.observed) f.fiducial[c].dof -= 1.0;
  f.kinematic.dof -= static_cast<double>(off.joint_offsets.size());
  for (const JointOffsetEstimate& b : off.backlash) f.kinematic.dof -= b.observed ? 1.0 : 0.0;
  return f;
}

namespace {

/// Each camera's images against their PnP covariance, each joint against
/// the kinematics: a family whose chi-square is beyond its distribution's
/// kFalseAlarm tail says its model does not explain the data.
void familyFindings(const Context& ctx, const Families& fam, Diagnosis& dx, Quality& q) {
  for (std::size_t c = 0; c < fam.fiducial.size(); ++c) {
    const FamilyStat& s = fam.fiducial[c];
    if (s.factors == 0 || s.dof <= 0.0) continue;
    q.statistics.push_back({"fiducial " + ctx.problem.camera_names[c], s.chi2, s.dof, s.pHigh()});
    if (s.pHigh() < kFalseAlarm) dx.flagged_cameras.push_back(c);
  }
  const FamilyStat& k = fam.kinematic;
  if (k.factors == 0 || k.dof <= 0.0) return;
  q.statistics.push_back({"kinematic", k.chi2, k.dof, k.pHigh()});
  if (k.pHigh() < kFalseAlarm) dx.kinematics_flagged = true;
}

/// The mount's estimate against its prior: under a right prior the
/// difference has the covariance prior - posterior, and its Mahalanobis
/// distance is chi-square with as many degrees of freedom as the data
/// inform.
void mountFinding(const Context& ctx, Quality& q) {
  const CalibrationSolution& sol = ctx.sol;
  const CalibrationProblemInput& in = ctx.problem;
  if (!sol.mount_estimated) return;
  Mat6 prior = Mat6::Zero();
  prior.diagonal() << Vec3::Constant(in.mount_sigma_rad * in.mount_sigma_rad),
      Vec3::Constant(in.mount_sigma_m * in.mount_sigma_m);
  const Mat6 C = prior - sol.mount_covariance;
  const Vec6 d = in.mount_prior.minus(sol.T_link_marker);
  // Whitened by the prior, so that the eigenvalues compare with 1.
  Mat6 Wp = Mat6::Zero();
  Wp.diagonal() = prior.diagonal().cwiseSqrt().cwiseInverse();
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(Wp * C * Wp);
  const Vec6 dw = eig.eigenvectors().transpose() * (Wp * d);
  double d2 = 0.0;
  int dof = 0;
  for (int k = 0; k < 6; ++k)
    if (eig.eigenvalues()[k] > 1e-3) {  // the data hold this direction to better than its prior
      d2 += dw[k] * dw[k] / eig.eigenvalues()[k];
      ++dof;
    }
  if (dof == 0) return;
  const double p = chiSquareSf(d2, dof);
  q.statistics.push_back({"mount_prior", d2, static_cast<double>(dof), p});
  if (p >= kFalseAlarm) return;
  const Vec6 xr = sol.T_link_marker.xyzRpy();
  Finding f;
  f.check = "mount_prior";
  f.severity = Severity::Check;
  f.fields = {"robot.T_link_marker", "robot.mount_sigma"};
  f.message = "the board mount moved " + fixed(d.tail<3>().norm() * 1e3, 1) + " mm, " +
              fixed(d.head<3>().norm() * 180.0 / M_PI, 2) + " deg from its rig.yaml prior: " +
              num(std::sqrt(d2), 3) + " sigma of what the prior and the data allow together (Mahalanobis, " +
              std::to_string(dof) + " dof, " + pWords(p) + "). The prior pulls every camera toward a mount the images "
              "contradict: set robot.T_link_marker to the estimate (or widen robot.mount_sigma) and calibrate again";
  f.estimate.emplace_back("xyz_rpy", "[" + num(xr[0], 6) + ", " + num(xr[1], 6) + ", " + num(xr[2], 6) + ", " +
                                         num(xr[3], 6) + ", " + num(xr[4], 6) + ", " + num(xr[5], 6) + "]");
  q.add(std::move(f));
}

/// The joint log against the URDF's limits: a reading beyond a limit by
/// more than 5 encoder sigmas is no encoder noise. A log in degrees, or of
/// another joint, shows here before anything else.
}  // namespace

std::optional<Finding> jointLimitFinding(const kinematics::KinematicChain& chain, const VecX& sigma_q,
                                         const JointLog& log, const std::string& joints_input) {
  const auto& joints = chain.joints();
  std::vector<std::string> fields;
  std::ostringstream what;
  bool degrees = true;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const auto& lim = joints[j].limits;
    const int col = log.column(joints[j].name);
    if (!lim.has_position_limits || col < 0) continue;
    const double margin = 5.0 * sigma_q[static_cast<Eigen::Index>(j)];
    const auto x = log.positions.col(col);
    long outside = 0, n = 0, outside_deg = 0;
    double lo = 1e300, hi = -1e300;
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      if (!std::isfinite(x[k])) continue;
      ++n;
      lo = std::min(lo, x[k]);
      hi = std::max(hi, x[k]);
      outside += x[k] < lim.lower - margin || x[k] > lim.upper + margin;
      const double rad = x[k] * M_PI / 180.0;
      outside_deg += rad < lim.lower - margin || rad > lim.upper + margin;
    }
    if (outside == 0) continue;
    // Degrees when no reading as radians is possible for a revolute joint
    // (beyond half a turn) and every one as degrees is within the limits.
    degrees = degrees && outside_deg == 0 && std::max(std::abs(lo), std::abs(hi)) > M_PI;
    fields.push_back(joints_input + ":" + joints[j].name);
    what << (fields.size() > 1 ? "; " : "") << joints[j].name << " " << outside << " of " << n << " readings (range "
         << num(lo, 4) << " to " << num(hi, 4) << ", limits " << num(lim.lower, 4) << " to " << num(lim.upper, 4)
         << ")";
  }
  if (fields.empty()) return std::nullopt;
  Finding f;
  f.check = degrees ? "joint_units" : "joint_limits";
  // Degrees make every pose wrong; readings a little past a limit may be a
  // zero offset or a conservative URDF, which the other checks judge.
  f.severity = degrees ? Severity::Unusable : Severity::Check;
  f.fields = fields;
  f.message = "joint readings outside the URDF's limits: " + what.str() +
              (degrees ? ". Read as degrees, every one of them is within its limits: the log is in degrees, "
                         "the kinematics expect radians"
                       : ". The log does not belong to these joints, or is in other units or another zero");
  if (degrees) f.estimate.emplace_back("unit", "degrees");
  return f;
}

Assessment assess(const Context& ctx) {
  Assessment a;
  Quality& q = a.quality;
  for (const Finding& f : ctx.sol.findings) q.add(f);
  if (auto f = jointLimitFinding(ctx.chain, ctx.sigma_q, ctx.joints, ctx.joints_input)) q.add(std::move(*f));
  mountFinding(ctx, q);
  a.families = familyStatistics(ctx);
  Diagnosis dx;
  familyFindings(ctx, a.families, dx, q);
  diagnose(ctx, a.families, dx, q);
  a.inflation = covarianceInflation(a.families, dx, ctx.problem.camera_names.size());
  return a;
}

}  // namespace fgcal::apps::quality
