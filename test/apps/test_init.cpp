// fgcal init: the starter rig.yaml loads back with the imported intrinsics,
// frames are matched in the URDF or left out with the URDF's optical frames
// offered (by what they are, nearest the camera's CAD link first),
// the board link's chain is printed, and every bad input is exit 2 with no
// file written. Also `fgcal --version`.

#include <algorithm>
#include <cstdlib>
#include <sstream>

#include <catch2/catch.hpp>

#include "apps_test_util.hpp"
#include "cli_test_util.hpp"
#include "fgcal/apps/intrinsics_import.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/rig_init.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal_test/shared_data.hpp"

using namespace fgcal::apps;
using fgcal::apps::test::CliRun;
using fgcal::apps::test::quoted;
using fgcal::apps::test::readFile;
using fgcal::apps::test::TempDir;
using fgcal::apps::test::writeFile;

namespace {

CliRun runFgcal(const std::string& args, const TempDir& scratch) {
  return fgcal::apps::test::runCommand(FGCAL_EXE, args, scratch.path());
}

void requireSameIntrinsics(const CameraConfig& got, const CameraConfig& want) {
  INFO("camera " << want.name);
  CHECK(got.distortion_model == want.distortion_model);
  CHECK(got.intrinsics == want.intrinsics);  // exact: numbers are written to round-trip
  CHECK(got.distortion_coeffs == want.distortion_coeffs);
  CHECK(got.resolution == want.resolution);
  CHECK(got.pixel_sigma == kInitPixelSigma);
}

// An OpenCV FileStorage calibration the importer accepts: the tutorial file
// from OpenCV's samples (k3 = 0) with the resolution OpenCV writes beside it.
std::string openCvFileWithResolution(const std::string& shared, const TempDir& dir) {
  const std::string path = dir / "opencv_camera.yml";
  writeFile(path, readFile(shared + "/intrinsics/opencv_tutorial_camera_params.yml") +
                      "image_width: 640\nimage_height: 480\n");
  return path;
}

}  // namespace

TEST_CASE("the board option is parsed into the target block, and a bad one names the expected form", "[init]") {
  const TargetConfig t = parseBoardSpec("5x7:0.04:0.03:DICT_4X4_50");
  CHECK(t.squares_x == 5);
  CHECK(t.squares_y == 7);
  CHECK(t.square_size == 0.04);
  CHECK(t.marker_size == 0.03);
  CHECK(t.dictionary == "DICT_4X4_50");
  for (const std::string bad : {"5x7:0.04:0.03", "5*7:0.04:0.03:DICT_4X4_50", "5x7:0.04m:0.03:DICT_4X4_50",
                                "5x7:0.03:0.04:DICT_4X4_50", "5x7:0.04:0.03:DICT_9X9_1", "1x7:0.04:0.03:DICT_4X4_50",
                                "5x7:0.04:0.03:DICT_4X4_50:extra"}) {
    INFO(bad);
    const InputError e = fgcal::apps::test::expectInputError([&] { parseBoardSpec(bad); });
    CHECK(e.location() == "--board");
    CHECK_THAT(e.what(), Catch::Contains("SQUARES_XxSQUARES_Y:SQUARE_SIZE:MARKER_SIZE:DICTIONARY"));
    CHECK_THAT(e.what(), Catch::Contains(bad));
  }
}

