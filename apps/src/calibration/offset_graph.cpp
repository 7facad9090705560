#include "calibration/offset_graph.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <iomanip>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "fgcal/apps/errors.hpp"
#include "fgcal/factors/joint_offset_factor.hpp"
#include "fgcal/factors/kinematic_factor.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/time_offset_factor.hpp"
#include "fgcal/kinematics/errors.hpp"

namespace fgcal::apps::offsets {

namespace {

std::string num(double v, int precision = 3) {
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

/// Absorption of a unit offset along the conditional mean of `block` given
/// offset k (the joint covariance's regression): what moves with it where the
/// data do not say which.
Absorption absorption(const std::string& name, const MatX& cov, Eigen::Index block, Eigen::Index k) {
  const Vec6 s = -cov.block<6, 1>(block, k) / cov(k, k);  // [w v] per rad of offset
  return {name, s.tail<3>().norm() * 1e3 * 1e-3, s.head<3>().norm() * 180.0 / M_PI * 1e-3};
}

/// The graph with every SE(3) prior (the mount's) a thousand times looser.
FactorGraph measurementsOnly(const FactorGraph& graph) {
  FactorGraph out;
  out.reserve(graph.size());
  for (const Factor::Ptr& f : graph) {
    if (const auto* p = dynamic_cast<const PriorFactorSE3*>(f.get()))
      out.emplace<PriorFactorSE3>(p->keys()[0], p->measured(),
                                  NoiseModel::fromCovariance(1e6 * p->noiseModel().covariance()));
    else
      out.add(f);
  }
  return out;
}

/// A prior std per chain joint from rig.yaml's number or map, else the default.
VecX chainSigma(const RigConfig& rig, const kinematics::KinematicChain& chain, const std::string& field, double all,
                const std::map<std::string, double>& per_joint, double fallback, std::string* source) {
  try {
    *source = !per_joint.empty() || all > 0.0 ? "rig.yaml" : "default";
    return !per_joint.empty() ? chain.sigmaVector(per_joint) : chain.sigmaVector(all > 0.0 ? all : fallback);
  } catch (const kinematics::KinematicsError& e) {
    throw rigFieldError(rig, field, e.what());
  }
}

VecX backlashSigma(const RigConfig& rig, const kinematics::KinematicChain& chain, std::string* source) {
  return chainSigma(rig, chain, "robot.backlash_sigma", rig.robot.backlash_sigma, rig.robot.backlash_sigmas,
                    kDefaultBacklashSigma, source);
}

}  // namespace

VecX backlashPriorSigma(const RigConfig& rig, const kinematics::KinematicChain& chain) {
  std::string source;
  return backlashSigma(rig, chain, &source);
}

OffsetModel makeModel(const EstimateSet& estimate, const RigConfig& rig, const kinematics::KinematicChain& chain,
                      const JointLog& log, const std::vector<int>& columns, const std::string& joint_log_name) {
  OffsetModel m;
  m.time_offsets = estimate.time_offset;
  m.joint_offsets = estimate.joint_offsets;
  m.backlash = estimate.backlash && chain.numJoints() > 0;
  m.origins = rig.robot.hasKinematicSigma() && chain.numJoints() > 0;
  // Rolling shutter: every camera's readout (the rig's order, that of the problem's cameras).
  if (chain.numJoints() > 0) {
    m.rolling_shutter = estimate.rolling_shutter;
    m.readout_s.resize(static_cast<Eigen::Index>(rig.cameras.size()));
    for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
      m.readout_s[static_cast<Eigen::Index>(c)] = rig.cameras[c].readout_ms * 1e-3;
      m.rows.push_back(rig.cameras[c].resolution[1]);
    }
  }
  if (!m.any()) return m;
  m.chain = std::make_shared<const kinematics::KinematicChain>(chain);
  m.joint_log_name = joint_log_name;
  if (m.exposureTiming() || m.backlash)
    m.trajectory = std::make_shared<const JointLogTrajectory>(log, columns, joint_log_name);
  const RobotConfig& r = rig.robot;
  if (m.joint_offsets)
    m.joint_offset_sigma = chainSigma(rig, chain, "robot.joint_offset_sigma", r.joint_offset_sigma,
                                      r.joint_offset_sigmas, kDefaultJointOffsetSigma, &m.joint_offset_sigma_source);
  if (m.backlash) {
    m.backlash_sigma = backlashSigma(rig, chain, &m.backlash_sigma_source);
    std::string unused;
    m.backlash_min_play =
        chainSigma(rig, chain, "robot.encoder_sigma", r.encoder_sigma, r.encoder_sigmas, r.encoder_sigma, &unused);
    m.backlash_path = motorPath(m.trajectory, log);
    m.backlash_reversing = backlashReversing(*m.backlash_path, m.backlash_min_play);
  }
  if (m.origins) {
    const auto n = chain.numJoints();
    m.origin_sigma.resize(6 * n);
    for (const auto& [joint, ms] : r.kinematic_sigmas)
      if (chain.indexOf(joint) < 0)
        throw rigFieldError(rig, "robot.kinematic_sigma." + joint,
                            "expected a movable joint of the chain " + chain.baseLink() + " -> " + chain.tipLink() +
                                ", got '" + joint + "'" + closestNote(joint, chain.jointNames(), "joints"));
    for (int i = 0; i < n; ++i) {
      std::array<double, 2> ms = r.kinematic_sigma;
      if (!r.kinematic_sigmas.empty()) {
        const auto it = r.kinematic_sigmas.find(chain.jointNames()[static_cast<std::size_t>(i)]);
        if (it == r.kinematic_sigmas.end())
          throw rigFieldError(rig, "robot.kinematic_sigma",
                              "the map lists no [metres, radians] for the chain's joint '" +
                                  chain.jointNames()[static_cast<std::size_t>(i)] + "' (every movable joint of " +
                                  chain.baseLink() + " -> " + chain.tipLink() + " needs one)");
        ms = it->second;
      }
      m.origin_sigma.segment<3>(6 * i).setConstant(ms[1]);
      m.origin_sigma.segment<3>(6 * i + 3).setConstant(ms[0]);
    }
  }
  return m;
}

Key timeOffsetKey(std::size_t camera) { return key('t', camera); }
Key readoutKey(std::size_t camera) { return key('r', camera); }

void addVariables(const OffsetModel& m, const std::vector<std::size_t>& cameras, const Values* previous,
                  FactorGraph& graph, Values& values) {
  auto start = [&](Key k, const VecX& zero) {
    values.insert(k, previous && previous->exists(k) ? previous->at<VecX>(k) : zero);
  };
  if (m.time_offsets)
    for (std::size_t c : cameras) {
      start(timeOffsetKey(c), VecX::Zero(1));
      graph.emplace<PriorFactorVector>(timeOffsetKey(c), VecX::Zero(1),
                                       NoiseModel::isotropic(1, kTimeOffsetPriorSigmaS));
    }
  if (m.rolling_shutter)
    for (std::size_t c : cameras) {
      const VecX centre = VecX::Constant(1, m.readout(c));
      start(readoutKey(c), centre);
      graph.emplace<PriorFactorVector>(readoutKey(c), centre, NoiseModel::isotropic(1, kReadoutPriorSigmaS));
    }
  if (m.joint_offsets) {
    const auto n = m.chain->numJoints();
    start(kJointOffsets, VecX::Zero(n));
    graph.emplace<PriorFactorVector>(kJointOffsets, VecX::Zero(n), NoiseModel::diagonal(m.joint_offset_sigma));
  }
  if (m.origins) {
    start(kOrigins, VecX::Zero(m.origin_sigma.size()));
    graph.emplace<PriorFactorVector>(kOrigins, VecX::Zero(m.origin_sigma.size()), NoiseModel::diagonal(m.origin_sigma));
  }
  if (m.backlash) {
    start(kBacklash, VecX::Zero(m.backlash_sigma.size()));
    graph.emplace<PriorFactorVector>(kBacklash, VecX::Zero(m.backlash_sigma.size()),
                                     NoiseModel::diagonal(m.backlash_sigma));
  }
}

std::shared_ptr<const BacklashLag> backlashLag(const OffsetModel& m, const Values* previous) {
  if (!m.backlash) return nullptr;
  const bool solved = previous && previous->exists(kBacklash);
  const VecX b = solved ? previous->at<VecX>(kBacklash) : m.backlash_sigma;
  VecX play = VecX::Zero(b.size());
  for (Eigen::Index k = 0; k < b.size(); ++k)
    if (m.backlash_reversing[static_cast<std::size_t>(k)]) play[k] = std::max(b[k], m.backlash_min_play[k]);
  return std::make_shared<const BacklashLag>(m.backlash_path, play);
}

bool backlashSettled(const OffsetModel& m, const BacklashLag* lag, const Values& solved) {
  if (!m.backlash || !lag) return true;
  const VecX& b = solved.at<VecX>(kBacklash);
  for (Eigen::Index k = 0; k < b.size(); ++k) {
    if (!m.backlash_reversing[static_cast<std::size_t>(k)]) continue;
    const double play = std::max(b[k], m.backlash_min_play[k]);
    if (std::abs(play - lag->play()[k]) > kBacklashLagTolerance * std::max(play, lag->play()[k])) return false;
  }
  return true;
}

std::string backlashUnsettled(const std::string& cameras) {
  return "the backlash's lag (the play operator's, run with the play of the solve before) had not settled after " +
         std::to_string(kBacklashLagRounds) + " more solves (" + cameras +
         "): the last solve's play still differs from the one its lag was computed with by more than " +
         num(100.0 * kBacklashLagTolerance) + " %; it is kept";
}

Factor::Ptr kinematicFactor(const OffsetModel& m, const BacklashLag* lag, Key board, Key mount,
                            const SE3& T_base_link, const VecX& q, std::int64_t instant_ns, NoiseModel::Ptr noise) {
  if (m.origins || m.backlash) {
    ChainCorrections c;
    if (m.origins) c.origins = kOrigins;
    if (m.joint_offsets) c.offsets = kJointOffsets;
    if (m.backlash) {
      if (!lag) throw std::logic_error("kinematicFactor: backlash estimated without its lag");
      c.backlash = kBacklash, c.backlash_lag = lag->at(instant_ns);
    }
    return std::make_shared<ChainKinematicFactor>(board, mount, std::move(c), m.chain, q, std::move(noise));
  }
  if (m.joint_offsets)
    return std::make_shared<JointOffsetKinematicFactor>(board, mount, kJointOffsets, m.chain, q, std::move(noise));
  return std::make_shared<KinematicFactor>(board, mount, T_base_link, std::move(noise));
}

Factor::Ptr imageFactor(const OffsetModel& m, Factor::Ptr image, std::size_t board_position, Key mount,
                        std::size_t camera, std::int64_t instant_ns, std::int64_t image_ns, double row,
                        RobustKernel::Ptr robust) {
  if (!m.exposureTiming()) {
    image->setRobustKernel(std::move(robust));
    return image;
  }
  TimeOffsetFactor::Timing timing{m.trajectory->seconds(instant_ns), m.trajectory->seconds(image_ns)};
  TimeOffsetFactor::Variables vars;
  vars.mount = mount;
  if (m.time_offsets) vars.time_offset = timeOffsetKey(camera);
  if (m.rolling_shutter) vars.readout = readoutKey(camera);
  if (m.joint_offsets) vars.joint_offsets = kJointOffsets;
  const double readout = m.readout(camera);
  if (m.rolling_shutter || readout != 0.0) {
    timing.row = row;
    timing.readout = readout;
  }
  return std::make_shared<TimeOffsetFactor>(std::move(image), board_position, vars, m.chain, m.trajectory, timing,
                                            std::move(robust));
}

double meanRow(const CalibrationProblemInput& p, std::size_t k) {
  const BoardObservation& o = p.observations[k];
  if (o.corners_count == 0) return 0.5;
  double v = 0.0;
  for (std::size_t c = o.corners_begin; c < o.corners_begin + o.corners_count; ++c) v += p.corners.pixel(c).y();
  return p.offsets.rowFraction(static_cast<std::size_t>(o.camera), v / o.corners_count);
}

CameraSpan cameraSpan(const CalibrationProblemInput& p, std::size_t c, Key pose) {
  CameraSpan span{c, p.camera_names[c], pose, INT64_MAX, INT64_MIN};
  for (const BoardObservation& o : p.observations)
    if (o.camera == static_cast<int>(c)) {
      span.first_image_ns = std::min(span.first_image_ns, o.stamp_ns);
      span.last_image_ns = std::max(span.last_image_ns, o.stamp_ns);
    }
  return span;
}

void merge(OffsetEstimates est, std::size_t instants, std::size_t* best_instants, OffsetEstimates* into) {
  for (auto& t : est.time_offsets) into->time_offsets.push_back(std::move(t));
  for (auto& r : est.readouts) into->readouts.push_back(std::move(r));
  for (auto& u : est.urdf_shares) into->urdf_shares.push_back(std::move(u));
  // Chain-wide estimates come from the solve with the most instants, like the mount.
  const auto chain_wide = [](const OffsetEstimates& e) {
    return !e.joint_offsets.empty() || !e.origins.empty() || !e.backlash.empty();
  };
  if (chain_wide(est) && (instants > *best_instants || !chain_wide(*into))) {
    *best_instants = instants;
    into->joint_offsets = std::move(est.joint_offsets);
    into->joint_offset_eigenvalues = est.joint_offset_eigenvalues;
    into->origins = std::move(est.origins);
    into->origin_directions_observed = est.origin_directions_observed;
    into->backlash = std::move(est.backlash);
    into->backlash_not_reversing = std::move(est.backlash_not_reversing);
    into->backlash_lag = std::move(est.backlash_lag);
  }
  for (auto& w : est.warnings) into->warnings.push_back(std::move(w));
}

namespace {

/// What the measurements say: the offsets' own priors are unary, so their
/// information is subtracted exactly from these marginals' (timeOffsets,
/// jointOffsets); the mount's prior is not, and is loosened instead. When that
/// leaves the system singular (a mount the measurements do not observe), the
/// solution's marginals serve, priors in, and the reported marginals may
/// reuse them.
struct InformationMarginals {
  std::optional<Marginals> measured;
  std::optional<Marginals> full;  // the solution's, priors in: the fallback
  const Marginals& get() const { return measured ? *measured : *full; }
};

InformationMarginals informationMarginals(const FactorGraph& graph, const Values& values,
                                          const std::vector<Key>& fixed) {
  InformationMarginals out;
  const FactorGraph measurements = measurementsOnly(graph);
  try {
    out.measured.emplace(measurements, values, fixed);
  } catch (const std::exception&) {
    out.measured.reset();
  }
  if (!out.measured) out.full.emplace(graph, values, fixed);
  return out;
}

/// The rule of a camera's scalar offset (its time offset, its readout): the
/// data's information on the variable at `key`, the prior's removed, against
/// the prior's own (both in ms^-2); observed when it exceeds it.
struct ScalarInformation {
  double information = 0.0, prior = 0.0;
  bool observed = false;
};

ScalarInformation scalarInformation(const Marginals& info_marg, Key key, double prior_sigma_s) {
  ScalarInformation s;
  s.prior = 1e-6 / (prior_sigma_s * prior_sigma_s);
  s.information = 1e-6 / info_marg.covariance(key)(0, 0) - s.prior;
  s.observed = s.information > s.prior;
  return s;
}

/// Each camera's time offset, observed when the data's information on it
/// exceeds its prior's (a warning when not); sigma_s comes later, from the
/// reported marginals.
std::vector<TimeOffsetEstimate> timeOffsets(const Values& values, const std::vector<CameraSpan>& cameras,
                                            const Marginals& info_marg, std::vector<std::string>& warnings) {
  std::vector<TimeOffsetEstimate> out;
  for (const CameraSpan& c : cameras) {
    const ScalarInformation info = scalarInformation(info_marg, timeOffsetKey(c.index), kTimeOffsetPriorSigmaS);
    TimeOffsetEstimate e;
    e.camera = c.name;
    e.offset_s = values.at<VecX>(timeOffsetKey(c.index))[0];
    e.information = info.information;
    e.observed = info.observed;
    if (!e.observed)
      warnings.push_back(
          "camera " + c.name + "'s time offset is not observed: the data's information on it is " +
          num(e.information) + " ms^-2 (its smallest eigenvalue), below its prior's " + num(info.prior) +
          " ms^-2 (0 +- " + num(kTimeOffsetPriorSigmaS * 1e3) +
          " ms): the leg moved too little while this camera saw the board. Its time_offset_ms is the prior's "
          "zero, not a measurement (observed: false)");
    out.push_back(e);
  }
  return out;
}

/// Each camera's rolling-shutter readout, by the time offsets' rule: observed
/// when the data's information on it exceeds its prior's.
std::vector<ReadoutEstimate> readouts(const OffsetModel& m, const Values& values,
                                      const std::vector<CameraSpan>& cameras, const Marginals& info_marg,
                                      std::vector<std::string>& warnings) {
  std::vector<ReadoutEstimate> out;
  for (const CameraSpan& c : cameras) {
    const ScalarInformation info = scalarInformation(info_marg, readoutKey(c.index), kReadoutPriorSigmaS);
    ReadoutEstimate e;
    e.camera = c.name;
    e.readout_s = values.at<VecX>(readoutKey(c.index))[0];
    e.prior_s = m.readout(c.index);
    e.information = info.information;
    e.observed = info.observed;
    if (!e.observed)
      warnings.push_back(
          "camera " + c.name + "'s rolling-shutter readout is not observed: the data's information on it is " +
          num(e.information) + " ms^-2, below its prior's " + num(info.prior) + " ms^-2 (" + num(e.prior_s * 1e3) +
          " +- " + num(kReadoutPriorSigmaS * 1e3) +
          " ms): the board moved too little across this camera's rows. Its readout_ms is the prior's (rig.yaml's "
          "readout_ms, else 0), not a measurement (readout_observed: false)");
    out.push_back(e);
  }
  return out;
}

/// The data's information on a per-joint vector (the joint offsets or the
/// backlash), everything else eliminated (in mrad^-2), its
/// eigen-decomposition, and which of its directions the data say less about
/// than the prior.
struct JointVectorInformation {
  MatX cov;        // joint covariance of the vector, the cameras' poses and the mount's
  VecX prior_info;  // the prior's, rad^-2
  Eigen::SelfAdjointEigenSolver<MatX> eig;
  std::vector<bool> unobserved;  // per eigenvector
};

JointVectorInformation jointVectorInformation(Key vector, const VecX& prior_sigma,
                                              const std::vector<CameraSpan>& cameras, std::optional<Key> mount,
                                              const Marginals& info_marg) {
  const Eigen::Index n = prior_sigma.size();
  std::vector<Key> keys{vector};
  for (const CameraSpan& c : cameras) keys.push_back(c.pose);
  if (mount) keys.push_back(*mount);
  JointVectorInformation ji;
  ji.cov = info_marg.jointCovariance(keys);
  const MatX S = ji.cov.topLeftCorner(n, n);
  ji.prior_info = prior_sigma.cwiseAbs2().cwiseInverse();
  MatX info = S.ldlt().solve(MatX::Identity(n, n));
  info.diagonal() -= ji.prior_info;
  info = 0.5 * (info + info.transpose()) * 1e-6;
  ji.eig.compute(info);
  const MatX& V = ji.eig.eigenvectors();
  ji.unobserved.resize(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i)
    ji.unobserved[static_cast<std::size_t>(i)] =
        ji.eig.eigenvalues()[i] <= 1e-6 * V.col(i).dot(ji.prior_info.cwiseProduct(V.col(i)));
  return ji;
}

/// The warning on joint k's unobserved zero offset or backlash (`what`),
/// with what a true one would do to the other estimates (e.absorbed).
std::string unobservedJointWarning(const JointOffsetEstimate& e, const char* what, Eigen::Index k, Eigen::Index n,
                                   double prior_info, bool mount) {
  const bool offset = std::string(what) == "zero offset";
  std::ostringstream w;
  w << "joint " << e.joint << "'s " << what << " is not observed: the data's information on it is "
    << num(e.eigenvalue) << " mrad^-2 (its smallest eigenvalue), below its prior's " << num(1e-6 * prior_info)
    << " (0 +- " << num(e.prior_sigma_rad) << " rad)";
  if (offset && k == 0) w << "; the joint nearest the base turns every board pose rigidly, as the camera poses can";
  if (offset && k == n - 1 && mount) w << "; the joint nearest the board folds into the board mount";
  w << ". Its " << (offset ? "offset_rad" : "rad") << " is the prior's zero, not a measurement (observed: false). A "
    << "true " << what << " of this joint goes into the other estimates, per mrad:";
  for (const Absorption& a : e.absorbed)
    w << " " << a.estimate << " " << std::fixed << std::setprecision(3) << a.mm_per_mrad << " mm, "
      << std::setprecision(4) << a.deg_per_mrad << " deg;";
  std::string text = w.str();
  text.back() = '.';
  return text;
}

/// Each joint's zero offset or backlash (`vector`), observed when it lies
/// mostly along directions the data observe (a warning with its absorption
/// when not); sigma_rad comes later, from the reported marginals. A joint in
/// `skip` (backlash of a joint that never moves both ways) is unobserved
/// without a warning of its own.
std::vector<JointOffsetEstimate> jointVector(const OffsetModel& m, Key vector, const VecX& prior_sigma,
                                             const char* what, const std::vector<bool>& skip, const Values& values,
                                             const std::vector<CameraSpan>& cameras, std::optional<Key> mount,
                                             const Marginals& info_marg, VecX* eigenvalues,
                                             std::vector<std::string>& warnings) {
  const Eigen::Index n = m.chain->numJoints();
  const JointVectorInformation ji = jointVectorInformation(vector, prior_sigma, cameras, mount, info_marg);
  if (eigenvalues) *eigenvalues = ji.eig.eigenvalues();
  const MatX& V = ji.eig.eigenvectors();
  const auto& names = m.chain->jointNames();
  const VecX o = values.at<VecX>(vector);
  std::vector<JointOffsetEstimate> out;
  for (Eigen::Index k = 0; k < n; ++k) {
    JointOffsetEstimate e;
    e.joint = names[static_cast<std::size_t>(k)];
    e.offset_rad = o[k];
    e.prior_sigma_rad = prior_sigma[k];
    double weight_unobserved = 0.0, best = -1.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double w = V(k, i) * V(k, i);
      if (ji.unobserved[static_cast<std::size_t>(i)]) weight_unobserved += w;
      if (w > best) best = w, e.eigenvalue = ji.eig.eigenvalues()[i];
    }
    e.observed = weight_unobserved < 0.5 && !skip[static_cast<std::size_t>(k)];
    if (!e.observed && !skip[static_cast<std::size_t>(k)]) {
      for (std::size_t c = 0; c < cameras.size(); ++c)
        e.absorbed.push_back(absorption(cameras[c].name, ji.cov, n + 6 * static_cast<Eigen::Index>(c), k));
      if (mount)
        e.absorbed.push_back(absorption("mount", ji.cov, n + 6 * static_cast<Eigen::Index>(cameras.size()), k));
      warnings.push_back(unobservedJointWarning(e, what, k, n, ji.prior_info[k], mount.has_value()));
    }
    out.push_back(e);
  }
  return out;
}

/// The backlash of every joint; those that never move both ways in the log
/// are named (backlash_not_reversing) for a finding of their own.
void backlash(const OffsetModel& m, const Values& values, const std::vector<CameraSpan>& cameras,
              std::optional<Key> mount, const Marginals& info_marg, OffsetEstimates& out) {
  std::vector<bool> skip;
  for (std::size_t k = 0; k < m.backlash_reversing.size(); ++k) {
    skip.push_back(!m.backlash_reversing[k]);
    if (skip.back()) out.backlash_not_reversing.push_back(m.chain->jointNames()[k]);
  }
  out.backlash = jointVector(m, kBacklash, m.backlash_sigma, "backlash", skip, values, cameras, mount, info_marg,
                             nullptr, out.warnings);
}

/// Each joint origin's correction, and which of its components the data
/// observe: the eigen-directions of the corrections' data information
/// (everything else eliminated, their prior's taken out) in units of the
/// prior's; a component is observed when it lies mostly along directions where
/// the data say more than the prior. The base-side origin moves every board
/// pose rigidly, as the camera poses can: never observed, its tolerance stays
/// in the cameras' covariance.
void originCorrections(const OffsetModel& m, const Values& values, const std::vector<CameraSpan>& cameras,
                       std::optional<Key> mount, const Marginals& info_marg, OffsetEstimates& out) {
  const Eigen::Index n6 = m.origin_sigma.size();
  const MatX S = info_marg.covariance(kOrigins);
  MatX info = S.ldlt().solve(MatX::Identity(n6, n6));
  info.diagonal() -= m.origin_sigma.cwiseAbs2().cwiseInverse();
  const MatX W = m.origin_sigma.asDiagonal() * (0.5 * (info + info.transpose())) * m.origin_sigma.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<MatX> eig(W);
  const VecX u = values.at<VecX>(kOrigins);
  out.origin_directions_observed = static_cast<int>((eig.eigenvalues().array() > 1.0).count());
  // What an unobserved component would move: the regression of the cameras
  // and the mount on it, as for the joint offsets.
  std::vector<Key> keys{kOrigins};
  for (const CameraSpan& c : cameras) keys.push_back(c.pose);
  if (mount) keys.push_back(*mount);
  const MatX cov = info_marg.jointCovariance(keys);
  const auto& names = m.chain->jointNames();
  for (std::size_t j = 0; j < names.size(); ++j) {
    OriginEstimate e;
    e.joint = names[j];
    const auto b = 6 * static_cast<Eigen::Index>(j);
    e.correction = u.segment<6>(b);
    e.prior_sigma = m.origin_sigma.segment<6>(b);
    for (int k = 0; k < 6; ++k) {
      double unobserved = 0.0;
      for (Eigen::Index i = 0; i < n6; ++i)
        if (eig.eigenvalues()[i] <= 1.0) unobserved += eig.eigenvectors()(b + k, i) * eig.eigenvectors()(b + k, i);
      e.observed[static_cast<std::size_t>(k)] = unobserved < 0.5;
      if (e.observed[static_cast<std::size_t>(k)]) continue;
      for (std::size_t c = 0; c < cameras.size(); ++c)
        e.absorbed[static_cast<std::size_t>(k)].push_back(
            absorption(cameras[c].name, cov, n6 + 6 * static_cast<Eigen::Index>(c), b + k));
      if (mount)
        e.absorbed[static_cast<std::size_t>(k)].push_back(
            absorption("mount", cov, n6 + 6 * static_cast<Eigen::Index>(cameras.size()), b + k));
    }
    out.origins.push_back(e);
  }
}

/// Each camera's covariance with the origins held at their estimates, from
/// the reported marginals (the unobserved offsets held there too): the Schur
/// complement Sigma_cc - Sigma_cu Sigma_uu^-1 Sigma_uc of their joint
/// covariance, the part of its sigma the URDF's tolerance does not explain.
void urdfShares(const Marginals& posterior, const OffsetModel& m, const std::vector<CameraSpan>& cameras,
                OffsetEstimates& out) {
  const Eigen::Index n6 = m.origin_sigma.size();
  for (const CameraSpan& c : cameras) {
    const MatX J = posterior.jointCovariance({c.pose, kOrigins});
    const MatX Suu = J.bottomRightCorner(n6, n6);
    const MatX Scu = J.topRightCorner(6, n6);
    const Mat6 exact = J.topLeftCorner<6, 6>() - Scu * Suu.ldlt().solve(Scu.transpose());
    out.urdf_shares.push_back({c.name, 0.5 * (exact + exact.transpose())});
  }
}

/// The reported marginals: the unobserved offsets held at their values by a
/// prior 1e-9 of their own size, the observed ones free. Reuses `full` when
/// nothing is held.
Marginals posteriorMarginals(const FactorGraph& graph, const std::vector<Key>& fixed, const Values& values,
                             const std::vector<CameraSpan>& cameras, const OffsetEstimates& est,
                             std::optional<Marginals>& full) {
  FactorGraph conditioned = graph;
  bool any_unobserved = false;
  for (const CameraSpan& c : cameras)
    for (const TimeOffsetEstimate& t : est.time_offsets)
      if (t.camera == c.name && !t.observed) {
        any_unobserved = true;
        conditioned.emplace<PriorFactorVector>(timeOffsetKey(c.index), values.at<VecX>(timeOffsetKey(c.index)),
                                               NoiseModel::isotropic(1, 1e-9 * kTimeOffsetPriorSigmaS));
      }
  for (const CameraSpan& c : cameras)
    for (const ReadoutEstimate& r : est.readouts)
      if (r.camera == c.name && !r.observed) {
        any_unobserved = true;
        conditioned.emplace<PriorFactorVector>(readoutKey(c.index), values.at<VecX>(readoutKey(c.index)),
                                               NoiseModel::isotropic(1, 1e-9 * kReadoutPriorSigmaS));
      }
  // Held: the joint vector's unobserved entries; the observed ones are left free.
  auto hold = [&](Key vector, const std::vector<JointOffsetEstimate>& entries) {
    if (std::all_of(entries.begin(), entries.end(), [](const JointOffsetEstimate& e) { return e.observed; })) return;
    VecX sigma(static_cast<Eigen::Index>(entries.size()));
    for (std::size_t k = 0; k < entries.size(); ++k)
      sigma[static_cast<Eigen::Index>(k)] = (entries[k].observed ? 1e9 : 1e-9) * entries[k].prior_sigma_rad;
    conditioned.emplace<PriorFactorVector>(vector, values.at<VecX>(vector), NoiseModel::diagonal(sigma));
    any_unobserved = true;
  };
  hold(kJointOffsets, est.joint_offsets);
  hold(kBacklash, est.backlash);
  return any_unobserved || !full ? Marginals(any_unobserved ? conditioned : graph, values, fixed) : std::move(*full);
}

/// The offsets' sigmas from the reported marginals; an unobserved joint
/// offset keeps its prior's.
void setSigmas(const Marginals& posterior, const std::vector<CameraSpan>& cameras, OffsetEstimates& est) {
  for (TimeOffsetEstimate& t : est.time_offsets)
    for (const CameraSpan& c : cameras)
      if (t.camera == c.name) t.sigma_s = std::sqrt(posterior.covariance(timeOffsetKey(c.index))(0, 0));
  for (ReadoutEstimate& r : est.readouts)
    for (const CameraSpan& c : cameras)
      if (r.camera == c.name)
        r.sigma_s = r.observed ? std::sqrt(posterior.covariance(readoutKey(c.index))(0, 0)) : kReadoutPriorSigmaS;
  auto sigmas = [&](Key vector, std::vector<JointOffsetEstimate>& entries) {
    if (entries.empty()) return;
    const MatX cov = posterior.covariance(vector);
    for (std::size_t k = 0; k < entries.size(); ++k) {
      JointOffsetEstimate& e = entries[k];
      e.sigma_rad = e.observed ? std::sqrt(cov(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k)))
                               : e.prior_sigma_rad;
    }
  };
  sigmas(kJointOffsets, est.joint_offsets);
  sigmas(kBacklash, est.backlash);
}

}  // namespace

