// Corner-level estimation (corner_calibration.hpp): the robust solve, the
// gates, the plain solves and the marginals; the graph itself is built by
// corner_calibration_graph.cpp.
#include "fgcal/apps/corner_calibration.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <numeric>
#include <optional>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "calibration/corner_calibration_graph.hpp"
#include "calibration/graph_parts.hpp"
#include "calibration/offset_graph.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/core/marginals.hpp"
#include "fgcal/factors/corner_factor.hpp"

namespace fgcal::apps {

std::vector<CornerCamera> cornerCameras(const RigConfig& rig, const std::vector<vision::CameraModel>& models,
                                        bool estimate_intrinsics, std::vector<std::string>* warnings) {
  if (models.size() != rig.cameras.size())
    throw std::invalid_argument("cornerCameras: " + std::to_string(models.size()) + " models for " +
                                std::to_string(rig.cameras.size()) + " cameras");
  std::vector<CornerCamera> out;
  for (std::size_t c = 0; c < models.size(); ++c) {
    const CameraConfig& cfg = rig.cameras[c];
    CornerCamera cam{models[c], cfg.pixel_sigma, VecX()};
    if (estimate_intrinsics) {
      const vision::CameraModel& m = models[c];
      const std::string model_name = vision::toString(m.distortion());
      const std::size_t ncoeff = m.coeffs().size();
      cam.intrinsics_sigma.resize(m.intrinsicsSize());
      const auto where = [&](const std::string& field) {
        return cameraField(cfg.name, field);
      };
      if (cfg.intrinsics_sigma.empty()) {
        const double f = kDefaultIntrinsicsSigmaFraction;
        cam.intrinsics_sigma.head<4>() << f * m.fx(), f * m.fy(), f * m.width(), f * m.height();
        if (warnings)
          warnings->push_back(rig.source + ": " + where("intrinsics_sigma") + " not given for camera " + cfg.name +
                              ": the estimated intrinsics have the default prior std of 2 % of fx, fy and of the "
                              "image width, height (docs/formats.md)");
      } else {
        for (int i = 0; i < 4; ++i) cam.intrinsics_sigma[i] = cfg.intrinsics_sigma[static_cast<std::size_t>(i)];
      }
      std::vector<double> ds = cfg.distortion_coeffs_sigma;
      if (ds.empty()) {
        ds = defaultDistortionSigma(model_name);
        if (ds.size() < ncoeff) ds.resize(ncoeff, 0.1);  // radtan with k3 (never from rig.yaml)
        if (warnings && ncoeff > 0)
          warnings->push_back(rig.source + ": " + where("distortion_coeffs_sigma") + " not given for camera " +
                              cfg.name + ": the estimated " + model_name +
                              " coefficients have the default prior std (docs/formats.md)");
      } else if (ds.size() != ncoeff) {
        throw rigFieldError(rig, where("distortion_coeffs_sigma"),
                            "expected " + std::to_string(ncoeff) + " numbers > 0, one per coefficient of the camera's " +
                                model_name + " model, got " + std::to_string(ds.size()));
      }
      for (std::size_t i = 0; i < ncoeff; ++i) cam.intrinsics_sigma[static_cast<Eigen::Index>(4 + i)] = ds[i];
    }
    out.push_back(std::move(cam));
  }
  return out;
}

namespace {

using corners::cameraKey;
using corners::CornerGraph;
using corners::CornerGraphBuilder;
using corners::intrinsicsKey;
using corners::kMountKey;

// Quantile of chi-square(k) by Wilson-Hilferty (within 1 % of the exact
// quantile at k >= 6 and z = 3.7).
double chi2Quantile(double k, double z) {
  const double a = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - a + z * std::sqrt(a), 3);
}
// z of the image gate: 99.99 %. With ~2,000 images a recording loses about
// 0.2 good images to it.
constexpr double kImageGateZ = 3.719;
// An image with fewer corners than this left after the corner gate is
// rejected: too little of it is left to trust the rest.
constexpr std::size_t kMinImageCorners = 4;

void checkInput(const CalibrationProblemInput& p, const CornerProblemInput& in) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("solveCornerCalibration: " + what); };
  if (in.cameras.size() != p.camera_names.size())
    fail(std::to_string(in.cameras.size()) + " corner cameras for " + std::to_string(p.camera_names.size()) +
         " cameras");
  if (in.corners.size() != p.observations.size())
    fail(std::to_string(in.corners.size()) + " corner lists for " + std::to_string(p.observations.size()) +
         " observations");
  for (std::size_t c = 0; c < in.cameras.size(); ++c) {
    const CornerCamera& cam = in.cameras[c];
    if (!(cam.pixel_sigma > 0.0) || !std::isfinite(cam.pixel_sigma))
      fail("camera " + p.camera_names[c] + ": pixel_sigma must be finite and > 0");
    if (!in.estimate_intrinsics) continue;
    if (cam.intrinsics_sigma.size() != cam.model.intrinsicsSize())
      fail("camera " + p.camera_names[c] + ": " + std::to_string(cam.intrinsics_sigma.size()) +
           " intrinsics sigmas for " + std::to_string(cam.model.intrinsicsSize()) + " intrinsics");
    if (!cam.intrinsics_sigma.allFinite() || !(cam.intrinsics_sigma.array() > 0.0).all())
      fail("camera " + p.camera_names[c] + ": intrinsics sigmas must be finite and > 0");
  }
  for (std::size_t o = 0; o < in.corners.size(); ++o)
    if (in.corners[o].pixels.size() != in.corners[o].board_points.size())
      fail("observation " + std::to_string(o) + ": " + std::to_string(in.corners[o].pixels.size()) +
           " pixels for " + std::to_string(in.corners[o].board_points.size()) + " board points");
}

