// Camera time offsets and joint zero offsets, estimated with the camera poses
// (`fgcal calibrate --estimate time-offset,joint-offsets`): what the graph
// needs to model them (OffsetModel) and what comes out (OffsetEstimates), with
// which of them the data observe.
//
// Time offset delta_c of camera c: an image stamped t was exposed at
// t + delta_c; the board it saw is the board of the joint log at t + delta_c
// (fgcal/factors/time_offset_factor.hpp). Joint zero offset o_k: the joint
// stood at q_k + o_k when its encoder read q_k; the kinematics are evaluated at
// q + o (fgcal/factors/joint_offset_factor.hpp). Gear backlash b_k
// (`--estimate backlash`): the joint stood at q_k + lambda_k(t) b_k, lambda
// the lag of a play operator of width b_k run over the joint log
// (BacklashLag), held fixed within a solve and recomputed from the estimated
// b between solves.
//
// Observability. Each offset's information is read from the marginal
// covariance of the solution (every other variable eliminated), with its
// prior's information taken out: what the data alone say. An offset whose
// data information is below its prior's is "not observed": its value is the
// prior's (zero) and no measurement; the calibration is then as if it were not
// estimated, and a true offset of that joint went into other estimates. On a
// leg: the joint nearest the base turns every board pose rigidly about its
// axis, so the camera poses absorb its offset; the joint nearest the board
// folds into the mount. How much, per mrad of offset, is reported (the linear
// response of the other estimates along the unobserved direction).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fgcal/apps/joint_trajectory.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/kinematics/chain.hpp"

namespace fgcal::apps {

/// The prior std of a time offset: a weak prior (0 +- 100 ms) that keeps the
/// problem well posed when the leg barely moves. An offset whose data
/// information is below it is reported as not observed.
inline constexpr double kTimeOffsetPriorSigmaS = 0.1;

/// The prior std of an estimated rolling-shutter readout (`--estimate
/// rolling-shutter`), about rig.yaml's readout_ms (0 when absent): loose
/// against the readouts of real sensors (5-35 ms), so that the data decide.
/// A readout whose data information is below it is reported as not observed.
inline constexpr double kReadoutPriorSigmaS = 0.02;
struct MotorPath;

/// What the calibration graph needs to estimate offsets (empty: neither).
struct OffsetModel {
  bool time_offsets = false;
  bool joint_offsets = false;
  /// The chain from the base to the marker link (both kinds of offsets).
  std::shared_ptr<const kinematics::KinematicChain> chain;
  /// The joint log as a smooth trajectory, chain order (time offsets, backlash).
  std::shared_ptr<const JointLogTrajectory> trajectory;
  /// The joint log as named in messages (joints.csv, or the bag's topic).
  std::string joint_log_name;
  /// Prior std of each joint's zero offset, chain order (joint offsets).
  Eigen::VectorXd joint_offset_sigma;
  /// Where the prior std came from, for the summary: "rig.yaml" or "default".
  std::string joint_offset_sigma_source;
  /// The URDF's tolerance (robot.kinematic_sigma): the origins of the chain's
  /// movable joints are variables (fgcal/factors/joint_offset_factor.hpp,
  /// OriginKinematicFactor) with this prior std, 6 per joint [w v] in chain
  /// order, so that what the leg's geometry cannot tell enters the camera
  /// poses' covariance.
  bool origins = false;
  Eigen::VectorXd origin_sigma;
  /// Gear backlash (`--estimate backlash`): one play b per movable joint of
  /// the chain, a variable of the graph; the true angle is q + lag(t) .* b,
  /// with lag the play operator's (BacklashLag) run with the previous round's
  /// b (offset_graph.hpp, backlashLag).
  bool backlash = false;
  /// Prior std of each joint's play, chain order (robot.backlash_sigma, else
  /// kDefaultBacklashSigma); where it came from, "rig.yaml" or "default".
  Eigen::VectorXd backlash_sigma;
  std::string backlash_sigma_source;
  /// The motor's path the play operator runs over (the joint log's smooth
  /// fit at the log's stamps), and per joint whether it moves both ways in
  /// the log (backlashReversing): a joint that does not shows its play as a
  /// constant lag, which cannot be told from a zero offset, and its play is
  /// not estimated.
  std::shared_ptr<const MotorPath> backlash_path;
  std::vector<bool> backlash_reversing;
  /// The smallest play the lag is computed with, per joint: the encoder
  /// sigma (robot.encoder_sigma). A play estimated below it (or negative)
  /// cannot be crossed distinguishably from the fit's own noise, which turns
  /// a joint at rest to and fro by a fraction of it; its lag*b is below the
  /// encoder's noise either way.
  Eigen::VectorXd backlash_min_play;

