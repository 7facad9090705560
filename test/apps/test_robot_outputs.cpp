// The outputs that go back into the robot's software, without running a
// calibration: the URDF write-back (text edit, joint choice, refusals, the
// check through urdfdom, fgcal's walker and KDL, on ANYmal C, ANYmal D and
// Go1), the Kalibr camchain (direction of T_cn_cnm1, read back with yaml-cpp
// and by Kalibr's own files' shape), the launch files' numbers, and the
// options' checks.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <map>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "apps_test_util.hpp"
#include "fgcal/apps/camchain.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/robot_outputs.hpp"
#include "fgcal/apps/tf_launch.hpp"
#include "fgcal/apps/urdf_update.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal_test/pose_gap.hpp"
#include "fgcal_test/shared_data.hpp"

#ifdef FGCAL_HAVE_KDL
#include <console_bridge/console.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <urdf_parser/urdf_parser.h>

#include "kdl_from_urdf.hpp"
#endif

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {

SE3 randomPose(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec6 xi;
  for (int i = 0; i < 6; ++i) xi[i] = n(rng);
  xi.head<3>() *= 1.2;
  xi.tail<3>() *= 0.3;
  return SE3::exp(xi);
}

using fgcal::test::rotationGap;
using fgcal::test::translationGap;

SE3 chainPose(const std::string& urdf_text, const std::string& base, const std::string& frame) {
  return kinematics::RobotModel::fromString(urdf_text, "test").chain(base, frame).forward(VecX());
}

std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string l;
  while (std::getline(ss, l)) out.push_back(l);
  return out;
}

// The line with the values of xyz= and rpy= emptied: what must not change.
std::string withoutOriginValues(const std::string& line) {
  static const std::regex values(R"re((xyz|rpy)\s*=\s*(["'])[^"']*\2)re");
  return std::regex_replace(line, values, "$1=$2$2");
}

#ifdef FGCAL_HAVE_KDL
// base -> frame through KDL, from urdfdom's own parse of the text (not fgcal's walker).
SE3 kdlPose(const std::string& urdf_text, const std::string& base, const std::string& frame) {
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE);  // urdfdom's notes on materials
  const auto model = urdf::parseURDF(urdf_text);
  REQUIRE(model);
  const KDL::Chain chain = fgcal::test::kdlChainFromUrdf(*model, base, frame);
  KDL::ChainFkSolverPos_recursive fk(chain);
  KDL::JntArray q(chain.getNrOfJoints());
  KDL::Frame F;
  REQUIRE(fk.JntToCart(q, F) >= 0);
  Mat3 R;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = F.M(r, c);
  return SE3(SO3(R), Vec3(F.p.x(), F.p.y(), F.p.z()));
}
#endif

const char* kSmallUrdf = R"(<?xml version="1.0"?>
<!-- a comment that mentions <joint name="cam_body_joint" type="fixed"> and must stay as it is -->
<robot name='tiny'>
  <link name="base_link"/>
  <link name="head"/>
  <link name="cam_body"/>
  <link name="cam_optical"/>
  <link name="cam2_body"/>
  <link name="leg"/>
  <joint name="head_joint" type="fixed">
    <parent link="base_link"/>
    <child link="head"/>
    <origin xyz="0.3 0 0.1" rpy="0 0.2 0"/>
  </joint>
  <joint type="fixed" name='cam_body_joint'>
    <origin rpy='0 0 0.1'   xyz='0.05 0.01 0'></origin>
    <parent link="head"/>
    <child link="cam_body"/>
  </joint>
  <joint name="cam_optical_joint" type="fixed">
    <parent link="cam_body"/>
    <child link="cam_optical"/>
    <origin xyz="0 0 0" rpy="-1.5707963267948966 0 -1.5707963267948966"/>
  </joint>
  <joint name="cam2_joint" type="fixed">
    <parent link="head"/>
    <child link="cam2_body"/>
  </joint>
  <joint name="leg_joint" type="revolute">
    <parent link="base_link"/>
    <child link="leg"/>
    <axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <transmission name="t">
    <joint name="cam_body_joint"><origin xyz="9 9 9"/></joint>
  </transmission>
  <![CDATA[ <joint name="cam2_joint"> ]]>
</robot>
)";

}  // namespace

// ---------------------------------------------------------------------------
// The text edit
// ---------------------------------------------------------------------------

TEST_CASE("urdf write-back: the origin is edited in place, whatever the quoting and attribute order",
          "[apps][urdf_out]") {
  std::mt19937 rng(7);
  const SE3 T = randomPose(rng);
  const std::string out = setJointOrigin(kSmallUrdf, "cam_body_joint", T);
  // Only the one <origin> line changed; its quotes and attribute order kept.
  const auto a = splitLines(kSmallUrdf), b = splitLines(out);
  REQUIRE(a.size() == b.size());
  int changed = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i] == b[i]) continue;
    ++changed;
    INFO(a[i] << "\n" << b[i]);
    CHECK(a[i].find("<origin rpy='0 0 0.1'") != std::string::npos);
    CHECK(withoutOriginValues(a[i]) == withoutOriginValues(b[i]));
    CHECK(b[i].find("<origin rpy='") != std::string::npos);
  }
  CHECK(changed == 1);
  // The comment, the <transmission>'s nested <joint> and the CDATA are untouched.
  CHECK(out.find("<joint name=\"cam_body_joint\"><origin xyz=\"9 9 9\"/></joint>") != std::string::npos);
  CHECK(out.find("mentions <joint name=\"cam_body_joint\" type=\"fixed\">") != std::string::npos);
  // The file says what was asked.
  const auto model = kinematics::RobotModel::fromString(out, "edited");
  const SE3 got = model.joint("cam_body_joint").T_parent_joint;
  CHECK(translationGap(got, T) < 1e-15);
  CHECK(rotationGap(got, T) < 1e-15);
}

