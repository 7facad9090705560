// RobotModel on the shared real URDFs: every file loads, its facts match
// expected_facts.csv, every foot is reached from the root with the expected leg
// joints, and chains between arbitrary links (base not the root, tip an
// intermediate link, up then down) compose as they must.
#include <map>
#include <random>
#include <set>

#include <catch2/catch.hpp>

#include "fgcal/kinematics/errors.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal_test/shared_data.hpp"
#include "kin_test_util.hpp"

using namespace fgcal;
using namespace fgcal::kinematics;
using fgcal::test::randomJointValues;

namespace {

bool poseNear(const SE3& a, const SE3& b, double tol) { return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff() <= tol; }

}  // namespace

TEST_CASE("every shared URDF loads and matches expected_facts.csv", "[kinematics][urdf][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "urdf");
  const auto facts = fgcal::test::readExpectedFacts(dir);
  REQUIRE(facts.size() == 11);
  for (const auto& f : facts) {
    INFO("file " << f.file);
    const RobotModel m = RobotModel::fromFile(dir + "/" + f.file);
    CHECK(m.name() == f.robot_name);
    CHECK(m.rootLink() == f.root_link);
    CHECK(static_cast<int>(m.links().size()) == f.n_links);
    CHECK(static_cast<int>(m.joints().size()) == f.n_joints);
    std::map<JointType, int> count;
    for (const auto& j : m.joints()) ++count[j.type];
    CHECK(count[JointType::Revolute] == f.n_revolute);
    CHECK(count[JointType::Continuous] == f.n_continuous);
    CHECK(count[JointType::Prismatic] == f.n_prismatic);
    CHECK(count[JointType::Fixed] == f.n_fixed);
    CHECK(static_cast<int>(m.leafLinks().size()) == f.n_leaf_links);
    CHECK(static_cast<int>(m.movableJointNames().size()) == f.n_revolute + f.n_continuous + f.n_prismatic);
    REQUIRE(f.feet.size() == 4);
    REQUIRE(f.leg_joints.size() == 4);
    for (std::size_t leg = 0; leg < 4; ++leg) {
      INFO("foot " << f.feet[leg]);
      const KinematicChain c = m.chain(m.rootLink(), f.feet[leg]);
      CHECK(c.jointNames() == f.leg_joints[leg]);
      CHECK(m.chainJointNames(m.rootLink(), f.feet[leg]) == f.leg_joints[leg]);
      for (const auto& j : c.joints()) CHECK_FALSE(j.upward);
    }
  }
}

TEST_CASE("links and joints come in tree order, not urdfdom's map order", "[kinematics][urdf][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "urdf");
  for (const char* file : {"anymal_c.urdf", "go1.urdf", "spot_with_arm.urdf"}) {
    INFO(file);
    const RobotModel m = RobotModel::fromFile(dir + "/" + file);
    REQUIRE(m.links().front().name == m.rootLink());
    CHECK(m.links().front().parent_joint.empty());
    std::set<std::string> seen{m.rootLink()};
    for (std::size_t i = 1; i < m.links().size(); ++i) {
      const LinkInfo& l = m.links()[i];
      REQUIRE_FALSE(l.parent_joint.empty());
      const JointInfo& j = m.joint(l.parent_joint);
      CHECK(j.child_link == l.name);
      CHECK(seen.count(j.parent_link) == 1);  // parent listed before child
      seen.insert(l.name);
    }
    // Joints follow the same order: each joint's parent link was already reached.
    std::set<std::string> reached{m.rootLink()};
    for (const auto& j : m.joints()) {
      CHECK(reached.count(j.parent_link) == 1);
      reached.insert(j.child_link);
    }
    for (const auto& j : m.joints())
      if (isMovable(j.type)) CHECK(j.axis.norm() == Approx(1.0).epsilon(1e-15));
  }
}

