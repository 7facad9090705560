// The diagnoses of hypotheses.hpp.
#include "quality/hypotheses.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "calibration/graph_parts.hpp"
#include "calibration/offset_graph.hpp"
#include "calibration/refit.hpp"
#include "fgcal/apps/joint_trajectory.hpp"
#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/offset_estimation.hpp"
#include "quality/chi_square.hpp"
#include "quality/words.hpp"

namespace fgcal::apps::quality {

namespace {

std::string cameraField(const Context& ctx, std::size_t c, const std::string& field) {
  return "cameras[" + ctx.problem.camera_names[c] + "]." + field;
}

std::string jointField(const Context& ctx, const std::string& joint) { return ctx.joints_input + ":" + joint; }

/// What an alternative (a parameter the graph left out: a scale, a delay, a
/// zero offset) must explain to be named: chi-square(6) at the false-alarm
/// rate, 22.46. Leaving out a parameter whose estimate is z sigmas from zero
/// moves a camera's estimate by at most z of its own sigmas (z^2 in NEES), so
/// below this bound no camera's NEES is pushed past its own 0.999 point; and
/// a correct input removes that much chi-square by chance less often than
/// the false-alarm rate even with 6 parameters freed.
double harmful() { return chiSquareQuantile(1.0 - kFalseAlarm, 6.0); }

/// The residual variance factor after a weighted least-squares fit: the
/// chi-square left over the degrees of freedom left, at least 1. A score
/// test scaled by it (quasi-likelihood) is not fooled by a misfit of
/// another cause (a wrong mount, a wrong board size): that misfit raises
/// the factor instead of the statistic.
double leftover(double chi2, double explained, double dof) {
  return dof > 0.0 ? std::max(1.0, (chi2 - explained) / dof) : 1.0;
}

// ---- Refitted hypotheses -------------------------------------------------

/// The flagged families' misfit, against which an alternative is judged.
struct Misfit {
  double chi2 = 0.0, dof = 0.0;  ///< summed over the flagged families

