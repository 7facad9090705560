// fgcal's own robot (data/robots/fgcal_quadruped.urdf): embedded text equals
// the file, it loads, four feet are reachable with HAA/HFE/KFE joints, about
// 90 kg, a body about 1 m long, and a plausible standing pose.
#include <filesystem>

#include <catch2/catch.hpp>
#include <urdf_parser/urdf_parser.h>

#include "fgcal/kinematics/default_robot.hpp"
#include "fgcal_test/files.hpp"

using namespace fgcal;
using namespace fgcal::kinematics;

TEST_CASE("default robot: embedded text is the file in data/robots", "[kinematics][default_robot]") {
  REQUIRE(std::filesystem::is_regular_file(FGCAL_DEFAULT_ROBOT_FILE));
  CHECK(defaultRobotUrdf() == fgcal::test::readFile(FGCAL_DEFAULT_ROBOT_FILE));
  CHECK(RobotModel::fromFile(FGCAL_DEFAULT_ROBOT_FILE).name() == defaultRobotName());
}

TEST_CASE("default robot: loads, four feet with HAA HFE KFE", "[kinematics][default_robot]") {
  const RobotModel m = loadDefaultRobot();
  CHECK(m.name() == "fgcal_quadruped");
  CHECK(m.rootLink() == defaultRobotBaseLink());
  CHECK(m.movableJointNames().size() == 12);
  CHECK(m.leafLinks().size() == 4);
  for (const std::string& foot : defaultRobotFeet()) {
    INFO(foot);
    const std::string leg = foot.substr(0, 2);
    const KinematicChain c = m.chain(defaultRobotBaseLink(), foot);
    CHECK(c.jointNames() == std::vector<std::string>{leg + "_haa_joint", leg + "_hfe_joint", leg + "_kfe_joint"});
    for (const auto& l : c.jointLimits()) {
      CHECK(l.has_position_limits);
      CHECK(l.lower < l.upper);
    }
  }
}

TEST_CASE("default robot: mass, size and geometry are HyQ-like", "[kinematics][default_robot]") {
  const RobotModel m = loadDefaultRobot();
  CHECK(m.totalMass() == Approx(90.0).margin(1.0));
  // Body length from the trunk's collision box (read with urdfdom directly).
  const auto model = urdf::parseURDF(defaultRobotUrdf());
  REQUIRE(model);
  const auto box = std::dynamic_pointer_cast<urdf::Box>(model->getLink("base_link")->collision->geometry);
  REQUIRE(box);
  CHECK(box->dim.x == Approx(1.0).margin(0.1));
  // Feet at q = 0: under the hips, legs straight down (0.35 + 0.35 m).
  for (const std::string& foot : defaultRobotFeet()) {
    const Vec3 p = m.chain("base_link", foot).forward(Vec3::Zero()).translation();
    const double sx = foot[1] == 'f' ? 1.0 : -1.0, sy = foot[0] == 'l' ? 1.0 : -1.0;
    CHECK(p.x() == Approx(0.3735 * sx).margin(1e-12));
    CHECK(p.y() == Approx(0.287 * sy).margin(1e-12));
    CHECK(p.z() == Approx(-0.70).margin(1e-12));
  }
  // A standing pose (front: HFE 0.6, KFE -1.2; hind mirrored): feet about 0.57 m
  // below the body and still under the hips in x, as knees bend in an X.
  const KinematicChain lf = m.chain("base_link", "lf_foot"), lh = m.chain("base_link", "lh_foot");
  const Vec3 p_lf = lf.forward(Vec3(0.0, 0.6, -1.2)).translation();
  const Vec3 p_lh = lh.forward(Vec3(0.0, -0.6, 1.2)).translation();
  CHECK(p_lf.z() == Approx(-2 * 0.35 * std::cos(0.6)).margin(1e-12));
  CHECK(p_lf.x() == Approx(0.3735).margin(1e-12));
  CHECK(p_lh.x() == Approx(-0.3735).margin(1e-12));
  // Positive HAA moves every foot towards the body centre line.
  for (const std::string& foot : defaultRobotFeet()) {
    const KinematicChain c = m.chain("base_link", foot);
    const double y0 = c.forward(Vec3::Zero()).translation().y();
    const double y1 = c.forward(Vec3(0.2, 0.0, 0.0)).translation().y();
    CHECK(std::abs(y1) < std::abs(y0));
  }
}