// What the solves carry from one to the next.
struct State {
  std::vector<SE3> cameras;
  std::vector<VecX> intrinsics;
  SE3 mount;
  std::vector<std::optional<SE3>> board;  // per observation: its board pose in the last solve
  std::vector<char> image_in;             // per observation
  std::vector<std::vector<char>> keep;    // per observation, per corner
  Values offsets;                         // time offsets and joint offsets, when estimated
};

// The corner graph over the cameras `cams`, with the images and corners
// still in.
CornerGraph buildGraph(const CalibrationProblemInput& p, const CornerProblemInput& in, const State& st,
                       const std::vector<std::size_t>& cams, bool mount_fixed, bool robust) {
  CornerGraphBuilder b(p, in);
  for (std::size_t c : cams) {
    b.addCamera(c, st.cameras[c]);
    if (in.estimate_intrinsics) b.addIntrinsics(c, st.intrinsics[c]);
  }
  b.addMount(st.mount, mount_fixed);
  b.addOffsets(cams, &st.offsets);
  std::vector<std::size_t> selected;
  for (std::size_t o = 0; o < p.observations.size(); ++o)
    if (st.image_in[o] && std::find(cams.begin(), cams.end(), static_cast<std::size_t>(p.observations[o].camera)) !=
                              cams.end())
      selected.push_back(o);
  for (std::size_t c : cams) {
    const auto n = std::count_if(selected.begin(), selected.end(),
                                 [&](std::size_t o) { return p.observations[o].camera == static_cast<int>(c); });
    if (n < 3) {
      std::ostringstream msg;
      msg << "camera " << p.camera_names[c] << " keeps " << n
          << " image(s) with corners after rejecting those inconsistent with the others; at least 3 are needed";
      throw DataError(msg.str());
    }
  }
  const auto groups = detail::groupInstants(p.observations, selected, p.sync_tolerance_ms * 1e6, !p.single_camera);
  if (groups.size() < 3) throw DataError("only " + std::to_string(groups.size()) + " instants with a detected board");
  const RobustKernel::Ptr kernel = robust ? huber(std::sqrt(kCornerGate)) : nullptr;
  for (std::size_t j = 0; j < groups.size(); ++j) {
    // The board pose of the last solve that had one of these images, else
    // the kinematics with the current mount.
    std::optional<SE3> init;
    for (std::size_t o : groups[j])
      if (!init && st.board[o]) init = st.board[o];
    const BoardObservation& first = p.observations[groups[j].front()];
    b.addInstant(j, groups[j], init ? *init : first.T_base_link * st.mount);
    for (std::size_t o : groups[j]) b.addCornerFactors(o, j, st.keep[o], kernel);
  }
  return std::move(b.graph());
}

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