TEST_CASE("optical frame candidates are the links named optical or turned like one, nearest the CAD link first",
          "[init][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(urdf, "urdf/anymal_c.urdf");
  const auto model = fgcal::kinematics::RobotModel::fromFile(urdf);
  // No CAD link: the kind decides, never the spelling ("cam0" is nearest
  // nothing). wide_angle_camera_front_camera_parent is no *optical* name but
  // is turned into the optical convention, so it is offered, after the named.
  const auto none = opticalFrameCandidates(model, "base", "cam0_optical_frame");
  REQUIRE(none.size() == 10);
  CHECK(none.front().named_optical);
  CHECK(none.front().optical_rotation);
  CHECK(none.front().distance_m < 0.0);
  const auto wide = std::find_if(none.begin(), none.end(), [](const OpticalFrameCandidate& c) {
    return c.link == "wide_angle_camera_front_camera_parent";
  });
  REQUIRE(wide != none.end());
  CHECK(!wide->named_optical);
  CHECK(wide->optical_rotation);
  CHECK(none.back().link.find("wide_angle") != std::string::npos);
  for (const auto& c : none) CHECK(c.link.find("color_frame") == std::string::npos);  // a body frame is not offered
  // A frame_id whose body is a URDF link: by distance from it, so the rear
  // camera's own optical frames come first although "front" is spelled alike.
  const auto rear = opticalFrameCandidates(model, "base", "depth_camera_rear_camera_optical");
  REQUIRE(rear.size() == 10);
  CHECK(rear[0].link.rfind("depth_camera_rear_", 0) == 0);
  CHECK(rear[1].link.rfind("depth_camera_rear_", 0) == 0);
  CHECK(rear[0].distance_m <= rear[1].distance_m);
  CHECK(rear[1].distance_m < rear[2].distance_m);
  CHECK(rear[0].distance_m < 0.05);
}

TEST_CASE("closest link names rank shared pieces before short unrelated names", "[init]") {
  const std::vector<std::string> links = {"base", "hatch", "LF_FOOT", "RF_FOOT", "depth_camera_front_color_optical_frame",
                                          "imu_link"};
  CHECK(nearestNames("LF_FOT", links, 1) == std::vector<std::string>{"LF_FOOT"});
  CHECK(nearestNames("cam0_optical_frame", links, 1) ==
        std::vector<std::string>{"depth_camera_front_color_optical_frame"});
  CHECK(nearestNames("x", links, 10).size() == links.size());
}

