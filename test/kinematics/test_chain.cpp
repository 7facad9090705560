// KinematicChain: forward kinematics against a hand-written product of URDF
// transforms, Jacobians against central differences (shared checker), the
// tip-to-marker variant, name-based inputs, and no heap allocation per call.
#include <random>

#include <catch2/catch.hpp>

#include "fgcal/kinematics/errors.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal_test/allocation_counter.hpp"
#include "fgcal_test/jacobian_check.hpp"
#include "fgcal_test/shared_data.hpp"
#include "kin_test_util.hpp"


using namespace fgcal;
using namespace fgcal::kinematics;
using fgcal::test::randomJointValues;

namespace {

// An arm with every feature: rpy origins, a non-normalized axis, a negative
// axis, a prismatic joint, a continuous joint, fixed joints between movable
// ones, and a side branch.
const char* kArm = R"(<robot name="arm">
  <link name="world"/> <link name="base"/> <link name="l1"/> <link name="l2"/> <link name="l2b"/>
  <link name="l3"/> <link name="l4"/> <link name="tool"/> <link name="side"/>
  <joint name="mount" type="fixed"><parent link="world"/><child link="base"/>
    <origin xyz="0.1 -0.2 0.3" rpy="0.3 -0.2 1.0"/></joint>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.2" rpy="0 0 0.5"/><axis xyz="0 0 2"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="j2" type="continuous"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.05 0.02 0.1" rpy="1.2 0.1 -0.4"/><axis xyz="1 1 0"/></joint>
  <joint name="f1" type="fixed"><parent link="l2"/><child link="l2b"/>
    <origin xyz="0.3 0 0" rpy="0 0.7 0"/></joint>
  <joint name="j3" type="prismatic"><parent link="l2b"/><child link="l3"/>
    <origin xyz="0 0.1 0" rpy="-0.5 0 0.2"/><axis xyz="0.2 -0.3 0.9"/>
    <limit lower="-0.2" upper="0.4" effort="1" velocity="1"/></joint>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/>
    <origin xyz="0.25 0 -0.05" rpy="0.1 0.2 0.3"/><axis xyz="0 -1 0"/>
    <limit lower="-1.5" upper="1.5" effort="1" velocity="1"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="l4"/><child link="tool"/>
    <origin xyz="0.1 0.0 0.02" rpy="3.0 0 0"/></joint>
  <joint name="side_joint" type="revolute"><parent link="l1"/><child link="side"/>
    <origin xyz="0 0.2 0" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>)";

SE3 origin(double x, double y, double z, double r, double p, double yw) {
  return SE3::fromXyzRpy(Vec3(x, y, z), Vec3(r, p, yw));
}
SE3 rot(const Vec3& axis, double q) { return SE3(SO3::exp(axis.normalized() * q), Vec3::Zero()); }
SE3 trans(const Vec3& axis, double q) { return SE3(SO3(), axis.normalized() * q); }

// URDF semantics written out by hand: T_world_tool(q).
SE3 armByHand(const VecX& q) {
  return origin(0.1, -0.2, 0.3, 0.3, -0.2, 1.0) * origin(0, 0, 0.2, 0, 0, 0.5) * rot(Vec3(0, 0, 2), q[0]) *
         origin(0.05, 0.02, 0.1, 1.2, 0.1, -0.4) * rot(Vec3(1, 1, 0), q[1]) * origin(0.3, 0, 0, 0, 0.7, 0) *
         origin(0, 0.1, 0, -0.5, 0, 0.2) * trans(Vec3(0.2, -0.3, 0.9), q[2]) *
         origin(0.25, 0, -0.05, 0.1, 0.2, 0.3) * rot(Vec3(0, -1, 0), q[3]) * origin(0.1, 0.0, 0.02, 3.0, 0, 0);
}

bool poseNear(const SE3& a, const SE3& b, double tol) { return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff() <= tol; }