  Misfit(const Families& fam, const Diagnosis& dx) {
    for (std::size_t c : dx.flagged_cameras) chi2 += fam.fiducial[c].chi2, dof += fam.fiducial[c].dof;
    if (dx.kinematics_flagged) chi2 += fam.kinematic.chi2, dof += fam.kinematic.dof;
  }
  /// An alternative's statistic: the chi-square its change removes, over the
  /// variance factor it leaves (quasi-likelihood, as the score tests). A
  /// misfit of another cause (encoders noisier than encoder_sigma says)
  /// lets almost any change remove some chi-square; what it removes is then
  /// small beside what is left, and the factor discounts it.
  double significance(double drop) const { return drop / leftover(chi2, drop, dof); }
  /// True when a change that removes `a` fits the data better than one that
  /// removes `b` by more than what names an alternative.
  bool beats(double a, double b) const { return (a - b) / leftover(chi2, a, dof) > harmful(); }
  /// True when what is left after the change is still beyond the families'
  /// tail: the alternative explains part of the misfit, not all of it.
  bool leftAfter(double drop) const { return dof > 0.0 && chiSquareSf(chi2 - drop, dof) < kFalseAlarm; }
};

/// The total chi-square of the final graph over `in`, or +inf when it cannot be solved.
double refitChi2(const CalibrationProblemInput& in, const CalibrationSolution& sol) {
  try {
    return detail::refitChiSquare(in, sol);
  } catch (const std::exception&) {
    return std::numeric_limits<double>::infinity();
  }
}

}  // namespace

// A focal length k times larger than the lens's puts a board of known size k
// times farther, and leaves where it is across the image: only the depth.
Vec3 scaledTranslation(const Vec3& t, double k, bool depth_only) {
  Vec3 out = t;
  if (depth_only)
    out.z() *= 1.0 / k;
  else
    out *= 1.0 / k;
  return out;
}

CalibrationProblemInput scaled(const CalibrationProblemInput& in, double k, int camera) {
  CalibrationProblemInput out = in;
  Mat6 D = Mat6::Identity();
  if (camera < 0)
    D.diagonal().tail<3>().setConstant(1.0 / k);
  else
    D(5, 5) = 1.0 / k;
  for (BoardObservation& o : out.observations) {
    if (camera >= 0 && o.camera != camera) continue;
    o.T_cam_marker = SE3(o.T_cam_marker.so3(), scaledTranslation(o.T_cam_marker.translation(), k, camera >= 0));
    o.covariance = D * o.covariance.matrix() * D;
  }
  return out;
}

namespace {

struct ScaleFit {
  double k = 1.0, sigma = 0.0, drop = 0.0;  ///< estimate, its 1-sigma, the chi-square it removes
  bool ok = false;
};

/// The factor k that minimises the refitted chi-square of the problem
/// `at(k)` (at(1) is the problem as given): Newton steps on a parabola
/// through three refits, from 1.
ScaleFit fitScale(const Context& ctx, const std::function<CalibrationProblemInput(double)>& at, double chi2_at_1) {
  ScaleFit fit;
  double k0 = 1.0, f0 = chi2_at_1;
  constexpr double h = 0.01;
  for (int it = 0; it < 4; ++it) {
    const double fp = refitChi2(at(k0 + h), ctx.sol);
    const double fm = refitChi2(at(k0 - h), ctx.sol);
    const double a = (fp + fm - 2.0 * f0) / (2.0 * h * h);
    if (!std::isfinite(a) || a <= 0.0) return fit;
    const double k = std::clamp(k0 - (fp - fm) / (4.0 * a * h), 0.6, 1.6);
    fit.sigma = 1.0 / std::sqrt(a);
    const double fk = refitChi2(at(k), ctx.sol);
    if (!(fk < f0)) break;
    const bool settled = std::abs(k - k0) < 0.2 * fit.sigma;
    k0 = k;
    f0 = fk;
    if (settled) break;
  }
  fit.k = k0;
  fit.drop = chi2_at_1 - f0;
  fit.ok = k0 != 1.0;
  return fit;
}

/// The observations' kinematics re-evaluated at joint readings changed by `change`.
CalibrationProblemInput rejointed(const Context& ctx, const std::function<void(VecX&)>& change) {
  CalibrationProblemInput out = ctx.problem;
  for (BoardObservation& o : out.observations) {
    if (o.joint_positions.size() != ctx.chain.numJoints()) continue;
    change(o.joint_positions);
    Mat6 cov;
    o.T_base_link = ctx.chain.forwardWithCovariance(o.joint_positions, ctx.sigma_q, &cov);
    o.link_covariance = cov;
  }
  return out;
}

/// The observations' kinematics on a leg whose link before joint i (its
/// <origin>'s translation) is k times the URDF's; their covariance is kept
/// (a link a few percent longer changes the encoders' effect by as much).
CalibrationProblemInput relinked(const Context& ctx, int i, double k) {
  CalibrationProblemInput out = ctx.problem;
  VecX u = VecX::Zero(6 * ctx.chain.numJoints());
  u.segment<3>(6 * i + 3) = (k - 1.0) * ctx.chain.originTranslation(i);
  for (BoardObservation& o : out.observations)
    if (o.joint_positions.size() == ctx.chain.numJoints())
      o.T_base_link = ctx.chain.forwardCorrected(o.joint_positions, u, SE3());
  return out;
}

/// A hypothesis that explains the flagged families better than the input as given.
struct Explanation {
  double drop = 0.0;
  Finding finding;
  std::string alike;  ///< what it says in a few words, for a finding that cannot be told from it
};

Explanation boardExplanation(const Context& ctx, const ScaleFit& board) {
  const TargetConfig& t = ctx.rig.target;
  Explanation e{board.drop, {}, "the board's squares " + fixed(t.square_size / board.k * 1e3, 2) + " mm"};
  Finding& f = e.finding;
  f.check = "board_scale";
  f.severity = Severity::Check;
  f.fields = {"target.square_size", "target.marker_size"};
  f.message = "the board's squares measure " + fixed(t.square_size / board.k * 1e3, 2) + " mm (+-" +
              fixed(t.square_size * board.sigma / (board.k * board.k) * 1e3, 2) + ") in the images and kinematics; " +
              "rig.yaml says " + fixed(t.square_size * 1e3, 2) + " mm. Every distance PnP gives is " +
              fixed((board.k - 1.0) * 100.0, 1) + " % off (the change removes chi-square " + num(board.drop) +
              "). Measure the printed board and correct target.square_size and target.marker_size";
  f.estimate = {{"square_size", num(t.square_size / board.k, 6)}, {"marker_size", num(t.marker_size / board.k, 6)}};
  return e;
}

Explanation linkExplanation(const Context& ctx, int i, const ScaleFit& link) {
  const std::string& joint = ctx.chain.jointNames()[static_cast<std::size_t>(i)];
  const double length = ctx.chain.originTranslation(i).norm();
  const std::string now = fixed(link.k * length * 1e3, 1) + " mm";
  Explanation e{link.drop, {}, "the link before joint " + joint + " " + now + " long"};
  Finding& f = e.finding;
  f.check = "leg_length";
  f.severity = Severity::Check;
  f.fields = {"robot.urdf"};
  f.message = "the link before joint " + joint + " (its <origin> in the URDF, " + fixed(length * 1e3, 1) +
              " mm) measures " + now + " (+-" + fixed(link.sigma * length * 1e3, 1) +
              ") in the images and kinematics (the change removes chi-square " + num(link.drop) +
              "): the leg is not its URDF. Measure the leg and correct the URDF, or give its tolerance as "
              "robot.kinematic_sigma";
  f.estimate = {{joint + "_origin_scale", num(link.k, 6)}};
  return e;
}

/// The board's size and each link of the leg (the translation of each
/// joint's <origin> after the first, whose move the cameras' poses take up;
/// not when robot.kinematic_sigma already frees them):
/// both move the board nearer to or farther from the cameras. The one that
/// removes the most is named; another whose significance falls short of it
/// by no more than what names an alternative (chi-square(6) at 10^-3)
/// cannot be told from it, and is named beside it. Then, unless
/// that explains the whole misfit, each camera's depth scale (a focal
/// length that is not the lens's).
void tryScales(const Context& ctx, double chi2_0, const Misfit& misfit, std::optional<Explanation>& best) {
  std::vector<Explanation> sizes;
  const ScaleFit board = fitScale(ctx, [&](double k) { return scaled(ctx.problem, k, -1); }, chi2_0);
  if (board.ok && misfit.significance(board.drop) > harmful()) sizes.push_back(boardExplanation(ctx, board));
  if (!ctx.problem.offsets.origins)
    for (int i = 1; i < ctx.chain.numJoints(); ++i) {
      if (ctx.chain.originTranslation(i).norm() == 0.0) continue;
      const ScaleFit link = fitScale(ctx, [&](double k) { return relinked(ctx, i, k); }, chi2_0);
      if (link.ok && misfit.significance(link.drop) > harmful()) sizes.push_back(linkExplanation(ctx, i, link));
    }
  const auto top = std::max_element(sizes.begin(), sizes.end(),
                                    [](const Explanation& a, const Explanation& b) { return a.drop < b.drop; });
  if (top != sizes.end() && (!best || top->drop > best->drop)) {
    for (const Explanation& other : sizes) {
      if (&other == &*top || misfit.beats(top->drop, other.drop)) continue;
      for (const std::string& field : other.finding.fields)
        if (std::find(top->finding.fields.begin(), top->finding.fields.end(), field) == top->finding.fields.end())
          top->finding.fields.push_back(field);
      top->finding.message += ". The images fit about as well with " + other.alike + " (it removes chi-square " +
                              num(other.drop) + "): check that too";
    }
    best = std::move(*top);
  }
  if (ctx.problem.camera_names.size() < 2) return;  // one camera's depth scale is the board's
  if (best && !misfit.leftAfter(best->drop)) return;
  for (std::size_t c = 0; c < ctx.problem.camera_names.size(); ++c) {
    const ScaleFit cam =
        fitScale(ctx, [&](double k) { return scaled(ctx.problem, k, static_cast<int>(c)); }, chi2_0);
    if (!cam.ok || !(misfit.significance(cam.drop) > harmful()) || (best && cam.drop <= best->drop)) continue;
    const vision::CameraModel& m = ctx.models[c];
    Explanation e{cam.drop, {}, {}};
    Finding& f = e.finding;
    f.check = "camera_scale";
    f.severity = Severity::Check;
    f.fields = {cameraField(ctx, c, "intrinsics")};
    f.message = "camera " + ctx.problem.camera_names[c] + " sees every depth " + fixed((cam.k - 1.0) * 100.0, 1) +
                " % off where the other cameras and the kinematics agree (the change removes chi-square " +
                num(cam.drop) + "): its focal length does not fit the images; fx, fy near " + fixed(m.fx() / cam.k, 1) +
                ", " + fixed(m.fy() / cam.k, 1) + " would. Check that these are this camera's intrinsics";
    f.estimate = {{"fx", num(m.fx() / cam.k, 6)}, {"fy", num(m.fy() / cam.k, 6)}};
    best = std::move(e);
  }
}

/// Each joint's sign flipped, and each pair of joints swapped.
void tryJoints(const Context& ctx, double chi2_0, const Misfit& misfit, std::optional<Explanation>& best) {
  const std::vector<std::string>& names = ctx.chain.jointNames();
  const int n = ctx.chain.numJoints();
  for (int j = 0; j < n; ++j) {
    const double chi2 = refitChi2(rejointed(ctx, [j](VecX& q) { q[j] = -q[j]; }), ctx.sol);
    const double drop = chi2_0 - chi2;
    if (!(misfit.significance(drop) > harmful()) || (best && drop <= best->drop)) continue;
    const std::string& name = names[static_cast<std::size_t>(j)];
    best = Explanation{drop,
                       {"joint_sign", Severity::Unusable, {jointField(ctx, name)},
                        "joint " + name + "'s readings fit the images with the opposite sign (the change removes "
                        "chi-square " + num(drop) + " of " + num(chi2_0) + "): its direction in the log is reversed "
                        "against the URDF's axis. Negate the column, or fix the joint's axis",
                        {{"sign", "-1"}},
                        {}},
                       {}};
  }
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      const double chi2 = refitChi2(rejointed(ctx, [a, b](VecX& q) { std::swap(q[a], q[b]); }), ctx.sol);
      const double drop = chi2_0 - chi2;
      if (!(misfit.significance(drop) > harmful()) || (best && drop <= best->drop)) continue;
      const std::string &na = names[static_cast<std::size_t>(a)], &nb = names[static_cast<std::size_t>(b)];
      best = Explanation{drop,
                         {"joint_swap", Severity::Unusable, {jointField(ctx, na), jointField(ctx, nb)},
                          "joints " + na + " and " + nb + " fit the images with their readings swapped (the change "
                          "removes chi-square " + num(drop) + " of " + num(chi2_0) + "): the log's columns name the "
                          "wrong joints",
                          {{"swap", "[" + na + ", " + nb + "]"}},
                          {}},
                         {}};
    }
}

// ---- Score tests -----------------------------------------------------------

/// The chain's joint velocities at each observation, from the joints of the
/// observations 10 to 150 ms before and after it: neighbours that read
/// other samples of the log, so that the velocity's noise is not the
/// observation's own encoder noise (a difference of the two samples around
/// a stamp correlates with what was interpolated from them).
std::vector<std::optional<VecX>> jointVelocities(const Context& ctx) {
  const auto& obs = ctx.problem.observations;
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < obs.size(); ++i)
    if (obs[i].joint_positions.size() == ctx.chain.numJoints() && obs[i].joint_positions.allFinite())
      order.push_back(i);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return obs[a].stamp_ns < obs[b].stamp_ns; });
  constexpr std::int64_t kNear = 10'000'000, kFar = 150'000'000;  // ns
  std::vector<std::optional<VecX>> out(obs.size());
  std::size_t lo = 0, hi = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::int64_t t = obs[order[k]].stamp_ns;
    while (lo + 1 < order.size() && obs[order[lo + 1]].stamp_ns <= t - kNear) ++lo;  // the last one before t - 10 ms
    while (hi < order.size() && obs[order[hi]].stamp_ns < t + kNear) ++hi;            // the first one after t + 10 ms
    if (hi >= order.size() || obs[order[lo]].stamp_ns > t - kNear) continue;
    const BoardObservation &a = obs[order[lo]], &b = obs[order[hi]];
    if (t - a.stamp_ns > kFar || b.stamp_ns - t > kFar) continue;  // a pause in the recording: no velocity
    out[order[k]] = (b.joint_positions - a.joint_positions) / (static_cast<double>(b.stamp_ns - a.stamp_ns) * 1e-9);
  }
  return out;
}