TEST_CASE("joint and link names may coincide (ANYmal C)", "[kinematics][urdf][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "urdf");
  const RobotModel m = RobotModel::fromFile(dir + "/anymal_c.urdf");
  REQUIRE(m.hasLink("LF_HAA"));
  REQUIRE(m.hasJoint("LF_HAA"));
  CHECK(m.joint("LF_HAA").type == JointType::Revolute);
  CHECK(m.link("LF_HAA").parent_joint != "LF_HAA");  // the link LF_HAA hangs below a fixed joint
  // The leg has fixed links between the revolute joints: 10 joints walked, 3 movable.
  const KinematicChain leg = m.chain("base", "LF_FOOT");
  CHECK(leg.numJoints() == 3);
  CHECK(leg.numPathJoints() == 10);
  CHECK(leg.jointNames() == std::vector<std::string>{"LF_HAA", "LF_HFE", "LF_KFE"});
  // Link LF_HAA is the parent of joint LF_HAA: a chain to that link does not
  // include the joint of the same name, a chain to its child LF_HIP does.
  CHECK(m.joint("LF_HAA").parent_link == "LF_HAA");
  CHECK(m.chain("base", "LF_HAA").numJoints() == 0);
  CHECK(m.chain("base", "LF_HIP").jointNames() == std::vector<std::string>{"LF_HAA"});
  CHECK(m.chain("LF_HAA", "LF_FOOT").jointNames() == leg.jointNames());
}

TEST_CASE("a base that is not the root and a tip that is an intermediate link", "[kinematics][urdf][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "urdf");
  std::mt19937 gen(11);
  struct Case {
    const char* file;
    const char* root;
    const char* body;
    const char* foot;
    const char* thigh;
  };
  for (const Case& cs : {Case{"hyq.urdf", "base_link", "trunk", "lf_foot", "lf_upperleg"},
                         Case{"a1.urdf", "base", "trunk", "FL_foot", "FL_thigh"},
                         Case{"aliengo.urdf", "base", "trunk", "RL_foot", "RL_thigh"}}) {
    INFO(cs.file);
    const RobotModel m = RobotModel::fromFile(dir + std::string("/") + cs.file);
    const KinematicChain root_body = m.chain(cs.root, cs.body);
    CHECK(root_body.numJoints() == 0);
    const KinematicChain root_foot = m.chain(cs.root, cs.foot);
    const KinematicChain body_foot = m.chain(cs.body, cs.foot);
    const KinematicChain body_thigh = m.chain(cs.body, cs.thigh);
    CHECK(body_foot.jointNames() == root_foot.jointNames());
    REQUIRE(body_thigh.numJoints() == 2);
    CHECK(body_thigh.jointNames()[0] == body_foot.jointNames()[0]);
    CHECK(body_thigh.jointNames()[1] == body_foot.jointNames()[1]);
    for (int k = 0; k < 20; ++k) {
      const VecX q = randomJointValues(body_foot, gen);
      const SE3 T_root_body = root_body.forward(VecX(0));
      CHECK(poseNear(body_foot.forward(q), T_root_body.inverse() * root_foot.forward(q), 1e-12));
      // The thigh pose depends only on the first two joints, and the foot is
      // the thigh pose times the remaining (KFE + fixed) motion.
      const SE3 T_body_thigh = body_thigh.forward(VecX(q.head(2)));
      const SE3 T_thigh_foot = m.chain(cs.thigh, cs.foot).forward(VecX(q.tail(1)));
      CHECK(poseNear(body_foot.forward(q), T_body_thigh * T_thigh_foot, 1e-12));
    }
  }
}

TEST_CASE("a chain that goes up then down equals a composition of root chains", "[kinematics][urdf][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "urdf");
  std::mt19937 gen(5);
  const RobotModel m = RobotModel::fromFile(dir + "/anymal_c.urdf");
  const KinematicChain lf = m.chain("base", "LF_FOOT");
  const KinematicChain rf = m.chain("base", "RF_FOOT");
  const KinematicChain lf_rf = m.chain("LF_FOOT", "RF_FOOT");
  REQUIRE(lf_rf.jointNames() == std::vector<std::string>{"LF_KFE", "LF_HFE", "LF_HAA", "RF_HAA", "RF_HFE", "RF_KFE"});
  CHECK(lf_rf.numPathJoints() == 20);
  for (int i = 0; i < 6; ++i) CHECK(lf_rf.joints()[static_cast<std::size_t>(i)].upward == (i < 3));
  for (int k = 0; k < 50; ++k) {
    const VecX q_lf = randomJointValues(lf, gen);
    const VecX q_rf = randomJointValues(rf, gen);
    VecX q(6);
    q << q_lf.reverse(), q_rf;
    const SE3 expected = lf.forward(q_lf).inverse() * rf.forward(q_rf);
    CHECK(poseNear(lf_rf.forward(q), expected, 1e-12));
    // By name gives the same.
    const std::map<std::string, double> by_name{{"LF_HAA", q_lf[0]}, {"LF_HFE", q_lf[1]}, {"LF_KFE", q_lf[2]},
                                                {"RF_HAA", q_rf[0]}, {"RF_HFE", q_rf[1]}, {"RF_KFE", q_rf[2]},
                                                {"LH_HAA", 1.0}};
    CHECK(poseNear(lf_rf.forward(by_name), expected, 1e-12));
    // The reversed chain is the inverse.
    const KinematicChain rf_lf = m.chain("RF_FOOT", "LF_FOOT");
    CHECK(poseNear(rf_lf.forward(VecX(q.reverse())), expected.inverse(), 1e-12));
  }
  // Between a camera frame and a foot (what a camera-to-board chain would be).
  const KinematicChain cam_foot = m.chain("depth_camera_front_depth_optical_frame", "LF_FOOT");
  CHECK(cam_foot.jointNames() == lf.jointNames());
  const SE3 T_base_cam = m.chain("base", "depth_camera_front_depth_optical_frame").forward(VecX(0));
  const VecX q = randomJointValues(lf, gen);
  CHECK(poseNear(cam_foot.forward(q), T_base_cam.inverse() * lf.forward(q), 1e-12));
}

