// The offsets' part of a calibration graph (PnP or corners): their variables
// and priors, the kinematic and image factors that see them, and after the
// final solve their estimates, what the data observe of them and the
// time-offset margin check (fgcal/apps/offset_estimation.hpp).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fgcal/apps/calibrate_options.hpp"
#include "fgcal/apps/calibration_problem.hpp"
#include "fgcal/apps/corner_calibration.hpp"
#include "fgcal/apps/offset_estimation.hpp"
#include "fgcal/apps/report.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/core/factor_graph.hpp"
#include "fgcal/core/marginals.hpp"
#include "fgcal/core/values.hpp"
#include "fgcal/vision/camera_model.hpp"

namespace fgcal::apps::offsets {

/// The model for `--estimate time-offset`, `joint-offsets` and `backlash`:
/// the chain, the joint log's trajectory (time offsets and backlash;
/// `columns` are the chain's columns of `log`), the priors from rig.yaml
/// (robot.joint_offset_sigma, robot.backlash_sigma, else their defaults), the
/// backlash's motor path and which joints move both ways, and with
/// robot.kinematic_sigma the origin corrections' prior. Only the offsets of
/// `estimate` count (not its intrinsics). Throws InputError naming rig.yaml's
/// field (rigFieldError) when a map form lacks a chain joint or names another.
OffsetModel makeModel(const EstimateSet& estimate, const RigConfig& rig,
                      const kinematics::KinematicChain& chain, const JointLog& log, const std::vector<int>& columns,
                      const std::string& joint_log_name);

/// The prior std of each joint's play, chain order: rig.yaml's
/// robot.backlash_sigma (a number or a map), else kDefaultBacklashSigma.
/// Throws InputError naming the field when its map does not fit the chain.
VecX backlashPriorSigma(const RigConfig& rig, const kinematics::KinematicChain& chain);

/// Camera c's time offset (VecX of size 1, seconds) and the joint offsets (VecX, chain order).
Key timeOffsetKey(std::size_t camera);
/// Camera c's rolling-shutter readout (VecX of size 1, seconds; --estimate rolling-shutter).
Key readoutKey(std::size_t camera);
inline constexpr Key kJointOffsets = key('o', 0);
/// The origin corrections (VecX of 6 n, robot.kinematic_sigma).
inline constexpr Key kOrigins = key('u', 0);
/// The joints' backlash (VecX, chain order, --estimate backlash).
inline constexpr Key kBacklash = key('g', 0);

/// Adds the offset variables of `model` for `cameras` (indices) with their
/// priors. Values are taken from `previous` when it holds them (a previous
/// round of the same calibration), else zero.
void addVariables(const OffsetModel& model, const std::vector<std::size_t>& cameras, const Values* previous,
                  FactorGraph& graph, Values& values);

/// A solve may change b by this fraction of the play its lag ran with and be
/// final. The lag's shape depends on b only near reversals, so b is the
/// fixed point of a strong contraction: on the simulated leg the next solve
/// changes it by 0.05 - 0.07 of what the last one did, so a change of 2 %
/// leaves b ~0.1 % (a hundredth of its sigma) off the fixed point.
inline constexpr double kBacklashLagTolerance = 0.02;
/// At most this many solves are added to a camera set's rounds for the lag
/// to settle; one or two do it from the robust solve's b.
inline constexpr int kBacklashLagRounds = 4;

/// The lag coefficients of a graph's kinematic factors with backlash: the
/// play operator (BacklashLag) over the model's motor path with the play of
/// `previous` (the last solve's), or without it the prior's sigma (a nominal
/// play, robot.backlash_sigma), at least the model's backlash_min_play; no
/// lag for a joint that does not move both ways. Null without backlash.
std::shared_ptr<const BacklashLag> backlashLag(const OffsetModel& model, const Values* previous);

/// Whether the play `solved` holds is the one `lag` ran with, within
/// kBacklashLagTolerance (each at least backlash_min_play, the joints that
/// move both ways): the solve is then the fixed point of b and its lag. True
/// without backlash.
bool backlashSettled(const OffsetModel& model, const BacklashLag* lag, const Values& solved);
/// The note when it is not, after kBacklashLagRounds more solves of the
/// camera set `cameras` ("a, b"): the last solve is kept.
std::string backlashUnsettled(const std::string& cameras);

/// The kinematic factor of the instant stamped `instant_ns`: KinematicFactor;
/// with joint offsets only JointOffsetKinematicFactor at the encoder readings
/// q; with origins or backlash ChainKinematicFactor, with backlash the lag
/// coefficients of `lag` at the instant (required then, see backlashLag).
Factor::Ptr kinematicFactor(const OffsetModel& model, const BacklashLag* lag, Key board, Key mount,
                            const SE3& T_base_link, const VecX& q, std::int64_t instant_ns, NoiseModel::Ptr noise);

/// An image factor on (..., board, ...): as it is, or with time offsets or a
/// rolling shutter the board at the image's exposure (TimeOffsetFactor), of
/// the pixel row `row` (r = v / (rows - 1), OffsetModel::rowFraction: the
/// corner's for a corner factor; for a PnP pose its corners' mean, the
/// approximation docs/outputs.md describes). `robust` applies either way;
/// `image` must have been built without a kernel.
Factor::Ptr imageFactor(const OffsetModel& model, Factor::Ptr image, std::size_t board_position, Key mount,
                        std::size_t camera, std::int64_t instant_ns, std::int64_t image_ns, double row,
                        RobustKernel::Ptr robust);

/// The row fraction standing for observation k's whole image (its PnP pose):
/// its detected corners' mean row (OffsetModel::rowFraction); 0.5 without
/// corners.
double meanRow(const CalibrationProblemInput& problem, std::size_t k);

/// The origin corrections of `estimates` as the graph's variable (6 n,
/// chain order); empty when they were not estimated.
VecX originVector(const OffsetEstimates& estimates);
/// The backlash of `estimates` as the graph's variable (chain order); empty
/// when it was not estimated.
VecX backlashVector(const OffsetEstimates& estimates);

/// One camera of the solve, for the estimates and the margin check.
struct CameraSpan {
  std::size_t index = 0;  ///< camera index (its keys)
  std::string name;
  Key pose;
  std::int64_t first_image_ns = 0, last_image_ns = 0;  ///< its used images
};

/// Camera c's span for summarize: every image of the camera in the problem,
/// the outliers too (an image whose exposure falls past the joint log is no
/// outlier but a log too short).
CameraSpan cameraSpan(const CalibrationProblemInput& problem, std::size_t c, Key pose);

/// Adds one solve's estimates to the solution's (F1 solves the cameras one by
/// one): every camera's time offsets, the joint offsets of the solve with the
/// most instants (like the mount), every warning.
void merge(OffsetEstimates estimates, std::size_t instants, std::size_t* best_instants, OffsetEstimates* into);

/// What the final solve of a graph reports: the offsets' estimates, and the
/// marginals every other estimate takes its covariance from.
struct Summary {
  OffsetEstimates estimates;
  Marginals marginals;
};

/// After the final solve of `graph` (its `values`, variables held `fixed`):
/// the offsets' estimates with observability (from the measurements' own
/// information), absorption and warnings, and the solution's marginals with
/// every unobserved offset held at its value. Without that conditioning an
/// unobserved offset's prior (0.05 rad by default) would pass into the
/// cameras' covariance through the direction they absorb it along (a base-side
/// joint's offset turns the cameras by as much), though the cameras are
/// reported as if the offset were not estimated. Without offsets: the plain
/// marginals. Throws InputError (checkTimeOffsetMargin) when a time offset
/// moves a camera's images past the joint log, DegenerateSystem when the
/// information is singular.
Summary summarize(const OffsetModel& model, const FactorGraph& graph, const std::vector<Key>& fixed,
                  const Values& values, const std::vector<CameraSpan>& cameras, std::optional<Key> mount);

/// The board pose of observation k from the kinematics and the calibration
/// `sol`: FK(q + o) M, moved along the joint log to the exposure
/// t + delta_c + r R_c of pixel row `row` (r = row / (rows - 1); absent: the
/// image's corners' mean row, meanRow) when time offsets were estimated or
/// the camera has a rolling shutter (`delta_s` replaces the camera's time
/// offset when given). What the reprojection and the report compare the
/// detected corners with: per corner, when hasReadout.
SE3 boardFromKinematics(const CalibrationProblemInput& problem, const CalibrationSolution& sol, std::size_t k,
                        std::optional<double> delta_s = std::nullopt, std::optional<double> row = std::nullopt);
/// Camera `camera`'s readout (s) as the solution models it: the estimate
/// (the prior's centre when not observed), else rig.yaml's held value.
double readoutOf(const CalibrationProblemInput& problem, const CalibrationSolution& sol, std::size_t camera);
/// readoutOf is non-zero: the camera's corners are seen at their own rows' times.
bool hasReadout(const CalibrationProblemInput& problem, const CalibrationSolution& sol, std::size_t camera);

/// The reprojection RMS of a camera's corners through kinematics +
/// calibration (boardFromKinematics) with its time offset set to each of
/// `points` values evenly over estimate +- max(10 ms, 6 sigma), everything
/// else at the solution, over the detected corners (problem.corners) of
/// `observations`. Empty when the camera's time offset was not estimated.
std::optional<ReportTimeOffsetSweep> sweepTimeOffset(const CalibrationProblemInput& problem,
                                                     const CalibrationSolution& sol, std::size_t camera,
                                                     const std::vector<std::size_t>& observations,
                                                     const vision::CameraModel& model, int points = 41);

}  // namespace fgcal::apps::offsets
