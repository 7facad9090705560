// The simulated passive leg motion (internal to the simulator): joint-space
// waypoints at which the board is seen well by the cameras, chosen for
// diversity of the board's orientation and position, joined by minimum-jerk
// segments (zero velocity and acceleration at every waypoint, straight lines
// in joint space).
#pragma once

#include <vector>

#include "commands/simulate/scene.hpp"

namespace fgcal::apps::sim {

class LegTrajectory {
 public:
  LegTrajectory() = default;
  LegTrajectory(std::vector<double> times, std::vector<VecX> waypoints)
      : times_(std::move(times)), waypoints_(std::move(waypoints)) {}

  /// Joint values at t seconds (clamped to [0, duration()]).
  VecX at(double t) const;
  double duration() const { return times_.empty() ? 0.0 : times_.back(); }
  const std::vector<double>& times() const { return times_; }
  const std::vector<VecX>& waypoints() const { return waypoints_; }

 private:
  std::vector<double> times_;  // waypoint times, times_[0] = 0
  std::vector<VecX> waypoints_;
};

/// The joint side of geared joints with backlash, driven by the motor side
/// `motor` (what the encoders read): each joint follows its motor through a
/// dead zone of width b (a play operator), q = clamp(q before, m - b/2,
/// m + b/2), started b/2 behind its first move (at rest when it never moves).
/// Every joint is monotone on each minimum-jerk segment, where the play
/// operator's output is that clamp of its value at the segment's start: at(t)
/// is exact at any t, with no stepping. b = 0 returns the motor's values.
class JointPlay {
 public:
  JointPlay(const LegTrajectory& motor, VecX backlash);
  VecX at(double t) const;

 private:
  const LegTrajectory* motor_;
  VecX half_;                // b / 2 per joint
  bool none_ = true;         // every b is 0
  std::vector<VecX> start_;  // the joint side at each waypoint time
};

/// Plans at least `duration` seconds of motion. Throws DataError when no
/// sampled configuration shows the board to any camera.
LegTrajectory planLegMotion(const kinematics::KinematicChain& chain, const SE3& T_link_marker,
                            const std::vector<SimCamera>& cameras, const vision::CharucoTarget& target,
                            const Workspace& ws, double duration, Rng& rng);

}  // namespace fgcal::apps::sim