TEST_CASE("urdf write-back: an absent <origin> is inserted on its own line, an absent attribute added",
          "[apps][urdf_out]") {
  const SE3 T(SO3::fromRpy(0.1, -0.2, 0.3), Vec3(0.01, 0.02, 0.03));
  const std::string out = setJointOrigin(kSmallUrdf, "cam2_joint", T);
  const auto a = splitLines(kSmallUrdf), b = splitLines(out);
  REQUIRE(b.size() == a.size() + 1);
  // The new line sits right after the joint's start tag with the children's indentation.
  std::size_t k = 0;
  while (k < a.size() && a[k] == b[k]) ++k;
  CHECK(b[k].rfind("    <origin xyz=\"0.01 0.02 0.03\" rpy=\"", 0) == 0);
  CHECK(a[k - 1].find("<joint name=\"cam2_joint\"") != std::string::npos);
  for (std::size_t i = k; i < a.size(); ++i) CHECK(a[i] == b[i + 1]);
  const SE3 got = kinematics::RobotModel::fromString(out, "edited").joint("cam2_joint").T_parent_joint;
  CHECK(translationGap(got, T) < 1e-15);
  CHECK(rotationGap(got, T) < 1e-15);

  // <origin xyz="..."/> without rpy: rpy is added after the last attribute.
  const std::string only_xyz = replaced(kSmallUrdf, "<origin xyz=\"0.3 0 0.1\" rpy=\"0 0.2 0\"/>",
                                        "<origin xyz=\"0.3 0 0.1\" />");
  const std::string out2 = setJointOrigin(only_xyz, "head_joint", T);
  INFO(out2);
  CHECK(std::regex_search(out2, std::regex(R"re(<origin xyz="0\.01 0\.02 0\.03" rpy="[-0-9.e ]+" />)re")));
  const SE3 got2 = kinematics::RobotModel::fromString(out2, "edited").joint("head_joint").T_parent_joint;
  CHECK(rotationGap(got2, T) < 1e-15);

  CHECK_THROWS_AS(setJointOrigin(kSmallUrdf, "no_such_joint", T), std::invalid_argument);
  CHECK_THROWS_AS(setJointOrigin("<robot><joint name=\"a\"", "a", T), std::invalid_argument);
}

TEST_CASE("urdf write-back: fixed-axis rpy round-trips through urdfdom at and near gimbal lock",
          "[apps][urdf_out]") {
  std::vector<SE3> poses;
  for (const double pitch : {M_PI / 2, -M_PI / 2, M_PI / 2 - 1e-9, -M_PI / 2 + 1e-7, M_PI / 2 - 1e-4})
    for (const double yaw : {0.0, 0.7, -2.9})
      poses.emplace_back(SO3::fromRpy(0.4, pitch, yaw), Vec3(0.1, -0.2, 0.3));
  std::mt19937 rng(3);
  for (int i = 0; i < 200; ++i) poses.push_back(randomPose(rng));
  poses.emplace_back(SO3::fromRpy(M_PI, 0.0, M_PI), Vec3::Zero());  // rotation by pi
  double worst_t = 0.0, worst_r = 0.0;
  for (const SE3& T : poses) {
    const SE3 got =
        kinematics::RobotModel::fromString(setJointOrigin(kSmallUrdf, "head_joint", T), "edited").joint("head_joint")
            .T_parent_joint;
    worst_t = std::max(worst_t, translationGap(got, T));
    worst_r = std::max(worst_r, rotationGap(got, T));
  }
  INFO("worst " << worst_t << " m, " << worst_r << " rad");
  CHECK(worst_t < 1e-15);
  CHECK(worst_r < 1e-12);
}

// ---------------------------------------------------------------------------
// Which joint, and the refusals
// ---------------------------------------------------------------------------

