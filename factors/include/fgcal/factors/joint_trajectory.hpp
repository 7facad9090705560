// Joint positions as a differentiable function of time: what a factor needs
// to evaluate the kinematics at an instant it estimates (a camera's time
// offset moves the exposure off the image stamp). fgcal's calibration builds
// one from the joint log (apps: a smoothing spline of joints.csv or of a
// bag's joint states); a user can give any other, e.g. a controller's
// reference trajectory.
#pragma once

#include "fgcal/core/types.hpp"

namespace fgcal {

class JointTrajectory {
 public:
  virtual ~JointTrajectory() = default;

  /// The size of q, in the order of the chain the factors evaluate.
  virtual int numJoints() const = 0;

  /// q(t) into *q and, when q_dot is non-null, dq/dt into *q_dot (both
  /// resized to numJoints()); t in seconds on the trajectory's own clock.
  /// Must be defined for every finite t and continuous with its derivative,
  /// also past the recorded span (e.g. continued at the end velocity), so
  /// that an optimizer may step there; whether an estimate may end there is
  /// the caller's to check. Safe to call concurrently.
  virtual void evaluate(double t, VecX* q, VecX* q_dot) const = 0;
};

}  // namespace fgcal
