// The failure diagnosis of failure.hpp.
#include "quality/failure.hpp"

#include "quality/assess.hpp"
#include "quality/chi_square.hpp"
#include "quality/words.hpp"

#include "fgcal/vision/pnp.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <iomanip>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace fgcal::apps::quality {

namespace {

std::string percent(double f) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(0) << 100.0 * f << " %";
  return s.str();
}

bool agree(const SE3& a, const SE3& b) {
  constexpr double kTol = 0.05;  // 3 deg, 5 cm: the initializer's rule, on a.minus(b) = [w v]
  // Most pairs of a failed solve disagree: two bounds on the difference's
  // log, without the log, turn those away. Its angle |w| is the relative
  // rotation's, whose trace is 1 + 2 cos|w|. Its |v| is at least
  // |t_b - t_a|: v = V(w)^-1 R_a^T (t_b - t_a), and V's singular values are
  // 1 and 2 sin(|w|/2) / |w| <= 1. Both bounds keep a margin: a pair they
  // pass is judged by the log itself, so the answer is the log's.
  static const double kMinTrace = 1.0 + 2.0 * std::cos(kTol * (1.0 + 1e-6));
  const double trace = a.so3().matrix().cwiseProduct(b.so3().matrix()).sum();
  if (trace < kMinTrace) return false;
  if ((b.translation() - a.translation()).squaredNorm() > kTol * kTol * (1.0 + 1e-6)) return false;
  const Vec6 d = a.minus(b);
  return d.head<3>().norm() < kTol && d.tail<3>().norm() < kTol;
}

/// The largest number of proposals that agree with one of them (sampled: bounded O(n^2)).
std::size_t consensus(const std::vector<SE3>& p) {
  const std::size_t stride = std::max<std::size_t>(1, p.size() / 150);
  std::size_t best = 0;
  for (std::size_t i = 0; i < p.size(); i += stride) {
    std::size_t support = 0;
    for (const SE3& q : p) support += agree(p[i], q);
    best = std::max(best, support);
  }
  return best;
}

struct Alternative {
  double agreement = 0.0;
  Finding finding;
  /// The change to the joint log's columns (by chain index) it stands for; none for another marker link.
  std::function<void(VecX&)> change;
};

/// Each observation's T_base_link with the chain's joints changed by `change`.
std::vector<SE3> rejointed(const FailureContext& ctx, const std::function<void(VecX&)>& change) {
  std::vector<SE3> out;
  for (const BoardObservation& o : ctx.problem.observations) {
    VecX q = o.joint_positions;
    if (q.size() != ctx.chain.numJoints()) {
      out.push_back(o.T_base_link);
      continue;
    }
    change(q);
    out.push_back(ctx.chain.forward(q));
  }
  return out;
}

void consider(double score, Finding f, std::optional<Alternative>& best,
              std::function<void(VecX&)> change = nullptr) {
  if (!best || score > best->agreement) best = Alternative{score, std::move(f), std::move(change)};
}

/// The chain's joint log with `change` applied to every sample.
JointLog changedLog(const FailureContext& ctx, const std::function<void(VecX&)>& change) {
  JointLog log = ctx.joints;
  const auto& names = ctx.chain.jointNames();
  std::vector<int> cols;
  for (const std::string& n : names) cols.push_back(log.column(n));
  if (std::find(cols.begin(), cols.end(), -1) != cols.end()) return log;
  for (Eigen::Index k = 0; k < log.positions.rows(); ++k) {
    VecX q(static_cast<Eigen::Index>(cols.size()));
    for (std::size_t j = 0; j < cols.size(); ++j) q[static_cast<Eigen::Index>(j)] = log.positions(k, cols[j]);
    change(q);
    for (std::size_t j = 0; j < cols.size(); ++j) log.positions(k, cols[j]) = q[static_cast<Eigen::Index>(j)];
  }
  return log;
}