OptimizerResult solveGraph(const CornerGraph& g, int threads) {
  OptimizerOptions opt;
  opt.threads = threads;
  opt.fixed_keys = g.fixed;
  opt.max_iterations = 100;
  opt.linear_solver = OptimizerOptions::LinearSolver::SchurComplement;
  OptimizerResult r = optimize(g.graph, g.values, opt);
  if (r.termination == Termination::NotPositiveDefinite || r.termination == Termination::NonFiniteCost)
    throw DataError("the corner calibration problem is degenerate: " + r.message);
  return r;
}

// The gates on the solve `r` of `g` (corner_calibration.hpp). Updates st.keep
// and st.image_in, records rejected images and each image's chi-square sum;
// true when anything was rejected.
bool gate(const CalibrationProblemInput& p, const CornerGraph& g, const Values& at, State& st,
          CornerSolution& out) {
  // Per observation: its corner factors' chi-square values.
  std::vector<std::vector<std::pair<std::size_t, double>>> per_image(p.observations.size());
  for (const corners::CornerRef& ref : g.corners)
    per_image[ref.observation].emplace_back(ref.corner, detail::chiSquare(g.graph[ref.factor], at));
  bool rejected_any = false;
  for (std::size_t o = 0; o < per_image.size(); ++o) {
    const auto& chis = per_image[o];
    if (chis.empty()) continue;
    std::size_t failing = 0;
    for (const auto& [k, chi2] : chis) failing += chi2 > kCornerGate;
    double sum = 0.0;
    std::size_t kept = 0;
    for (const auto& [k, chi2] : chis)
      if (chi2 <= kCornerGate) {
        sum += chi2;
        ++kept;
      }
    out.solution.fiducial_chi2[o] = sum;
    std::ostringstream why;
    why << std::setprecision(3);
    if (failing > kImageRejectFraction * static_cast<double>(chis.size())) {
      why << failing << " of its " << chis.size() << " corners beyond the corner gate (chi-square > " << kCornerGate
          << "): the image disagrees with the others as a whole (a wrong board pose)";
    } else if (kept < kMinImageCorners) {
      why << "only " << kept << " of its " << chis.size() << " corners pass the corner gate";
    } else if (const double limit = chi2Quantile(2.0 * static_cast<double>(kept), kImageGateZ); sum > limit) {
      why << "its " << kept << " corners together are inconsistent with the other images (chi-square " << sum
          << " > " << limit << ", the 99.99 % point of chi-square(" << 2 * kept << "))";
    } else {
      for (const auto& [k, chi2] : chis)
        if (chi2 > kCornerGate) {
          st.keep[o][k] = 0;
          ++out.corners_rejected;
          rejected_any = true;
        }
      continue;
    }
    st.image_in[o] = 0;
    out.solution.used[o] = 0;
    out.solution.rejected.push_back({o, why.str()});
    rejected_any = true;
  }
  return rejected_any;
}

// Keeps the estimates of a solve as the next one's start.
void carry(const CalibrationProblemInput& p, const CornerProblemInput& in, const CornerGraph& g, const Values& v,
           const std::vector<std::size_t>& cams, bool mount_fixed, State& st) {
  for (std::size_t c : cams) {
    st.cameras[c] = v.at<SE3>(cameraKey(c));
    if (in.estimate_intrinsics) st.intrinsics[c] = CornerFactor::intrinsicsAt(v, intrinsicsKey(c));
  }
  if (!mount_fixed) st.mount = v.at<SE3>(kMountKey);
  for (std::size_t j = 0; j < g.groups.size(); ++j)
    for (std::size_t o : g.groups[j]) st.board[o] = v.at<SE3>(corners::boardKey(j));
  if (p.offsets.time_offsets)
    for (std::size_t c : cams)
      st.offsets.insertOrAssign(offsets::timeOffsetKey(c), v.at<VecX>(offsets::timeOffsetKey(c)));
  if (p.offsets.rolling_shutter)
    for (std::size_t c : cams) st.offsets.insertOrAssign(offsets::readoutKey(c), v.at<VecX>(offsets::readoutKey(c)));
  if (p.offsets.joint_offsets) st.offsets.insertOrAssign(offsets::kJointOffsets, v.at<VecX>(offsets::kJointOffsets));
  if (p.offsets.origins) st.offsets.insertOrAssign(offsets::kOrigins, v.at<VecX>(offsets::kOrigins));
  if (p.offsets.backlash) st.offsets.insertOrAssign(offsets::kBacklash, v.at<VecX>(offsets::kBacklash));
}