Summary summarize(const OffsetModel& m, const FactorGraph& graph, const std::vector<Key>& fixed, const Values& values,
                  const std::vector<CameraSpan>& cameras, std::optional<Key> mount) {
  if (!m.any()) return {OffsetEstimates(), Marginals(graph, values, fixed)};
  OffsetEstimates out;
  // The joint log must cover every image at its exposure, or the estimate means nothing.
  // (its first row at the offset, its last a readout later).
  if (m.exposureTiming())
    for (const CameraSpan& c : cameras) {
      const double delta = m.time_offsets ? values.at<VecX>(timeOffsetKey(c.index))[0] : 0.0;
      const double readout = m.rolling_shutter ? values.at<VecX>(readoutKey(c.index))[0]
                                               : m.readout(c.index);
      checkTimeOffsetMargin({c.name, c.first_image_ns, c.last_image_ns}, delta, *m.trajectory, m.joint_log_name,
                            std::max(0.0, readout));
    }
  InformationMarginals info = informationMarginals(graph, values, fixed);
  if (m.time_offsets) out.time_offsets = timeOffsets(values, cameras, info.get(), out.warnings);
  if (m.rolling_shutter) out.readouts = readouts(m, values, cameras, info.get(), out.warnings);
  if (m.joint_offsets)
    out.joint_offsets = jointVector(m, kJointOffsets, m.joint_offset_sigma, "zero offset",
                                    std::vector<bool>(static_cast<std::size_t>(m.chain->numJoints()), false), values,
                                    cameras, mount, info.get(), &out.joint_offset_eigenvalues, out.warnings);
  if (m.backlash) backlash(m, values, cameras, mount, info.get(), out);
  if (m.origins) originCorrections(m, values, cameras, mount, info.get(), out);
  Marginals posterior = posteriorMarginals(graph, fixed, values, cameras, out, info.full);
  setSigmas(posterior, cameras, out);
  if (m.origins) {
    const VecX sd = posterior.covariance(kOrigins).diagonal().cwiseSqrt();
    for (std::size_t j = 0; j < out.origins.size(); ++j) out.origins[j].sigma = sd.segment<6>(6 * static_cast<Eigen::Index>(j));
    urdfShares(posterior, m, cameras, out);
  }
  return {std::move(out), std::move(posterior)};
}

