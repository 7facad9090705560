// Pieces both calibration graphs use (graph_parts.hpp).
#include "calibration/graph_parts.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numeric>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "fgcal/apps/errors.hpp"
#include "fgcal/factors/kinematic_factor.hpp"

namespace fgcal::apps::detail {

std::vector<std::vector<std::size_t>> groupInstants(const std::vector<BoardObservation>& obs,
                                                    const std::vector<std::size_t>& selected,
                                                    double tolerance_ns, bool share) {
  std::vector<std::size_t> order = selected;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return obs[a].stamp_ns < obs[b].stamp_ns; });
  std::vector<std::vector<std::size_t>> groups;
  for (std::size_t i : order) {
    bool placed = false;
    if (share && !groups.empty()) {
      auto& g = groups.back();
      const bool close = static_cast<double>(obs[i].stamp_ns - obs[g.front()].stamp_ns) <= tolerance_ns;
      const bool camera_free =
          std::none_of(g.begin(), g.end(), [&](std::size_t k) { return obs[k].camera == obs[i].camera; });
      if (close && camera_free) {
        g.push_back(i);
        placed = true;
      }
    }
    if (!placed) groups.push_back({i});
  }
  return groups;
}

namespace {

SE3 robustInitialGuess(const std::vector<SE3>& proposals) {
  const std::size_t n = proposals.size();
  const std::size_t stride = std::max<std::size_t>(1, n / 200);  // bounded O(n^2)
  auto agree = [](const SE3& a, const SE3& b) {
    const Vec6 d = a.minus(b);
    return d.head<3>().norm() < 0.05 && d.tail<3>().norm() < 0.05;  // 3 deg, 5 cm
  };
  std::size_t best = 0, best_support = 0;
  for (std::size_t i = 0; i < n; i += stride) {
    std::size_t support = 0;
    for (std::size_t k = 0; k < n; k += stride) support += agree(proposals[i], proposals[k]);
    if (support > best_support) {
      best_support = support;
      best = i;
    }
  }
  SE3 mean = proposals[best];
  for (int it = 0; it < 5; ++it) {
    Vec6 sum = Vec6::Zero();
    int count = 0;
    for (const SE3& p : proposals)
      if (agree(mean, p)) {
        sum += mean.minus(p);
        ++count;
      }
    if (count == 0) break;
    mean = mean.plus(sum / count);
  }
  return mean;
}

}  // namespace

std::vector<SE3> initialCameraPoses(const CalibrationProblemInput& in) {
  const std::size_t M = in.camera_names.size();
  std::vector<SE3> init(M);
  for (std::size_t c = 0; c < M; ++c) {
    std::vector<SE3> proposals;
    for (const auto& o : in.observations)
      if (o.camera == static_cast<int>(c))
        proposals.push_back(o.T_base_link * in.mount_prior * o.T_cam_marker.inverse());
    if (proposals.size() < 3) {
      std::ostringstream msg;
      msg << "camera " << in.camera_names[c] << " sees the board in " << proposals.size()
          << " usable image(s); at least 3 are needed";
      throw DataError(msg.str());
    }
    init[c] = (c < in.camera_guesses.size() && in.camera_guesses[c]) ? *in.camera_guesses[c]
                                                                      : robustInitialGuess(proposals);
  }
  return init;
}

NoiseModel::Ptr mountPriorNoise(double sigma_m, double sigma_rad) {
  Vec6 s;
  s << sigma_rad, sigma_rad, sigma_rad, sigma_m, sigma_m, sigma_m;
  return NoiseModel::diagonal(s);
}

std::vector<std::vector<std::size_t>> cameraSets(const CalibrationProblemInput& in) {
  const std::size_t M = in.camera_names.size();
  std::vector<std::vector<std::size_t>> sets;
  if (in.single_camera) {
    for (std::size_t c = 0; c < M; ++c) sets.push_back({c});
    return sets;
  }
  std::vector<std::size_t> all(M);
  std::iota(all.begin(), all.end(), 0);
  sets.push_back(all);
  return sets;
}