TEST_CASE("init from camera_info files in ROS, Kalibr and OpenCV format loads back with their intrinsics",
          "[init][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(shared, "");
  TempDir dir;
  const std::string ros = shared + "/intrinsics/ros_camera_info_plumb_bob.yaml";
  const std::string kalibr = shared + "/intrinsics/kalibr_camchain_euroc_stereo_equidistant.yaml";
  const std::string ocv = openCvFileWithResolution(shared, dir);

  InitOptions o;
  o.urdf = shared + "/urdf/anymal_c.urdf";
  o.base_link = "base";
  o.marker_link = "LF_FOOT";
  o.board = "5x7:0.04:0.03:DICT_4X4_50";
  // A name that matches a URDF link through the optical-frame convention, a
  // Kalibr camchain's second camera picked by its name, and a name the URDF
  // does not know.
  o.camera_infos = {"depth_camera_front:" + ros, "cam1:" + kalibr, "wide:" + ocv};
  o.output = dir / "rig.yaml";
  std::ostringstream printed;
  const InitPlan plan = runInit(o, printed);

  const RigConfig rig = loadRigConfig(o.output);
  REQUIRE(rig.cameras.size() == 3);
  CHECK(rig.cameras[0].name == "depth_camera_front");
  CHECK(rig.cameras[1].name == "cam1");
  CHECK(rig.cameras[2].name == "wide");
  requireSameIntrinsics(rig.cameras[0], importIntrinsics(ros, 1.0).at(0));
  requireSameIntrinsics(rig.cameras[1], importIntrinsics(kalibr, 1.0).at(1));
  requireSameIntrinsics(rig.cameras[2], importIntrinsics(ocv, 1.0).at(0));
  // Each camera keeps its source file as intrinsics_file (absolute once loaded).
  CHECK(rig.cameras[0].intrinsics_file == std::filesystem::path(ros).lexically_normal().string());
  CHECK(rig.cameras[1].intrinsics_file == std::filesystem::path(kalibr).lexically_normal().string());
  CHECK(rig.cameras[2].intrinsics_file == std::filesystem::path(ocv).lexically_normal().string());

  // The defaults the file documents.
  CHECK(rig.robot.base_link == "base");
  CHECK(rig.robot.marker_link == "LF_FOOT");
  CHECK(rig.robot.urdf == std::filesystem::path(o.urdf).lexically_normal().string());
  CHECK(rig.robot.T_link_marker.matrix().isApprox(Eigen::Matrix4d::Identity(), 0.0));
  CHECK(rig.robot.mount_sigma_m == 0.005);
  CHECK(rig.robot.mount_sigma_rad == 0.05);
  CHECK(rig.robot.encoder_sigma == 0.001);
  CHECK(rig.sync_tolerance_ms == 1.0);
  CHECK(rig.target.squares_x == 5);
  CHECK(rig.target.squares_y == 7);
  CHECK(rig.target.dictionary == "DICT_4X4_50");

  // Frames: matched by name, or left out with the URDF's optical frames offered.
  const std::string text = readFile(o.output);
  CHECK_THAT(text, Catch::Contains("    frame: depth_camera_front_color_optical_frame"));
  CHECK_THAT(text, Catch::Contains("# CHECK frame: left out: no URDF link is named like camera 'cam1'"));
  CHECK_THAT(text, Catch::Contains("# CHECK frame: left out: no URDF link is named like camera 'wide'"));
  CHECK_THAT(text, Catch::Contains("measure it"));
  // The reader knows every field init writes: no unknown-key warning.
  CHECK(rig.warnings.empty());
  CHECK(rig.cameras[0].frame == "depth_camera_front_color_optical_frame");
  CHECK(rig.cameras[1].frame.empty());
  REQUIRE(plan.cameras.size() == 3);
  CHECK(plan.cameras[0].frame == "depth_camera_front_color_optical_frame");
  CHECK(plan.cameras[1].frame.empty());

  // The chain base -> LF_FOOT with joint names and types, as printed.
  CHECK(plan.chain_joints == std::vector<std::string>{"LF_HAA", "LF_HFE", "LF_KFE"});
  const std::string out = printed.str();
  CHECK_THAT(out, Catch::Contains("base -> LF_FOOT"));
  CHECK_THAT(out, Catch::Contains("-- base_LF_HAA (fixed) --> LF_HAA"));
  CHECK_THAT(out, Catch::Contains("-- LF_HAA (revolute) --> LF_HIP"));
  CHECK_THAT(out, Catch::Contains("-- LF_KFE (revolute) --> LF_SHANK"));
  CHECK_THAT(out, Catch::Contains("-- LF_shank_fixed_LF_FOOT (fixed) --> LF_FOOT"));
  CHECK(out.find("LF_HAA (revolute)") < out.find("LF_KFE (revolute)"));
}

TEST_CASE("init names a Kalibr camchain's cameras by the file when no NAME is given", "[init][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(shared, "");
  TempDir dir;
  InitOptions o;
  o.urdf = shared + "/urdf/anymal_c.urdf";
  o.base_link = "base";
  o.marker_link = "RH_FOOT";
  o.board = "6x8:0.03:0.022:DICT_5X5_100";
  o.camera_infos = {shared + "/intrinsics/kalibr_camchain_euroc_stereo_equidistant.yaml"};
  o.output = dir / "rig.yaml";
  std::ostringstream printed;
  runInit(o, printed);
  const RigConfig rig = loadRigConfig(o.output);
  REQUIRE(rig.cameras.size() == 2);
  CHECK(rig.cameras[0].name == "cam0");
  CHECK(rig.cameras[1].name == "cam1");
  CHECK(rig.target.squares_x == 6);
  CHECK(rig.target.marker_size == 0.022);
  CHECK_THAT(printed.str(), Catch::Contains("-- RH_KFE (revolute) --> RH_SHANK"));

  // Two cameras of one name would make an ambiguous rig.
  o.output = dir / "twice.yaml";
  o.camera_infos = {"a:" + shared + "/intrinsics/ros_camera_info_plumb_bob.yaml",
                    "a:" + shared + "/intrinsics/kalibr_camchain_mono_equidistant.yaml"};
  const InputError e = fgcal::apps::test::expectInputError([&] { planInit(o); });
  CHECK_THAT(e.what(), Catch::Contains("two cameras are named 'a'"));
  CHECK_FALSE(std::filesystem::exists(o.output));
}