// The information the images add about camera c's intrinsics, in units of
// the prior's, and the warning when a direction rests on the prior.
void intrinsicsObservability(const std::string& camera, IntrinsicsEstimate& e, std::vector<std::string>& warnings) {
  const Eigen::Index n = e.value.size();
  const Eigen::LDLT<MatX> ldlt(e.covariance);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return;
  const MatX info = ldlt.solve(MatX::Identity(n, n));
  const MatX S = e.prior_sigma.asDiagonal();
  MatX data = S * info * S - MatX::Identity(n, n);  // prior-whitened: the prior itself is I
  data = 0.5 * (data + data.transpose());
  const Eigen::SelfAdjointEigenSolver<MatX> eig(data);
  if (eig.info() != Eigen::Success) return;
  e.data_information = eig.eigenvalues();
  static const char* kNames[] = {"fx", "fy", "cx", "cy"};
  const auto name = [&](Eigen::Index i) -> std::string {
    if (i < 4) return kNames[i];
    return "distortion_coeffs[" + std::to_string(i - 4) + "]";
  };
  for (Eigen::Index d = 0; d < n; ++d) {
    const double lambda = e.data_information[d];
    if (lambda >= kWarnIntrinsicsInformation) break;
    // The direction, in the prior-whitened coordinates: its largest components.
    const VecX v = eig.eigenvectors().col(d);
    std::vector<Eigen::Index> order(static_cast<std::size_t>(n));
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return std::abs(v[a]) > std::abs(v[b]); });
    std::ostringstream w;
    w << std::setprecision(3) << "camera " << camera
      << ": the images observe its intrinsics poorly along ";
    int shown = 0;
    for (Eigen::Index i : order) {
      if (shown == 3 || std::abs(v[i]) < 0.2) break;
      w << (shown++ ? " + " : "") << std::fixed << std::setprecision(2) << v[i] << " " << name(i);
    }
    w << std::defaultfloat << std::setprecision(3)
      << " (in units of each one's prior sigma): the smallest eigenvalue of the information the images add is "
      << lambda << " of the prior's (below " << kWarnIntrinsicsInformation
      << "), so that direction rests on the rig.yaml prior (intrinsics_sigma, distortion_coeffs_sigma), not on "
         "the data. Show the board closer to the image corners and at more varied angles, or give a tighter prior";
    warnings.push_back(w.str());
  }
}

// Where the solves start: the PnP solution when it has the cameras; without
// one (it failed: e.g. intrinsics so wrong that no image's pose agrees with
// the others), the cameras start from their detections as the PnP graph's
// do, the boards from the kinematics.
struct Start {
  const CalibrationSolution& pnp;
  bool from_pnp = false;
  std::vector<SE3> initial;  // per camera, without a PnP solution

  Start(const CalibrationProblemInput& p, const CalibrationSolution& pnp_solution)
      : pnp(pnp_solution), from_pnp(pnp_solution.cameras.size() == p.camera_names.size()) {
    if (!from_pnp) initial = detail::initialCameraPoses(p);
  }
  SE3 camera(std::size_t c) const { return from_pnp ? pnp.cameras[c].T_base_cam : initial[c]; }
  SE3 initialGuess(std::size_t c) const { return from_pnp ? pnp.cameras[c].initial_guess : initial[c]; }
};

