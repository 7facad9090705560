// Every error the issue lists, each with its message: the file, the link or
// joint, the cause and what was expected. Never a crash, never a silent default.
#include <catch2/catch.hpp>

#include "fgcal/kinematics/errors.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal_test/shared_data.hpp"
#include "kin_test_util.hpp"

using namespace fgcal;
using namespace fgcal::kinematics;
using Catch::Matchers::Contains;

namespace {

// Two links joined by one joint, whose type and extra tags are given.
std::string twoLinks(const std::string& type, const std::string& extra) {
  return "<robot name='r'><link name='a'/><link name='b'/><joint name='j' type='" + type +
         "'><parent link='a'/><child link='b'/>" + extra + "</joint></robot>";
}
const std::string kLimit = "<limit lower='-1' upper='1' effort='1' velocity='1'/>";

// A -> B (floating) -> C (revolute) -> D, and A -> E (planar) -> F (revolute).
const char* kWithFloating = R"(<robot name='fb'>
  <link name='world'/><link name='trunk'/><link name='leg'/><link name='slider'/><link name='arm'/>
  <joint name='free' type='floating'><parent link='world'/><child link='trunk'/></joint>
  <joint name='hip' type='revolute'><parent link='trunk'/><child link='leg'/>
    <axis xyz='0 1 0'/><limit lower='-1' upper='1' effort='1' velocity='1'/></joint>
  <joint name='table' type='planar'><parent link='world'/><child link='slider'/><axis xyz='0 0 1'/></joint>
  <joint name='elbow' type='revolute'><parent link='slider'/><child link='arm'/>
    <axis xyz='0 1 0'/><limit lower='-1' upper='1' effort='1' velocity='1'/></joint>
</robot>)";

}  // namespace

TEST_CASE("error: URDF file missing", "[kinematics][errors]") {
  fgcal::test::ScratchDir tmp("missing");
  const std::string path = (tmp.path / "no_such_robot.urdf").string();
  CHECK_THROWS_AS(RobotModel::fromFile(path), UrdfError);
  CHECK_THROWS_WITH(RobotModel::fromFile(path), Contains(path) && Contains("cannot be opened") &&
                                                    Contains("No such file"));
  CHECK_THROWS_WITH(RobotModel::fromFile(tmp.path.string()), Contains("is a directory"));
}

TEST_CASE("error: XML malformed", "[kinematics][errors]") {
  fgcal::test::ScratchDir tmp("malformed");
  const std::string path = tmp.write("broken.urdf", "<robot name='r'>\n  <link name='a'/>\n  <link name='b'\n</robot>\n");
  CHECK_THROWS_AS(RobotModel::fromFile(path), UrdfError);
  CHECK_THROWS_WITH(RobotModel::fromFile(path), Contains("broken.urdf") && Contains("not well-formed XML") &&
                                                    Contains("line"));
  const std::string empty = tmp.write("empty.urdf", "");
  CHECK_THROWS_WITH(RobotModel::fromFile(empty), Contains("empty.urdf") && Contains("is empty"));
  CHECK_THROWS_WITH(RobotModel::fromString("<notrobot/>", "x.urdf"),
                    Contains("x.urdf") && Contains("not a valid URDF") && Contains("<robot"));
}

TEST_CASE("error: not a valid URDF quotes urdfdom's reason", "[kinematics][errors]") {
  // A revolute joint without <limit> makes urdfdom refuse the file (docs/toolchain.md, gotcha 4).
  CHECK_THROWS_WITH(RobotModel::fromString(twoLinks("revolute", ""), "nolimit.urdf"),
                    Contains("nolimit.urdf") && Contains("not a valid URDF") && Contains("does not specify limits"));
  CHECK_THROWS_WITH(RobotModel::fromString(twoLinks("banana", ""), "t.urdf"), Contains("no known type [banana]"));
  CHECK_THROWS_WITH(RobotModel::fromString(twoLinks("revolute", "<origin xyz='1 2 x'/>" + kLimit), "o.urdf"),
                    Contains("o.urdf") && Contains("Malformed parent origin"));
}

TEST_CASE("error: base or tip link unknown", "[kinematics][errors]") {
  const RobotModel m = RobotModel::fromString(twoLinks("revolute", kLimit), "two.urdf");
  CHECK_THROWS_AS(m.chain("nope", "b"), UrdfError);
  CHECK_THROWS_WITH(m.chain("nope", "b"),
                    Contains("two.urdf") && Contains("base link 'nope'") && Contains("its links are: a, b"));
  CHECK_THROWS_WITH(m.chain("a", "B"), Contains("two.urdf") && Contains("tip link 'B'"));
  CHECK_THROWS_WITH(m.joint("k"), Contains("two.urdf") && Contains("joint 'k'"));
  CHECK_THROWS_WITH(m.link("c"), Contains("two.urdf") && Contains("link 'c'"));
}