TEST_CASE("urdf write-back: the default joint is the camera body's when the optical joint is a pure rotation",
          "[apps][urdf_out]") {
  const UrdfUpdatePlan p = planUrdfUpdate(kSmallUrdf, "tiny.urdf", "base_link",
                                          {{"front", "cam_optical", "", "cameras[front]"}}, "rig.yaml");
  REQUIRE(p.edits.size() == 1);
  CHECK(p.edits[0].joint == "cam_body_joint");
  CHECK(p.edits[0].default_joint);
  // A frame whose own joint has a translation: that joint.
  const UrdfUpdatePlan q = planUrdfUpdate(kSmallUrdf, "tiny.urdf", "base_link",
                                          {{"front", "cam_body", "", "cameras[front]"}}, "rig.yaml");
  CHECK(q.edits[0].joint == "cam_body_joint");
  // Named joint above the frame: taken as is; the chain around it is right.
  const UrdfUpdatePlan r = planUrdfUpdate(kSmallUrdf, "tiny.urdf", "base_link",
                                          {{"front", "cam_optical", "head_joint", "cameras[front]"}}, "rig.yaml");
  CHECK(r.edits[0].joint == "head_joint");
  std::mt19937 rng(11);
  const SE3 T = randomPose(rng);
  const UrdfUpdateResult u = applyUrdfUpdate(r, {{"front", T}});
  CHECK(u.cameras_checked == 1);
  CHECK(u.max_translation_error_m < 1e-12);
  const SE3 got = chainPose(u.text, "base_link", "cam_optical");
  CHECK(translationGap(got, T) < 1e-12);
  CHECK(rotationGap(got, T) < 1e-12);
}

TEST_CASE("urdf write-back: bad frames and joints are refused naming the field and the way out",
          "[apps][urdf_out]") {
  const auto fails = [](const std::vector<UrdfCameraFrame>& cams, const std::vector<std::string>& words) {
    try {
      planUrdfUpdate(kSmallUrdf, "tiny.urdf", "base_link", cams, "rig.yaml");
      FAIL("expected an InputError");
    } catch (const InputError& e) {
      INFO(e.what());
      CHECK(e.file() == "rig.yaml");
      for (const auto& w : words) CHECK(std::string(e.what()).find(w) != std::string::npos);
    }
  };
  // A frame that is not a link: the closest link names are listed.
  fails({{"front", "cam_opticl", "", "cameras[front]"}}, {"cameras[front].frame", "tiny.urdf", "cam_optical"});
  // A urdf_joint that is not above the frame.
  fails({{"front", "cam_optical", "cam2_joint", "cameras[front]"}},
        {"cameras[front].urdf_joint", "cam2_joint", "cam_optical_joint", "cam_body_joint", "head_joint"});
  fails({{"front", "cam_optical", "cam_body_jiont", "cameras[front]"}}, {"cam_body_joint"});
  // A movable joint between the base and the frame.
  fails({{"front", "leg", "", "cameras[front]"}}, {"revolute", "leg_joint", "pan-tilt"});
  // Two cameras sharing a joint: the default of one moves the other.
  fails({{"front", "cam_optical", "", "cameras[front]"}, {"body", "cam_body", "", "cameras[body]"}},
        {"cam_body_joint", "camera body", "cameras[front]"});
  // The base itself.
  fails({{"front", "base_link", "", "cameras[front]"}}, {"base link"});
  // cam2_joint has no <origin>: an identity, i.e. a pure rotation, so its
  // default is the joint above it, head_joint, which front's chain holds too.
  fails({{"front", "cam_optical", "", "cameras[front]"}, {"two", "cam2_body", "", "cameras[two]"}},
        {"cameras[two].frame", "head_joint", "camera front", "cam2_joint"});
  // Separate branches are fine.
  CHECK_NOTHROW(planUrdfUpdate(
      kSmallUrdf, "tiny.urdf", "base_link",
      {{"front", "cam_optical", "", "cameras[front]"}, {"two", "cam2_body", "cam2_joint", "cameras[two]"}},
      "rig.yaml"));
}

TEST_CASE("urdf write-back: edit distance and closest names", "[apps][urdf_out]") {
  CHECK(editDistance("kitten", "sitting") == 3);
  CHECK(editDistance("", "abc") == 3);
  CHECK(editDistance("same", "same") == 0);
  const auto c = closestNames("camera_optical_fac", {"trunk", "camera_optical_face", "camera_optical_chin", "imu"}, 2);
  REQUIRE(c.size() == 2);
  CHECK(c[0] == "camera_optical_face");
  CHECK(c[1] == "camera_optical_chin");
}

// ---------------------------------------------------------------------------
// Real robots: ANYmal C, ANYmal D, Unitree Go1
// ---------------------------------------------------------------------------

