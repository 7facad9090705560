// Independent oracle: orocos KDL chains built straight from urdfdom's model.
// Forward kinematics must agree to 1e-12 and the Jacobians (KDL's is [v w] in
// base axes at the tip; ours is [w v] in tip axes) to 1e-10 on every foot of
// every shared URDF and on longer chains (Spot's arm, ANYmal D's payload).
#include <random>

#include <catch2/catch.hpp>
#include <console_bridge/console.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <urdf_parser/urdf_parser.h>

#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal_test/shared_data.hpp"
#include "kdl_from_urdf.hpp"
#include "kin_test_util.hpp"

using namespace fgcal;
using namespace fgcal::kinematics;

namespace {

SE3 fromKdl(const KDL::Frame& F) {
  Mat3 R;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = F.M(r, c);
  return SE3(R, Vec3(F.p.x(), F.p.y(), F.p.z()));
}

// Returns the number of configurations compared.
int compareWithKdl(const std::string& file, const std::string& base, const std::string& tip, int samples,
                   std::mt19937& gen) {
  INFO(file << ": " << base << " -> " << tip);
  const RobotModel m = RobotModel::fromFile(file);
  // The oracle reads the file with urdfdom directly; its warnings (undefined
  // materials in mini_cheetah, a1) are noise here.
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_ERROR);
  const auto urdf_model = urdf::parseURDFFile(file);
  REQUIRE(urdf_model);
  const KinematicChain c = m.chain(base, tip);
  const KDL::Chain kc = fgcal::test::kdlChainFromUrdf(*urdf_model, base, tip);
  REQUIRE(static_cast<int>(kc.getNrOfJoints()) == c.numJoints());
  REQUIRE(static_cast<int>(kc.getNrOfSegments()) == c.numPathJoints());
  KDL::ChainFkSolverPos_recursive fk(kc);
  KDL::ChainJntToJacSolver jac(kc);
  KDL::JntArray qk(kc.getNrOfJoints());
  KDL::Jacobian Jk(kc.getNrOfJoints());
  KinematicChain::Jacobian J;
  double worst_fk = 0.0, worst_jac = 0.0;
  for (int s = 0; s < samples; ++s) {
    const VecX q = s == 0 ? VecX(VecX::Zero(c.numJoints())) : fgcal::test::randomJointValues(c, gen);
    qk.data = q;
    KDL::Frame F;
    REQUIRE(fk.JntToCart(qk, F) >= 0);
    REQUIRE(jac.JntToJac(qk, Jk) >= 0);
    const SE3 T = c.forward(q, &J);
    const SE3 Tk = fromKdl(F);
    worst_fk = std::max(worst_fk, (T.matrix() - Tk.matrix()).cwiseAbs().maxCoeff());
    // KDL: [v; w] of the tip, in base axes, reference point at the tip.
    const Mat3 Rt = Tk.rotation().transpose();
    MatX J_expected(6, c.numJoints());
    J_expected.topRows(3) = Rt * Jk.data.bottomRows(3);
    J_expected.bottomRows(3) = Rt * Jk.data.topRows(3);
    if (c.numJoints() > 0) worst_jac = std::max(worst_jac, (MatX(J) - J_expected).cwiseAbs().maxCoeff());
  }
  CHECK(worst_fk < 1e-12);
  CHECK(worst_jac < 1e-10);
  return samples;
}

}  // namespace

TEST_CASE("FK and Jacobian equal KDL on every foot of every shared URDF", "[kinematics][kdl][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "urdf");
  std::mt19937 gen(42);
  int compared = 0;
  for (const auto& f : fgcal::test::readExpectedFacts(dir))
    for (const auto& foot : f.feet) compared += compareWithKdl(dir + "/" + f.file, f.root_link, foot, 25, gen);
  CHECK(compared == 11 * 4 * 25);
}

TEST_CASE("FK and Jacobian equal KDL on non-root bases and longer chains", "[kinematics][kdl][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "urdf");
  std::mt19937 gen(43);
  compareWithKdl(dir + "/hyq.urdf", "trunk", "rh_foot", 50, gen);
  compareWithKdl(dir + "/hyq.urdf", "trunk", "lf_upperleg", 50, gen);
  compareWithKdl(dir + "/anymal_c.urdf", "base", "LF_FOOT", 50, gen);          // fixed links between joints
  compareWithKdl(dir + "/anymal_c.urdf", "LF_HAA", "LF_shank_fixed", 50, gen);  // link named like a joint
  compareWithKdl(dir + "/anymal_d.urdf", "base", "inspection_payload_camera", 50, gen);
  compareWithKdl(dir + "/a1.urdf", "trunk", "FL_foot", 50, gen);
  compareWithKdl(dir + "/go2.urdf", "base", "FL_calflower1", 50, gen);
  compareWithKdl(dir + "/aliengo.urdf", "trunk", "RL_foot", 50, gen);  // continuous thigh joint
  compareWithKdl(dir + "/solo12.urdf", "base_link", "HR_FOOT", 50, gen);
  compareWithKdl(dir + "/mini_cheetah.urdf", "body", "toe_hl", 50, gen);
  compareWithKdl(dir + "/spot_with_arm.urdf", "body", "arm_link_fngr", 50, gen);  // 7-joint arm
}