void tryJoints(const FailureContext& ctx, std::optional<Alternative>& best) {
  const auto& names = ctx.chain.jointNames();
  const int n = ctx.chain.numJoints();
  auto field = [&](int j) { return ctx.joints_input + ":" + names[static_cast<std::size_t>(j)]; };
  for (int j = 0; j < n; ++j) {
    const auto flip = [j](VecX& q) { q[j] = -q[j]; };
    const double a = agreement(ctx.problem, rejointed(ctx, flip), ctx.judgedMount());
    consider(a,
             {"joint_sign", Severity::Unusable, {field(j)},
              "with joint " + names[static_cast<std::size_t>(j)] + "'s readings negated, " + percent(a) +
                  " of the images agree on their camera's pose: its direction in the log is reversed against the "
                  "URDF's axis. Negate the column, or fix the joint's axis",
              {{"sign", "-1"}},
              {}},
             best, flip);
  }
  for (int x = 0; x < n; ++x)
    for (int y = x + 1; y < n; ++y) {
      const auto swap = [x, y](VecX& q) { std::swap(q[x], q[y]); };
      const double a = agreement(ctx.problem, rejointed(ctx, swap), ctx.judgedMount());
      consider(a,
               {"joint_swap", Severity::Unusable, {field(x), field(y)},
                "with joints " + names[static_cast<std::size_t>(x)] + " and " + names[static_cast<std::size_t>(y)] +
                    " swapped, " + percent(a) + " of the images agree on their camera's pose: the log's columns "
                    "name the wrong joints",
                {},
                {}},
               best, swap);
    }
}

/// The other leaves of the URDF as the board's link, their joints read from the whole log.
void tryMarkerLinks(const FailureContext& ctx, std::optional<Alternative>& best) {
  if (!ctx.all_joints) return;
  for (const std::string& leaf : ctx.robot.leafLinks()) {
    if (leaf == ctx.chain.tipLink() || leaf == ctx.chain.baseLink()) continue;
    std::vector<SE3> links;
    try {
      const kinematics::KinematicChain chain = ctx.robot.chain(ctx.chain.baseLink(), leaf);
      if (chain.numJoints() == 0) continue;
      std::vector<int> columns;
      for (const std::string& j : chain.jointNames()) {
        const int c = ctx.all_joints->column(j);
        if (c < 0) throw std::runtime_error("joint not logged");
        columns.push_back(c);
      }
      for (const BoardObservation& o : ctx.problem.observations) {
        std::string why;
        const auto q = interpolate(*ctx.all_joints, o.stamp_ns, columns, &why);
        if (!q) throw std::runtime_error(why);
        links.push_back(chain.forward(*q));
      }
    } catch (const std::exception&) {
      continue;  // a leaf whose joints the log does not hold cannot be tried
    }
    const double a = agreement(ctx.problem, links, ctx.judgedMount());
    consider(a,
             {"marker_link", Severity::Unusable, {"robot.marker_link"},
              "with the board on " + leaf + ", " + percent(a) + " of the images agree on their camera's pose; on " +
                  ctx.chain.tipLink() + " (rig.yaml) they do not: the board is fixed to another link",
              {{"marker_link", leaf}},
              {}},
             best);
  }
}

/// The board's scale, then each camera's depth scale, on a grid of 1 %
/// from 0.70 to 1.40 (what the scale hypotheses of a solved graph fit).
void tryScales(const FailureContext& ctx, std::optional<Alternative>& best) {
  std::vector<SE3> links;
  for (const BoardObservation& o : ctx.problem.observations) links.push_back(o.T_base_link);
  const int M = static_cast<int>(ctx.problem.camera_names.size());
  for (int camera = -1; camera < (M > 1 ? M : 0); ++camera) {
    double best_k = 1.0, best_a = -1.0;
    for (int step = 70; step <= 140; ++step) {
      const double k = step / 100.0;
      const double a = agreement(ctx.problem, links, ctx.judgedMount(), k, camera);
      if (a > best_a) best_a = a, best_k = k;
    }
    if (camera < 0) {
      const TargetConfig& t = ctx.rig.target;
      consider(best_a,
               {"board_scale", Severity::Unusable, {"target.square_size", "target.marker_size"},
                "with the board " + percent(1.0 / best_k - 1.0) + " larger than rig.yaml says, " + percent(best_a) +
                    " of the images agree on their camera's pose: measure the printed board",
                {{"square_size", num(t.square_size / best_k, 4)}, {"marker_size", num(t.marker_size / best_k, 4)}},
                {}},
               best);
    } else {
      const std::string& name = ctx.problem.camera_names[static_cast<std::size_t>(camera)];
      consider(best_a,
               {"camera_scale", Severity::Unusable, {"cameras[" + name + "].intrinsics"},
                "with camera " + name + "'s depths " + percent(1.0 / best_k - 1.0) + " longer, " + percent(best_a) +
                    " of the images agree on their camera's pose: its focal length does not fit the lens; check that "
                    "these are this camera's intrinsics",
                {},
                {}},
               best);
    }
  }
}