// The offsets from the PnP solution when it estimated them.
Values startOffsets(const CalibrationProblemInput& p, const CalibrationSolution& pnp) {
  Values v;
  for (const TimeOffsetEstimate& t : pnp.offsets.time_offsets)
    for (std::size_t c = 0; c < p.camera_names.size(); ++c)
      if (p.offsets.time_offsets && p.camera_names[c] == t.camera)
        v.insertOrAssign(offsets::timeOffsetKey(c), VecX::Constant(1, t.offset_s));
  for (const ReadoutEstimate& r : pnp.offsets.readouts)
    for (std::size_t c = 0; c < p.camera_names.size(); ++c)
      if (p.offsets.rolling_shutter && p.camera_names[c] == r.camera && r.observed)
        v.insertOrAssign(offsets::readoutKey(c), VecX::Constant(1, r.readout_s));
  if (p.offsets.joint_offsets && !pnp.offsets.joint_offsets.empty()) {
    VecX o(static_cast<Eigen::Index>(pnp.offsets.joint_offsets.size()));
    for (Eigen::Index k = 0; k < o.size(); ++k) o[k] = pnp.offsets.joint_offsets[static_cast<std::size_t>(k)].offset_rad;
    v.insertOrAssign(offsets::kJointOffsets, o);
  }
  if (p.offsets.origins && !pnp.offsets.origins.empty()) v.insertOrAssign(offsets::kOrigins, offsets::originVector(pnp.offsets));
  if (p.offsets.backlash && !pnp.offsets.backlash.empty())
    v.insertOrAssign(offsets::kBacklash, offsets::backlashVector(pnp.offsets));
  return v;
}

// The first solve's state: every image and corner in (an image without
// corners has nothing to say, and is marked unused in `sol`), each board where
// the PnP solution had it.
State initialState(const CalibrationProblemInput& p, const CornerProblemInput& in, const Start& start,
                   CalibrationSolution& sol) {
  const std::size_t N = p.observations.size();
  State st;
  st.image_in.assign(N, 1);
  st.board.resize(N);
  st.keep.resize(N);
  for (std::size_t o = 0; o < N; ++o) {
    st.keep[o].assign(in.corners[o].pixels.size(), 1);
    if (in.corners[o].pixels.empty()) {
      st.image_in[o] = 0;
      sol.used[o] = 0;
    }
    if (o < start.pnp.instant_of.size() && start.pnp.instant_of[o] >= 0)
      st.board[o] = start.pnp.instant_estimates[static_cast<std::size_t>(start.pnp.instant_of[o])].T_base_marker;
  }
  for (std::size_t c = 0; c < p.camera_names.size(); ++c) {
    st.cameras.push_back(start.camera(c));
    st.intrinsics.push_back(in.cameras[c].model.intrinsicsVector());
  }
  st.mount = start.from_pnp && start.pnp.mount_estimated ? start.pnp.T_link_marker : p.mount_prior;
  st.offsets = startOffsets(p, start.pnp);
  return st;
}
// One camera set's solves (every camera for F2, each alone for F1) and what
// they share.
struct CameraSet {
  const CalibrationProblemInput& p;
  const CornerProblemInput& in;
  const std::vector<std::size_t>& cams;
  std::string names;  // "a, b": for the solve labels and warnings
  bool mount_fixed = false;
  int threads = 1;
};

std::string cameraList(const CalibrationProblemInput& p, const std::vector<std::size_t>& cams) {
  std::string list;
  for (std::size_t c : cams) list += (list.empty() ? "" : ", ") + p.camera_names[c];
  return list;
}

// Across F1's per-camera solves: the mount and the joint offsets reported are
// those of the solve with the most instants.
struct BestSolve {
  SE3 mount;
  Mat6 mount_cov = Mat6::Zero();
  std::size_t mount_instants = 0;
  std::size_t offset_instants = 0;
};

// The robust solve on every image and corner still in, then the gates on its
// residuals; its estimates are the next solve's start.
void robustSolve(const CameraSet& set, State& st, CornerSolution& out) {
  auto t = Clock::now();
  const CornerGraph g = buildGraph(set.p, set.in, st, set.cams, set.mount_fixed, true);
  out.build_seconds += since(t);
  const OptimizerResult r = solveGraph(g, set.threads);
  out.solution.solves.push_back(r);
  out.solution.solve_labels.push_back("robust corners (" + set.names + ")");
  t = Clock::now();
  gate(set.p, g, r.values, st, out);
  carry(set.p, set.in, g, r.values, set.cams, set.mount_fixed, st);
  out.gate_seconds += since(t);
}

struct FinalSolve {
  CornerGraph graph;
  OptimizerResult result;
};

