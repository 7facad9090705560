// The simulator's option checks (internal to the simulator): what can be
// checked from the options alone, then what needs the robot (joint names) or
// the image clocks (camera delays), all before anything is written.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fgcal/apps/simulator.hpp"
#include "fgcal/kinematics/chain.hpp"

namespace fgcal::apps::sim {

/// InputError naming the option for any value out of range, an unknown
/// distortion model or camera name.
void validateOptions(const SimulationOptions& o);

/// --joint-offsets and --backlash name movable joints of the marker chain.
void checkJointOffsets(const SimulationOptions& o, const kinematics::KinematicChain& chain);

/// A camera's frame period in ms (33.3 at 30 Hz; 66.7 for xtion_rgb at 15 Hz
/// when there are several cameras), which bounds its readout.
double framePeriodMs(const std::string& camera, int cameras);

/// Every image of a camera is rendered inside joints.csv, from stamp + delay
/// to stamp + delay + readout + exposure: stamps_ns per camera (rig.yaml
/// order), the first and last joint stamps.
void checkCameraDelays(const SimulationOptions& o, const std::vector<std::string>& names,
                       const std::vector<std::vector<int64_t>>& stamps_ns, int64_t first_joint_ns,
                       int64_t last_joint_ns);

}  // namespace fgcal::apps::sim