/// How many of camera c's images agree on its pose (agreement()'s count for
/// one camera) when each is posed by PnP through camera m's lens model, from
/// the pose rig.yaml's model gave; m == c: as given. An image the other model
/// cannot pose does not agree.
std::size_t agreeingWithLens(const FailureContext& ctx, int c, int m) {
  const SE3 failed(SO3(), Vec3::Constant(std::nan("")));  // agrees with nothing
  std::vector<SE3> proposals;
  std::vector<Vec3> points;
  std::vector<vision::Vec2> pixels;
  for (const BoardObservation& o : ctx.problem.observations) {
    if (o.camera != c) continue;
    SE3 T_cam_marker = o.T_cam_marker;
    if (m != c) {
      points.clear();
      pixels.clear();
      ctx.problem.corners.appendCorrespondences(o.corners_begin, o.corners_count, points, pixels);
      try {
        const vision::PoseEstimate e =
            vision::refinePose((*ctx.models)[static_cast<std::size_t>(m)], o.T_cam_marker, points, pixels);
        T_cam_marker = e.converged ? e.T_cam_marker : failed;
      } catch (const std::exception&) {
        T_cam_marker = failed;
      }
    }
    proposals.push_back(o.T_base_link * ctx.judgedMount() * T_cam_marker.inverse());
  }
  return consensus(proposals);
}

/// Rig.yaml's lens models given to the wrong cameras: each pair of cameras
/// with their intrinsics swapped, and each camera with another's. Each
/// camera's images are posed once through each lens model; the alternatives
/// combine those counts.
void tryOtherIntrinsics(const FailureContext& ctx, std::optional<Alternative>& best) {
  const std::size_t M = ctx.problem.camera_names.size();
  const std::size_t total = ctx.problem.observations.size();
  if (!ctx.models || ctx.problem.corners.px.empty() || M < 2 || total == 0) return;
  std::vector<std::vector<std::size_t>> agreeing(M, std::vector<std::size_t>(M));  // [camera][lens]
  std::size_t as_given = 0;
  for (std::size_t c = 0; c < M; ++c)
    for (std::size_t m = 0; m < M; ++m) {
      agreeing[c][m] = agreeingWithLens(ctx, static_cast<int>(c), static_cast<int>(m));
      if (m == c) as_given += agreeing[c][c];
    }
  auto fields = [&](std::size_t c) {
    const std::string n = "cameras[" + ctx.problem.camera_names[c] + "]";
    return std::vector<std::string>{n + ".intrinsics", n + ".distortion_coeffs"};
  };
  auto share = [&](std::size_t n) { return static_cast<double>(n) / static_cast<double>(total); };
  for (std::size_t a = 0; a < M; ++a)
    for (std::size_t b = 0; b < M; ++b) {
      if (a == b) continue;
      const std::string& na = ctx.problem.camera_names[a];
      const std::string& nb = ctx.problem.camera_names[b];
      const double one = share(as_given - agreeing[a][a] + agreeing[a][b]);
      consider(one,
               {"intrinsics", Severity::Unusable, fields(a),
                "with camera " + nb + "'s intrinsics for camera " + na + ", " + percent(one) +
                    " of the images agree on their camera's pose: rig.yaml gives " + na +
                    " intrinsics that are not its lens's (copied from another camera?)",
                {},
                {}},
               best);
      if (b < a) continue;
      const double both =
          share(as_given - agreeing[a][a] - agreeing[b][b] + agreeing[a][b] + agreeing[b][a]);
      std::vector<std::string> f = fields(a);
      for (const std::string& x : fields(b)) f.push_back(x);
      consider(both,
               {"intrinsics", Severity::Unusable, f,
                "with cameras " + na + " and " + nb + "'s intrinsics swapped, " + percent(both) +
                    " of the images agree on their camera's pose: rig.yaml gives each camera the other's lens",
                {},
                {}},
               best);
    }
}