TEST_CASE("error: unknown link in a big robot lists some names", "[kinematics][errors][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "urdf");
  const RobotModel m = RobotModel::fromFile(dir + "/anymal_c.urdf");
  CHECK_THROWS_WITH(m.chain("base", "LF_foot"), Contains("anymal_c.urdf") && Contains("tip link 'LF_foot'") &&
                                                    Contains("(78 in all)"));
}

TEST_CASE("error: no path between base and tip", "[kinematics][errors]") {
  // urdfdom only accepts one tree, so links without a path between them can
  // only come from a file with two trees: that file is refused at load time,
  // naming both roots.
  const char* forest = "<robot name='f'><link name='a'/><link name='b'/><link name='c'/>"
                       "<joint name='j' type='fixed'><parent link='a'/><child link='c'/></joint></robot>";
  CHECK_THROWS_AS(RobotModel::fromString(forest, "forest.urdf"), UrdfError);
  CHECK_THROWS_WITH(RobotModel::fromString(forest, "forest.urdf"),
                    Contains("forest.urdf") && Contains("[a]") && Contains("[b]") && Contains("no path"));
}

TEST_CASE("error: floating or planar joint inside the chain", "[kinematics][errors]") {
  const RobotModel m = RobotModel::fromString(kWithFloating, "fb.urdf");
  CHECK(m.joint("free").type == JointType::Floating);
  CHECK(m.joint("table").type == JointType::Planar);
  // Chains that avoid those joints work.
  CHECK(m.chain("trunk", "leg").jointNames() == std::vector<std::string>{"hip"});
  CHECK(m.chain("slider", "arm").numJoints() == 1);
  // Chains through them do not.
  CHECK_THROWS_AS(m.chain("world", "leg"), UrdfError);
  CHECK_THROWS_WITH(m.chain("world", "leg"), Contains("fb.urdf") && Contains("joint 'free' (floating") &&
                                                 Contains("from 'world' to 'leg'") && Contains("only revolute"));
  CHECK_THROWS_WITH(m.chain("leg", "arm"), Contains("joint 'free' (floating"));
  CHECK_THROWS_WITH(m.chain("arm", "world"), Contains("joint 'table' (planar"));
}

TEST_CASE("error: zero joint axis", "[kinematics][errors]") {
  CHECK_THROWS_AS(RobotModel::fromString(twoLinks("revolute", "<axis xyz='0 0 0'/>" + kLimit), "zero.urdf"), UrdfError);
  CHECK_THROWS_WITH(RobotModel::fromString(twoLinks("prismatic", "<axis xyz='0 0 0'/>" + kLimit), "zero.urdf"),
                    Contains("zero.urdf") && Contains("joint 'j' (prismatic)") && Contains("non-zero"));
  // A fixed joint's axis is never used, so a zero axis there is fine.
  CHECK_NOTHROW(RobotModel::fromString(twoLinks("fixed", "<axis xyz='0 0 0'/>"), "fixed.urdf"));
  // Also guarded when a chain is built from hand-made steps.
  JointInfo j;
  j.name = "hand";
  j.type = JointType::Revolute;
  j.axis = Vec3::Zero();
  CHECK_THROWS_WITH(KinematicChain("a", "b", {PathStep{j, false}}, "hand.urdf"),
                    Contains("hand.urdf") && Contains("joint 'hand'"));
  // A non-unit axis is normalized, not refused.
  const RobotModel m = RobotModel::fromString(twoLinks("revolute", "<axis xyz='0 0 3'/>" + kLimit), "three.urdf");
  CHECK(m.joint("j").axis == Vec3::UnitZ());
}

TEST_CASE("error: wrong joint vectors and missing names", "[kinematics][errors]") {
  const RobotModel m = RobotModel::fromString(twoLinks("revolute", kLimit), "two.urdf");
  const KinematicChain c = m.chain("a", "b");
  CHECK_THROWS_AS(c.forward(VecX(2)), KinematicsError);
  CHECK_THROWS_WITH(c.forward(VecX(2)), Contains("1 movable joints") && Contains("2 values"));
  KinematicChain::Jacobian J;
  CHECK_THROWS_AS(c.forward(VecX(0), &J), KinematicsError);
  CHECK_THROWS_WITH(c.covariance(VecX(1), VecX(3)), Contains("sigma vector has 3 values"));
  CHECK_THROWS_WITH(c.jointVector({{"k", 0.0}}), Contains("joint 'j'") && Contains("missing"));
  CHECK_THROWS_WITH(c.sigmaVector(std::map<std::string, double>{}), Contains("encoder sigma for joint 'j'"));
  CHECK_THROWS_WITH(c.sigmaVector(-0.1), Contains(">= 0"));
  CHECK_THROWS_WITH(c.sigmaVector({{"j", -1.0}}, 0.1), Contains("joint 'j'") && Contains(">= 0"));
}