/// The board where camera c puts it (X Z) against where the kinematics put
/// it (FK(q) mount), in the board's frame, [w v]; its covariance (the PnP
/// pose's, scaled as in the graph, and the kinematic factor's); the
/// kinematic Jacobian at the board. Nothing for an observation without the
/// chain's joints.
struct BoardGap {
  Vec6 e;
  Mat6 W;  ///< the inverse of its covariance
  kinematics::KinematicChain::Jacobian J;
};
/// The command of a finding's fix: the run's, estimating what it estimated
/// and `more`, with the corner method when `corners` asks for it.
std::string fixCommand(const Context& ctx, const std::vector<std::string>& more, bool corners = false) {
  std::vector<std::string> estimate = names(ctx.estimate);
  for (const std::string& m : more)
    if (std::find(estimate.begin(), estimate.end(), m) == estimate.end()) estimate.push_back(m);
  std::string s = ctx.command + (corners && ctx.method != Method::Corners ? " --method corners" : "");
  if (!estimate.empty()) s += " --estimate ";
  for (std::size_t i = 0; i < estimate.size(); ++i) s += (i ? "," : "") + estimate[i];
  return s;
}
std::string fixCommand(const Context& ctx, const std::string& more, bool corners = false) {
  return fixCommand(ctx, more.empty() ? std::vector<std::string>{} : std::vector<std::string>{more}, corners);
}

std::optional<BoardGap> boardGap(const Context& ctx, std::size_t k) {
  const BoardObservation& o = ctx.problem.observations[k];
  if (o.joint_positions.size() != ctx.chain.numJoints()) return std::nullopt;
  BoardGap g;
  // The kinematics as the solution models them: with the estimated joint
  // offsets, backlash and the leg's origin corrections (robot.kinematic_sigma),
  // moved to the image's exposure (time offset, rolling shutter), so that
  // what they already explain is not offered again as an alternative.
  VecX q = o.joint_positions;
  const auto& jo = ctx.sol.offsets.joint_offsets;
  if (static_cast<Eigen::Index>(jo.size()) == q.size())
    for (Eigen::Index j = 0; j < q.size(); ++j) q[j] += jo[static_cast<std::size_t>(j)].offset_rad;
  const VecX b = offsets::backlashVector(ctx.sol.offsets);
  if (ctx.problem.offsets.backlash && b.size() == q.size() && ctx.sol.offsets.backlash_lag)
    q += ctx.sol.offsets.backlash_lag->at(o.stamp_ns).cwiseProduct(b);
  const VecX u = offsets::originVector(ctx.sol.offsets);
  SE3 K = u.size() ? ctx.chain.forwardCorrected(q, u, ctx.sol.T_link_marker, &g.J)
                   : ctx.chain.forward(q, ctx.sol.T_link_marker, &g.J);
  if (ctx.problem.offsets.exposureTiming()) K = offsets::boardFromKinematics(ctx.problem, ctx.sol, k);
  const SE3 B = ctx.sol.cameras[static_cast<std::size_t>(o.camera)].T_base_cam * o.T_cam_marker;
  g.e = (K.inverse() * B).log();
  g.W = (detail::kinematicCovariance(o, ctx.problem) + ctx.problem.fiducial_covariance_scale * o.covariance.matrix())
            .inverse();
  return g;
}

/// Each camera's images against the kinematics along the board's velocity:
/// an image exposed tau later than stamped sees the board moved by tau
/// times its twist (X Z = FK mount Exp(tau twist)). Every image with a board
/// pose counts, the gated ones too: a large delay is what the gate rejects.
/// Weighted least squares for tau per camera, tested against its sigma.
void timeOffsetTest(const Context& ctx, const std::vector<std::optional<BoardGap>>& gaps, Quality& q) {
  if (ctx.estimate.time_offset) return;
  const std::size_t M = ctx.problem.camera_names.size();
  std::vector<double> num_(M, 0.0), den(M, 0.0), chi2(M, 0.0), n(M, 0.0);
  const std::vector<std::optional<VecX>> velocities = jointVelocities(ctx);
  for (std::size_t i = 0; i < ctx.problem.observations.size(); ++i) {
    const BoardObservation& o = ctx.problem.observations[i];
    const auto& qd = velocities[i];
    const auto& g = gaps[i];
    if (!qd || !g) continue;
    const Vec6 twist = g->J * *qd;  // the board's body twist, [w v], per second
    const auto c = static_cast<std::size_t>(o.camera);
    num_[c] += twist.dot(g->W * g->e);
    den[c] += twist.dot(g->W * twist);
    chi2[c] += g->e.dot(g->W * g->e);
    n[c] += 1.0;
  }
  for (std::size_t c = 0; c < M; ++c) {
    if (!(den[c] > 0.0)) continue;
    const double tau = num_[c] / den[c], explained = tau * tau * den[c];
    const double v = leftover(chi2[c], explained, 6.0 * n[c] - 7.0);
    const double sigma = std::sqrt(v / den[c]), z2 = explained / v;
    const std::string& name = ctx.problem.camera_names[c];
    q.statistics.push_back({"time_offset " + name, z2, 1.0, chiSquareSf(z2, 1.0)});
    if (!(z2 > harmful())) continue;
    Finding f;
    f.check = "time_offset";
    f.severity = Severity::Check;
    f.fields = {cameraField(ctx, c, "time_offset_ms")};
    f.message = "camera " + name + "'s images fit the joints " + num(std::abs(tau) * 1e3, 3) + " ms (+-" +
                num(sigma * 1e3, 2) + ") " + (tau > 0 ? "later" : "earlier") +
                " than stamped: its residuals follow the board's velocity. Estimate the offset with the command below";
    f.estimate = {{"time_offset_ms", num(tau * 1e3, 4)}};
    f.command = fixCommand(ctx, "time-offset");
    q.add(std::move(f));
  }
}

