// fgcal's own robot model, a HyQ-like quadruped (data/robots/fgcal_quadruped.urdf),
// embedded in the library at build time so that the simulator and the demo
// work from any folder, installed or not. The file itself is also installed to
// <prefix>/share/fgcal/robots/ for users who want to read or edit it.
#pragma once

#include <array>
#include <string>

#include "fgcal/kinematics/robot_model.hpp"

namespace fgcal::kinematics {

/// The URDF text of the default robot.
const std::string& defaultRobotUrdf();
/// Its <robot name>: "fgcal_quadruped".
const std::string& defaultRobotName();
/// Its base link, "base_link" (the trunk, and the URDF root).
const std::string& defaultRobotBaseLink();
/// Its feet in the order LF, RF, LH, RH: lf_foot rf_foot lh_foot rh_foot.
const std::array<std::string, 4>& defaultRobotFeet();
/// The parsed model; its source() is "fgcal_quadruped.urdf (built in)".
RobotModel loadDefaultRobot();

}  // namespace fgcal::kinematics