// Plain least squares on what passed, gated again until nothing more is
// rejected; the last of kRounds solves is kept without a further gate. With
// backlash, a solve whose b is not the one its lag was computed with is
// solved again with the lag of its b (up to kBacklashLagRounds more).
FinalSolve finalSolve(const CameraSet& set, State& st, CornerSolution& out) {
  constexpr int kRounds = 5;
  for (int round = 0, lag_rounds = 0;; ++round) {
    auto t = Clock::now();
    CornerGraph g = buildGraph(set.p, set.in, st, set.cams, set.mount_fixed, false);
    out.build_seconds += since(t);
    OptimizerResult r = solveGraph(g, set.threads);
    t = Clock::now();
    carry(set.p, set.in, g, r.values, set.cams, set.mount_fixed, st);
    const bool last = round + 1 == kRounds;
    const bool rejected = !last && gate(set.p, g, r.values, st, out);
    out.gate_seconds += since(t);
    if (rejected) continue;
    if (!offsets::backlashSettled(set.p.offsets, g.backlash_lag.get(), r.values)) {
      if (lag_rounds++ < offsets::kBacklashLagRounds) {
        --round;  // a round for the lag, not for the gate
        continue;
      }
      detail::addFinding(out.solution, "convergence", Severity::Note, {}, offsets::backlashUnsettled(set.names));
    }
    if (last) {
      out.solution.gate_settled = false;
      detail::addFinding(out.solution, "convergence", Severity::Check, {},
                         "corner outlier rejection had not settled after " + std::to_string(kRounds - 1) +
                             " gated solves (" + set.names + "); the last solve is kept without a further gate");
    }
    return {std::move(g), std::move(r)};
  }
}

// The final solve, its board pose per instant and the warnings on it.
void recordInstants(const CameraSet& set, const FinalSolve& f, CornerSolution& out) {
  CalibrationSolution& sol = out.solution;
  const CornerGraph& g = f.graph;
  const OptimizerResult& r = f.result;
  sol.solves.push_back(r);
  sol.solve_labels.push_back("final corners (" + set.names + ")");
  for (std::size_t j = 0; j < g.groups.size(); ++j) {
    InstantEstimate ie;
    ie.stamp_ns = set.p.observations[g.groups[j].front()].stamp_ns;
    ie.observations = g.groups[j];
    ie.T_base_marker = r.values.at<SE3>(corners::boardKey(j));
    ie.kinematic_chi2 = detail::chiSquare(g.graph[g.kinematic[j]], r.values);
    for (std::size_t o : g.groups[j]) sol.instant_of[o] = static_cast<int>(sol.instant_estimates.size());
    sol.instant_estimates.push_back(std::move(ie));
  }
  const std::size_t instants = g.groups.size();
  detail::addSolveFindings(sol, instants, set.p.single_camera, set.names, r);
  out.corners_used += static_cast<long>(g.corners.size());
  sol.instants += static_cast<int>(instants);
}

// The offsets' estimates (when estimated) and the marginals, with the
// unobserved offsets held (offset_graph.hpp).
offsets::Summary summarize(const CameraSet& set, const FinalSolve& f) {
  std::vector<offsets::CameraSpan> spans;
  for (std::size_t c : set.cams) spans.push_back(offsets::cameraSpan(set.p, c, cameraKey(c)));
  try {
    offsets::Summary summary = offsets::summarize(set.p.offsets, f.graph.graph, f.graph.fixed, f.result.values, spans,
                                                  set.mount_fixed ? std::nullopt : std::optional<Key>(kMountKey));
    summary.estimates.backlash_lag = f.graph.backlash_lag;
    return summary;
  } catch (const DegenerateSystem& e) {
    throw DataError(std::string("the corner calibration problem is degenerate: ") + e.what());
  }
}

// Camera c's estimated intrinsics with their covariance and prior, and the
// warnings on what the images leave to the prior.
IntrinsicsEstimate intrinsicsEstimate(const CameraSet& set, std::size_t c, const Values& v, const Marginals& marg,
                                      std::vector<std::string>& warnings) {
  IntrinsicsEstimate e;
  e.value = CornerFactor::intrinsicsAt(v, intrinsicsKey(c));
  e.covariance = marg.covariance(intrinsicsKey(c));
  e.prior = set.in.cameras[c].model.intrinsicsVector();
  e.prior_sigma = set.in.cameras[c].intrinsics_sigma;
  intrinsicsObservability(set.p.camera_names[c], e, warnings);
  return e;
}

