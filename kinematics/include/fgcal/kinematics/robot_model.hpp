// A robot read from a URDF (through urdfdom, which stays out of this header):
// its name, links and joints in our own types, and the chains between any two
// of its links. Meshes are never loaded; only the kinematic tree and inertials.
#pragma once

#include <string>
#include <unordered_map>
#include <vector>

#include "fgcal/kinematics/chain.hpp"
#include "fgcal/kinematics/joint.hpp"

namespace fgcal::kinematics {

class RobotModel {
 public:
  /// Reads a URDF file. Throws UrdfError naming the file when it is missing or
  /// unreadable, not well-formed XML, not a valid URDF (urdfdom's reason is
  /// quoted), not a single tree, or has a movable joint with a zero axis.
  static RobotModel fromFile(const std::string& path);
  /// Parses URDF text; `source` names it in error messages.
  static RobotModel fromString(const std::string& urdf_xml, const std::string& source = "<string>");

  const std::string& name() const { return name_; }
  /// The file path, or the label given to fromString.
  const std::string& source() const { return source_; }
  const std::string& rootLink() const { return root_link_; }

  /// Links depth-first from the root (children in joint-name order), so that a
  /// parent always precedes its children; independent of urdfdom's map order.
  const std::vector<LinkInfo>& links() const { return links_; }
  /// Joints in the same order (each joint just before its child link's subtree).
  const std::vector<JointInfo>& joints() const { return joints_; }
  std::vector<std::string> linkNames() const;
  std::vector<std::string> jointNames() const;
  /// Names of all revolute, continuous and prismatic joints, in tree order.
  std::vector<std::string> movableJointNames() const;
  /// Links without child joints (not always feet: sensors, rotors, shells).
  std::vector<std::string> leafLinks() const;

  bool hasLink(const std::string& name) const { return link_index_.count(name) > 0; }
  bool hasJoint(const std::string& name) const { return joint_index_.count(name) > 0; }
  /// Throws UrdfError naming the file when the link or joint does not exist.
  const LinkInfo& link(const std::string& name) const;
  const JointInfo& joint(const std::string& name) const;

  /// Sum of the <inertial> masses, kg.
  double totalMass() const;

  /// The chain from base_link to tip_link: any two links of the tree. The path
  /// goes up from the base to the deepest common ancestor, then down to the tip.
  /// Throws UrdfError when a link is unknown, when there is no path, or when a
  /// floating or planar joint lies on the path.
  KinematicChain chain(const std::string& base_link, const std::string& tip_link) const;
  /// The movable joints of that chain, in chain order (what joints.csv must hold).
  std::vector<std::string> chainJointNames(const std::string& base_link, const std::string& tip_link) const {
    return chain(base_link, tip_link).jointNames();
  }

 private:
  RobotModel() = default;
  void requireLink(const std::string& name, const char* role) const;

  std::string name_, source_, root_link_;
  std::vector<LinkInfo> links_;
  std::vector<JointInfo> joints_;
  std::unordered_map<std::string, std::size_t> link_index_, joint_index_;

  friend class RobotModelBuilder;
};

}  // namespace fgcal::kinematics