/// A rolling shutter the run does not model (or models too short): within an
/// image, each corner sits where the board was at its row's time, so the
/// corners' residuals follow their image velocity in proportion to how far
/// their row lies below the image's mean row (the mean row's delay is a time
/// offset's; this skew is not). Per camera, the extra readout by weighted
/// least squares of every used corner's residual on (r - r_mean) x its image
/// velocity (the board's twist J qdot moved through the camera), scaled by
/// what the fit leaves over, and tested one-sided: a shorter readout than
/// modelled is no rolling shutter to add.
void rollingShutterTest(const Context& ctx, const std::vector<std::optional<BoardGap>>& gaps, Quality& q) {
  if (ctx.estimate.rolling_shutter || ctx.problem.corners.px.empty()) return;
  const std::size_t M = ctx.problem.camera_names.size();
  // Per image of each camera, its corners' score and information: the
  // corners of one image share that image's error of the board pose, so the
  // variance of the estimate is taken from the images' scatter (a
  // cluster-robust sandwich), not from the corners as if independent.
  std::vector<std::vector<std::pair<double, double>>> per_image(M);
  const std::vector<std::optional<VecX>> velocities = jointVelocities(ctx);
  constexpr double kStep = 1e-3;  // s, for the corners' image velocity
  for (std::size_t i = 0; i < ctx.problem.observations.size(); ++i) {
    const BoardObservation& o = ctx.problem.observations[i];
    const auto& qd = velocities[i];
    const auto& g = gaps[i];
    if (!qd || !g || !ctx.sol.used[i] || o.corners_count < 6) continue;
    const auto c = static_cast<std::size_t>(o.camera);
    const vision::CameraModel& model = ctx.models[c];
    if (model.height() < 2) continue;
    const Vec6 twist = g->J * *qd;
    const SE3 T_cam_base = ctx.sol.cameras[c].T_base_cam.inverse();
    const bool per_row = offsets::hasReadout(ctx.problem, ctx.sol, c);
    const SE3 K = offsets::boardFromKinematics(ctx.problem, ctx.sol, i);
    const double s2 = ctx.rig.cameras[c].pixel_sigma * ctx.rig.cameras[c].pixel_sigma;
    const double rows = static_cast<double>(model.height() - 1);
    double mean = 0.0;
    for (std::size_t j = o.corners_begin; j < o.corners_begin + o.corners_count; ++j)
      mean += ctx.problem.corners.pixel(j).y() / rows;
    mean /= static_cast<double>(o.corners_count);
    double score = 0.0, info = 0.0;
    for (std::size_t j = o.corners_begin; j < o.corners_begin + o.corners_count; ++j) {
      const Eigen::Vector2d px = ctx.problem.corners.pixel(j);
      const Vec3 p = ctx.problem.corners.boardPoint(j);
      const SE3 Kj = per_row ? offsets::boardFromKinematics(ctx.problem, ctx.sol, i, std::nullopt, px.y()) : K;
      const auto at = model.project(T_cam_base * Kj * p);
      const auto ahead = model.project(T_cam_base * Kj.plus(kStep * twist) * p);
      const auto behind = model.project(T_cam_base * Kj.plus(-kStep * twist) * p);
      if (!at || !ahead || !behind) continue;
      const Eigen::Vector2d gk = (px.y() / rows - mean) * (*ahead - *behind) / (2.0 * kStep);
      const Eigen::Vector2d res = px - *at;
      score += gk.dot(res) / s2;
      info += gk.squaredNorm() / s2;
    }
    per_image[c].emplace_back(score, info);
  }
  for (std::size_t c = 0; c < M; ++c) {
    double score = 0.0, den = 0.0;
    for (const auto& [a, b] : per_image[c]) score += a, den += b;
    if (per_image[c].size() < 10 || !(den > 0.0)) continue;
    const double extra = score / den;
    double meat = 0.0;
    for (const auto& [a, b] : per_image[c]) meat += (a - extra * b) * (a - extra * b);
    const auto k = static_cast<double>(per_image[c].size());
    const double sigma = std::sqrt(meat * k / (k - 1.0)) / den;
    const double z2 = extra > 0.0 && sigma > 0.0 ? (extra / sigma) * (extra / sigma) : 0.0;
    const std::string& name = ctx.problem.camera_names[c];
    q.statistics.push_back({"rolling_shutter " + name, z2, 1.0, chiSquareSf(z2, 1.0)});
    if (!(z2 > harmful())) continue;
    const double readout = offsets::readoutOf(ctx.problem, ctx.sol, c);
    Finding f;
    f.check = "rolling_shutter";
    f.severity = Severity::Check;
    f.fields = {cameraField(ctx, c, "readout_ms")};
    f.message = "camera " + name + "'s corners lag the board's motion from the image's top rows to its bottom ones as a "
                "rolling shutter's readout of " + num((readout + extra) * 1e3, 3) + " ms (+-" + num(sigma * 1e3, 2) +
                ") would" + (readout > 0.0 ? " (rig.yaml says " + num(readout * 1e3, 3) + " ms)" : "") +
                ": each row was exposed later than the one above. Estimate the readout with the command below (the "
                "corner method reads each corner at its row's time)";
    f.estimate = {{"readout_ms", num((readout + extra) * 1e3, 4)}};
    f.command = fixCommand(ctx, std::vector<std::string>{"time-offset", "rolling-shutter"}, true);
    q.add(std::move(f));
  }
}

/// Per joint, what a unit of the tested parameter does to its angle at
/// observation i (1 for a zero offset; the lag for backlash).
using JointEffect = std::function<VecX(std::size_t i)>;

/// One image's PnP pose against the camera's [fx fy cx cy]: how the pose
/// that PnP's least squares over the image's corners finds moves when they
/// change (the implicit function of its normal equations: dT = -N^-1 M
/// dtheta, T's right perturbation [w v]). Nothing when the corners do not
/// fix the pose.
std::optional<Eigen::Matrix<double, 6, 4>> pnpIntrinsicsEffect(const Context& ctx, const BoardObservation& o) {
  const vision::CameraModel& model = ctx.models[static_cast<std::size_t>(o.camera)];
  const int K = model.intrinsicsSize();
  const Mat3& R = o.T_cam_marker.so3().matrix();
  Mat6 N = Mat6::Zero();
  Eigen::Matrix<double, 6, 4> Mt = Eigen::Matrix<double, 6, 4>::Zero();
  std::vector<double> Jk(static_cast<std::size_t>(2 * K));
  int used = 0;
  for (std::size_t p = o.corners_begin; p < o.corners_begin + o.corners_count; ++p) {
    const Vec3 P = ctx.problem.corners.boardPoint(p);
    Eigen::Vector2d uv;
    vision::Mat23 Jp;
    if (!model.projectWith(model.intrinsicsData(), o.T_cam_marker * P, &uv, &Jp, Jk.data())) continue;
    Eigen::Matrix<double, 3, 6> dp;  // d(p_cam)/d[w v]
    dp << -R * hat(P), R;
    const Eigen::Matrix<double, 2, 6> JT = Jp * dp;
    const Eigen::Map<const Eigen::Matrix<double, 2, Eigen::Dynamic>> Jt(Jk.data(), 2, K);
    N += JT.transpose() * JT;
    Mt += JT.transpose() * Jt.leftCols<4>();
    ++used;
  }
  const Eigen::LDLT<Mat6> ldlt(N);
  if (used < 4 || ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::nullopt;
  return Eigen::Matrix<double, 6, 4>(-ldlt.solve(Mt));
}

}  // namespace

std::string namedCause(const Quality& q, std::size_t earlier, const std::vector<std::string>& fields) {
  static const char* const kCauses[] = {"board_scale", "camera_scale", "leg_length",  "joint_sign",
                                        "joint_swap",  "joint_units",  "joint_limits", "mount_prior",
                                        "time_offset", "joint_offset", "backlash",     "rolling_shutter",
                                        "distortion",  "intrinsics"};
  for (std::size_t i = 0; i < earlier && i < q.findings.size(); ++i) {
    const Finding& f = q.findings[i];
    if (f.severity == Severity::Note || std::find(std::begin(kCauses), std::end(kCauses), f.check) == std::end(kCauses))
      continue;
    const bool same_input = std::any_of(f.fields.begin(), f.fields.end(), [&](const std::string& field) {
      return std::find(fields.begin(), fields.end(), field) != fields.end();
    });
    if (!same_input) return f.check;
  }
  return {};
}

void addAssumingTheRest(Quality& q, Finding f, std::size_t earlier) {
  const std::string cause = namedCause(q, earlier, f.fields);
  if (!cause.empty()) {
    f.severity = Severity::Note;
    f.message += ". It may follow from the " + cause + " finding: judge it again once that input is fixed";
  }
  q.add(std::move(f));
}