  /// Rolling shutter, per camera (the problem's order): the readout R_c in
  /// seconds (rig.yaml's readout_ms; 0 is a global shutter) and the image's
  /// rows. A corner in row v is exposed at its image's stamp + delta_c +
  /// v / (rows - 1) R_c (fgcal/factors/time_offset_factor.hpp). With
  /// `rolling_shutter` (`--estimate rolling-shutter`) every camera's R_c is a
  /// variable with readout_s as its prior's centre (kReadoutPriorSigmaS);
  /// without, R_c is held at readout_s.
  bool rolling_shutter = false;
  Eigen::VectorXd readout_s;
  std::vector<int> rows;

  bool any() const { return time_offsets || joint_offsets || origins || backlash || exposureTiming(); }
  /// An image factor needs the board at its exposure rather than at its
  /// stamp: a time offset or a rolling shutter, estimated or known.
  bool exposureTiming() const {
    return time_offsets || rolling_shutter || (readout_s.size() > 0 && (readout_s.array() != 0.0).any());
  }
  /// Camera c's readout_s entry, 0 when the model has none for it.
  double readout(std::size_t camera) const {
    return camera < static_cast<std::size_t>(readout_s.size()) ? readout_s[static_cast<Eigen::Index>(camera)] : 0.0;
  }
  /// r = v / (rows - 1) of a pixel row v of camera c, clamped to [0, 1].
  double rowFraction(std::size_t camera, double v) const;
};

/// The motor side of geared joints as the joint log gives it: its smooth fit
/// (`trajectory`) at the log's own stamps, dense against a reversal (100 Hz -
/// 1 kHz, where crossing a play of a few mrad takes tenths of a second).
struct MotorPath {
  std::shared_ptr<const JointLogTrajectory> trajectory;
  std::vector<double> t;  ///< seconds on the trajectory's clock, increasing
  Eigen::MatrixXd q;      ///< the fit's positions, samples x joints
  Eigen::MatrixXd v;      ///< and velocities
};
/// `trajectory` (the smooth fit of `log`'s columns) sampled at `log`'s stamps.
std::shared_ptr<const MotorPath> motorPath(std::shared_ptr<const JointLogTrajectory> trajectory, const JointLog& log);

/// A joint moves both ways when the log, cut where its velocity changes
/// sign, holds a stretch in each direction longer than this many encoder
/// sigmas (robot.encoder_sigma).
inline constexpr double kBacklashReversalTravel = 10.0;

/// Per joint of `path`, whether it moves both ways: the path, cut where the
/// fit's velocity changes sign, has a stretch in each direction that travels
/// more than kBacklashReversalTravel x `encoder_sigma` (per joint). A joint
/// at rest, its readings' noise turning the fit to and fro, does not.
std::vector<bool> backlashReversing(const MotorPath& path, const Eigen::VectorXd& encoder_sigma);

/// The lag coefficients of gear play: a joint driven through a dead zone of
/// width b follows its motor x (what the encoder reads) as the play
/// operator y = clamp(y_prev, x - b/2, x + b/2), so it stands at
/// x + lambda b with lambda = (y - x) / b in [-0.5, 0.5]: -0.5 while the
/// motor drives it forward, +0.5 backward, and after a reversal lambda turns
/// over the motor's travel of b, not at zero velocity. The operator runs over
/// the motor path's samples and starts at the first with the lag of the
/// direction of the joint's first motion (b/2 behind it: lambda = -0.5 when
/// it first moves forward), as sim::JointPlay does; that motion is the first
/// to take the fit more than b/2 from its start, so that the fit's noise at
/// rest does not decide it. Between samples it clamps at the fit's value,
/// exact while the motor is monotone there.
class BacklashLag {
 public:
  BacklashLag() = default;
  /// The operator over `path` with play `play` per joint; a joint whose play
  /// is not positive has no lag (lambda 0).
  BacklashLag(std::shared_ptr<const MotorPath> path, const Eigen::VectorXd& play);

  /// lambda per joint at a stamp of the joint log; before the first sample,
  /// the first sample's.
  Eigen::VectorXd at(std::int64_t stamp_ns) const;
  /// The play per joint the operator ran with.
  const Eigen::VectorXd& play() const { return play_; }