double chiSquare(const Factor& f, const Values& v) {
  // Without allocating for the small factors of these graphs (a gate judges
  // some 10^5 corners), through Factor::error otherwise.
  constexpr std::size_t kKeys = 8;
  constexpr int kDim = 16;
  if (f.keys().size() > kKeys || f.dim() > kDim) return f.noiseModel().whiten(f.error(v)).squaredNorm();
  const Variable* vars[kKeys];
  for (std::size_t i = 0; i < f.keys().size(); ++i) vars[i] = &v.variable(f.keys()[i]);
  double r[kDim];
  f.evaluate(vars, r, nullptr);
  f.noiseModel().whitenResidual(r);
  double sq = 0.0;
  for (int i = 0; i < f.dim(); ++i) sq += r[i] * r[i];
  return sq;
}

Mat6 kinematicCovariance(const BoardObservation& o, const CalibrationProblemInput& in) {
  Mat6 cov = KinematicFactor::markerCovariance(o.link_covariance, in.mount_prior);
  cov.diagonal().head<3>().array() += in.kinematic_floor_rad * in.kinematic_floor_rad;
  cov.diagonal().tail<3>().array() += in.kinematic_floor_m * in.kinematic_floor_m;
  return cov;
}

NoiseModel::Ptr kinematicNoise(const BoardObservation& o, const CalibrationProblemInput& in) {
  return NoiseModel::fromCovariance(kinematicCovariance(o, in));
}

void addCrossCovariances(const std::vector<std::size_t>& cams, const MatX& joint, CalibrationSolution& sol) {
  for (std::size_t i = 0; i < cams.size(); ++i)
    for (std::size_t j = i + 1; j < cams.size(); ++j) {
      const auto bi = 6 * static_cast<Eigen::Index>(i), bj = 6 * static_cast<Eigen::Index>(j);
      CalibrationSolution::CrossCovariance c;
      c.a = std::min(cams[i], cams[j]);
      c.b = std::max(cams[i], cams[j]);
      c.cov = cams[i] < cams[j] ? Mat6(joint.block<6, 6>(bi, bj)) : Mat6(joint.block<6, 6>(bj, bi));
      sol.camera_cross_covariances.push_back(c);
    }
}

void addFinding(CalibrationSolution& sol, std::string check, Severity severity, std::vector<std::string> fields,
                std::string message) {
  sol.warnings.push_back(message);
  sol.findings.push_back({std::move(check), severity, std::move(fields), std::move(message), {}, {}});
}

void addOffsetFindings(const CalibrationProblemInput& p, CalibrationSolution& sol) {
  for (const auto& w : sol.offsets.warnings) addFinding(sol, "offset_observability", Severity::Note, {}, w);
  const std::vector<std::string>& still = sol.offsets.backlash_not_reversing;
  if (still.empty()) return;
  std::vector<std::string> fields;
  std::string joints;
  for (const std::string& j : still) {
    fields.push_back(p.offsets.joint_log_name + ":" + j);
    joints += (joints.empty() ? "" : ", ") + j;
  }
  addFinding(sol, "backlash_not_reversing", Severity::Check, std::move(fields),
             "--estimate backlash: " + joints + (still.size() > 1 ? " never move" : " never moves") +
                 " both ways in the joint log (" + p.offsets.joint_log_name +
                 "), so a play crossed in one direction only cannot be told from a zero offset: no backlash is "
                 "estimated for " + (still.size() > 1 ? "them" : "it") +
                 " (rad 0, observed: false), and the poses carry whatever lag there is. Record the leg moving "
                 "each joint back and forth");
}

void addSolveFindings(CalibrationSolution& sol, std::size_t instants, bool single_camera, const std::string& cams,
                      const OptimizerResult& r) {
  if (instants < static_cast<std::size_t>(kWarnMinInstants)) {
    std::ostringstream w;
    w << "too few instants: the board was used at " << instants << " instant(s)"
      << (single_camera ? " by " + cams : std::string()) << "; at least " << kWarnMinInstants
      << " are advised for a trustworthy result. Record longer, with the board in view of the cameras";
    addFinding(sol, "few_instants", Severity::Note, {}, w.str());
  }
  if (!r.converged && r.termination != Termination::MaxIterations)
    addFinding(sol, "convergence", Severity::Check, {}, "optimizer stopped: " + r.message);
}