TEST_CASE("fgcal init: each bad input exits 2, says what was expected and writes nothing", "[init][shared][cli]") {
  FGCAL_REQUIRE_SHARED_DATA(shared, "");
  TempDir dir;
  const std::string urdf = quoted(shared + "/urdf/anymal_c.urdf");
  const std::string ros = quoted(shared + "/intrinsics/ros_camera_info_plumb_bob.yaml");
  const std::string out = dir / "rig.yaml";
  auto args = [&](const std::string& base, const std::string& marker, const std::string& board,
                  const std::string& info, const std::string& output) {
    return "init --urdf " + urdf + " --base-link " + base + " --marker-link " + marker + " --board " + board +
           " --camera-info " + info + " -o " + quoted(output);
  };
  struct Case {
    const char* what;
    std::string args, output, expect;
  };
  const std::vector<Case> cases = {
      {"base link not in the URDF", args("base_link", "LF_FOOT", "5x7:0.04:0.03:DICT_4X4_50", ros, out), out,
       "'base_link' is not a link of robot 'anymal'; closest links: base"},
      {"marker link not in the URDF", args("base", "LF_FOT", "5x7:0.04:0.03:DICT_4X4_50", ros, out), out,
       "closest links: LF_FOOT"},
      {"bad board", args("base", "LF_FOOT", "5x7:0.04:DICT_4X4_50", ros, out), out,
       "--board: expected SQUARES_XxSQUARES_Y:SQUARE_SIZE:MARKER_SIZE:DICTIONARY"},
      {"missing camera-info file", args("base", "LF_FOOT", "5x7:0.04:0.03:DICT_4X4_50", "cam0:/nonexistent.yaml", out),
       out, "/nonexistent.yaml"},
      {"camera-info the importer refuses (k3 != 0)",
       args("base", "LF_FOOT", "5x7:0.04:0.03:DICT_4X4_50",
            quoted(shared + "/intrinsics/opencv_tutorial_camera_charuco.yml"), out),
       out, "coefficient k3"},
      {"output folder missing", args("base", "LF_FOOT", "5x7:0.04:0.03:DICT_4X4_50", ros, dir / "no/such/rig.yaml"),
       dir / "no/such/rig.yaml", "does not exist"},
      {"URDF missing", "init --urdf /nonexistent.urdf --base-link base --marker-link LF_FOOT --board "
                       "5x7:0.04:0.03:DICT_4X4_50 --camera-info " + ros + " -o " + quoted(out),
       out, "/nonexistent.urdf"},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    const CliRun r = runFgcal(c.args, dir);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains(c.expect));
    CHECK_FALSE(std::filesystem::exists(c.output));
    CHECK(r.out.find("wrote") == std::string::npos);
  }
  // Nothing at all left in the folder (no temporary file either).
  CHECK(std::filesystem::is_empty(dir.path()));

  // An existing file is kept unless --force.
  writeFile(out, "my edited rig\n");
  const CliRun kept = runFgcal(args("base", "LF_FOOT", "5x7:0.04:0.03:DICT_4X4_50", ros, out), dir);
  CHECK(kept.exit_code == 2);
  CHECK_THAT(kept.err, Catch::Contains("--force"));
  CHECK(readFile(out) == "my edited rig\n");
  const CliRun forced = runFgcal(args("base", "LF_FOOT", "5x7:0.04:0.03:DICT_4X4_50", ros, out) + " --force", dir);
  CHECK(forced.exit_code == 0);
  CHECK_THAT(forced.out, Catch::Contains("-- LF_HFE (revolute) --> LF_THIGH"));
  CHECK(loadRigConfig(out).cameras.at(0).name == "test_camera");
}