namespace {

const TimeOffsetEstimate* timeOffsetOf(const CalibrationSolution& sol, const std::string& camera) {
  for (const TimeOffsetEstimate& t : sol.offsets.time_offsets)
    if (t.camera == camera) return &t;
  return nullptr;
}

}  // namespace

double readoutOf(const CalibrationProblemInput& p, const CalibrationSolution& sol, std::size_t camera) {
  for (const ReadoutEstimate& r : sol.offsets.readouts)
    if (r.camera == p.camera_names[camera]) return r.observed ? r.readout_s : r.prior_s;
  return p.offsets.readout(camera);
}

bool hasReadout(const CalibrationProblemInput& p, const CalibrationSolution& sol, std::size_t camera) {
  return readoutOf(p, sol, camera) != 0.0;
}

VecX backlashVector(const OffsetEstimates& est) {
  VecX b(static_cast<Eigen::Index>(est.backlash.size()));
  for (std::size_t j = 0; j < est.backlash.size(); ++j) b[static_cast<Eigen::Index>(j)] = est.backlash[j].offset_rad;
  return b;
}

VecX originVector(const OffsetEstimates& est) {
  VecX u(6 * static_cast<Eigen::Index>(est.origins.size()));
  for (std::size_t j = 0; j < est.origins.size(); ++j) u.segment<6>(6 * static_cast<Eigen::Index>(j)) = est.origins[j].correction;
  return u;
}

