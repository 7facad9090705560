// Fuzz target: the URDF loader (RobotModel::fromString, urdfdom underneath)
// on arbitrary text. An accepted model is walked: the chain from the root to
// every leaf (up to 8), forward kinematics with its Jacobian and the encoder
// noise propagation at zero and at unit joint angles.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fgcal/kinematics/errors.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fgcal::kinematics;
  if (size > 64 * 1024) return 0;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const RobotModel model = RobotModel::fromString(text, "fuzz.urdf");
    (void)model.totalMass();
    const auto leaves = model.leafLinks();
    for (std::size_t i = 0; i < leaves.size() && i < 8; ++i) {
      try {
        const KinematicChain chain = model.chain(model.rootLink(), leaves[i]);
        const Eigen::Index n = static_cast<Eigen::Index>(chain.numJoints());
        for (const double a : {0.0, 1.0}) {
          const fgcal::VecX q = fgcal::VecX::Constant(n, a);
          KinematicChain::Jacobian J;
          (void)chain.forward(q, &J);
          Eigen::Matrix<double, 6, 6> cov;
          (void)chain.forwardWithCovariance(q, fgcal::VecX::Constant(n, 0.001), &cov);
        }
        if (leaves.size() > 1) (void)model.chain(leaves[i], leaves[(i + 1) % leaves.size()]);
      } catch (const KinematicsError&) {
      }
    }
  } catch (const KinematicsError&) {
  } catch (const std::exception& e) {
    fgcal::fuzz::unexpected(e);
  }
  return 0;
}