void checkJacobiansAt(const KinematicChain& c, const VecX& q, const SE3& T_tip_marker) {
  KinematicChain::Jacobian J;
  const SE3 T = c.forward(q, &J);
  CHECK(poseNear(T, c.forward(q), 1e-13));
  CHECK_JACOBIAN(MatX(J), [&](const VecX& x) { return c.forward(x); }, q);
  KinematicChain::Jacobian Jm;
  const SE3 Tm = c.forward(q, T_tip_marker, &Jm);
  CHECK(poseNear(Tm, T * T_tip_marker, 1e-13));
  CHECK_JACOBIAN(MatX(Jm), [&](const VecX& x) { return c.forward(x) * T_tip_marker; }, q);
  // DESIGN's formula for the marker: Ad(T_tip_marker^-1) J.
  CHECK((MatX(Jm) - T_tip_marker.inverse().adjoint() * MatX(J)).cwiseAbs().maxCoeff() < 1e-12);
}

}  // namespace

TEST_CASE("FK equals the URDF transforms multiplied by hand", "[kinematics][chain]") {
  const RobotModel m = RobotModel::fromString(kArm, "arm.urdf");
  const KinematicChain c = m.chain("world", "tool");
  REQUIRE(c.jointNames() == std::vector<std::string>{"j1", "j2", "j3", "j4"});
  CHECK(c.numPathJoints() == 7);
  CHECK(c.jointTypes() == std::vector<JointType>{JointType::Revolute, JointType::Continuous, JointType::Prismatic,
                                                 JointType::Revolute});
  std::mt19937 gen(1);
  CHECK(poseNear(c.forward(VecX::Zero(4)), armByHand(VecX::Zero(4)), 1e-14));
  for (int k = 0; k < 100; ++k) {
    const VecX q = randomJointValues(c, gen);
    CHECK(poseNear(c.forward(q), armByHand(q), 1e-13));
  }
  // Up and down through the side branch: side -> tool = (world->side)^-1 (world->tool).
  const KinematicChain side_tool = m.chain("side", "tool");
  REQUIRE(side_tool.jointNames() == std::vector<std::string>{"side_joint", "j2", "j3", "j4"});
  const KinematicChain world_side = m.chain("world", "side");
  for (int k = 0; k < 20; ++k) {
    const VecX q = randomJointValues(c, gen);
    const double qs = 0.3 * k / 20.0 - 0.1;
    VecX q_side(4);
    q_side << qs, q.tail(3);
    VecX q_ws(2);
    q_ws << q[0], qs;
    CHECK(poseNear(side_tool.forward(q_side), world_side.forward(q_ws).inverse() * c.forward(q), 1e-12));
  }
}

TEST_CASE("the Jacobian equals central differences, with and without a marker", "[kinematics][chain][jacobian]") {
  const RobotModel m = RobotModel::fromString(kArm, "arm.urdf");
  std::mt19937 gen(2);
  const SE3 T_tip_marker = origin(0.02, -0.03, 0.05, 0.4, -0.3, 2.0);
  for (const auto& [base, tip] : std::vector<std::pair<std::string, std::string>>{
           {"world", "tool"}, {"tool", "world"}, {"side", "tool"}, {"l3", "side"}, {"l2", "l4"}}) {
    INFO(base << " -> " << tip);
    const KinematicChain c = m.chain(base, tip);
    checkJacobiansAt(c, VecX::Zero(c.numJoints()), T_tip_marker);
    for (int k = 0; k < 10; ++k) checkJacobiansAt(c, randomJointValues(c, gen), T_tip_marker);
  }
}

TEST_CASE("the Jacobian equals central differences on real robots", "[kinematics][chain][jacobian][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "urdf");
  std::mt19937 gen(3);
  const SE3 T_foot_board = origin(0.0, 0.0, 0.02, 0.0, 0.0, 0.3);
  struct Case {
    const char* file;
    const char* base;
    const char* tip;
  };
  for (const Case& cs : {Case{"hyq.urdf", "trunk", "lf_foot"}, Case{"anymal_c.urdf", "LF_FOOT", "RH_FOOT"},
                         Case{"anymal_c.urdf", "wide_angle_camera_front_camera", "LH_FOOT"},
                         Case{"mini_cheetah.urdf", "body", "toe_hr"}, Case{"spot_with_arm.urdf", "body", "arm_link_fngr"},
                         Case{"spot_with_arm.urdf", "front_left_lower_leg", "arm_link_fngr"}}) {
    INFO(cs.file << ": " << cs.base << " -> " << cs.tip);
    const RobotModel m = RobotModel::fromFile(dir + "/" + cs.file);
    const KinematicChain c = m.chain(cs.base, cs.tip);
    for (int k = 0; k < 5; ++k) checkJacobiansAt(c, randomJointValues(c, gen), T_foot_board);
  }
}