namespace {

// The commit id inside `git describe` output: "5e14d11", "v1.0-3-g5e14d11"
// and either with "-dirty".
std::string describedCommit(std::string d) {
  const std::string dirty = "-dirty";
  if (d.size() > dirty.size() && d.compare(d.size() - dirty.size(), dirty.size(), dirty) == 0)
    d.resize(d.size() - dirty.size());
  const auto g = d.rfind("-g");
  return g == std::string::npos ? d : d.substr(g + 2);
}

std::string commandOutput(const std::string& cmd, const TempDir& scratch) {
  const std::string out = scratch / "command_output";
  if (std::system((cmd + " >" + quoted(out) + " 2>/dev/null").c_str()) != 0) return "";
  std::string s = readFile(out);
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s;
}

}  // namespace

TEST_CASE("fgcal --version prints the project version and the commit it was built from", "[version][cli]") {
  TempDir dir;
  const CliRun r = runFgcal("--version", dir);
  CHECK(r.exit_code == 0);
  const std::string expected = std::string("fgcal ") + FGCAL_PROJECT_VERSION;
  REQUIRE(r.out.rfind(expected, 0) == 0);
  std::string rest = r.out.substr(expected.size());
  while (!rest.empty() && rest.back() == '\n') rest.pop_back();
  // Built from a clone (this test's own sources are one when git says so):
  // the commit is HEAD's.
  const std::string head = commandOutput("git -C " + quoted(FGCAL_SOURCE_DIR) + " rev-parse HEAD", dir);
  const std::string top = commandOutput("git -C " + quoted(FGCAL_SOURCE_DIR) + " rev-parse --show-toplevel", dir);
  if (!head.empty() && std::filesystem::equivalent(top, FGCAL_SOURCE_DIR)) {
    REQUIRE(rest.rfind(" (git ", 0) == 0);
    REQUIRE(rest.back() == ')');
    const std::string commit = describedCommit(rest.substr(6, rest.size() - 7));
    CHECK(commit.size() >= 7);
    CHECK(head.rfind(commit, 0) == 0);
  } else {
    CHECK(rest.empty());
  }
}

TEST_CASE("the version header leaves the commit out without git or outside a clone", "[version]") {
  TempDir dir;
  const std::string script = std::string(FGCAL_SOURCE_DIR) + "/cmake/fgcal_version.cmake";
  auto generate = [&](const std::string& git, const std::string& source) {
    const std::string header = dir / "fgcal_version.hpp";
    std::filesystem::remove(header);
    const std::string cmd = quoted(FGCAL_CMAKE_COMMAND) + " -DVERSION=9.8.7 -DSOURCE_DIR=" + quoted(source) +
                            " -DGIT_EXECUTABLE=" + quoted(git) + " -DOUTPUT=" + quoted(header) + " -P " +
                            quoted(script) + " >/dev/null 2>&1";
    REQUIRE(std::system(cmd.c_str()) == 0);
    return readFile(header);
  };
  // No git at all.
  const std::string no_git = generate("", FGCAL_SOURCE_DIR);
  CHECK_THAT(no_git, Catch::Contains("#define FGCAL_VERSION \"9.8.7\""));
  CHECK_THAT(no_git, Catch::Contains("#define FGCAL_GIT_DESCRIBE \"\""));
  // Sources that are not the top of a clone (a folder in a temp dir).
  const std::string git = commandOutput("command -v git", dir);
  if (!git.empty()) {
    std::filesystem::create_directories(dir.path() / "src");
    const std::string not_clone = generate(git, dir / "src");
    CHECK_THAT(not_clone, Catch::Contains("#define FGCAL_GIT_DESCRIBE \"\""));
  }
}

