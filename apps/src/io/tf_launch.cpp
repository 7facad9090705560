// Static-transform launch files for ROS 2 and ROS 1 (see tf_launch.hpp).
#include "fgcal/apps/tf_launch.hpp"

#include <Eigen/Geometry>

#include "io/text_format.hpp"

namespace fgcal::apps {

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// A ROS node name: letters, digits and '_', not starting with a digit.
std::string nodeName(const std::string& camera) {
  std::string n = "fgcal_";
  for (const char c : camera)
    n += ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')) ? c : '_';
  return n + "_static_tf";
}

// Text for inside an XML comment, which must not hold "--".
std::string xmlComment(const std::string& s) {
  std::string out = detail::xmlEscape(s);
  for (std::size_t i = out.find("--"); i != std::string::npos; i = out.find("--", i)) out.insert(i + 1, " ");
  return out;
}

// A Python single-quoted string literal (frame ids are checked to hold no quote).
std::string py(const std::string& s) { return "'" + s + "'"; }

struct Numbers {
  std::string x, y, z, qx, qy, qz, qw;
};

Numbers numbersOf(const SE3& T) {
  Eigen::Quaterniond q(T.rotation());
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const auto f = [](double v) { return detail::formatDoubleCsv(v); };
  const Vec3& t = T.translation();
  return {f(t.x()), f(t.y()), f(t.z()), f(q.x()), f(q.y()), f(q.z()), f(q.w())};
}

}  // namespace

const char* const kLaunchExtensions =
    ".launch.py (ROS 2 Python), .launch.xml (ROS 2 XML) or .launch (ROS 1 roslaunch XML)";

std::optional<LaunchFlavor> launchFlavorFor(const std::string& path) {
  if (endsWith(path, ".py")) return LaunchFlavor::Ros2Python;
  if (endsWith(path, ".xml")) return LaunchFlavor::Ros2Xml;
  if (endsWith(path, ".launch")) return LaunchFlavor::Ros1Xml;
  return std::nullopt;
}

const char* launchFlavorName(LaunchFlavor flavor) {
  switch (flavor) {
    case LaunchFlavor::Ros2Python: return "ROS 2 Python launch file";
    case LaunchFlavor::Ros2Xml: return "ROS 2 XML launch file";
    case LaunchFlavor::Ros1Xml: return "ROS 1 roslaunch XML";
  }
  return "";
}

std::string frameIdProblem(const std::string& frame) {
  if (frame.empty()) return "a frame id must not be empty";
  for (const char c : frame)
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '"' || c == '\'' || c == '\\' || c == '<' ||
        c == '>' || c == '&')
      return "a frame id on a launch command line must not hold whitespace, quotes, backslashes or <>&";
  return "";
}

std::string formatStaticTfLaunch(const std::vector<StaticTransform>& transforms, LaunchFlavor flavor) {
  std::string s;
  if (flavor == LaunchFlavor::Ros2Python) {
    s += "# Static transforms of the cameras calibrated by fgcal: pose of each camera frame in its parent\n";
    s += "# (metres, unit quaternion x y z w). ROS 2 Humble or later: ros2 launch <this file>.\n";
    s += "# Do not also publish these frames from a URDF (robot_state_publisher): a frame has one parent.\n";
    s += "from launch import LaunchDescription\n";
    s += "from launch_ros.actions import Node\n\n\n";
    s += "def generate_launch_description():\n";
    s += "    return LaunchDescription([\n";
    for (const StaticTransform& t : transforms) {
      const Numbers n = numbersOf(t.T_parent_child);
      s += "        Node(  # camera " + t.camera + "\n";
      s += "            package='tf2_ros',\n";
      s += "            executable='static_transform_publisher',\n";
      s += "            name=" + py(nodeName(t.camera)) + ",\n";
      s += "            arguments=['--x', " + py(n.x) + ", '--y', " + py(n.y) + ", '--z', " + py(n.z) + ",\n";
      s += "                       '--qx', " + py(n.qx) + ", '--qy', " + py(n.qy) + ", '--qz', " + py(n.qz) +
           ", '--qw', " + py(n.qw) + ",\n";
      s += "                       '--frame-id', " + py(t.parent) + ", '--child-frame-id', " + py(t.child) + "],\n";
      s += "        ),\n";
    }
    s += "    ])\n";
    return s;
  }
  if (flavor == LaunchFlavor::Ros2Xml) {
    s += "<?xml version=\"1.0\"?>\n";
    s += "<!-- Static transforms of the cameras calibrated by fgcal: pose of each camera frame in its parent\n";
    s += "     (metres, unit quaternion x y z w). ROS 2 Humble or later: ros2 launch <this file>.\n";
    s += "     Do not also publish these frames from a URDF (robot_state_publisher): a frame has one parent. -->\n";
    s += "<launch>\n";
    for (const StaticTransform& t : transforms) {
      const Numbers n = numbersOf(t.T_parent_child);
      s += "  <!-- camera " + xmlComment(t.camera) + " -->\n";
      s += "  <node pkg=\"tf2_ros\" exec=\"static_transform_publisher\" name=\"" + nodeName(t.camera) + "\"\n";
      s += "        args=\"--x " + n.x + " --y " + n.y + " --z " + n.z + " --qx " + n.qx + " --qy " + n.qy +
           " --qz " + n.qz + " --qw " + n.qw + " --frame-id " + t.parent + " --child-frame-id " + t.child + "\"/>\n";
    }
    s += "</launch>\n";
    return s;
  }
  s += "<?xml version=\"1.0\"?>\n";
  s += "<!-- Static transforms of the cameras calibrated by fgcal (ROS 1, tf2_ros): args=\"x y z qx qy qz qw\n";
  s += "     parent child\", the pose of each camera frame in its parent in metres and a unit quaternion.\n";
  s += "     Do not also publish these frames from a URDF (robot_state_publisher): a frame has one parent. -->\n";
  s += "<launch>\n";
  for (const StaticTransform& t : transforms) {
    const Numbers n = numbersOf(t.T_parent_child);
    s += "  <!-- camera " + xmlComment(t.camera) + " -->\n";
    s += "  <node pkg=\"tf2_ros\" type=\"static_transform_publisher\" name=\"" + nodeName(t.camera) + "\"\n";
    s += "        args=\"" + n.x + " " + n.y + " " + n.z + " " + n.qx + " " + n.qy + " " + n.qz + " " + n.qw + " " +
         t.parent + " " + t.child + "\"/>\n";
  }
  s += "</launch>\n";
  return s;
}

}  // namespace fgcal::apps