TEST_CASE("urdf write-back on ANYmal C, ANYmal D and Go1: chains give the calibration, nothing else changes",
          "[apps][urdf_out][shared_data]") {
  FGCAL_REQUIRE_SHARED_DATA(urdf_dir, "urdf");
  struct Case {
    std::string file, base;
    std::vector<std::pair<std::string, std::string>> frames;  // frame, expected default joint
  };
  const std::vector<Case> cases = {
      {"anymal_c.urdf",
       "base",
       {{"depth_camera_front_depth_optical_frame", "depth_camera_front_camera_to_camera_parent"},
        {"depth_camera_rear_depth_optical_frame", "depth_camera_rear_camera_to_camera_parent"},
        {"depth_camera_left_depth_optical_frame", "depth_camera_left_camera_to_camera_parent"},
        {"wide_angle_camera_front_camera", ""}}},
      {"anymal_d.urdf",
       "base",
       {{"depth_camera_front_lower_depth_optical_frame", ""},
        {"depth_camera_rear_upper_depth_optical_frame", ""},
        {"depth_camera_left_depth_optical_frame", ""},
        {"wide_angle_camera_front_camera_parent", ""}}},
      {"go1.urdf",
       "trunk",
       {{"camera_optical_face", "camera_joint_face"},
        {"camera_optical_chin", "camera_joint_chin"},
        {"camera_optical_left", "camera_joint_left"},
        {"camera_optical_rearDown", "camera_joint_rearDown"}}},
  };
  std::mt19937 rng(5);
  for (const Case& c : cases) {
    INFO(c.file);
    const std::string path = urdf_dir + "/" + c.file;
    const std::string text = readFile(path);
    std::vector<UrdfCameraFrame> cams;
    std::map<std::string, SE3> truth;
    for (std::size_t i = 0; i < c.frames.size(); ++i) {
      const std::string name = "cam" + std::to_string(i);
      cams.push_back({name, c.frames[i].first, "", "cameras[" + name + "]"});
      // Near the CAD pose (a few cm / degrees off), as a calibration finds it.
      Vec6 d;
      for (int k = 0; k < 6; ++k) d[k] = std::uniform_real_distribution<double>(-0.05, 0.05)(rng);
      truth[name] = chainPose(text, c.base, c.frames[i].first) * SE3::exp(d);
    }
    const UrdfUpdatePlan plan = planUrdfUpdate(text, path, c.base, cams, "rig.yaml");
    for (std::size_t i = 0; i < c.frames.size(); ++i) {
      INFO(c.frames[i].first << " -> " << plan.edits[i].joint);
      CHECK(plan.edits[i].default_joint);
      if (!c.frames[i].second.empty()) CHECK(plan.edits[i].joint == c.frames[i].second);
    }
    const UrdfUpdateResult u = applyUrdfUpdate(plan, truth);
    CHECK(u.cameras_checked == static_cast<int>(c.frames.size()));
    CHECK(u.max_translation_error_m <= 1e-9);
    CHECK(u.max_rotation_error_rad <= 1e-9);
    double worst_walker = 0.0, worst_kdl = 0.0;
    for (std::size_t i = 0; i < c.frames.size(); ++i) {
      const SE3& want = truth.at(cams[i].camera);
      const SE3 walker = chainPose(u.text, c.base, c.frames[i].first);
      worst_walker = std::max({worst_walker, translationGap(walker, want), rotationGap(walker, want)});
#ifdef FGCAL_HAVE_KDL
      const SE3 kdl = kdlPose(u.text, c.base, c.frames[i].first);
      worst_kdl = std::max({worst_kdl, translationGap(kdl, want), rotationGap(kdl, want)});
#endif
    }
    INFO("worst gap: fgcal walker " << worst_walker << ", KDL " << worst_kdl);
    CHECK(worst_walker <= 1e-9);
    CHECK(worst_kdl <= 1e-9);
    // Line by line: only the edited joints' <origin> lines differ, and in them
    // only the values of xyz and rpy.
    const auto a = splitLines(text), b = splitLines(u.text);
    REQUIRE(a.size() == b.size());
    int changed = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (a[i] == b[i]) continue;
      ++changed;
      INFO("line " << i + 1 << ":\n" << a[i] << "\n" << b[i]);
      CHECK(a[i].find("<origin") != std::string::npos);
      CHECK(withoutOriginValues(a[i]) == withoutOriginValues(b[i]));
    }
    CHECK(changed == static_cast<int>(c.frames.size()));
  }
}

TEST_CASE("urdf write-back refuses a camera on ANYmal D's pan-tilt payload, naming the joint",
          "[apps][urdf_out][shared_data]") {
  FGCAL_REQUIRE_SHARED_DATA(urdf_dir, "urdf");
  const std::string path = urdf_dir + "/anymal_d.urdf";
  try {
    planUrdfUpdate(readFile(path), path, "base", {{"payload", "inspection_payload_camera", "", "cameras[payload]"}},
                   "rig.yaml");
    FAIL("expected an InputError");
  } catch (const InputError& e) {
    INFO(e.what());
    const std::string m = e.what();
    CHECK(m.find("cameras[payload].frame") != std::string::npos);
    CHECK(m.find("revolute") != std::string::npos);
    CHECK((m.find("inspection_payload_pan_to_tilt") != std::string::npos ||
           m.find("inspection_payload_mount_to_pan") != std::string::npos));
  }
  // Go1: the depth and colour frames of one ANYmal C camera share the camera body joint.
  const std::string c_path = urdf_dir + "/anymal_c.urdf";
  CHECK_THROWS_AS(planUrdfUpdate(readFile(c_path), c_path, "base",
                                 {{"depth", "depth_camera_front_depth_optical_frame", "", "cameras[depth]"},
                                  {"color", "depth_camera_front_color_optical_frame", "", "cameras[color]"}},
                                 "rig.yaml"),
                  InputError);
  // ... and naming each one's own joint separates them.
  const UrdfUpdatePlan p =
      planUrdfUpdate(readFile(c_path), c_path, "base",
                     {{"depth", "depth_camera_front_depth_optical_frame",
                       "depth_camera_front_camera_parent_to_depth_optical_frame", "cameras[depth]"},
                      {"color", "depth_camera_front_color_optical_frame", "", "cameras[color]"}},
                     "rig.yaml");
  CHECK(p.edits.size() == 2);
}