TEST_CASE("init --bag finds the ANYmal bag's cameras with their topics and intrinsics in every bag format",
          "[init][bag][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(bags, "bags/anymal_small");
  FGCAL_REQUIRE_SHARED_DATA(urdf, "urdf/anymal_c.urdf");
  const RigConfig truth = loadRigConfig(bags + "/rig.yaml");
  REQUIRE(truth.cameras.size() == 2);
  for (const std::string bag : {"anymal_small.mcap", "anymal_small.bag", "anymal_small_db3"}) {
    INFO(bag);
    TempDir dir;
    InitOptions o;
    o.urdf = urdf;
    o.base_link = "base";
    o.marker_link = "LF_FOOT";
    o.board = "5x7:0.04:0.03:DICT_4X4_50";
    o.bag = bags + "/" + bag;
    o.output = dir / "rig.yaml";
    std::ostringstream printed;
    const InitPlan plan = runInit(o, printed);
    const RigConfig rig = loadRigConfig(o.output);
    REQUIRE(rig.cameras.size() == 2);
    CHECK(rig.joint_states_topic == "/joint_states");
    CHECK(rig.cameras[0].name == "cam0");
    CHECK(rig.cameras[0].topic == "/cam0/image_raw");
    CHECK(rig.cameras[0].camera_info_topic == "/cam0/camera_info");
    CHECK(rig.cameras[1].name == "cam1");
    CHECK(rig.cameras[1].topic == "/cam1/image_raw/compressed");  // the camera's only image topic
    CHECK(rig.cameras[1].camera_info_topic == "/cam1/camera_info");
    for (std::size_t i = 0; i < 2; ++i) requireSameIntrinsics(rig.cameras[i], truth.cameras[i]);
    CHECK(rig.cameras[0].intrinsics_file.empty());  // the bag's values are written as numbers
    CHECK(rig.warnings.empty());
    CHECK(rig.target.squares_x == truth.target.squares_x);
    CHECK(rig.target.square_size == truth.target.square_size);
    CHECK(rig.target.dictionary == truth.target.dictionary);

    // The camera_info frame_ids are not links of anymal_c.urdf: left out,
    // with a comment naming the frame_id, the URDF's optical frames and a
    // commented suggestion per camera on branches --urdf-out can update apart.
    const std::string text = readFile(o.output);
    CHECK(text.find("\n    frame:") == std::string::npos);
    CHECK_THAT(text, Catch::Contains("# CHECK frame: left out: the camera_info frame_id 'cam0_optical_frame' is not a "
                                     "URDF link"));
    CHECK_THAT(text, Catch::Contains("'cam1_optical_frame'"));
    CHECK(plan.cameras.at(0).frame.empty());
    CHECK(plan.cameras.at(0).suggested_frame == "depth_camera_front_color_optical_frame");
    CHECK(plan.cameras.at(1).suggested_frame == "depth_camera_rear_color_optical_frame");
    CHECK_THAT(text, Catch::Contains("    # frame: depth_camera_front_color_optical_frame\n"));
    CHECK_THAT(text, Catch::Contains("    # urdf_joint: depth_camera_front_camera_parent_to_color_frame  # the joint "
                                     "--urdf-out updates"));
    CHECK_THAT(printed.str(), Catch::Contains("before calibrate --urdf-out: edit rig.yaml"));
    CHECK_THAT(printed.str(), Catch::Contains("-- LF_HAA (revolute) --> LF_HIP"));
  }
}

TEST_CASE("init --bag takes a camera_info frame_id that is a URDF link as the camera's frame", "[init][bag][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(bags, "bags/anymal_small");
  FGCAL_REQUIRE_SHARED_DATA(urdf_in, "urdf/anymal_c.urdf");
  // anymal_c.urdf with a link named like the bag's cam0 frame_id.
  TempDir dir;
  const std::string urdf = dir / "robot.urdf";
  writeFile(urdf, fgcal::apps::test::replaced(readFile(urdf_in), "</robot>",
                                              "<link name=\"cam0_optical_frame\"/>\n"
                                              "<joint name=\"cam0_joint\" type=\"fixed\"><parent link=\"face_front\"/>"
                                              "<child link=\"cam0_optical_frame\"/></joint>\n</robot>"));
  InitOptions o;
  o.urdf = urdf;
  o.base_link = "base";
  o.marker_link = "LF_FOOT";
  o.board = "5x7:0.04:0.03:DICT_4X4_50";
  o.bag = bags + "/anymal_small.mcap";
  o.output = dir / "rig.yaml";
  std::ostringstream printed;
  const InitPlan plan = runInit(o, printed);
  REQUIRE(plan.cameras.size() == 2);
  CHECK(plan.cameras[0].frame == "cam0_optical_frame");
  CHECK(plan.cameras[1].frame.empty());
  CHECK_THAT(readFile(o.output), Catch::Contains("    frame: cam0_optical_frame  # the camera_info frame_id"));
  CHECK(loadRigConfig(o.output).cameras.at(0).frame == "cam0_optical_frame");
  CHECK(loadRigConfig(o.output).robot.urdf == std::filesystem::path(urdf).lexically_normal().string());
}