namespace {

/// The used images' gaps fitted on `tested` parameters, whose effect on
/// image i's gap is effect(i) (6 x tested; nothing leaves the image out),
/// beside every camera's pose and the mount (when estimated), and the
/// board's scale when `with_scale`: the tested parameters' estimate (the
/// correction to the input) and covariance, scaled by what the fit leaves
/// over. A parameter the images do not inform comes out NaN. Empty when no
/// image counts.
struct GapFit {
  VecX x;
  MatX C;
};
std::optional<GapFit> fitGaps(const Context& ctx, const std::vector<std::optional<BoardGap>>& gaps,
                              Eigen::Index tested, const std::function<std::optional<MatX>(std::size_t)>& effect,
                              bool with_scale) {
  const auto M = static_cast<Eigen::Index>(ctx.problem.camera_names.size());
  const Eigen::Index cams = tested, scale = with_scale ? cams + 6 * M : -1;
  const Eigen::Index mount = ctx.sol.mount_estimated ? cams + 6 * M + (with_scale ? 1 : 0) : -1;
  const Eigen::Index P = cams + 6 * M + (with_scale ? 1 : 0) + (mount >= 0 ? 6 : 0);
  MatX H = MatX::Zero(P, P);
  VecX g = VecX::Zero(P);
  double chi2 = 0.0, count = 0.0;
  MatX Z(6, P);
  for (std::size_t i = 0; i < ctx.problem.observations.size(); ++i) {
    const BoardObservation& o = ctx.problem.observations[i];
    if (i >= ctx.sol.used.size() || !ctx.sol.used[i] || !gaps[i]) continue;
    const std::optional<MatX> A = effect(i);
    if (!A) continue;
    Z.setZero();
    Z.leftCols(tested) = *A;
    Z.block<6, 6>(0, cams + 6 * o.camera) = o.T_cam_marker.inverse().adjoint();  // the camera's pose, through its image
    if (scale >= 0) Z.block<3, 1>(3, scale) = o.T_cam_marker.so3().matrix().transpose() * o.T_cam_marker.translation();
    if (mount >= 0) Z.block<6, 6>(0, mount) = -Mat6::Identity();
    const BoardGap& gap = *gaps[i];
    H += Z.transpose() * gap.W * Z;
    g -= Z.transpose() * gap.W * gap.e;
    chi2 += gap.e.dot(gap.W * gap.e);
    count += 1.0;
  }
  if (count == 0.0) return std::nullopt;
  // Solved on the unit-diagonal scaling of H, by its eigenvectors: the
  // directions the images do not inform (a parameter no image moves, or
  // one that the cameras' poses take up exactly, as a link that moves the
  // whole leg rigidly) are left out, and a tested parameter with a part in
  // them is not tested (NaN).
  VecX d(P);
  for (Eigen::Index k = 0; k < P; ++k) d[k] = H(k, k) > 0.0 ? 1.0 / std::sqrt(H(k, k)) : 1.0;
  const Eigen::SelfAdjointEigenSolver<MatX> eig(d.asDiagonal() * H * d.asDiagonal());
  if (eig.info() != Eigen::Success) return std::nullopt;
  const VecX& l = eig.eigenvalues();
  const MatX& V = eig.eigenvectors();
  VecX inv = VecX::Zero(P);
  double rank = 0.0;
  for (Eigen::Index k = 0; k < P; ++k)
    if (l[k] > 1e-9 * l[P - 1]) inv[k] = 1.0 / l[k], rank += 1.0;
  const MatX Hinv = d.asDiagonal() * V * inv.asDiagonal() * V.transpose() * d.asDiagonal();
  const VecX x = Hinv * g;
  const double v = leftover(chi2, g.dot(x), 6.0 * count - rank);
  GapFit fit;
  fit.x = x.head(tested);
  fit.C = v * Hinv.topLeftCorner(tested, tested);
  for (Eigen::Index k = 0; k < tested; ++k) {
    double uninformed = 0.0;
    for (Eigen::Index j = 0; j < P; ++j)
      if (inv[j] == 0.0) uninformed += V(k, j) * V(k, j);
    if (uninformed > 1e-6 || H(k, k) == 0.0) fit.x[k] = std::numeric_limits<double>::quiet_NaN();
  }
  return fit;
}

/// Each camera's intrinsics [fx fy cx cy] against the kinematics: a lens
/// model off by d moves every PnP pose by pnpIntrinsicsEffect() d, and the
/// board as the camera sees it with it: fitGaps() on those moves, with the
/// board's scale free too (a principal point's shift is nearly a rotation
/// of the camera, which the solution has already taken up; what tells them
/// apart is how the shift's effect varies across the image and the board's
/// distance; a focal length common to every camera is the board's size,
/// which board_scale judges). A camera with fewer than 10 such images is
/// not tested (too few to tell a lens from a pose). A parameter beyond its
/// sigma's tail names the camera's intrinsics, with the values the data
/// suggest. It runs on every result, flagged or not, and silences no misfit
/// finding: it assumes the rest of the model holds (addAssumingTheRest).
void intrinsicsTest(const Context& ctx, const std::vector<std::optional<BoardGap>>& gaps, Quality& q) {
  if (ctx.estimate.intrinsics || ctx.problem.corners.px.empty()) return;
  const std::size_t earlier = q.findings.size();  // the findings made before this test
  const auto M = static_cast<Eigen::Index>(ctx.problem.camera_names.size());
  std::vector<double> images(static_cast<std::size_t>(M), 0.0);
  for (std::size_t i = 0; i < ctx.problem.observations.size(); ++i)
    if (i < ctx.sol.used.size() && ctx.sol.used[i] && gaps[i] && ctx.problem.observations[i].corners_count >= 4)
      images[static_cast<std::size_t>(ctx.problem.observations[i].camera)] += 1.0;
  const auto fit = fitGaps(ctx, gaps, 4 * M, [&](std::size_t i) -> std::optional<MatX> {
    const BoardObservation& o = ctx.problem.observations[i];
    if (o.corners_count < 4 || images[static_cast<std::size_t>(o.camera)] < 10.0) return std::nullopt;
    const auto effect = pnpIntrinsicsEffect(ctx, o);
    if (!effect) return std::nullopt;
    MatX A = MatX::Zero(6, 4 * M);
    A.block<6, 4>(0, 4 * o.camera) = *effect;
    return A;
  }, true);
  if (!fit) return;
  static const char* const kNames[] = {"fx", "fy", "cx", "cy"};
  for (Eigen::Index c = 0; c < M; ++c) {
    if (images[static_cast<std::size_t>(c)] < 10.0) continue;
    const std::string& name = ctx.problem.camera_names[static_cast<std::size_t>(c)];
    const VecX now = ctx.models[static_cast<std::size_t>(c)].intrinsicsVector();
    Finding f;
    std::ostringstream which;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Index j = 4 * c + k;
      const double z2 = fit->x[j] * fit->x[j] / fit->C(j, j);
      if (!std::isfinite(z2)) continue;  // a parameter these images do not inform
      q.statistics.push_back({std::string("intrinsics ") + name + " " + kNames[k], z2, 1.0, chiSquareSf(z2, 1.0)});
      if (!(z2 > harmful())) continue;
      which << (f.estimate.empty() ? "" : ", ") << kNames[k] << " " << fixed(now[k] + fit->x[j], 1) << " (+-"
            << fixed(std::sqrt(fit->C(j, j)), 1) << "; rig.yaml " << fixed(now[k], 1) << ")";
      f.estimate.emplace_back(kNames[k], num(now[k] + fit->x[j], 6));
    }
    if (f.estimate.empty()) continue;
    f.check = "intrinsics";
    f.severity = Severity::Check;
    f.fields = {cameraField(ctx, static_cast<std::size_t>(c), "intrinsics")};
    f.message = "camera " + name + "'s images fit the kinematics with " + which.str() +
                ": rig.yaml's intrinsics do not fit its images (a calibration of another camera, or of another "
                "resolution or crop?). Estimate them at corner level with the command below";
    f.command = fixCommand(ctx, "intrinsics", true);
    addAssumingTheRest(q, std::move(f), earlier);
  }
}

