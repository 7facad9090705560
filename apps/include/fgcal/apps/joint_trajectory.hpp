// The joint log as a smooth, differentiable trajectory: what the time-offset
// factors evaluate at t + delta (fgcal/factors/time_offset_factor.hpp).
//
// A joint log is sampled (500 Hz in simulations, 100 Hz - 1 kHz on robots)
// and each sample carries encoder noise. Linear interpolation between samples,
// as the kinematic factors use at image stamps, has a derivative that jumps at
// every sample and is dominated by that noise (0.002 rad over 2 ms is 1.4
// rad/s, the speed of the leg itself): a time offset estimated through it
// would see noise as information. So each joint is fitted by a cubic B-spline
// with uniform knots (least squares, plus a tiny penalty on the second
// differences of its coefficients that bridges gaps and NaN samples): C2,
// with an exact derivative, and the noise averaged over the samples of a knot
// interval; the knot spacing is chosen from the log by generalized
// cross-validation (as wide as the motion allows, up to 5 x the base one). Past the log's span it continues at its end velocity (C1), so an
// optimizer may step there; calibrate refuses an estimate that leaves the span
// (checkTimeOffsetMargin).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/factors/joint_trajectory.hpp"

namespace fgcal::apps {

/// The base knot spacing: 20 ms, or 4 sample periods of a slower log. Over
/// 20 ms a passively moved leg is a cubic to ~1e-6 rad (a minimum-jerk
/// segment of 0.5 s), while 10 samples at 500 Hz are averaged.
inline constexpr double kJointTrajectoryKnotSpacingS = 0.02;

/// The knot spacings tried, in multiples of the base one: the default rule
/// takes the one of least generalized cross-validation score. A time offset
/// carries the board from one instant to another through the difference of
/// the trajectory at two times (fgcal/factors/time_offset_factor.hpp); with
/// knots every 20 ms on a 500 Hz log with 0.002 rad of encoder noise, that
/// difference over 15 ms is off by ~8e-4 rad per joint (nearly 0.4 x the
/// noise itself: the two ends share few samples), and 0.5 - 0.9 mm at a
/// board on a leg. Knots every 60 - 100 ms, when the motion allows them,
/// bring it to 1-2e-4 rad.
inline constexpr double kJointTrajectoryKnotFactors[] = {1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0};

class JointLogTrajectory final : public JointTrajectory {
 public:
  /// Fits `columns` of `log` (e.g. a chain's joints, chain order).
  /// knot_spacing_s <= 0: the default rule above (cross-validated). Throws InputError naming
  /// `source` when the log has fewer than 2 samples or a column has no finite
  /// value.
  JointLogTrajectory(const JointLog& log, const std::vector<int>& columns, const std::string& source,
                     double knot_spacing_s = 0.0);

  int numJoints() const override { return static_cast<int>(coefficients_.cols()); }
  void evaluate(double t, VecX* q, VecX* q_dot) const override;

  /// A stamp on this trajectory's clock: seconds after the log's first sample.
  double seconds(std::int64_t stamp_ns) const;
  std::int64_t firstStampNs() const { return first_ns_; }
  std::int64_t lastStampNs() const { return last_ns_; }
  /// The log's span in seconds on this clock: [0, duration()].
  double duration() const { return duration_; }
  double knotSpacing() const { return h_; }

 private:
  // q(t) = sum_m c_{k+m} b_m(u) for t in knot interval k, u in [0, 1).
  void evaluateInside(double t, double* q, double* q_dot) const;

  std::int64_t first_ns_ = 0, last_ns_ = 0;
  double duration_ = 0.0;
  double h_ = 0.0;
  int intervals_ = 0;
  Eigen::MatrixXd coefficients_;  // (intervals + 3) x joints
};

/// Where a camera's images sit in the joint log, for the time-offset check.
struct TimeOffsetMargin {
  std::string camera;
  std::int64_t first_image_ns = 0, last_image_ns = 0;
};

/// Throws InputError naming `log_name` (joints.csv or the bag's joint topic)
/// and the camera when `time_offset_s` moves its first image before the
/// log's first sample or its last image (its last row, `readout_s` after the
/// first, for a rolling shutter) after the log's last sample: the joints
/// there are not known, so the estimate cannot be trusted. The message gives
/// the offset, the readout, the margin at that end and what to do.
void checkTimeOffsetMargin(const TimeOffsetMargin& images, double time_offset_s, const JointLogTrajectory& trajectory,
                           const std::string& log_name, double readout_s = 0.0);

}  // namespace fgcal::apps