TEST_CASE("fgcal init --bag: a bag without cameras or a missing bag exits 2 and writes nothing", "[init][bag][cli]") {
  FGCAL_REQUIRE_SHARED_DATA(shared, "");
  TempDir dir;
  const std::string out = dir / "rig.yaml";
  auto args = [&](const std::string& bag) {
    return "init --urdf " + quoted(shared + "/urdf/anymal_c.urdf") +
           " --base-link base --marker-link LF_FOOT --board 5x7:0.04:0.03:DICT_4X4_50 --bag " + quoted(bag) + " -o " +
           quoted(out);
  };
  // rosbag2's own test bag: test_msgs only, no CameraInfo topic.
  const CliRun no_cameras = runFgcal(args(shared + "/bags/rosbag2_tests/resources/mcap/cdr_test"), dir);
  CHECK(no_cameras.exit_code == 2);
  CHECK_THAT(no_cameras.err, Catch::Contains("expected at least one sensor_msgs/CameraInfo topic"));
  CHECK_THAT(no_cameras.err, Catch::Contains("--camera-info"));
  const CliRun missing = runFgcal(args(dir / "nothing.mcap"), dir);
  CHECK(missing.exit_code == 2);
  CHECK_THAT(missing.err, Catch::Contains("nothing.mcap"));
  // --bag and --camera-info together are refused by the option parser.
  const CliRun both = runFgcal(args(shared + "/bags/anymal_small/anymal_small.mcap") + " --camera-info " +
                                   quoted(shared + "/intrinsics/ros_camera_info_plumb_bob.yaml"),
                               dir);
  CHECK(both.exit_code == 2);
  CHECK(std::filesystem::is_empty(dir.path()));
}

TEST_CASE("init prints a chain that climbs from the base link before going down to the marker link",
          "[init][shared]") {
  FGCAL_REQUIRE_SHARED_DATA(shared, "");
  TempDir dir;
  InitOptions o;
  o.urdf = shared + "/urdf/anymal_c.urdf";
  o.base_link = "LF_FOOT";  // a base below the common ancestor: the path goes up to `base`, then down
  o.marker_link = "RH_FOOT";
  o.board = "5x7:0.04:0.03:DICT_4X4_50";
  o.camera_infos = {shared + "/intrinsics/ros_camera_info_plumb_bob.yaml"};
  o.output = dir / "rig.yaml";
  const InitPlan plan = planInit(o);
  CHECK(plan.chain_joints ==
        std::vector<std::string>{"LF_KFE", "LF_HFE", "LF_HAA", "RH_HAA", "RH_HFE", "RH_KFE"});
  REQUIRE(plan.chain_lines.size() == 21);  // the base link, then 10 joints up and 10 down
  CHECK(plan.chain_lines.front() == "LF_FOOT");
  CHECK(plan.chain_lines[1] == "  <- LF_shank_fixed_LF_FOOT (fixed, walked upward) -- LF_shank_fixed");
  CHECK(plan.chain_lines[10] == "  <- base_LF_HAA (fixed, walked upward) -- base");
  CHECK(plan.chain_lines[11] == "  -- base_RH_HAA (fixed) --> RH_HAA");
  CHECK(plan.chain_lines.back() == "  -- RH_shank_fixed_RH_FOOT (fixed) --> RH_FOOT");
  CHECK_FALSE(std::filesystem::exists(o.output));  // planInit writes nothing
}