// ---------------------------------------------------------------------------
// Kalibr camchain
// ---------------------------------------------------------------------------

TEST_CASE("camchain: T_cn_cnm1 maps points of camera n-1 into camera n; read back with yaml-cpp",
          "[apps][camchain]") {
  std::mt19937 rng(9);
  std::vector<CamchainCamera> cams(3);
  std::map<std::string, SE3> T_base;
  for (std::size_t i = 0; i < cams.size(); ++i) {
    cams[i].name = "c" + std::to_string(i);
    cams[i].camera_model = "pinhole";
    cams[i].intrinsics = {500.0 + i, 501.0, 320.5, 240.25};
    cams[i].distortion_model = i == 1 ? "equidistant" : "radtan";
    cams[i].distortion_coeffs = {0.01, -0.02, 1e-4, -1e-5};
    cams[i].resolution = {640, 480};
    if (i == 2) cams[i].rostopic = "/c2/image_raw";
    T_base[cams[i].name] = randomPose(rng);
  }
  for (auto& c : cams) c.T_cam0_cam = T_base.at("c0").inverse() * T_base.at(c.name);
  const std::string text = formatKalibrCamchain(cams);
  INFO(text);
  CHECK(looksLikeKalibrCamchain(text));

  // An independent reader: Kalibr's key names and the direction of the transform.
  const YAML::Node root = YAML::Load(text);
  CHECK(root.size() == 3);  // Kalibr counts cameras as top-level keys
  CHECK_FALSE(root["cam0"]["T_cn_cnm1"]);
  CHECK_FALSE(root["cam0"]["rostopic"]);
  CHECK(root["cam2"]["rostopic"].as<std::string>() == "/c2/image_raw");
  CHECK(root["cam1"]["distortion_model"].as<std::string>() == "equidistant");
  CHECK(root["cam1"]["resolution"][0].as<int>() == 640);
  CHECK(root["cam0"]["intrinsics"][0].as<double>() == 500.0);
  for (int n = 1; n < 3; ++n) {
    Eigen::Matrix4d M;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) M(r, c) = root["cam" + std::to_string(n)]["T_cn_cnm1"][r][c].as<double>();
    // A point of camera n-1 mapped into camera n: the same base point both ways.
    const Vec3 p_prev(0.1, -0.3, 1.7);
    const Vec3 p_base = T_base.at("c" + std::to_string(n - 1)) * p_prev;
    const Vec3 p_n = T_base.at("c" + std::to_string(n)).inverse() * p_base;
    const Vec3 mapped = M.topLeftCorner<3, 3>() * p_prev + M.topRightCorner<3, 1>();
    CHECK((mapped - p_n).norm() < 1e-12);
  }
  // Our reader gives back the same relative poses.
  const auto back = parseKalibrCamchain(text, "camchain.yaml");
  REQUIRE(back.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(back[i].name == cams[i].name);
    CHECK(translationGap(back[i].T_cam0_cam, cams[i].T_cam0_cam) < 1e-12);
    CHECK(rotationGap(back[i].T_cam0_cam, cams[i].T_cam0_cam) < 1e-12);
    CHECK(back[i].intrinsics == cams[i].intrinsics);
    CHECK(back[i].distortion_coeffs == cams[i].distortion_coeffs);
  }
  // Evaluated against the truth it came from: zero error, no NEES.
  GroundTruth truth;
  truth.T_base_cam = T_base;
  const RelativeEvaluation ev = evaluateCamchain(back, truth, "camchain.yaml");
  REQUIRE(ev.pairs.size() == 3);
  for (const auto& [name, e] : ev.pairs) {
    CHECK(e.translation_mm < 1e-9);
    CHECK(std::isnan(e.nees));
  }
  CHECK(formatRelativeEvaluationTable(ev).find("no base frame") != std::string::npos);
  // A known offset shows up in the pair's error.
  GroundTruth moved = truth;
  moved.T_base_cam["c1"] = T_base.at("c1") * SE3(SO3(), Vec3(0.002, 0, 0));
  const RelativeEvaluation ev2 = evaluateCamchain(back, moved, "camchain.yaml");
  CHECK(ev2.pairs[0].first == "T_c0_c1");
  CHECK(ev2.pairs[0].second.translation_mm == Approx(2.0).epsilon(1e-6));
  CHECK(ev2.pairs[1].second.translation_mm < 1e-9);  // T_c0_c2
}