SE3 boardFromKinematics(const CalibrationProblemInput& p, const CalibrationSolution& sol, std::size_t k,
                        std::optional<double> delta_s, std::optional<double> row) {
  const BoardObservation& obs = p.observations[k];
  const SE3& M = sol.T_link_marker;
  const OffsetModel& m = p.offsets;
  VecX o;
  if (m.joint_offsets && !sol.offsets.joint_offsets.empty()) {
    o.resize(static_cast<Eigen::Index>(sol.offsets.joint_offsets.size()));
    for (Eigen::Index j = 0; j < o.size(); ++j) o[j] = sol.offsets.joint_offsets[static_cast<std::size_t>(j)].offset_rad;
  }
  const VecX u = m.origins ? originVector(sol.offsets) : VecX();
  VecX q = obs.joint_positions;
  if (o.size()) q += o;
  const bool backlash = m.backlash && !sol.offsets.backlash.empty() && sol.offsets.backlash_lag;
  if (backlash) q += sol.offsets.backlash_lag->at(obs.stamp_ns).cwiseProduct(backlashVector(sol.offsets));
  const SE3 board = u.size()                  ? m.chain->forwardCorrected(q, u, M)
                    : o.size() || backlash ? m.chain->forward(q) * M
                                              : obs.T_base_link * M;
  if (!m.exposureTiming()) return board;
  // Moved along the joint log's trajectory from the stamp to the exposure of
  // the row, as the time-offset factor sees it.
  const auto camera = static_cast<std::size_t>(obs.camera);
  const std::string& name = p.camera_names[camera];
  const TimeOffsetEstimate* t = m.time_offsets ? timeOffsetOf(sol, name) : nullptr;
  const double readout = readoutOf(p, sol, camera);
  const double r = row ? m.rowFraction(camera, *row) : meanRow(p, k);
  const double delta = delta_s.value_or(t ? t->offset_s : 0.0) + r * readout;
  if (delta == 0.0) return board;
  const double stamp = m.trajectory->seconds(obs.stamp_ns);
  VecX q_a, q_b;
  m.trajectory->evaluate(stamp, &q_a, nullptr);
  m.trajectory->evaluate(stamp + delta, &q_b, nullptr);
  if (o.size()) {
    q_a += o;
    q_b += o;
  }
  return board * m.chain->forward(q_a, M, nullptr).between(m.chain->forward(q_b, M, nullptr));
}