TEST_CASE("joint values and sigmas by name", "[kinematics][chain]") {
  const RobotModel m = RobotModel::fromString(kArm, "arm.urdf");
  const KinematicChain c = m.chain("world", "tool");
  const std::map<std::string, double> row{{"j4", 0.4}, {"j2", 0.2}, {"side_joint", 9.0}, {"j1", 0.1}, {"j3", 0.3}};
  const VecX q = c.jointVector(row);
  CHECK(q == (VecX(4) << 0.1, 0.2, 0.3, 0.4).finished());
  CHECK(poseNear(c.forward(row), c.forward(q), 0.0));
  CHECK(c.sigmaVector(0.001) == VecX::Constant(4, 0.001));
  const VecX s = c.sigmaVector({{"j1", 0.01}, {"j3", 0.0005}}, 0.002);
  CHECK(s == (VecX(4) << 0.01, 0.002, 0.0005, 0.002).finished());
  // Per-joint sigmas weigh each Jacobian column.
  KinematicChain::Jacobian J;
  c.forward(q, &J);
  const Mat6 expected = MatX(J) * s.array().square().matrix().asDiagonal() * MatX(J).transpose();
  CHECK((c.covariance(q, s) - expected).cwiseAbs().maxCoeff() < 1e-15);
  // The one-pass call gives the same pose, Jacobian and covariance, with a marker too.
  const SE3 T_tip_marker = origin(0.01, 0.02, 0.03, 0.1, 0.2, 0.3);
  KinematicChain::Jacobian Jm, Jm1;
  Mat6 Sigma;
  const SE3 Tm = c.forwardWithCovariance(q, s, &Sigma, T_tip_marker, &Jm1);
  CHECK(poseNear(Tm, c.forward(q, T_tip_marker, &Jm), 1e-15));
  CHECK((Jm1 - Jm).cwiseAbs().maxCoeff() < 1e-15);
  const Mat6 expected_m = MatX(Jm) * s.array().square().matrix().asDiagonal() * MatX(Jm).transpose();
  CHECK((Sigma - expected_m).cwiseAbs().maxCoeff() < 1e-15);
  CHECK((Sigma - c.covariance(q, s, T_tip_marker)).cwiseAbs().maxCoeff() == 0.0);
}

TEST_CASE("FK, Jacobian and covariance allocate nothing per call", "[kinematics][chain]") {
  const RobotModel m = RobotModel::fromString(kArm, "arm.urdf");
  const KinematicChain c = m.chain("world", "tool");
  const VecX q = VecX::Constant(4, 0.1), s = VecX::Constant(4, 0.001);
  const SE3 T_tip_marker = origin(0, 0, 0.02, 0, 0, 0);
  KinematicChain::Jacobian J(6, 4);
  Mat6 Sigma;
  double sink = 0.0;
  const long before = fgcal_test::heap_allocations.load();
  for (int k = 0; k < 100; ++k) {
    sink += c.forward(q).translation().x();
    sink += c.forward(q, &J).translation().x();
    sink += c.forward(q, T_tip_marker, &J).translation().x();
    sink += c.forwardWithCovariance(q, s, &Sigma, T_tip_marker).translation().x();
    sink += c.forwardWithCovariance(q, s, &Sigma, T_tip_marker, &J).translation().x();
    sink += c.covariance(q, s)(0, 0);
  }
  CHECK(fgcal_test::heap_allocations.load() - before == 0);
  CHECK(std::isfinite(sink));
}
