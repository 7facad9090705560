// Our own description of URDF joints and links, so that no urdfdom type leaks
// into the public API: a robot model is a list of these, and a chain is built
// from a path of them.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "fgcal/core/se3.hpp"

namespace fgcal::kinematics {

enum class JointType { Revolute, Continuous, Prismatic, Fixed, Floating, Planar };

/// "revolute", "continuous", ... as URDF spells them.
const char* toString(JointType type);

/// One degree of freedom the chain walker can follow: revolute, continuous, prismatic.
inline bool isMovable(JointType type) {
  return type == JointType::Revolute || type == JointType::Continuous || type == JointType::Prismatic;
}

struct JointLimits {
  /// False for continuous joints and joints without <limit>: lower/upper are then -inf/+inf.
  bool has_position_limits = false;
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  double effort = 0.0;    ///< 0 when not given
  double velocity = 0.0;  ///< 0 when not given
};

struct JointInfo {
  std::string name;
  JointType type = JointType::Fixed;
  std::string parent_link;
  std::string child_link;
  /// URDF <origin>: the joint frame (= child link frame at q = 0) in the parent link frame.
  SE3 T_parent_joint;
  /// Unit axis in the joint frame; URDF's default (1, 0, 0) when <axis> is absent.
  /// Meaningless for fixed and floating joints.
  Vec3 axis = Vec3::UnitX();
  JointLimits limits;
  /// Name of the joint this one mimics (URDF <mimic>), empty when none. The
  /// chain walker treats a mimic joint as an independent joint: its value must
  /// be given like any other.
  std::string mimic_joint;
};

struct LinkInfo {
  std::string name;
  std::string parent_joint;               ///< empty for the root link
  std::vector<std::string> child_joints;  ///< sorted by name
  bool has_inertial = false;
  double mass = 0.0;  ///< kg; 0 without <inertial>
  /// Centre of mass frame in the link frame, and the inertia tensor about the
  /// centre of mass in that frame (kg m^2).
  SE3 T_link_com;
  Mat3 inertia = Mat3::Zero();
};

}  // namespace fgcal::kinematics