std::optional<ReportTimeOffsetSweep> sweepTimeOffset(const CalibrationProblemInput& p, const CalibrationSolution& sol,
                                                     std::size_t camera, const std::vector<std::size_t>& observations,
                                                     const vision::CameraModel& model, int points) {
  const TimeOffsetEstimate* est = p.offsets.time_offsets ? timeOffsetOf(sol, p.camera_names[camera]) : nullptr;
  if (!est) return std::nullopt;
  ReportTimeOffsetSweep sw;
  sw.camera = est->camera;
  sw.estimate_ms = est->offset_s * 1e3;
  sw.sigma_ms = est->sigma_s * 1e3;
  const double half = std::max(0.010, 6.0 * est->sigma_s);
  const SE3 T_cam_base = sol.cameras[camera].T_base_cam.inverse();
  for (int i = 0; i < points; ++i) {
    const double delta = est->offset_s - half + 2.0 * half * i / std::max(1, points - 1);
    double sq = 0.0;
    long n = 0;
    for (std::size_t k : observations) {
      const BoardObservation& o = p.observations[k];
      const bool per_row = hasReadout(p, sol, camera);
      const SE3 T_image = T_cam_base * boardFromKinematics(p, sol, k, delta);
      for (std::size_t c = o.corners_begin; c < o.corners_begin + o.corners_count; ++c) {
        const SE3 T_cam_marker = per_row ? T_cam_base * boardFromKinematics(p, sol, k, delta, p.corners.pixel(c).y())
                                         : T_image;
        if (const auto uv = model.project(T_cam_marker * p.corners.boardPoint(c))) {
          sq += (*uv - p.corners.pixel(c)).squaredNorm();
          ++n;
        }
      }
    }
    sw.delta_ms.push_back(delta * 1e3);
    sw.rms_px.push_back(n ? std::sqrt(sq / static_cast<double>(n)) : std::nan(""));
  }
  return sw;
}

}  // namespace fgcal::apps::offsets