TEST_CASE("text that is not UTF-8 is read as Latin-1; a loop of joints is named", "[kinematics][errors]") {
  // A Latin-1 comment (an author's name with e-acute, byte 0xE9) and a lone
  // byte 0xFF: the XML parser would read past the end of invalid UTF-8, so
  // the text is converted first and the URDF loads.
  const std::string latin1 = "<?xml version='1.0'?><!-- author: Ren\xE9 \xFF --><robot name='r'><link name='a'/>"
                             "<link name='b'/><joint name='j' type='revolute'><parent link='a'/><child link='b'/>" +
                             kLimit + "</joint></robot>";
  const RobotModel m = RobotModel::fromString(latin1, "latin1.urdf");
  CHECK(m.hasJoint("j"));
  // Truncated multi-byte sequences at the very end must not crash either.
  CHECK_THROWS_AS(RobotModel::fromString("<robot name='r'>\xE2\x82", "cut.urdf"), UrdfError);

  const std::string loop = "<robot name='r'><link name='a'/><link name='b'/>"
                           "<joint name='j1' type='fixed'><parent link='a'/><child link='b'/></joint>"
                           "<joint name='j2' type='fixed'><parent link='b'/><child link='a'/></joint></robot>";
  CHECK_THROWS_WITH(RobotModel::fromString(loop, "loop.urdf"),
                    Contains("loop.urdf") && Contains("loop") && Contains("one tree"));
}

TEST_CASE("a link that is the child of two joints is refused before urdfdom links a loop through it",
          "[kinematics][errors]") {
  // b has the parents a and c, and c has the parent b: urdfdom finds the root
  // a, returns the model, and its links form the cycle b -> c -> b, which it
  // never frees and which a walk down from the root never leaves. One parent
  // per link (the walk up from b stops at a) did not see it.
  const std::string two_parents =
      "<robot name='r'><link name='a'/><link name='b'/><link name='c'/>"
      "<joint name='j1' type='fixed'><parent link='a'/><child link='b'/></joint>"
      "<joint name='j2' type='fixed'><parent link='c'/><child link='b'/></joint>"
      "<joint name='j3' type='fixed'><parent link='b'/><child link='c'/></joint></robot>";
  CHECK_THROWS_AS(RobotModel::fromString(two_parents, "two.urdf"), UrdfError);
  CHECK_THROWS_WITH(RobotModel::fromString(two_parents, "two.urdf"),
                    Contains("two.urdf") && Contains("link 'b' is the child of two joints, 'j1' and 'j2'") &&
                        Contains("one tree"));
  // Without a loop (a -> b, a -> c -> b) a second parent is refused the same way.
  const std::string diamond =
      "<robot name='r'><link name='a'/><link name='b'/><link name='c'/>"
      "<joint name='j1' type='fixed'><parent link='a'/><child link='b'/></joint>"
      "<joint name='j2' type='fixed'><parent link='a'/><child link='c'/></joint>"
      "<joint name='j3' type='fixed'><parent link='c'/><child link='b'/></joint></robot>";
  CHECK_THROWS_WITH(RobotModel::fromString(diamond, "diamond.urdf"),
                    Contains("link 'b' is the child of two joints, 'j1' and 'j3'"));
}

TEST_CASE("a byte-order mark is dropped and valid UTF-8 names survive beside Latin-1 bytes", "[kinematics][errors]") {
  // UTF-8 link name "b\xC3\xA9" (b-e-acute) and a stray Latin-1 byte in a comment.
  const std::string text = "\xEF\xBB\xBF<?xml version='1.0'?><!-- \xE9 --><robot name='r'><link name='a'/>"
                           "<link name='b\xC3\xA9'/><joint name='j' type='revolute'><parent link='a'/>"
                           "<child link='b\xC3\xA9'/>" +
                           kLimit + "</joint></robot>";
  const RobotModel m = RobotModel::fromString(text, "bom.urdf");
  CHECK(m.link("b\xC3\xA9").name == "b\xC3\xA9");
}
