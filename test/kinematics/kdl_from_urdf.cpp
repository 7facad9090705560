// Test oracle (see kdl_from_urdf.hpp): urdfdom joints -> KDL segments, the way
// kdl_parser does it, without ROS.
#include "kdl_from_urdf.hpp"

#include <stdexcept>
#include <vector>

#include <kdl/frames.hpp>
#include <kdl/joint.hpp>
#include <kdl/segment.hpp>

namespace fgcal::test {

namespace {
KDL::Frame toKdl(const urdf::Pose& p) {
  return KDL::Frame(KDL::Rotation::Quaternion(p.rotation.x, p.rotation.y, p.rotation.z, p.rotation.w),
                    KDL::Vector(p.position.x, p.position.y, p.position.z));
}
}  // namespace

KDL::Chain kdlChainFromUrdf(const urdf::ModelInterface& model, const std::string& base, const std::string& tip) {
  std::vector<urdf::JointConstSharedPtr> joints;  // tip first
  urdf::LinkConstSharedPtr link = model.getLink(tip);
  if (!link) throw std::runtime_error("no link " + tip);
  while (link->name != base) {
    if (!link->parent_joint) throw std::runtime_error(base + " is not an ancestor of " + tip);
    joints.push_back(link->parent_joint);
    link = model.getLink(link->parent_joint->parent_link_name);
  }
  KDL::Chain chain;
  for (auto it = joints.rbegin(); it != joints.rend(); ++it) {
    const urdf::Joint& j = **it;
    const KDL::Frame F = toKdl(j.parent_to_joint_origin_transform);
    KDL::Vector axis(j.axis.x, j.axis.y, j.axis.z);
    axis.Normalize();
    KDL::Joint kj(j.name, KDL::Joint::Fixed);
    switch (j.type) {
      case urdf::Joint::REVOLUTE:
      case urdf::Joint::CONTINUOUS:
        kj = KDL::Joint(j.name, F.p, F.M * axis, KDL::Joint::RotAxis);
        break;
      case urdf::Joint::PRISMATIC:
        kj = KDL::Joint(j.name, F.p, F.M * axis, KDL::Joint::TransAxis);
        break;
      case urdf::Joint::FIXED:
        break;
      default:
        throw std::runtime_error("joint type of " + j.name + " not handled by the oracle");
    }
    chain.addSegment(KDL::Segment(j.child_link_name, kj, F));
  }
  return chain;
}

}  // namespace fgcal::test