// The final solve's estimates with their marginal covariances: the cameras
// (and their intrinsics), the offsets, and the mount when this set saw the
// most instants.
void recordEstimates(const CameraSet& set, const Start& start, const FinalSolve& f, BestSolve& best,
                     CornerSolution& out) {
  const auto t = Clock::now();
  CalibrationSolution& sol = out.solution;
  const Values& v = f.result.values;
  const std::size_t instants = f.graph.groups.size();
  offsets::Summary summary = summarize(set, f);
  const Marginals& marg = summary.marginals;
  if (set.p.offsets.any()) offsets::merge(std::move(summary.estimates), instants, &best.offset_instants, &sol.offsets);
  if (set.cams.size() > 1) {
    std::vector<Key> poses;
    for (std::size_t c : set.cams) poses.push_back(cameraKey(c));
    detail::addCrossCovariances(set.cams, marg.jointCovariance(poses), sol);
  }
  for (std::size_t c : set.cams) {
    CameraEstimate& ce = sol.cameras[c];
    ce.name = set.p.camera_names[c];
    ce.T_base_cam = v.at<SE3>(cameraKey(c));
    ce.covariance = marg.covariance(cameraKey(c));
    ce.initial_guess = start.initialGuess(c);
    ce.observations_used = 0;
    if (set.in.estimate_intrinsics) out.intrinsics[c] = intrinsicsEstimate(set, c, v, marg, sol.warnings);
  }
  if (!set.mount_fixed && instants > best.mount_instants) {
    best.mount_instants = instants;
    best.mount = v.at<SE3>(kMountKey);
    best.mount_cov = marg.covariance(kMountKey);
  }
  out.marginals_seconds += since(t);  // with the covariance solves
}

// After every camera set: the corners the final solves kept, the images each
// camera used, the mount, and the warnings on the whole.
void finish(const CalibrationProblemInput& p, const State& st, bool mount_fixed, const BestSolve& best,
            CornerSolution& out) {
  CalibrationSolution& sol = out.solution;
  const std::size_t N = p.observations.size();
  out.corner_used.resize(N);
  for (std::size_t o = 0; o < N; ++o) {
    out.corner_used[o] = st.keep[o];
    if (!st.image_in[o]) std::fill(out.corner_used[o].begin(), out.corner_used[o].end(), 0);
    if (st.image_in[o]) ++sol.cameras[static_cast<std::size_t>(p.observations[o].camera)].observations_used;
  }
  sol.mount_estimated = !mount_fixed;
  sol.T_link_marker = mount_fixed ? p.mount_prior : best.mount;
  sol.mount_covariance = best.mount_cov;
  detail::addObservabilityWarnings(p, mount_fixed, sol);
  detail::addOffsetFindings(p, sol);
  if (p.single_camera && !mount_fixed && p.camera_names.size() > 1)
    detail::addFinding(sol, "single_camera_mount", Severity::Note, {},
                       "single-camera solves estimate the mount once per camera; the one of the camera with the "
                       "most instants is reported");
}

}  // namespace

CornerSolution solveCornerCalibration(const CalibrationProblemInput& p, const CornerProblemInput& in,
                                      const CalibrationSolution& pnp, int threads) {
  checkInput(p, in);
  if (threads < 1) throw std::invalid_argument("solveCornerCalibration: threads must be >= 1");
  const std::size_t M = p.camera_names.size();
  const std::size_t N = p.observations.size();
  const bool mount_fixed = p.fix_mount || (p.mount_sigma_m <= 0.0 && p.mount_sigma_rad <= 0.0);
  const Start start(p, pnp);

  CornerSolution out;
  CalibrationSolution& sol = out.solution;
  sol.used.assign(N, 1);
  sol.fiducial_chi2.assign(N, std::nan(""));
  sol.instant_of.assign(N, -1);
  sol.cameras.resize(M);
  if (in.estimate_intrinsics) out.intrinsics.resize(M);
  State st = initialState(p, in, start, sol);
  BestSolve best{p.mount_prior};
  for (const auto& cams : detail::cameraSets(p)) {
    const CameraSet set{p, in, cams, cameraList(p, cams), mount_fixed, threads};
    robustSolve(set, st, out);
    const FinalSolve f = finalSolve(set, st, out);
    recordInstants(set, f, out);
    recordEstimates(set, start, f, best, out);
  }
  finish(p, st, mount_fixed, best, out);
  return out;
}

}  // namespace fgcal::apps