TEST_CASE("fgcal --help names the program fgcal, and each command shows an example, the exit codes and the docs",
          "[help][cli]") {
  TempDir dir;
  const CliRun top = runFgcal("--help", dir);
  INFO(top.out << top.err);
  CHECK(top.exit_code == 0);
  CHECK(top.out.find("Usage: fgcal [OPTIONS] SUBCOMMAND") != std::string::npos);
  CHECK(top.out.find(FGCAL_EXE) == std::string::npos);  // not the build path
  CHECK(top.out.find("/fgcal") == std::string::npos);
  for (const char* part : {"Exit codes: 0 success (verdict ok or check); 1 the data cannot support a calibration", "2 bad input or usage",
                           "docs/formats.md", "docs/outputs.md", "Examples:"})
    CHECK(top.out.find(part) != std::string::npos);
  for (const char* cmd : {"calibrate", "import", "simulate", "evaluate", "demo", "pose-graph-demo", "bag-info", "init"}) {
    const CliRun r = runFgcal(std::string(cmd) + " --help", dir);
    INFO(cmd << ":\n" << r.out << r.err);
    CHECK(r.exit_code == 0);
    CHECK(r.out.find(std::string("Usage: fgcal ") + cmd) != std::string::npos);
    CHECK(r.out.find(std::string("Example:\n  fgcal ") + cmd + " ") != std::string::npos);
    CHECK(r.out.find("Exit codes: 0 success") != std::string::npos);
    CHECK(r.out.find("docs/outputs.md") != std::string::npos);
  }
  // --estimate: one line per quantity, each starting with its name.
  const CliRun cal = runFgcal("calibrate --help", dir);
  for (const char* q : {"time-offset: ", "joint-offsets: ", "intrinsics: "}) {
    const auto at = cal.out.find(q);
    REQUIRE(at != std::string::npos);
    const auto line_start = cal.out.rfind('\n', at) + 1;
    CHECK(cal.out.find_first_not_of(' ', line_start) == at);
  }
}

// One word per idea across the commands: -o/--out names what a command
// writes, --force lets it replace what is there, --camera-count is simulate's
// number of cameras (calibrate's --cameras is a list of names). The old
// spellings stay accepted for one version.
TEST_CASE("every command writes to -o/--out and replaces with --force; the old spellings are still accepted",
          "[init][cli]") {
  TempDir dir;
  const std::string ds = quoted(dir / "ds");
  const std::string small = " --frames 2 --seed 3 --camera-count 1";
  CliRun r = runFgcal("simulate -o " + ds + small, dir);
  REQUIRE(r.exit_code == 0);
  CHECK(readFile(dir / "ds/rig.yaml").find("multisense_left") != std::string::npos);
  r = runFgcal("simulate --out " + ds + small, dir);  // an earlier simulation is kept without --force
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("--force") != std::string::npos);
  CHECK(runFgcal("simulate --out " + ds + small + " --force", dir).exit_code == 0);
  CHECK(runFgcal("simulate --out " + ds + " --frames 2 --seed 3 --cameras 1 --overwrite", dir).exit_code == 0);
  r = runFgcal("simulate --out " + ds + " --frames 2 --camera-count 9 --force", dir);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("--camera-count") != std::string::npos);
  for (const char* command : {"calibrate", "init", "import", "simulate"}) {
    CAPTURE(command);
    const CliRun help = runFgcal(std::string(command) + " --help", dir);
    CHECK(help.exit_code == 0);
    CHECK(help.out.find("-o,--out") != std::string::npos);
  }
  CHECK(runFgcal("init --help", dir).out.find("--force") != std::string::npos);
  CHECK(runFgcal("simulate --help", dir).out.find("--force") != std::string::npos);
}