 private:
  std::shared_ptr<const MotorPath> path_;
  Eigen::VectorXd play_;
  Eigen::MatrixXd y_;  // the joint side at each sample, samples x joints
};

/// How much an unobserved joint offset moves another estimate, per mrad.
struct Absorption {
  std::string estimate;  ///< a camera name, or "mount"
  double mm_per_mrad = 0.0;
  double deg_per_mrad = 0.0;
};

struct TimeOffsetEstimate {
  std::string camera;
  double offset_s = 0.0;
  double sigma_s = 0.0;  ///< marginal 1-sigma
  /// The data's information on it (its prior's taken out), in ms^-2.
  double information = 0.0;
  bool observed = true;
};

/// A camera's estimated rolling-shutter readout (first row to last).
struct ReadoutEstimate {
  std::string camera;
  double readout_s = 0.0;
  double sigma_s = 0.0;        ///< marginal 1-sigma
  double prior_s = 0.0;        ///< the prior's centre, rig.yaml's readout_ms
  /// The data's information on it (its prior's taken out), in ms^-2.
  double information = 0.0;
  bool observed = true;
};

struct JointOffsetEstimate {
  std::string joint;
  double offset_rad = 0.0;
  double sigma_rad = 0.0;        ///< marginal 1-sigma
  double prior_sigma_rad = 0.0;
  bool observed = true;
  /// The data information (mrad^-2) of the eigen-direction of the offsets'
  /// information this joint weighs most in: its smallest eigenvalue when not observed.
  double eigenvalue = 0.0;
  /// Not observed: what a true offset of 1 mrad does to each camera and the mount.
  std::vector<Absorption> absorbed;
};

/// The estimated correction of one movable joint's origin (robot.kinematic_sigma):
/// the transform before the joint became C Exp(correction), [w v].
struct OriginEstimate {
  std::string joint;
  Eigen::Matrix<double, 6, 1> correction = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> sigma = Eigen::Matrix<double, 6, 1>::Zero();        ///< marginal 1-sigma
  Eigen::Matrix<double, 6, 1> prior_sigma = Eigen::Matrix<double, 6, 1>::Zero();  ///< robot.kinematic_sigma
  /// Per component: the data's information along it exceeds its prior's
  /// (mostly observed directions of the corrections' eigen-analysis).
  std::array<bool, 6> observed{};
  /// Per component not observed: what a true correction of 1 mrad (rotation)
  /// or 1 mm (translation) does to each camera and the mount (Absorption's
  /// "per mrad" reads per mm for a translation).
  std::array<std::vector<Absorption>, 6> absorbed;
};

/// How much of a camera's 1-sigma comes from the URDF's tolerance: its
/// marginal with the origins free against held at their estimates.
struct UrdfShare {
  std::string camera;
  Eigen::Matrix<double, 6, 6> covariance_urdf_exact = Eigen::Matrix<double, 6, 6>::Zero();
};

struct OffsetEstimates {
  std::vector<TimeOffsetEstimate> time_offsets;    ///< one per camera, when estimated
  std::vector<ReadoutEstimate> readouts;           ///< one per camera, with --estimate rolling-shutter
  std::vector<OriginEstimate> origins;             ///< one per movable joint of the chain, with kinematic_sigma
  std::vector<UrdfShare> urdf_shares;              ///< one per camera, with kinematic_sigma
  int origin_directions_observed = 0;              ///< of 6 n
  std::vector<JointOffsetEstimate> joint_offsets;  ///< one per movable joint of the chain, when estimated
  /// Eigenvalues (ascending) of the joint offsets' data information, mrad^-2.
  Eigen::VectorXd joint_offset_eigenvalues;
  /// One per movable joint of the chain, with --estimate backlash: offset_rad
  /// holds the play b, by the same observability rule as the joint offsets.
  std::vector<JointOffsetEstimate> backlash;
  /// The joints whose play is not estimated: they never move both ways in the log.
  std::vector<std::string> backlash_not_reversing;
  /// The lag coefficients the final solve's kinematic factors used (the play
  /// operator with the play of the round before it); null without backlash.
  std::shared_ptr<const BacklashLag> backlash_lag;
  std::vector<std::string> warnings;
};

/// The estimates into calibration.yaml's fields: per camera time_offset_ms
/// and time_offset_sigma_ms (cameras matched by name), joint_offsets. What is
/// not observed is written as its prior (0 and the prior's sigma) with
/// observed: false, never as the solver's near-zero number.
void addOffsetResults(const OffsetEstimates& estimates, CalibrationOutput* output);

/// The lines of the calibrate summary: each offset with its 1-sigma, and for
/// a joint offset the data do not observe, what it does to the cameras per mrad.
std::string formatOffsetSummary(const OffsetEstimates& estimates);

}  // namespace fgcal::apps
