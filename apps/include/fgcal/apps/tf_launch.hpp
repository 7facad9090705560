// `fgcal calibrate --tf-out`: launch files that publish each calibrated camera
// as a static transform (tf2_ros static_transform_publisher), parent = the
// rig's base link, child = the camera's frame (rig.yaml `frame:`, else its
// name).
// - ROS 2 (Humble and later), a Python launch file (a path ending in ".py",
//   e.g. cameras.launch.py): one launch_ros Node per camera with the
//   new-style arguments --x --y --z --qx --qy --qz --qw --frame-id
//   --child-frame-id (tf2_ros/src/static_transform_broadcaster_program.cpp).
// - ROS 2, XML launch (a path ending in ".xml", e.g. cameras.launch.xml): one
//   <node pkg="tf2_ros" exec="static_transform_publisher" args="--x ..."/>
//   per camera, the same arguments.
// - ROS 1, roslaunch XML (a path ending in ".launch"): one
//   <node pkg="tf2_ros" type="static_transform_publisher"
//   args="x y z qx qy qz qw parent child"/> per camera.
// Any other path is refused (kLaunchExtensions lists the accepted ones).
// Publishing a frame that robot_state_publisher already publishes from the
// URDF gives it two parents: use these for cameras outside the URDF, or the
// --urdf-out write-back for cameras inside it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "fgcal/core/se3.hpp"

namespace fgcal::apps {

struct StaticTransform {
  std::string camera;  ///< for the node name and comments
  std::string parent, child;
  SE3 T_parent_child;  ///< pose of child in parent (p_parent = T * p_child)
};

enum class LaunchFlavor { Ros2Python, Ros2Xml, Ros1Xml };

/// The accepted endings, for messages: ".launch.py (ROS 2 Python), ...".
extern const char* const kLaunchExtensions;

/// Ros2Python for a path ending in ".py", Ros2Xml for ".xml", Ros1Xml for
/// ".launch"; nullopt for any other path.
std::optional<LaunchFlavor> launchFlavorFor(const std::string& path);

/// "ROS 2 Python launch file", "ROS 2 XML launch file", "ROS 1 roslaunch XML".
const char* launchFlavorName(LaunchFlavor flavor);

/// Frame ids tf accepts on a command line: non-empty, no whitespace, no
/// quotes or backslashes. Returns "" when `frame` is fine, else what is wrong.
std::string frameIdProblem(const std::string& frame);

/// The launch file text. Numbers in the shortest form that reads back to the
/// same double; the quaternion is unit with qw >= 0.
std::string formatStaticTfLaunch(const std::vector<StaticTransform>& transforms, LaunchFlavor flavor);

}  // namespace fgcal::apps