TEST_CASE("camchain: Kalibr's own files are read; bad ones name the key", "[apps][camchain][shared_data]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "intrinsics");
  const auto euroc = loadKalibrCamchain(dir + "/kalibr_camchain_euroc_stereo_equidistant.yaml");
  REQUIRE(euroc.size() == 2);
  CHECK(euroc[0].name == "cam0");
  CHECK(euroc[0].intrinsics[0] == Approx(461.342).epsilon(1e-5));
  // cam1's T_cn_cnm1 has tx = -0.11006: cam1 sits at +0.11 m along cam0's x.
  CHECK(euroc[1].T_cam0_cam.inverse().translation().x() == Approx(-0.11006).epsilon(1e-3));
  CHECK(euroc[1].rostopic.find("cam1") != std::string::npos);
  const auto mono = loadKalibrCamchain(dir + "/kalibr_camchain_mono_equidistant.yaml");
  CHECK(mono.size() == 1);

  const auto fails = [](const std::string& text, const std::string& where) {
    try {
      parseKalibrCamchain(text, "bad.yaml");
      FAIL("expected an InputError");
    } catch (const InputError& e) {
      INFO(e.what());
      CHECK(e.file() == "bad.yaml");
      CHECK(std::string(e.what()).find(where) != std::string::npos);
    }
  };
  const std::string cam = "  camera_model: pinhole\n  intrinsics: [1.0, 1.0, 1.0, 1.0]\n  distortion_model: none\n"
                          "  distortion_coeffs: []\n  resolution: [10, 10]\n";
  fails("cam0:\n" + cam + "cam1:\n" + cam, "cam1");                      // no T_cn_cnm1
  fails("cam0:\n" + cam + "cam2:\n" + cam, "cam1");                      // a gap
  fails("cam0:\n" + cam + "imu0:\n  rostopic: /imu\n", "imu0");          // not a camera
  fails("cam0:\n  camera_model: pinhole\n  intrinsics: [1.0, 2.0]\n", "cam0.intrinsics");
  CHECK_FALSE(looksLikeKalibrCamchain("cameras:\n  a: {}\n"));
  CHECK_FALSE(looksLikeKalibrCamchain("cam0: [unclosed"));
}

// ---------------------------------------------------------------------------
// Launch files
// ---------------------------------------------------------------------------

