#include "fgcal/apps/calibration_problem.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <optional>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "calibration/graph_parts.hpp"
#include "calibration/offset_graph.hpp"
#include "calibration/refit.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/core/marginals.hpp"
#include "fgcal/factors/kinematic_factor.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"

namespace fgcal::apps {

namespace {

using detail::addObservabilityWarnings;
using detail::chiSquare;
using detail::groupInstants;
using detail::initialCameraPoses;
using detail::mountPriorNoise;

constexpr Key kMount = key('m', 0);
Key cameraKey(std::size_t i) { return key('c', i); }
Key boardKey(std::size_t j) { return key('b', j); }




/// The offsets' current values, to start the next solve from (and the
/// backlash's, to compute its lag from).
void keepOffsets(const Values& solved, Values* state) {
  for (Key k : solved.keys())
    if (keySymbol(k) == keySymbol(offsets::timeOffsetKey(0)) || keySymbol(k) == keySymbol(offsets::readoutKey(0)) ||
        k == offsets::kJointOffsets || k == offsets::kOrigins || k == offsets::kBacklash)
      state->insertOrAssign(k, solved.at<VecX>(k));
}

struct Graph {
  FactorGraph graph;
  Values values;
  std::vector<std::pair<std::size_t, std::size_t>> fiducial;  // (factor index, observation)
  std::vector<std::size_t> kinematic;                         // factor index per instant
  std::vector<std::vector<std::size_t>> groups;               // observations per instant
  std::vector<Key> fixed;
  std::shared_ptr<const BacklashLag> backlash_lag;  // the kinematic factors' lag, with backlash
};

/// Checks the settings; true when the mount is held fixed.
bool checkSettings(const CalibrationProblemInput& in) {
  if (in.camera_names.empty()) throw DataError("no camera to calibrate");
  const bool mount_fixed = in.fix_mount || (in.mount_sigma_m <= 0.0 && in.mount_sigma_rad <= 0.0);
  if (!mount_fixed && (!(in.mount_sigma_m > 0.0) || !(in.mount_sigma_rad > 0.0)))
    throw DataError("mount_sigma must be both positive (estimate the mount) or both zero (hold it fixed)");
  if (const std::string problem = fiducialCovarianceScaleProblem(in.fiducial_covariance_scale); !problem.empty())
    throw DataError("fiducial_covariance_scale: " + problem);
  return mount_fixed;
}


/// Degenerate motion: with the mount estimated, a leg that never moves
/// cannot tell the mount from the cameras; the answer would only echo the
/// mount prior. Say so rather than return a confident-looking result.
void checkMotion(const CalibrationProblemInput& in, bool mount_fixed) {
  if (mount_fixed || in.observations.empty() || in.observations.front().joint_positions.size() == 0) return;
  const Eigen::Index nq = in.observations.front().joint_positions.size();
  VecX mean = VecX::Zero(nq), sq = VecX::Zero(nq);
  int n = 0;
  for (const auto& o : in.observations)
    if (o.joint_positions.size() == nq && o.joint_positions.allFinite()) {
      mean += o.joint_positions;
      sq += o.joint_positions.cwiseAbs2();
      ++n;
    }
  if (n == 0) return;
  mean /= n;
  const double spread = std::sqrt(std::max(0.0, (sq / n - mean.cwiseAbs2()).maxCoeff()));
  if (spread >= 1e-3) return;
  std::ostringstream msg;
  msg << "degenerate motion: the leg joints barely move over the " << n
      << " images (largest joint standard deviation " << spread
      << " rad); the board mount and the camera poses cannot be told apart. Move the leg through "
         "different configurations, or hold the mount fixed (--fix-mount) if it is known";
  throw DataError(msg.str());
}

/// The observations of `cams` still in (DataError when a camera keeps fewer than 3).
std::vector<std::size_t> selectObservations(const CalibrationProblemInput& in, const std::vector<char>& used,
                                            const std::vector<std::size_t>& cams) {
  std::vector<std::size_t> selected;
  for (std::size_t i = 0; i < in.observations.size(); ++i)
    if (used[i] &&
        std::find(cams.begin(), cams.end(), static_cast<std::size_t>(in.observations[i].camera)) != cams.end())
      selected.push_back(i);
  for (std::size_t c : cams) {
    const auto n = std::count_if(selected.begin(), selected.end(),
                                 [&](std::size_t i) { return in.observations[i].camera == static_cast<int>(c); });
    if (n < 3) {
      std::ostringstream msg;
      msg << "camera " << in.camera_names[c] << " keeps " << n
          << " image(s) after rejecting those inconsistent with the others; at least 3 are needed";
      throw DataError(msg.str());
    }
  }
  return selected;
}

/// What a graph is built over: the cameras, the observations still in, where
/// the cameras start, the mount's state, whether fiducials are robust, and
/// where the offsets start (the previous solve's; zero when absent).
struct GraphSpec {
  const std::vector<std::size_t>& cams;
  const std::vector<char>& used;
  const std::vector<SE3>& init;
  bool mount_fixed = false;
  bool robust = false;
  const Values* offsets = nullptr;
};

/// One instant's kinematic factor and its board's fiducial factors.
void addInstant(const CalibrationProblemInput& in, const std::vector<std::size_t>& group, std::size_t j,
                const RobustKernel::Ptr& kernel, Graph& g) {
  const BoardObservation& first = in.observations[group.front()];
  g.values.insert(boardKey(j), first.T_base_link * in.mount_prior);
  g.kinematic.push_back(g.graph.size());
  // With joint offsets the kinematics are re-evaluated at q + o, and with
  // time offsets each image sees the board at its exposure (offset_graph.hpp).
  g.graph.add(offsets::kinematicFactor(in.offsets, g.backlash_lag.get(), boardKey(j), kMount, first.T_base_link,
                                       first.joint_positions, first.stamp_ns, detail::kinematicNoise(first, in)));
  for (std::size_t i : group) {
    const BoardObservation& o = in.observations[i];
    const auto camera = static_cast<std::size_t>(o.camera);
    g.fiducial.emplace_back(g.graph.size(), i);
    g.graph.add(offsets::imageFactor(
        in.offsets,
        std::make_shared<RelativePoseFactor>(cameraKey(camera), boardKey(j), o.T_cam_marker,
                                             NoiseModel::fromCovariance(in.fiducial_covariance_scale * o.covariance.matrix())),
        1, kMount, camera, first.stamp_ns, o.stamp_ns, offsets::meanRow(in, i), kernel));
  }
}

/// The graph over a set of cameras (all for F2, one at a time for F1) and
/// the observations still in.
Graph buildGraph(const CalibrationProblemInput& in, const GraphSpec& spec) {
  Graph g;
  const std::vector<std::size_t> selected = selectObservations(in, spec.used, spec.cams);
  g.groups = groupInstants(in.observations, selected, in.sync_tolerance_ms * 1e6, !in.single_camera);
  for (std::size_t c : spec.cams) g.values.insert(cameraKey(c), spec.init[c]);
  g.values.insert(kMount, in.mount_prior);
  if (spec.mount_fixed)
    g.fixed.push_back(kMount);
  else
    g.graph.emplace<PriorFactorSE3>(kMount, in.mount_prior, mountPriorNoise(in.mount_sigma_m, in.mount_sigma_rad));
  offsets::addVariables(in.offsets, spec.cams, spec.offsets, g.graph, g.values);
  g.backlash_lag = offsets::backlashLag(in.offsets, spec.offsets);
  const RobustKernel::Ptr kernel = spec.robust ? huber(std::sqrt(kFiducialGate)) : nullptr;
  for (std::size_t j = 0; j < g.groups.size(); ++j) addInstant(in, g.groups[j], j, kernel, g);
  return g;
}

OptimizerResult solveGraph(const Graph& g) {
  const std::size_t instants = g.groups.size();
  if (instants < 3) throw DataError("only " + std::to_string(instants) + " instants with a detected board");
  OptimizerOptions opt;
  opt.fixed_keys = g.fixed;
  opt.max_iterations = 200;
  // The board poses eliminated as their factors are evaluated, nothing of H
  // kept per instant: a long recording's solve needs the memory of its
  // factors, not of its Hessian (docs/studies/calibrate_memory.md). That
  // needs a small reduced system (the cameras, the mount, the offsets); a rig
  // of more cameras than it takes is solved with H stored.
  int reduced = 0;
  for (std::size_t i = 0; i < g.values.size(); ++i)
    if (keySymbol(g.values.keys()[i]) != keySymbol(boardKey(0))) reduced += g.values.variableAt(i).dim();
  opt.linear_solver = reduced <= OptimizerOptions::kStreamedMaxReducedColumns
                          ? OptimizerOptions::LinearSolver::StreamedSchurComplement
                          : OptimizerOptions::LinearSolver::SchurComplement;
  OptimizerResult r = optimize(g.graph, g.values, opt);
  if (r.termination == Termination::NotPositiveDefinite || r.termination == Termination::NonFiniteCost)
    throw DataError("the calibration problem is degenerate: " + r.message);
  return r;
}

/// The chi-square gate on every fiducial factor of `g` at `at`: records the
/// chi-square, rejects those above the gate; true when any was rejected.
bool gate(const CalibrationProblemInput& in, const Graph& g, const Values& at, CalibrationSolution& sol) {
  bool rejected_any = false;
  for (const auto& [f, i] : g.fiducial) {
    const double chi2 = chiSquare(g.graph[f], at);
    sol.fiducial_chi2[i] = chi2;
    if (chi2 > kFiducialGate) {
      sol.used[i] = 0;
      std::ostringstream why;
      why << "inconsistent with the other images (chi-square " << chi2 << " > " << kFiducialGate
          << ", against its PnP covariance x " << in.fiducial_covariance_scale << ")";
      sol.rejected.push_back({i, why.str()});
      rejected_any = true;
    }
  }
  return rejected_any;
}

/// The state carried from one camera set to the next.
struct SolveState {
  const CalibrationProblemInput& in;
  bool mount_fixed = false;
  std::vector<SE3> init;  ///< where each camera starts: the previous solve's estimate
  CalibrationSolution sol;
  SE3 mount_estimate;
  Mat6 mount_cov = Mat6::Zero();
  std::size_t mount_instants = 0;  ///< F1: the mount of the camera with the most instants is reported
  Values offsets{};                ///< the offsets of the previous solve, when estimated
  std::size_t offset_instants = 0;  ///< F1: likewise the joint offsets
};

/// A solve's values reduced to the cameras of `cams` and the mount: what
/// is kept of it (the board poses go to instant_estimates).
Values camerasAndMount(const Values& v, const std::vector<std::size_t>& cams) {
  Values out;
  for (std::size_t c : cams) out.insert(cameraKey(c), v.at<SE3>(cameraKey(c)));
  out.insert(kMount, v.at<SE3>(kMount));
  return out;
}

/// The final solve's warnings, camera estimates with their marginal
/// covariances, the mount when this set saw the most instants, and its board
/// poses. The board poses are recorded last, once `g`'s factors and values
/// are released (its instant groups are moved out): on a long recording the
/// two together would be the calibration's peak of memory.
void recordFinal(SolveState& st, const std::vector<std::size_t>& cams, const std::string& cam_list, Graph& g,
                 const OptimizerResult& r) {
  const CalibrationProblemInput& in = st.in;
  CalibrationSolution& sol = st.sol;
  const std::size_t instants = g.groups.size();
  detail::addSolveFindings(sol, instants, in.single_camera, cam_list, r);
  std::vector<Key> keep;
  for (std::size_t c : cams) keep.push_back(cameraKey(c));
  if (!st.mount_fixed) keep.push_back(kMount);
  std::vector<MatX> cov;
  if (in.offsets.any()) {
    // With offsets: their estimates, and the marginals with the unobserved ones held (offset_graph.hpp).
    std::vector<offsets::CameraSpan> spans;
    for (std::size_t c : cams) spans.push_back(offsets::cameraSpan(in, c, cameraKey(c)));
    offsets::Summary summary = offsets::summarize(in.offsets, g.graph, g.fixed, r.values, spans,
                                                  st.mount_fixed ? std::nullopt : std::optional<Key>(kMount));
    summary.estimates.backlash_lag = g.backlash_lag;
    const MatX joint = summary.marginals.jointCovariance(keep);
    for (std::size_t k = 0; k < keep.size(); ++k) cov.push_back(joint.block<6, 6>(6 * k, 6 * k));
    detail::addCrossCovariances(cams, joint, sol);
    offsets::merge(std::move(summary.estimates), instants, &st.offset_instants, &sol.offsets);
  } else {
    // The cameras' and the mount's marginals with the board poses eliminated
    // one by one: the memory of a few 6x6 blocks, not of the whole system's factor.
    MatX joint;
    try {
      joint = Marginals::reducedJointCovariance(g.graph, r.values, keep, g.fixed);
    } catch (const DegenerateSystem& e) {  // the data leave a direction free: exit 1, not a bug
      throw DataError(e.what());
    }
    for (std::size_t k = 0; k < keep.size(); ++k) cov.push_back(joint.block<6, 6>(6 * k, 6 * k));
    detail::addCrossCovariances(cams, joint, sol);
  }
  for (std::size_t k = 0; k < cams.size(); ++k) {
    const std::size_t c = cams[k];
    CameraEstimate& ce = sol.cameras[c];
    ce.name = in.camera_names[c];
    ce.T_base_cam = r.values.at<SE3>(cameraKey(c));
    ce.covariance = cov[k];
    ce.observations_used = static_cast<int>(std::count_if(g.fiducial.begin(), g.fiducial.end(), [&](auto& p) {
      return in.observations[p.second].camera == static_cast<int>(c);
    }));
  }
  sol.instants += static_cast<int>(instants);
  if (!st.mount_fixed && instants > st.mount_instants) {
    st.mount_instants = instants;
    st.mount_estimate = r.values.at<SE3>(kMount);
    st.mount_cov = cov.back();
  }
  std::vector<double> kinematic_chi2(instants);
  for (std::size_t j = 0; j < instants; ++j) kinematic_chi2[j] = chiSquare(g.graph[g.kinematic[j]], r.values);
  g.graph = FactorGraph();
  g.values = Values();
  g.fiducial = {};
  sol.instant_estimates.reserve(sol.instant_estimates.size() + instants);
  for (std::size_t j = 0; j < instants; ++j) {
    InstantEstimate ie;
    ie.stamp_ns = in.observations[g.groups[j].front()].stamp_ns;
    ie.T_base_marker = r.values.at<SE3>(boardKey(j));
    ie.kinematic_chi2 = kinematic_chi2[j];
    for (std::size_t i : g.groups[j]) sol.instant_of[i] = static_cast<int>(sol.instant_estimates.size());
    ie.observations = std::move(g.groups[j]);
    sol.instant_estimates.push_back(std::move(ie));
  }
}

/// One camera set: a robust solve on everything, the gate on its residuals,
/// then plain least squares on what passed, gated again until nothing more
/// is rejected. After 5 gated solves that each rejected more, one more solve
/// is kept without a further gate (CalibrationSolution::gate_settled), as
/// the corner method does. With backlash, a solve whose b is not the
/// one its lag was computed with is solved again with the lag of its b (up
/// to kBacklashLagRounds more), so that the final solve is the fixed point.
void solveCameraSet(SolveState& st, const std::vector<std::size_t>& cams) {
  std::string cam_list;
  for (std::size_t c : cams) cam_list += (cam_list.empty() ? "" : ", ") + st.in.camera_names[c];
  {  // the robust graph is gone before the first final one is built
    const Graph robust_graph = buildGraph(st.in, {cams, st.sol.used, st.init, st.mount_fixed, true, &st.offsets});
    OptimizerResult r = solveGraph(robust_graph);
    gate(st.in, robust_graph, r.values, st.sol);
    for (std::size_t c : cams) st.init[c] = r.values.at<SE3>(cameraKey(c));
    keepOffsets(r.values, &st.offsets);
    r.values = camerasAndMount(r.values, cams);
    st.sol.solves.push_back(std::move(r));
    st.sol.solve_labels.push_back("robust (" + cam_list + ")");
  }
  constexpr int kGatedRounds = 5;
  for (int rejections = 0, lag_rounds = 0;;) {
    Graph g = buildGraph(st.in, {cams, st.sol.used, st.init, st.mount_fixed, false, &st.offsets});
    OptimizerResult r = solveGraph(g);
    const bool last = rejections == kGatedRounds;
    const bool rejected_any = !last && gate(st.in, g, r.values, st.sol);
    for (std::size_t c : cams) st.init[c] = r.values.at<SE3>(cameraKey(c));
    keepOffsets(r.values, &st.offsets);
    if (rejected_any) {
      ++rejections;
      continue;
    }
    if (!offsets::backlashSettled(st.in.offsets, g.backlash_lag.get(), r.values)) {
      if (lag_rounds++ < offsets::kBacklashLagRounds) continue;
      detail::addFinding(st.sol, "convergence", Severity::Note, {}, offsets::backlashUnsettled(cam_list));
    }
    if (last) {
      st.sol.gate_settled = false;
      detail::addFinding(st.sol, "convergence", Severity::Check, {},
                         "outlier rejection had not settled after " + std::to_string(kGatedRounds) +
                             " gated solves (" + cam_list + "); the last solve is kept without a further gate");
    }
    recordFinal(st, cams, cam_list, g, r);
    r.values = camerasAndMount(r.values, cams);
    st.sol.solves.push_back(std::move(r));
    st.sol.solve_labels.push_back("final (" + cam_list + ")");
    return;
  }
}

}  // namespace

std::string fiducialCovarianceScaleProblem(double scale) {
  if (std::isfinite(scale) && scale >= 1.0) return "";
  std::ostringstream got;
  got << "expected a finite number >= 1 (1 treats the images as independent), got " << std::setprecision(17)
      << scale;
  return got.str();
}

namespace detail {

double refitChiSquare(const CalibrationProblemInput& in, const CalibrationSolution& sol) {
  const bool mount_fixed = in.fix_mount || (in.mount_sigma_m <= 0.0 && in.mount_sigma_rad <= 0.0);
  std::vector<SE3> init(in.camera_names.size());
  for (std::size_t c = 0; c < init.size(); ++c) init[c] = sol.cameras[c].T_base_cam;
  double chi2 = 0.0;
  for (const auto& cams : cameraSets(in))
    chi2 += 2.0 * solveGraph(buildGraph(in, {cams, sol.used, init, mount_fixed, false, nullptr})).final_cost;
  return chi2;
}

}  // namespace detail

CalibrationSolution solveCalibration(const CalibrationProblemInput& in) {
  SolveState st{in, checkSettings(in), {}, {}, in.mount_prior};
  st.init = initialCameraPoses(in);
  const std::vector<SE3> initial_guesses = st.init;
  checkMotion(in, st.mount_fixed);

  CalibrationSolution& sol = st.sol;
  const std::size_t M = in.camera_names.size();
  sol.used.assign(in.observations.size(), 1);
  sol.fiducial_chi2.assign(in.observations.size(), std::nan(""));
  sol.instant_of.assign(in.observations.size(), -1);
  sol.cameras.resize(M);
  for (const auto& cams : detail::cameraSets(in)) solveCameraSet(st, cams);
  for (std::size_t c = 0; c < M; ++c) sol.cameras[c].initial_guess = initial_guesses[c];
  sol.mount_estimated = !st.mount_fixed;
  sol.T_link_marker = st.mount_estimate;
  sol.mount_covariance = st.mount_cov;
  addObservabilityWarnings(in, st.mount_fixed, sol);
  detail::addOffsetFindings(in, sol);
  if (in.single_camera && !st.mount_fixed && M > 1)
    detail::addFinding(sol, "single_camera_mount", Severity::Note, {},
                       "single-camera solves estimate the mount once per camera; the one of the camera with the "
                       "most instants is reported");
  return std::move(st.sol);
}

}  // namespace fgcal::apps

