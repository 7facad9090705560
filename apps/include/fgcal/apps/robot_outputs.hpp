// The outputs of `fgcal calibrate` that go back into the robot's software:
// --urdf-out (the robot's URDF with the calibrated joint origins,
// urdf_update.hpp), --kalibr-out (a Kalibr camchain, camchain.hpp) and
// --tf-out (static-transform launch files, tf_launch.hpp).
//
// Two calls, so that the calibration pipeline stays one stage each:
// planRobotOutputs checks every option against rig.yaml and the URDF before
// the (slow) detection and solve; robotOutputFiles returns the files' (path,
// content) pairs, written by the caller in one writeFilesAtomically with
// calibration.yaml, so a failed run leaves every earlier output untouched.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/urdf_update.hpp"

namespace fgcal::apps {

struct RobotOutputOptions {
  std::string urdf_out;    ///< empty: not written
  std::string kalibr_out;  ///< empty: not written
  /// --tf-out, each a launch file: ".py" ROS 2 Python, ".xml" ROS 2 XML,
  /// ".launch" ROS 1 XML (tf_launch.hpp); empty: none written.
  std::vector<std::string> tf_outs;
};

struct RobotOutputPlan {
  RobotOutputOptions options;
  std::string base_link;
  /// Cameras in rig order (the calibrated ones), with what the files need.
  std::vector<CameraConfig> cameras;
  UrdfUpdatePlan urdf;  ///< used when options.urdf_out is set
  bool any() const {
    return !options.urdf_out.empty() || !options.kalibr_out.empty() || !options.tf_outs.empty();
  }
};

/// Checks the options (InputError, exit 2): every output's folder exists, no
/// output path is used twice or equals one of `other_outputs` (e.g.
/// calibration.yaml); --urdf-out needs at least one camera with `frame:` and
/// every such camera's joint must be writable (planUrdfUpdate); --tf-out needs
/// a launch file extension (kLaunchExtensions) and frame ids tf accepts. `rig` holds the cameras that will be calibrated.
RobotOutputPlan planRobotOutputs(const RobotOutputOptions& options, const RigConfig& rig, const std::string& rig_path,
                                 const std::vector<std::string>& other_outputs);

struct RobotOutputFiles {
  std::vector<std::pair<std::string, std::string>> files;  ///< (path, content)
  /// Lines for the calibrate summary (the URDF check with its figures, what
  /// each file is), each ending in '\n'.
  std::string summary;
};

/// The files for a calibration result `out` (cameras by name). The URDF is
/// checked through urdfdom and fgcal's chain walker (applyUrdfUpdate) before
/// it is returned.
RobotOutputFiles robotOutputFiles(const RobotOutputPlan& plan, const CalibrationOutput& out);

}  // namespace fgcal::apps