TEST_CASE("tf launch files: ROS 2 new-style and ROS 1 arguments round-trip the poses", "[apps][tf_out]") {
  std::mt19937 rng(13);
  std::vector<StaticTransform> tfs;
  for (int i = 0; i < 4; ++i)
    tfs.push_back({"cam-" + std::to_string(i) + ".x", "base_link", "frame_" + std::to_string(i), randomPose(rng)});
  tfs[3].T_parent_child = SE3(SO3::fromRpy(M_PI, 0.0, 0.0), Vec3(0, 0, 1e-5));  // qw = 0
  CHECK(launchFlavorFor("cams.launch") == LaunchFlavor::Ros1Xml);
  CHECK(launchFlavorFor("cams.launch.py") == LaunchFlavor::Ros2Python);
  CHECK(launchFlavorFor("cams.launch.xml") == LaunchFlavor::Ros2Xml);
  CHECK_FALSE(launchFlavorFor("cams.txt"));
  CHECK_FALSE(launchFlavorFor("cams.launch.yaml"));

  const auto poseOf = [](const std::vector<double>& v) {
    Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
    CHECK(std::abs(q.norm() - 1.0) < 1e-15);
    CHECK(v[6] >= 0.0);
    return SE3(SO3(q.normalized().toRotationMatrix()), Vec3(v[0], v[1], v[2]));
  };
  {
    const std::string py = formatStaticTfLaunch(tfs, LaunchFlavor::Ros2Python);
    INFO(py);
    CHECK(py.find("from launch_ros.actions import Node") != std::string::npos);
    CHECK(py.find("def generate_launch_description():") != std::string::npos);
    const std::regex node(
        R"re(arguments=\['--x', '([^']+)', '--y', '([^']+)', '--z', '([^']+)',\s*'--qx', '([^']+)', '--qy', '([^']+)', '--qz', '([^']+)', '--qw', '([^']+)',\s*'--frame-id', '([^']+)', '--child-frame-id', '([^']+)'\])re");
    std::size_t k = 0;
    for (auto it = std::sregex_iterator(py.begin(), py.end(), node); it != std::sregex_iterator(); ++it, ++k) {
      REQUIRE(k < tfs.size());
      std::vector<double> v;
      for (int g = 1; g <= 7; ++g) v.push_back(std::stod((*it)[g].str()));
      const SE3 T = poseOf(v);
      CHECK(translationGap(T, tfs[k].T_parent_child) < 1e-15);
      CHECK(rotationGap(T, tfs[k].T_parent_child) < 1e-14);
      CHECK((*it)[8].str() == "base_link");
      CHECK((*it)[9].str() == tfs[k].child);
    }
    CHECK(k == tfs.size());
    CHECK(py.find("name='fgcal_cam_0_x_static_tf'") != std::string::npos);
  }
  {
    const std::string xml = formatStaticTfLaunch(tfs, LaunchFlavor::Ros1Xml);
    INFO(xml);
    CHECK(xml.find("<launch>") != std::string::npos);
    const std::regex node(R"re(pkg="tf2_ros" type="static_transform_publisher" name="[^"]+"\s+args="([^"]+)")re");
    std::size_t k = 0;
    for (auto it = std::sregex_iterator(xml.begin(), xml.end(), node); it != std::sregex_iterator(); ++it, ++k) {
      REQUIRE(k < tfs.size());
      std::istringstream args((*it)[1].str());
      std::vector<std::string> w{std::istream_iterator<std::string>(args), std::istream_iterator<std::string>()};
      REQUIRE(w.size() == 9);  // x y z qx qy qz qw parent child
      std::vector<double> v;
      for (int g = 0; g < 7; ++g) v.push_back(std::stod(w[g]));
      const SE3 T = poseOf(v);
      CHECK(translationGap(T, tfs[k].T_parent_child) < 1e-15);
      CHECK(rotationGap(T, tfs[k].T_parent_child) < 1e-14);
      CHECK(w[7] == "base_link");
      CHECK(w[8] == tfs[k].child);
    }
    CHECK(k == tfs.size());
  }
  {
    const std::string xml = formatStaticTfLaunch(tfs, LaunchFlavor::Ros2Xml);
    INFO(xml);
    CHECK(xml.find("<launch>") != std::string::npos);
    const std::regex node(
        R"re(pkg="tf2_ros" exec="static_transform_publisher" name="([^"]+)"\s+args="--x (\S+) --y (\S+) --z (\S+) --qx (\S+) --qy (\S+) --qz (\S+) --qw (\S+) --frame-id (\S+) --child-frame-id (\S+)")re");
    std::size_t k = 0;
    for (auto it = std::sregex_iterator(xml.begin(), xml.end(), node); it != std::sregex_iterator(); ++it, ++k) {
      REQUIRE(k < tfs.size());
      std::vector<double> v;
      for (int g = 2; g <= 8; ++g) v.push_back(std::stod((*it)[g].str()));
      const SE3 T = poseOf(v);
      CHECK(translationGap(T, tfs[k].T_parent_child) < 1e-15);
      CHECK(rotationGap(T, tfs[k].T_parent_child) < 1e-14);
      CHECK((*it)[9].str() == "base_link");
      CHECK((*it)[10].str() == tfs[k].child);
    }
    CHECK(k == tfs.size());
    CHECK(xml.find("name=\"fgcal_cam_0_x_static_tf\"") != std::string::npos);
  }
  CHECK(frameIdProblem("camera_optical_face").empty());
  CHECK_FALSE(frameIdProblem("has space").empty());
  CHECK_FALSE(frameIdProblem("").empty());
}

TEST_CASE("tf launch files: both XML forms are well-formed XML (xmllint), whatever the camera names",
          "[apps][tf_out]") {
  if (std::system("xmllint --version > /dev/null 2>&1") != 0) {
    WARN("xmllint not found (apt-get install libxml2-utils): XML well-formedness not checked");
    return;
  }
  std::mt19937 rng(5);
  // Names with what XML comments and attributes cannot hold as is.
  std::vector<StaticTransform> tfs{{"cam--a", "base_link", "a_optical", randomPose(rng)},
                                   {"b<&>\"'-", "base_link", "b_optical", randomPose(rng)}};
  TempDir tmp;
  for (const LaunchFlavor flavor : {LaunchFlavor::Ros2Xml, LaunchFlavor::Ros1Xml}) {
    const std::string path = tmp / (flavor == LaunchFlavor::Ros2Xml ? "cams.launch.xml" : "cams.launch");
    writeFile(path, formatStaticTfLaunch(tfs, flavor));
    INFO(readFile(path));
    CHECK(std::system(("xmllint --noout '" + path + "'").c_str()) == 0);
    // Two <node> elements under <launch>, with the attribute each ROS expects.
    const std::string count = tmp / "count.txt";
    const std::string attr = flavor == LaunchFlavor::Ros2Xml ? "exec" : "type";
    REQUIRE(std::system(("xmllint --xpath 'count(/launch/node[@pkg=\"tf2_ros\"][@" + attr +
                         "=\"static_transform_publisher\"])' '" + path + "' > '" + count + "'")
                            .c_str()) == 0);
    CHECK(readFile(count).substr(0, 2) == "2\n");
  }
}

// ---------------------------------------------------------------------------
// rig.yaml fields and the options' checks
// ---------------------------------------------------------------------------

namespace {
const char* kRig = R"(robot:
  urdf: tiny.urdf
  base_link: base_link
  marker_link: leg
  T_link_marker: [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]
  mount_sigma: [0.002, 0.01]
  encoder_sigma: 0.001
target: {type: charuco, squares_x: 5, squares_y: 7, square_size: 0.04, marker_size: 0.03, dictionary: DICT_4X4_50}
cameras:
  - name: front
    camera_model: pinhole
    distortion_model: none
    intrinsics: [500, 500, 320, 240]
    resolution: [640, 480]
    pixel_sigma: 0.5
    frame: cam_optical
  - name: two
    camera_model: pinhole
    distortion_model: none
    intrinsics: [500, 500, 320, 240]
    resolution: [640, 480]
    pixel_sigma: 0.5
)";
}  // namespace

