// Fuzz target: the --urdf-out text edit (setJointOrigin) on any URDF that
// urdfdom accepts. For every joint (up to 8) the origin is set to a fixed pose
// with several rotations, gimbal lock included; the edited text must parse
// again and give exactly that origin to the joint, with every other joint
// unchanged. The text scanner (comments, CDATA, quoting, entities, nested
// <joint> elements) must agree with urdfdom on what the joint's <origin> is.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "fgcal/apps/urdf_update.hpp"
#include "fgcal/kinematics/errors.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fuzz_common.hpp"

namespace {
[[noreturn]] void finding(const std::string& what) {
  std::fprintf(stderr, "fuzz target: %s\n", what.c_str());
  std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fgcal;
  if (size > 64 * 1024) return 0;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const kinematics::RobotModel before = kinematics::RobotModel::fromString(text, "fuzz.urdf");
    const auto& joints = before.joints();
    for (std::size_t k = 0; k < joints.size() && k < 8; ++k) {
      const std::string& name = joints[k].name;
      const SE3 T(SO3::fromRpy(0.3, k % 2 ? M_PI / 2 : -0.2, 1.1), Vec3(0.125, -1e-5, 3.0));
      std::string edited;
      try {
        edited = apps::setJointOrigin(text, name, T);
      } catch (const std::invalid_argument&) {
        continue;  // a structure the edit refuses: reported to the user, never written
      }
      const kinematics::RobotModel after = kinematics::RobotModel::fromString(edited, "edited.urdf");
      const SE3 got = after.joint(name).T_parent_joint;
      if ((got.translation() - T.translation()).norm() > 1e-12 ||
          got.so3().between(T.so3()).log().norm() > 1e-12)
        finding("joint '" + name + "' does not carry the origin that was written");
      for (const auto& j : joints)
        if (j.name != name && after.joint(j.name).T_parent_joint.matrix() != j.T_parent_joint.matrix())
          finding("editing joint '" + name + "' changed joint '" + j.name + "'");
    }
  } catch (const kinematics::KinematicsError&) {
  } catch (const std::exception& e) {
    fuzz::unexpected(e);
  }
  return 0;
}