/// The board's size and the leg's lengths against the kinematics, on every
/// result, flagged or not: a board larger than rig.yaml says puts every PnP
/// pose farther by that ratio ([0, R^T t] per unit); a link longer than its
/// URDF (the translation of joint j's <origin>) moves the board along the
/// chain's origin Jacobian. Each by fitGaps(): the board's scale alone, the
/// links together (not when robot.kinematic_sigma already frees them; not
/// the first joint's origin, where the leg sits on the body: moving it moves
/// the whole leg as the cameras' poses do). Not
/// when a refitted alternative has named either. The two move the board
/// alike, so that when both are beyond their tail the finding names both.
/// Like the intrinsics' test, they assume the rest of the model holds.
void sizeTests(const Context& ctx, const std::vector<std::optional<BoardGap>>& gaps, Quality& q) {
  if (q.has("board_scale") || q.has("leg_length")) return;
  const std::size_t earlier = q.findings.size();  // the findings made before this test
  const int n = ctx.chain.numJoints();
  const auto board = fitGaps(ctx, gaps, 1, [&](std::size_t i) -> std::optional<MatX> {
    const SE3& T = ctx.problem.observations[i].T_cam_marker;
    MatX A = MatX::Zero(6, 1);
    A.block<3, 1>(3, 0) = T.so3().matrix().transpose() * T.translation();
    return A;
  }, false);
  double board_z2 = 0.0;
  if (board) {
    board_z2 = board->x[0] * board->x[0] / board->C(0, 0);
    if (!std::isfinite(board_z2)) board_z2 = 0.0;
    q.statistics.push_back({"board_scale", board_z2, 1.0, chiSquareSf(board_z2, 1.0)});
  }
  const TargetConfig& t = ctx.rig.target;
  const std::string board_alike =
      board ? "the board's squares " + fixed(t.square_size * (1.0 + board->x[0]) * 1e3, 2) + " mm" : "";
  std::optional<GapFit> legs;
  if (n > 0 && !ctx.problem.offsets.origins) {
    const VecX u = VecX::Zero(6 * n);
    kinematics::KinematicChain::OriginJacobian Ju;
    legs = fitGaps(ctx, gaps, n, [&](std::size_t i) -> std::optional<MatX> {
      const BoardObservation& o = ctx.problem.observations[i];
      if (o.joint_positions.size() != n) return std::nullopt;
      ctx.chain.forwardCorrected(o.joint_positions, u, ctx.sol.T_link_marker, nullptr, &Ju);
      MatX A = MatX::Zero(6, n);
      for (int j = 1; j < n; ++j) A.col(j) = -Ju.block<6, 3>(0, 6 * j + 3) * ctx.chain.originTranslation(j);
      return A;
    }, false);
  }
  bool leg_named = false;
  if (legs) {
    Finding f;
    std::ostringstream which;
    for (int j = 1; j < n; ++j) {
      const std::string& joint = ctx.chain.jointNames()[static_cast<std::size_t>(j)];
      const double z2 = legs->x[j] * legs->x[j] / legs->C(j, j);
      if (!std::isfinite(z2)) continue;  // a link these images do not inform
      q.statistics.push_back({"leg_length " + joint, z2, 1.0, chiSquareSf(z2, 1.0)});
      if (!(z2 > harmful())) continue;
      const double length = ctx.chain.originTranslation(j).norm();
      which << (f.estimate.empty() ? "" : ", ") << "the link before joint " << joint << " "
            << fixed((1.0 + legs->x[j]) * length * 1e3, 1) << " mm (+-"
            << fixed(std::sqrt(legs->C(j, j)) * length * 1e3, 1)
            << "; the URDF's <origin> " << fixed(length * 1e3, 1) << " mm)";
      f.estimate.emplace_back(joint + "_origin_scale", num(1.0 + legs->x[j], 6));
    }
    if (!f.estimate.empty()) {
      leg_named = true;
      f.check = "leg_length";
      f.severity = Severity::Check;
      f.fields = {"robot.urdf"};
      f.message = "the images and the kinematics fit with " + which.str() +
                  ": the leg is not its URDF. Measure the leg and correct the URDF, or give its tolerance as "
                  "robot.kinematic_sigma";
      if (board_z2 > harmful()) {
        f.fields.push_back("target.square_size");
        f.fields.push_back("target.marker_size");
        f.message += ". A board of another size moves the board alike (" + board_alike + " fit too): check "
                     "that rig.yaml's board is the printed one";
      }
      addAssumingTheRest(q, std::move(f), earlier);
    }
  }
  if (board && board_z2 > harmful() && !leg_named) {
    Finding f;
    f.check = "board_scale";
    f.severity = Severity::Check;
    f.fields = {"target.square_size", "target.marker_size"};
    f.message = "the board's squares measure " + fixed(t.square_size * (1.0 + board->x[0]) * 1e3, 2) + " mm (+-" +
                fixed(t.square_size * std::sqrt(board->C(0, 0)) * 1e3, 2) + ") in the images and kinematics; " +
                "rig.yaml says " + fixed(t.square_size * 1e3, 2) + " mm. Measure the printed board and correct " +
                "target.square_size and target.marker_size, or, if it measures what rig.yaml says, the leg's " +
                "lengths in the URDF (they move the board alike)";
    f.estimate = {{"square_size", num(t.square_size * (1.0 + board->x[0]), 6)},
                  {"marker_size", num(t.marker_size * (1.0 + board->x[0]), 6)}};
    addAssumingTheRest(q, std::move(f), earlier);
  }
}

/// The tested parameter of every joint at once, by weighted least squares of
/// the images against the kinematics along J diag(effect): x, its covariance
/// scaled by what the fit leaves over, and the z^2 of each joint. Empty when
/// no image counts or the normal matrix is singular; `held` joints (no
/// effect at all) are held at 0.
struct JointScore {
  VecX x;
  MatX C;
};
std::optional<JointScore> jointScore(const Context& ctx, const std::vector<std::optional<BoardGap>>& gaps,
                                     const JointEffect& effect, const std::vector<bool>& held) {
  const int n = ctx.chain.numJoints();
  MatX H = MatX::Zero(n, n);
  VecX g = VecX::Zero(n);
  double chi2 = 0.0, count = 0.0;
  for (std::size_t i = 0; i < ctx.problem.observations.size(); ++i) {
    if (i >= ctx.sol.used.size() || !ctx.sol.used[i] || !gaps[i]) continue;
    const BoardGap& gap = *gaps[i];
    const MatX A = gap.J * effect(i).asDiagonal();
    H += A.transpose() * gap.W * A;
    g += A.transpose() * gap.W * gap.e;
    chi2 += gap.e.dot(gap.W * gap.e);
    count += 1.0;
  }
  for (int k = 0; k < n; ++k)
    if (held[static_cast<std::size_t>(k)]) H(k, k) = 1.0, g[k] = 0.0;
  const Eigen::LDLT<MatX> ldlt(H);
  if (count == 0.0 || ldlt.info() != Eigen::Success || !ldlt.isPositive()) return std::nullopt;
  JointScore s;
  s.x = ldlt.solve(g);
  const double v =
      leftover(chi2, g.dot(s.x), 6.0 * count - n - 6.0 * static_cast<double>(ctx.problem.camera_names.size()));
  s.C = v * ldlt.solve(MatX::Identity(n, n));
  return s;
}

/// The joints of a score whose parameter is beyond its sigma's tail (and,
/// when `positive`, above 0), as one finding `check` with `message`'s start
/// and the command `fix`; every joint's statistic into q.statistics.
void jointFinding(const Context& ctx, const JointScore& s, const std::vector<bool>& held, bool positive,
                  const std::string& check, const std::string& message, const std::string& fix, Quality& q) {
  std::vector<std::string> fields;
  std::ostringstream which;
  Finding f;
  for (int j = 0; j < ctx.chain.numJoints(); ++j) {
    if (held[static_cast<std::size_t>(j)]) continue;
    const std::string& name = ctx.chain.jointNames()[static_cast<std::size_t>(j)];
    const double z2 = s.x[j] * s.x[j] / s.C(j, j);
    q.statistics.push_back({check + " " + name, z2, 1.0, chiSquareSf(z2, 1.0)});
    if (!(z2 > harmful()) || (positive && s.x[j] <= 0.0)) continue;
    fields.push_back(jointField(ctx, name));
    which << (fields.size() > 1 ? ", " : "") << name << " " << fixed(s.x[j] * 1e3, 1) << " mrad (+-"
          << fixed(std::sqrt(s.C(j, j)) * 1e3, 1) << ")";
    f.estimate.emplace_back(name, num(s.x[j], 4));
  }
  if (fields.empty()) return;
  f.check = check;
  f.severity = Severity::Check;
  f.fields = fields;
  f.message = message + which.str() + ". Estimate " + (check == "backlash" ? "the backlash" : "the offsets") +
              " with the command below";
  f.command = fixCommand(ctx, fix);
  q.add(std::move(f));
}

