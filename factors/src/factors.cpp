// The SE(3) prior and relative-pose factors are header-only templates of
// fgcal::core's TypedFactor; this unit compiles them once so that errors in
// the headers show up when the library is built.
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/kinematic_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"