TEST_CASE("a chain from a link to itself is the identity with no joints", "[kinematics][urdf][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "urdf");
  const RobotModel m = RobotModel::fromFile(dir + "/hyq.urdf");
  for (const char* link : {"base_link", "trunk", "lf_upperleg", "rh_foot"}) {
    const KinematicChain c = m.chain(link, link);
    CHECK(c.numJoints() == 0);
    CHECK(c.numPathJoints() == 0);
    CHECK(poseNear(c.forward(VecX(0)), SE3(), 0.0));
    KinematicChain::Jacobian J;
    c.forward(VecX(0), &J);
    CHECK(J.cols() == 0);
  }
}

TEST_CASE("the chain reports joint names, types and limits", "[kinematics][urdf][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "urdf");
  const RobotModel hyq = RobotModel::fromFile(dir + "/hyq.urdf");
  const KinematicChain leg = hyq.chain("trunk", "lf_foot");
  REQUIRE(leg.jointTypes() == std::vector<JointType>(3, JointType::Revolute));
  const auto limits = leg.jointLimits();
  CHECK(limits[0].has_position_limits);
  CHECK(limits[0].lower == Approx(-1.2217304764).margin(1e-12));
  CHECK(limits[0].upper == Approx(0.436332312999).margin(1e-12));
  CHECK(limits[2].lower == Approx(-2.44346095279).margin(1e-12));
  CHECK(limits[0].effort == Approx(150.0));
  CHECK(limits[0].velocity == Approx(12.0));
  CHECK(leg.indexOf("lf_hfe_joint") == 1);
  CHECK(leg.indexOf("rf_hfe_joint") == -1);

  const RobotModel aliengo = RobotModel::fromFile(dir + "/aliengo.urdf");
  const KinematicChain fl = aliengo.chain("trunk", "FL_foot");
  CHECK(fl.jointTypes() ==
        std::vector<JointType>{JointType::Revolute, JointType::Continuous, JointType::Revolute});
  CHECK_FALSE(fl.jointLimits()[1].has_position_limits);
  CHECK(std::isinf(fl.jointLimits()[1].upper));

  // Leaves are not feet (A1's thigh shoulders), and the movable-joint helper
  // lists exactly what joints.csv must provide for a chain.
  const RobotModel a1 = RobotModel::fromFile(dir + "/a1.urdf");
  const auto leaves = a1.leafLinks();
  CHECK(std::find(leaves.begin(), leaves.end(), "FL_thigh_shoulder") != leaves.end());
  CHECK(a1.chainJointNames("trunk", "FL_thigh_shoulder") == std::vector<std::string>{"FL_hip_joint"});

  // ANYmal D: 14 movable joints, two of them on the inspection payload.
  const RobotModel anymal_d = RobotModel::fromFile(dir + "/anymal_d.urdf");
  CHECK(anymal_d.movableJointNames().size() == 14);
  CHECK(anymal_d.chainJointNames("base", "inspection_payload_camera") ==
        std::vector<std::string>{"inspection_payload_mount_to_pan", "inspection_payload_pan_to_tilt"});
}