/// The images against the kinematics along the leg's Jacobian: a joint read
/// o off its true angle moves the board by J o. A joint whose offset is
/// beyond its sigma's tail is named.
void jointOffsetTest(const Context& ctx, const std::vector<std::optional<BoardGap>>& gaps, Quality& q) {
  if (ctx.estimate.joint_offsets) return;
  const auto n = static_cast<std::size_t>(ctx.chain.numJoints());
  const std::vector<bool> none(n, false);
  const VecX ones = VecX::Ones(static_cast<Eigen::Index>(n));
  const auto s = jointScore(ctx, gaps, [&](std::size_t) { return ones; }, none);
  if (s)
    jointFinding(ctx, *s, none, false, "joint_offset",
                 "the images and the kinematics disagree along the leg's joints as a zero offset would: ",
                 "joint-offsets", q);
}

/// Each camera's corners about its own PnP poses: with intrinsics that fit,
/// their chi-square against pixel_sigma is chi-square(2n - 6) per image.
/// Beyond its tail: a radial pattern (corner error growing with the
/// distance from the principal point) is the distortion; none, the corners
/// are noisier than pixel_sigma says. Either is a check only when the
/// camera's images also fit the solution worse than their covariance says
/// (its family flagged): each image's PnP covariance follows its own
/// scatter, so a misfit that leaves the family alone leaves the poses honest.
void cornerScatterTest(const Context& ctx, const Diagnosis& dx, Quality& q) {
  const std::size_t M = ctx.problem.camera_names.size();
  const DetectedCorners& corners = ctx.problem.corners;
  if (corners.px.empty()) return;
  for (std::size_t c = 0; c < M; ++c) {
    const double sigma = ctx.rig.cameras[c].pixel_sigma;
    const CornerScatter sc = cornerScatter(ctx.problem, ctx.models[c], sigma, static_cast<int>(c), &ctx.sol.used);
    const double chi2 = sc.chi2, dof = sc.dof, radial = sc.radial;
    if (!(dof > 0.0)) continue;
    const double p = chiSquareSf(chi2, dof);
    const std::string& name = ctx.problem.camera_names[c];
    q.statistics.push_back({"corner_scatter " + name, chi2, dof, p});
    q.statistics.push_back({"corner_radial " + name, radial, 2.0, chiSquareSf(radial, 2.0)});
    if (p >= kFalseAlarm) continue;
    const double rms = sigma * std::sqrt(chi2 / dof);
    const bool flagged =
        std::find(dx.flagged_cameras.begin(), dx.flagged_cameras.end(), c) != dx.flagged_cameras.end();
    Finding f;
    f.severity = flagged ? Severity::Check : Severity::Note;
    if (radial > harmful()) {
      f.check = "distortion";
      f.fields = {cameraField(ctx, c, "distortion_coeffs"), cameraField(ctx, c, "intrinsics")};
      f.message = "camera " + name + "'s corners miss their own best board pose by " + fixed(rms, 2) +
                  " px RMS (pixel_sigma " + num(sigma) + "), growing with the distance from the principal point: "
                  "its distortion (or focal length) does not fit the lens. Check distortion_model and "
                  "distortion_coeffs, or estimate them with --method corners --estimate intrinsics";
      f.command = fixCommand(ctx, "intrinsics", true);
    } else {
      f.check = "pixel_sigma";
      f.severity = Severity::Note;
      f.fields = {cameraField(ctx, c, "pixel_sigma")};
      f.message = "camera " + name + "'s corners scatter " + fixed(rms, 2) + " px RMS about their own best board "
                  "poses, with no pattern; pixel_sigma says " + num(sigma) + " px. Each image's PnP covariance "
                  "follows its own scatter, so the poses stay honest; set pixel_sigma to what the detector gives";
      f.estimate = {{"pixel_sigma", num(rms, 3)}};
    }
    q.add(std::move(f));
  }
}

/// The severity of an unexplained misfit of variance factor `ratio`: a check
/// when a covariance that much too small would push a camera's NEES past its
/// 0.999 point (22.46) one time in a hundred, i.e. beyond chi-square(6) at
/// 0.999 over chi-square(6) at 0.99 (1.34); a note below, where the inflated
/// covariance covers it.
Severity misfitSeverity(double ratio) {
  static const double kBound = chiSquareQuantile(1.0 - kFalseAlarm, 6.0) / chiSquareQuantile(0.99, 6.0);
  return ratio > kBound ? Severity::Check : Severity::Note;
}

/// What the refitted alternatives made of the misfit: `explained` when the
/// one named leaves none beyond the families' tail, `partly` (its check)
/// when it leaves some.
struct Refitted {
  bool explained = false;
  std::string partly;
};

/// The families no diagnosis explained: their variance factor, and what
/// the covariance then carries. A refitted alternative explains them when
/// what it leaves is within their tail; then, or when a score test named
/// an input (a delay, a zero offset, a mount, a distortion, degrees), no
/// misfit is reported: one wrong input misfits every family. An
/// alternative that leaves a misfit beyond the tail (`partly`) explains
/// only part of it, and the rest is reported as here.
void unexplained(const Context& ctx, const Families& fam, const Diagnosis& dx, const Refitted& refit, Quality& q) {
  if (refit.explained) return;
  static const char* const kDiagnoses[] = {"joint_units", "joint_offset", "time_offset", "mount_prior",
                                           "distortion"};
  for (const char* d : kDiagnoses)
    if (q.has(d)) return;
  const std::string& partly = refit.partly;
  const std::string beyond = partly.empty() ? "no input change explains it"
                                            : "the " + partly + " finding explains only part of it";
  for (std::size_t c : dx.flagged_cameras) {
    const FamilyStat& s = fam.fiducial[c];
    Finding f;
    f.check = "fiducial_fit";
    f.severity = misfitSeverity(s.ratio());
    f.fields = {cameraField(ctx, c, "intrinsics"), cameraField(ctx, c, "pixel_sigma")};
    f.message = "camera " + ctx.problem.camera_names[c] + "'s images fit the solution " +
                fixed(std::sqrt(s.ratio()), 2) + " times worse than their PnP covariance says (chi-square " +
                num(s.chi2) + " for " + num(s.dof) + " degrees of freedom, p = " + num(s.pHigh(), 2) +
                "), and " + beyond + ". Its covariance is inflated by the variance factor " +
                fixed(s.ratio(), 2) + " to cover it";
    f.estimate = {{"variance_factor", num(s.ratio(), 4)}};
    // A rolling shutter skews the image: no one board pose fits it, and PnP's is an approximation.
    if (ctx.method == Method::Pnp && offsets::hasReadout(ctx.problem, ctx.sol, c)) {
      f.fields.push_back(cameraField(ctx, c, "readout_ms"));
      f.message += ". The camera has a rolling shutter: a PnP pose of its skewed images is an approximation; the "
                   "corner method reads each corner at its row's time";
      f.command = fixCommand(ctx, std::vector<std::string>{}, true);
    }
    q.add(std::move(f));
  }
  if (dx.kinematics_flagged) {
    const FamilyStat& s = fam.kinematic;
    Finding f;
    f.check = "kinematic_fit";
    f.severity = misfitSeverity(s.ratio());
    f.fields = {"robot.encoder_sigma", "robot.urdf"};
    const double encoder = ctx.rig.robot.encoder_sigma;
    f.message = "the kinematics fit the board poses " + fixed(std::sqrt(s.ratio()), 2) +
                " times worse than encoder_sigma says (chi-square " + num(s.chi2) + " for " + num(s.dof) +
                " degrees of freedom, p = " + num(s.pHigh(), 2) + (partly.empty() ? "" : "; " + beyond) +
                "): the encoders are noisier than that, or the leg is not the URDF's (link lengths, backlash, "
                "deflection). The cameras' covariances are inflated by the variance factor " + fixed(s.ratio(), 2) +
                " to cover it";
    f.estimate = {{"variance_factor", num(s.ratio(), 4)}};
    if (encoder > 0.0) f.estimate.emplace_back("encoder_sigma", num(encoder * std::sqrt(s.ratio()), 3));
    q.add(std::move(f));
  }
}

}  // namespace

