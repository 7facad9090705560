// Each calibrated camera against its pose in the robot's URDF (rig.yaml
// `frame:`): the shift, the joint --urdf-out would rewrite and the other
// frames that rewrite also moves. A CAD pose is never exact, so a shift is
// a note; one beyond any mounting tolerance says that `frame:` names the
// wrong link (another camera's, or a body frame in place of the optical one).
#pragma once

#include <vector>

#include "fgcal/apps/quality.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/kinematics/robot_model.hpp"

namespace fgcal::apps::quality {

/// Beyond these, a camera's shift from its URDF frame is a check: a camera
/// bracket's tolerance is millimetres and a fraction of a degree; CAD that
/// misplaces a camera by 5 cm or 10 deg has another camera's or a body frame
/// in its place.
inline constexpr double kFrameShiftCheckMm = 50.0;
inline constexpr double kFrameShiftCheckDeg = 10.0;

/// One urdf_frame finding per camera with a `frame:` reached from the base
/// through fixed joints only.
std::vector<Finding> frameFindings(const RigConfig& rig, const kinematics::RobotModel& robot,
                                   const std::vector<CameraResult>& cameras);

}  // namespace fgcal::apps::quality