/// Corners that miss their own best board pose: in every camera, the board's
/// layout is not the printed one; in one, that camera's intrinsics.
std::optional<Finding> scatterFinding(const FailureContext& ctx) {
  if (!ctx.models || ctx.problem.corners.px.empty()) return std::nullopt;
  std::vector<std::string> missing;
  std::string worst;
  double worst_rms = 0.0;
  for (std::size_t c = 0; c < ctx.problem.camera_names.size(); ++c) {
    const double sigma = ctx.rig.cameras[c].pixel_sigma;
    const CornerScatter s = cornerScatter(ctx.problem, (*ctx.models)[c], sigma, static_cast<int>(c));
    if (!(s.dof > 0.0) || chiSquareSf(s.chi2, s.dof) >= kFalseAlarm) continue;
    const double rms = sigma * std::sqrt(s.chi2 / s.dof);
    if (rms < 2.0 * sigma) continue;  // noisier than pixel_sigma, not wrong: the PnP covariance follows it
    missing.push_back(ctx.problem.camera_names[c]);
    if (rms > worst_rms) worst_rms = rms, worst = ctx.problem.camera_names[c];
  }
  if (missing.empty()) return std::nullopt;
  if (missing.size() == ctx.problem.camera_names.size() && missing.size() > 1)
    return Finding{"board_layout", Severity::Unusable,
                   {"target.squares_x", "target.squares_y", "target.square_size", "target.marker_size",
                    "target.dictionary"},
                   "in every camera the detected corners miss their own best board pose (" + worst + ": " +
                       num(worst_rms, 3) + " px RMS): the board rig.yaml describes is not the printed one (rows and "
                       "columns swapped, another marker size or dictionary)",
                   {},
                   {}};
  return Finding{"intrinsics", Severity::Unusable,
                 {"cameras[" + worst + "].intrinsics", "cameras[" + worst + "].distortion_coeffs"},
                 "camera " + worst + "'s detected corners miss their own best board pose by " + num(worst_rms, 3) +
                     " px RMS: its intrinsics or distortion are not this lens's (another camera's?)",
                 {},
                 {}};
}

}  // namespace

double agreement(const CalibrationProblemInput& problem, const std::vector<SE3>& T_base_link, const SE3& mount,
                 double scale, int camera) {
  const std::size_t M = problem.camera_names.size();
  std::vector<std::vector<SE3>> proposals(M);
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    const BoardObservation& o = problem.observations[i];
    SE3 pose = o.T_cam_marker;
    if (scale != 1.0 && (camera < 0 || camera == o.camera))  // as scaled() does it, without copying the problem
      pose = SE3(pose.so3(), scaledTranslation(pose.translation(), scale, camera >= 0));
    proposals[static_cast<std::size_t>(o.camera)].push_back(T_base_link[i] * mount * pose.inverse());
  }
  std::size_t agreeing = 0, total = 0;
  for (const auto& p : proposals) {
    agreeing += consensus(p);
    total += p.size();
  }
  return total ? static_cast<double>(agreeing) / static_cast<double>(total) : 0.0;
}

std::vector<Finding> diagnoseFailure(const FailureContext& ctx) {
  const std::optional<Finding> limits = jointLimitFinding(ctx.chain, ctx.sigma_q, ctx.joints, ctx.joints_input);
  if (limits && limits->check == "joint_units") return {*limits};  // degrees: nothing else can be judged
  std::vector<SE3> given;
  for (const BoardObservation& o : ctx.problem.observations) given.push_back(o.T_base_link);
  const double now = agreement(ctx.problem, given, ctx.judgedMount());
  std::optional<Alternative> best;
  tryJoints(ctx, best);
  tryMarkerLinks(ctx, best);
  tryScales(ctx, best);
  tryOtherIntrinsics(ctx, best);
  // Named when at least a tenth of the images disagree as given (on correct
  // data all but a few in a thousand agree) and the alternative brings at
  // least half of them into agreement: a ratio, not a doubling, as when one
  // camera's images agree as given (a lens model that only biases its poses).
  const bool explains = best && best->agreement >= 0.5 && 1.0 - now >= 0.1 &&
                        1.0 - best->agreement <= 0.5 * (1.0 - now);
  if (!explains) {
    if (limits) return {*limits};
    if (auto scatter = scatterFinding(ctx)) return {*scatter};
    return {};
  }
  best->finding.message += " (as given: " + percent(now) + ")";
  // Readings beyond the limits that the alternative puts back within them are its consequence.
  if (limits && !(best->change && !jointLimitFinding(ctx.chain, ctx.sigma_q, changedLog(ctx, best->change),
                                                      ctx.joints_input)))
    return {best->finding, *limits};
  return {best->finding};
}

}  // namespace fgcal::apps::quality