CornerScatter cornerScatter(const CalibrationProblemInput& problem, const vision::CameraModel& m, double sigma,
                            int camera, const std::vector<char>* used) {
  CornerScatter out;
  const DetectedCorners& corners = problem.corners;
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();  // radial fit e_r = a rho + b rho^3
  Eigen::Vector2d y = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    const BoardObservation& o = problem.observations[i];
    if (o.camera != camera || o.corners_count < 4) continue;
    if (used && i < used->size() && !(*used)[i]) continue;
    int k = 0;
    for (std::size_t p = o.corners_begin; p < o.corners_begin + o.corners_count; ++p) {
      const auto uv = m.project(o.T_cam_marker * corners.boardPoint(p));
      if (!uv) continue;
      const Eigen::Vector2d px = corners.pixel(p);
      const Eigen::Vector2d e = *uv - px;
      out.chi2 += e.squaredNorm() / (sigma * sigma);
      ++k;
      const Eigen::Vector2d d((px.x() - m.cx()) / m.fx(), (px.y() - m.cy()) / m.fy());
      const double rho = d.norm();
      if (rho < 1e-9) continue;
      const double er = e.dot(Eigen::Vector2d(d.x() * m.fx(), d.y() * m.fy()).normalized());
      const Eigen::Vector2d b(rho, rho * rho * rho);
      A += b * b.transpose();
      y += b * er;
    }
    if (k > 3) out.dof += 2.0 * k - 6.0;
  }
  out.radial = A.determinant() > 0.0 ? y.dot(A.ldlt().solve(y)) / (sigma * sigma) : 0.0;
  return out;
}

std::vector<double> covarianceInflation(const Families& fam, const Diagnosis& dx, std::size_t cameras) {
  std::vector<double> out(cameras, 1.0);
  const double kin = dx.kinematics_flagged ? std::max(1.0, fam.kinematic.ratio()) : 1.0;
  for (std::size_t c = 0; c < cameras; ++c) out[c] = kin;
  for (std::size_t c : dx.flagged_cameras) out[c] = std::max(out[c], fam.fiducial[c].ratio());
  return out;
}

/// The images against the kinematics along the leg's Jacobian, against the
/// direction of motion: a joint with gear play b stands at its reading plus
/// lambda b, which moves the board by J diag(lambda) b (lambda the play
/// operator's lag over the joint log's smooth fit, as --estimate backlash
/// models it, from the trajectory the offsets already fitted when they did).
/// The play is not known here, and the lag's shape depends on it (it turns
/// over the motor's travel of b after each reversal): it is computed with
/// rig.yaml's backlash_sigma (else its default), the play --estimate backlash
/// starts from, at least the encoder sigma. A play that is positive and
/// beyond its sigma's tail is named; joints that do not move both ways are
/// not tested.
void backlashTest(const Context& ctx, const std::vector<std::optional<BoardGap>>& gaps, Quality& q) {
  if (ctx.estimate.backlash || ctx.chain.numJoints() == 0 || ctx.joints.stamps_ns.size() < 2) return;
  std::shared_ptr<const JointLogTrajectory> trajectory = ctx.problem.offsets.trajectory;
  if (!trajectory) {
    try {
      trajectory = std::make_shared<const JointLogTrajectory>(
          ctx.joints, columnIndices(ctx.joints, ctx.chain.jointNames(), ctx.joints_input), ctx.joints_input);
    } catch (const std::exception&) {
      return;  // a log the smooth fit cannot take: the joint log's own checks speak of it
    }
  }
  VecX play;
  try {
    play = offsets::backlashPriorSigma(ctx.rig, ctx.chain);
  } catch (const std::exception&) {  // a map that does not fit the chain: --estimate backlash says so
    play = VecX::Constant(ctx.chain.numJoints(), kDefaultBacklashSigma);
  }
  const std::shared_ptr<const MotorPath> path = motorPath(trajectory, ctx.joints);
  const std::vector<bool> reversing = backlashReversing(*path, ctx.sigma_q);
  std::vector<bool> still;
  for (Eigen::Index k = 0; k < play.size(); ++k) {
    still.push_back(!reversing[static_cast<std::size_t>(k)]);
    play[k] = still.back() ? 0.0 : std::max(play[k], ctx.sigma_q[k]);
  }
  const BacklashLag lagOf(path, play);
  const auto lag = [&](std::size_t i) { return lagOf.at(ctx.problem.observations[i].stamp_ns); };
  const auto s = jointScore(ctx, gaps, lag, still);
  if (s)
    jointFinding(ctx, *s, still, true, "backlash",
                 "the images and the kinematics disagree against the joints' direction of motion, as gear play "
                 "would: ",
                 "backlash", q);
}

void diagnose(const Context& ctx, const Families& fam, const Diagnosis& dx, Quality& q) {
  const bool flagged = dx.kinematics_flagged || !dx.flagged_cameras.empty();
  Refitted refit;
  // Refits need the PnP graph and its measurements as solved: not with the
  // corner graph or estimated time or joint offsets or backlash, whose graphs
  // differ (the leg's origin corrections of robot.kinematic_sigma are rebuilt
  // with it).
  if (flagged && ctx.method == Method::Pnp && !ctx.problem.offsets.exposureTiming() && !ctx.problem.offsets.joint_offsets &&
      !ctx.problem.offsets.backlash &&
      !q.has("joint_units")) {
    const double chi2_0 = refitChi2(ctx.problem, ctx.sol);
    if (std::isfinite(chi2_0)) {
      const Misfit misfit(fam, dx);
      std::optional<Explanation> best;
      // The scales first: a board measured wrong is the commonest of these
      // mistakes and its refits start near the solution. A scale that leaves
      // no misfit beyond the tail is the explanation; the joints' refits,
      // which start far from theirs, are then not needed.
      tryScales(ctx, chi2_0, misfit, best);
      if (!best || misfit.leftAfter(best->drop)) tryJoints(ctx, chi2_0, misfit, best);
      if (best) {
        const double z2 = misfit.significance(best->drop);
        q.statistics.push_back({"alternative " + best->finding.check, z2, 6.0, chiSquareSf(z2, 6.0)});
        if (misfit.leftAfter(best->drop))
          refit.partly = best->finding.check;
        else
          refit.explained = true;
        q.add(std::move(best->finding));
      }
    }
  }
  // The score tests and the corners' scatter read each image's PnP pose
  // through rig.yaml's intrinsics: with the intrinsics estimated, those are
  // not the solution's.
  if (ctx.estimate.intrinsics) {
    unexplained(ctx, fam, dx, refit, q);
    return;
  }
  if (!q.has("joint_sign") && !q.has("joint_swap") && !q.has("joint_units")) {
    // Each image's board by its camera against the kinematics, once for both tests.
    std::vector<std::optional<BoardGap>> gaps;
    gaps.reserve(ctx.problem.observations.size());
    for (std::size_t k = 0; k < ctx.problem.observations.size(); ++k) gaps.push_back(boardGap(ctx, k));
    timeOffsetTest(ctx, gaps, q);
    jointOffsetTest(ctx, gaps, q);
    backlashTest(ctx, gaps, q);
    rollingShutterTest(ctx, gaps, q);
    intrinsicsTest(ctx, gaps, q);
    sizeTests(ctx, gaps, q);
  }
  cornerScatterTest(ctx, dx, q);
  unexplained(ctx, fam, dx, refit, q);
}

}  // namespace fgcal::apps::quality