GatedImages gatedImages(const CalibrationProblemInput& in, const CalibrationSolution& sol) {
  GatedImages g;
  g.total.assign(in.camera_names.size(), 0);
  g.rejected.assign(in.camera_names.size(), 0);
  for (const auto& o : in.observations) ++g.total[static_cast<std::size_t>(o.camera)];
  for (const auto& r : sol.rejected) ++g.rejected[static_cast<std::size_t>(in.observations[r.observation].camera)];
  return g;
}

void addObservabilityWarnings(const CalibrationProblemInput& in, bool mount_fixed, CalibrationSolution& sol) {
  const std::size_t M = in.camera_names.size();
  if (!mount_fixed) {
    // The information in units of (0.1 deg, 1 mm)^-2, so that one threshold
    // speaks to both rotation and translation.
    Mat6 D = Mat6::Zero();
    D.diagonal() << Vec3::Constant(0.1 * M_PI / 180.0), Vec3::Constant(1e-3);
    const Eigen::LDLT<Mat6> ldlt(sol.mount_covariance);
    bool known = false;
    if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
      const Mat6 info = D * ldlt.solve(Mat6::Identity()) * D;
      const Eigen::SelfAdjointEigenSolver<Mat6> eig(0.5 * (info + info.transpose()));
      sol.mount_information_eigenvalues = eig.eigenvalues();
      known = eig.info() == Eigen::Success;
    }
    const Vec6& ev = sol.mount_information_eigenvalues;
    if (known && ev[0] < kWarnMountInformation) {
      // How far the board turned: the largest angle between link orientations.
      double turn = 0.0;
      const SO3* ref = nullptr;
      for (std::size_t i = 0; i < in.observations.size(); ++i) {
        if (!sol.used[i]) continue;
        if (!ref) ref = &in.observations[i].T_base_link.so3();
        turn = std::max(turn, ref->between(in.observations[i].T_base_link.so3()).log().norm());
      }
      std::ostringstream w;
      w << std::setprecision(3) << "the board mount is poorly observed: the smallest eigenvalues of its information are "
        << ev[0] << ", " << ev[1] << " in units of (0.1 deg, 1 mm)^-2 (below " << kWarnMountInformation
        << "); too little rotation of the board (at most " << std::setprecision(2) << std::fixed
        << turn * 180.0 / M_PI << " deg away from the first image) or too few instants (" << sol.instants
        << ") to tell the mount from the cameras. Turn the board through more varied orientations, record longer, "
           "or hold the mount fixed if it is known";
      addFinding(sol, "mount_observability", Severity::Note, {"robot.T_link_marker", "robot.mount_sigma"}, w.str());
    }
  }
  if (!in.single_camera && M > 1) {
    std::vector<int> shared(M, 0);
    for (const InstantEstimate& ie : sol.instant_estimates)
      if (ie.observations.size() > 1)
        for (std::size_t i : ie.observations) ++shared[static_cast<std::size_t>(in.observations[i].camera)];
    for (std::size_t c = 0; c < M; ++c)
      if (shared[c] == 0)
        addFinding(sol, "no_shared_instant", Severity::Note, {"cameras[" + in.camera_names[c] + "]"},
                   "camera " + in.camera_names[c] +
                               " never sees the board at the same instant as another camera: no mutual constraint; "
                               "its pose relative to the other cameras rests on the kinematics alone. Move the board "
                               "where the cameras' views overlap");
  }
  const auto [total, rejected] = gatedImages(in, sol);
  for (std::size_t c = 0; c < M; ++c) {
    if (total[c] == 0 || static_cast<double>(rejected[c]) <= kWarnOutlierRate * static_cast<double>(total[c])) continue;
    std::ostringstream w;
    w << "high outlier rate: " << rejected[c] << " of " << total[c] << " images of camera " << in.camera_names[c]
      << " (" << std::setprecision(3) << 100.0 * rejected[c] / total[c]
      << " %) were rejected as inconsistent with the others. Check its intrinsics, the time stamps of images and "
         "joints, and that the board is rigidly fixed";
    addFinding(sol, "outlier_rate", Severity::Check,
               {"cameras[" + in.camera_names[c] + "].intrinsics", "cameras[" + in.camera_names[c] + "].pixel_sigma"},
               w.str());
  }
}

}  // namespace fgcal::apps::detail