TEST_CASE("rig.yaml frame and urdf_joint are read, written back, and urdf_joint alone is refused",
          "[apps][urdf_out][rig]") {
  RigConfig rig = parseRigConfig(kRig, "rig.yaml", "/tmp");
  CHECK(rig.warnings.empty());
  CHECK(rig.cameras[0].frame == "cam_optical");
  CHECK(rig.cameras[0].urdf_joint.empty());
  CHECK(rig.cameras[1].frame.empty());
  rig.cameras[1].frame = "cam2_body";
  rig.cameras[1].urdf_joint = "cam2_joint";
  const RigConfig back = parseRigConfig(writeRigConfig(rig), "rig.yaml", "/tmp");
  CHECK(back.cameras[1].frame == "cam2_body");
  CHECK(back.cameras[1].urdf_joint == "cam2_joint");
  try {
    parseRigConfig(replaced(kRig, "    frame: cam_optical\n", "    urdf_joint: cam_body_joint\n"), "rig.yaml", "/tmp");
    FAIL("expected an InputError");
  } catch (const InputError& e) {
    INFO(e.what());
    CHECK(e.location() == "cameras[front].urdf_joint");
    CHECK(std::string(e.what()).find("frame") != std::string::npos);
  }
}

TEST_CASE("robot outputs: options are checked before any work, and the files are what they say",
          "[apps][urdf_out][camchain][tf_out]") {
  TempDir tmp;
  writeFile(tmp / "tiny.urdf", kSmallUrdf);
  writeFile(tmp / "rig.yaml", kRig);
  const RigConfig rig = loadRigConfig(tmp / "rig.yaml");
  const auto fails = [&](const RobotOutputOptions& o, const std::string& word) {
    try {
      planRobotOutputs(o, rig, tmp / "rig.yaml", {tmp / "calibration.yaml"});
      FAIL("expected an InputError");
    } catch (const InputError& e) {
      INFO(e.what());
      CHECK(std::string(e.what()).find(word) != std::string::npos);
    }
  };
  fails({tmp / "missing/robot.urdf", "", {}}, "does not exist");
  fails({"", tmp / "missing/camchain.yaml", {}}, "does not exist");
  fails({"", "", {tmp / "missing/tf.launch"}}, "does not exist");
  fails({tmp / "calibration.yaml", "", {}}, "written there too");
  fails({tmp / "a.yaml", tmp / "a.yaml", {}}, "written there too");
  fails({tmp / "tiny.urdf", "", {}}, "another file");
  // --tf-out: a launch file extension, each path once (the message names both spellings).
  fails({"", "", {tmp / "tf.txt"}}, ".launch.py (ROS 2 Python), .launch.xml (ROS 2 XML) or .launch (ROS 1");
  fails({"", "", {tmp / "tf"}}, "expected a launch file ending in");
  fails({"", "", {tmp / "tf.launch", tmp / "./tf.launch"}}, "--tf-out " + tmp / "tf.launch" + " is written there too");
  fails({"", tmp / "cams.launch", {tmp / "cams.launch"}}, "--kalibr-out " + tmp / "cams.launch" + " is written there too");
  RigConfig no_frames = rig;
  for (auto& c : no_frames.cameras) c.frame.clear();
  try {
    planRobotOutputs({tmp / "out.urdf", "", {}}, no_frames, tmp / "rig.yaml", {});
    FAIL("expected an InputError");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("frame:") != std::string::npos);
  }

  const RobotOutputPlan plan = planRobotOutputs(
      {tmp / "out.urdf", tmp / "camchain.yaml", {tmp / "tf.launch", tmp / "tf.launch.xml"}}, rig, tmp / "rig.yaml", {});
  CalibrationOutput out;
  std::mt19937 rng(21);
  for (const char* name : {"front", "two"}) {
    CameraResult c;
    c.name = name;
    c.T_base_cam = randomPose(rng);
    out.cameras.push_back(c);
  }
  const RobotOutputFiles files = robotOutputFiles(plan, out);
  REQUIRE(files.files.size() == 4);
  CHECK(files.summary.find("URDF check") != std::string::npos);
  CHECK(files.summary.find("tf.launch (ROS 1 roslaunch XML, 2 camera(s)") != std::string::npos);
  CHECK(files.summary.find("tf.launch.xml (ROS 2 XML launch file, 2 camera(s)") != std::string::npos);
  CHECK(files.files[3].first == tmp / "tf.launch.xml");
  CHECK(files.files[3].second.find("--frame-id base_link --child-frame-id cam_optical\"") != std::string::npos);
  const SE3 got = chainPose(files.files[0].second, "base_link", "cam_optical");
  CHECK(translationGap(got, out.cameras[0].T_base_cam) < 1e-9);
  CHECK(rotationGap(got, out.cameras[0].T_base_cam) < 1e-9);
  const auto chain = parseKalibrCamchain(files.files[1].second, "camchain.yaml");
  REQUIRE(chain.size() == 2);
  const SE3 rel = out.cameras[0].T_base_cam.inverse() * out.cameras[1].T_base_cam;
  CHECK(translationGap(chain[1].T_cam0_cam, rel) < 1e-12);
  // Child frames: frame: when given, else the camera's name.
  CHECK(files.files[2].second.find(" base_link cam_optical\"") != std::string::npos);
  CHECK(files.files[2].second.find(" base_link two\"") != std::string::npos);
}
