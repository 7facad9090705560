// rig.yaml: the valid file, every validation error (file + field + what was
// expected), defaults, warnings, and the write -> parse round trip.
#include <catch2/catch.hpp>

#include "apps_test_util.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/urdf_update.hpp"
#include "fgcal_test/shared_data.hpp"
#include "rig_fixture.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {
RigConfig parse(const std::string& text) { return parseRigConfig(text, "rig.yaml", "/data/set"); }

// A Kalibr camchain with two cameras, distinct from the fixture's numbers.
const std::string kCamchain = R"(cam0:
  camera_model: pinhole
  distortion_model: radtan
  intrinsics: [458.654, 457.296, 367.215, 248.375]
  distortion_coeffs: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
  resolution: [752, 480]
cam1:
  camera_model: pinhole
  distortion_model: equidistant
  intrinsics: [457.587, 456.134, 379.999, 255.238]
  distortion_coeffs: [0.01, -0.02, 0.003, -0.0004]
  resolution: [752, 480]
)";

// The fixture with camera `cam`'s intrinsics group (distortion_model,
// intrinsics, distortion_coeffs, resolution) replaced by `instead`.
std::string withoutGroup(std::string text, const std::string& cam, const std::string& instead) {
  const auto start = text.find("  - name: " + cam + "\n");
  REQUIRE(start != std::string::npos);
  const auto from = text.find("    distortion_model:", start);
  const auto res = text.find("    resolution:", start);
  REQUIRE(from != std::string::npos);
  REQUIRE(res != std::string::npos);
  const auto to = text.find('\n', res) + 1;
  return text.replace(from, to - from, instead);
}
}  // namespace

TEST_CASE("rig.yaml: a valid file gives every field", "[apps][rig]") {
  const RigConfig rig = parse(kValidRig);
  CHECK(rig.robot.urdf == "/data/set/robot.urdf");
  CHECK(rig.robot.base_link == "base_link");
  CHECK(rig.robot.marker_link == "lf_foot");
  CHECK(rig.robot.T_link_marker.translation().isApprox(Vec3(0, 0, 0.02)));
  CHECK(rig.robot.mount_sigma_m == 0.002);
  CHECK(rig.robot.mount_sigma_rad == 0.01);
  CHECK_FALSE(rig.robot.isMountFixed());
  CHECK(rig.robot.encoder_sigma == 0.001);
  CHECK(rig.robot.encoder_sigmas.empty());
  CHECK(rig.target.type == "charuco");
  CHECK(rig.target.squares_x == 5);
  CHECK(rig.target.squares_y == 7);
  CHECK(rig.target.square_size == 0.04);
  CHECK(rig.target.marker_size == 0.03);
  CHECK(rig.target.dictionary == "DICT_4X4_50");
  REQUIRE(rig.cameras.size() == 2);
  const CameraConfig& c0 = rig.cameras[0];
  CHECK(c0.name == "cam0");
  CHECK(c0.camera_model == "pinhole");
  CHECK(c0.distortion_model == "radtan");
  CHECK(c0.intrinsics == std::array<double, 4>{600, 601, 320, 240});
  CHECK(c0.distortion_coeffs == std::vector<double>{0.1, -0.05, 0.001, 0.002});
  CHECK(c0.resolution == std::array<int, 2>{640, 480});
  CHECK(c0.pixel_sigma == 0.5);
  CHECK_FALSE(c0.T_base_cam_guess.has_value());
  const CameraConfig& c1 = rig.cameras[1];
  CHECK(c1.distortion_model == "equidistant");
  REQUIRE(c1.T_base_cam_guess.has_value());
  CHECK(c1.T_base_cam_guess->translation().isApprox(Vec3(0.3, 0, 0.1)));
  CHECK(rig.sync_tolerance_ms == 2.5);
  CHECK(rig.warnings.empty());
  CHECK(rig.cameraIndex("cam1") == 1);
  CHECK(rig.cameraIndex("cam9") == -1);
}

TEST_CASE("rig.yaml: optional fields and their documented defaults", "[apps][rig]") {
  SECTION("sync_tolerance_ms absent -> 1.0 ms") {
    const RigConfig rig = parse(replaced(kValidRig, "sync_tolerance_ms: 2.5\n", ""));
    CHECK(rig.sync_tolerance_ms == kDefaultSyncToleranceMs);
    CHECK(kDefaultSyncToleranceMs == 1.0);
  }
  SECTION("mount_sigma [0, 0] holds the mount fixed") {
    const RigConfig rig = parse(replaced(kValidRig, "[0.002, 0.01]", "[0, 0]"));
    CHECK(rig.robot.isMountFixed());
  }
  SECTION("encoder_sigma as a map joint -> sigma") {
    const RigConfig rig = parse(replaced(kValidRig, "encoder_sigma: 0.001",
                                         "encoder_sigma: {lf_haa_joint: 0.001, lf_hfe_joint: 0.002, lf_kfe_joint: 0.003}"));
    CHECK(rig.robot.encoder_sigma == 0.0);
    CHECK(rig.robot.encoder_sigmas ==
          std::map<std::string, double>{{"lf_haa_joint", 0.001}, {"lf_hfe_joint", 0.002}, {"lf_kfe_joint", 0.003}});
  }
  SECTION("joint_offset_sigma: absent (the default applies), a number, or a map like encoder_sigma") {
    const RigConfig none = parse(kValidRig);
    CHECK(none.robot.joint_offset_sigma == 0.0);
    CHECK(none.robot.joint_offset_sigmas.empty());
    const RigConfig one = parse(replaced(kValidRig, "encoder_sigma: 0.001", "encoder_sigma: 0.001\n  joint_offset_sigma: 0.02"));
    CHECK(one.robot.joint_offset_sigma == 0.02);
    CHECK(one.warnings.empty());
    const RigConfig map = parse(replaced(kValidRig, "encoder_sigma: 0.001",
                                         "encoder_sigma: 0.001\n  joint_offset_sigma: {lf_hfe_joint: 0.01, lf_kfe_joint: 0.03}"));
    CHECK(map.robot.joint_offset_sigma == 0.0);
    CHECK(map.robot.joint_offset_sigmas ==
          std::map<std::string, double>{{"lf_hfe_joint", 0.01}, {"lf_kfe_joint", 0.03}});
  }
  SECTION("backlash_sigma: a number or a map; zero, negative or not finite names the field") {
    const RigConfig one = parse(replaced(kValidRig, "encoder_sigma: 0.001", "encoder_sigma: 0.001\n  backlash_sigma: 0.005"));
    CHECK(one.robot.backlash_sigma == 0.005);
    CHECK(one.warnings.empty());
    const RigConfig map = parse(replaced(kValidRig, "encoder_sigma: 0.001",
                                         "encoder_sigma: 0.001\n  backlash_sigma: {lf_kfe_joint: 0.002}"));
    CHECK(map.robot.backlash_sigmas == std::map<std::string, double>{{"lf_kfe_joint", 0.002}});
    for (const char* bad : {"0", "-0.01", ".nan", ".inf"})
      CHECK_THROWS_WITH(parse(replaced(kValidRig, "encoder_sigma: 0.001",
                                       std::string("encoder_sigma: 0.001\n  backlash_sigma: ") + bad)),
                        Catch::Contains("robot.backlash_sigma"));
  }
  SECTION("distortion_model none without coefficients") {
    std::string text = replaced(kValidRig, "    distortion_coeffs: [0.1, -0.05, 0.001, 0.002]\n", "");
    text = replaced(text, "distortion_model: radtan", "distortion_model: none");
    const RigConfig rig = parse(text);
    CHECK(rig.cameras[0].distortion_model == "none");
    CHECK(rig.cameras[0].distortion_coeffs.empty());
  }
  SECTION("absolute URDF path stays as it is") {
    const RigConfig rig = parse(replaced(kValidRig, "urdf: robot.urdf", "urdf: /opt/robots/../robots/hyq.urdf"));
    CHECK(rig.robot.urdf == "/opt/robots/hyq.urdf");
  }
  SECTION("a rotation off by 1e-9 is accepted and re-orthonormalized") {
    const RigConfig rig = parse(replaced(kValidRig, "[[1,0,0,0],[0,1,0,0]", "[[1.000000001,0,0,0],[0,1,0,0]"));
    const Mat3 R = rig.robot.T_link_marker.rotation();
    CHECK((R.transpose() * R - Mat3::Identity()).norm() < 1e-14);
  }
}

TEST_CASE("rig.yaml: unknown keys are accepted with a warning naming them", "[apps][rig]") {
  std::string text = replaced(kValidRig, "target:\n", "calibration_date: today\ntarget:\n");
  text = replaced(text, "    pixel_sigma: 0.5\n", "    pixel_sigma: 0.5\n    rate_hz: 30\n");
  const RigConfig rig = parse(text);
  REQUIRE(rig.warnings.size() == 2);
  CHECK_THAT(rig.warnings[0], Catch::Contains("rig.yaml") && Catch::Contains("calibration_date") &&
                                  Catch::Contains("unknown key"));
  CHECK_THAT(rig.warnings[1], Catch::Contains("cameras[cam0].rate_hz") && Catch::Contains("pixel_sigma"));
  // A misspelt key names the key it most resembles, not the first known one.
  const RigConfig typo = parse(replaced(kValidRig, "    pixel_sigma: 0.5\n", "    pixel_sigma: 0.5\n    intrinsic_file: x.yaml\n"));
  REQUIRE(typo.warnings.size() == 1);
  CHECK_THAT(typo.warnings[0], Catch::Contains("cameras[cam0].intrinsic_file") &&
                                   Catch::Contains("closest known key: intrinsics_file;"));
}

TEST_CASE("rig.yaml: a principal point outside the image gives a warning", "[apps][rig]") {
  const RigConfig rig = parse(replaced(kValidRig, "[600, 601, 320, 240]", "[600, 601, -320, 240]"));
  REQUIRE(rig.warnings.size() == 1);
  CHECK_THAT(rig.warnings[0], Catch::Contains("cameras[cam0].intrinsics") && Catch::Contains("outside"));
}

TEST_CASE("rig.yaml: file and syntax errors", "[apps][rig]") {
  TempDir tmp;
  CHECK_INPUT_ERROR(loadRigConfig(tmp / "rig.yaml"), "rig.yaml", "", "not found");
  writeFile(tmp / "rig.yaml", "robot:\n  urdf: [robot.urdf\n  base_link: base\n");
  CHECK_INPUT_ERROR(loadRigConfig(tmp / "rig.yaml"), "rig.yaml", "line ", "YAML syntax error");
  CHECK_INPUT_ERROR(parse(""), "rig.yaml", "", "expected a mapping with keys robot, target, cameras");
  CHECK_INPUT_ERROR(parse("- a\n- b\n"), "rig.yaml", "", "expected a mapping", "a list of 2 items");

  SECTION("load resolves the URDF against the file's folder") {
    writeFile(tmp / "rig.yaml", kValidRig);
    CHECK(loadRigConfig(tmp / "rig.yaml").robot.urdf == (tmp.path() / "robot.urdf").string());
  }
}

TEST_CASE("rig.yaml: every validation error names file, field and what was expected", "[apps][rig]") {
  struct Case {
    const char* what;
    std::string from, to, location;
    std::vector<std::string> parts;
  };
  const std::vector<Case> cases = {
      {"radtan with 5 coefficients", "[0.1, -0.05, 0.001, 0.002]", "[0.1, -0.05, 0.001, 0.002, 0.3]",
       "cameras[cam0].distortion_coeffs",
       {"rig.yaml: cameras[cam0].distortion_coeffs: expected 4 numbers for distortion_model radtan", "got 5",
        "(line 21)"}},
      {"equidistant with 3 coefficients", "[0.1, 0.01, 0.001, 0.0001]", "[0.1, 0.01, 0.001]",
       "cameras[cam1].distortion_coeffs", {"4 numbers for distortion_model equidistant", "got 3"}},
      {"none with coefficients", "distortion_model: equidistant", "distortion_model: none",
       "cameras[cam1].distortion_coeffs", {"0 numbers for distortion_model none", "got 4"}},
      {"radtan without coefficients", "    distortion_coeffs: [0.1, -0.05, 0.001, 0.002]\n", "",
       "cameras[cam0].distortion_coeffs", {"missing", "4 numbers for distortion_model radtan"}},
      {"missing square_size", "  square_size: 0.04\n", "", "target.square_size", {"missing", "metres"}},
      {"missing robot", "robot:", "robotx:", "robot", {"missing", "urdf, base_link"}},
      {"missing marker_link", "  marker_link: lf_foot\n", "", "robot.marker_link", {"missing", "board is fixed"}},
      {"missing cameras", "cameras:", "camerax:", "cameras", {"missing", "list of cameras"}},
      {"missing pixel_sigma", "    pixel_sigma: 0.7\n", "", "cameras[cam1].pixel_sigma", {"missing"}},
      {"text for a number", "square_size: 0.04", "square_size: big", "target.square_size",
       {"expected a number", "'big'", "(line 13)"}},
      {"3x3 for a 4x4", "[[1,0,0,0],[0,1,0,0],[0,0,1,0.02],[0,0,0,1]]", "[[1,0,0],[0,1,0],[0,0,1]]",
       "robot.T_link_marker", {"expected a 4x4 matrix", "3x3"}},
      {"flat 16 for a 4x4", "[[1,0,0,0],[0,1,0,0],[0,0,1,0.02],[0,0,0,1]]", "[1,0,0,0,0,1,0,0,0,0,1,0.02,0,0,0,1]",
       "robot.T_link_marker", {"flat list of 16", "nested rows"}},
      {"row of 3 in a 4x4", "[0,1,0,0],[0,0,1,0.02]", "[0,1,0],[0,0,1,0.02]", "robot.T_link_marker[1]",
       {"row of 4 numbers", "got 3"}},
      {"not a rotation", "[[1,0,0,0],[0,1,0,0]", "[[1,0,0,0],[0,2,0,0]", "robot.T_link_marker",
       {"rigid transform", "not a rotation"}},
      {"mirror, det -1", "[[1,0,0,0],[0,1,0,0]", "[[-1,0,0,0],[0,1,0,0]", "robot.T_link_marker", {"det"}},
      {"rotation off by 1e-4", "[[1,0,0,0],[0,1,0,0]", "[[1.0001,0,0,0],[0,1,0,0]", "robot.T_link_marker",
       {"not a rotation"}},
      {"bad last row", "[0,0,0,1]]", "[0,0,1,1]]", "robot.T_link_marker", {"last row"}},
      {"bad guess", "[0,-1,0,0.1]", "[0,-1,0.5,0.1]", "cameras[cam1].T_base_cam_guess", {"not a rotation"}},
      {"squares_x 1", "squares_x: 5", "squares_x: 1", "target.squares_x", {"integer >= 2", "'1'"}},
      {"squares_y 6.5", "squares_y: 7", "squares_y: 6.5", "target.squares_y", {"integer >= 2", "'6.5'"}},
      {"square_size 0", "square_size: 0.04", "square_size: 0", "target.square_size", {"> 0"}},
      {"marker_size negative", "marker_size: 0.03", "marker_size: -0.03", "target.marker_size", {"> 0"}},
      {"marker as large as square", "marker_size: 0.03", "marker_size: 0.04", "target.marker_size",
       {"smaller than its square"}},
      {"board type", "type: charuco", "type: checkerboard", "target.type", {"charuco", "'checkerboard'"}},
      {"pixel_sigma 0", "pixel_sigma: 0.5", "pixel_sigma: 0", "cameras[cam0].pixel_sigma", {"> 0"}},
      {"pixel_sigma nan", "pixel_sigma: 0.5", "pixel_sigma: .nan", "cameras[cam0].pixel_sigma", {"finite"}},
      {"mount_sigma negative", "[0.002, 0.01]", "[-0.002, 0.01]", "robot.mount_sigma[0]", {">= 0"}},
      {"mount_sigma half fixed", "[0.002, 0.01]", "[0, 0.01]", "robot.mount_sigma", {"both 0", "both sigmas > 0"}},
      {"mount_sigma one number", "[0.002, 0.01]", "[0.002]", "robot.mount_sigma", {"2 numbers", "got 1"}},
      {"encoder_sigma 0", "encoder_sigma: 0.001", "encoder_sigma: 0", "robot.encoder_sigma", {"> 0"}},
      {"encoder_sigma map with 0", "encoder_sigma: 0.001", "encoder_sigma: {lf_haa_joint: 0}",
       "robot.encoder_sigma.lf_haa_joint", {"> 0"}},
      {"encoder_sigma list", "encoder_sigma: 0.001", "encoder_sigma: [0.001]", "robot.encoder_sigma",
       {"number > 0 or a map"}},
      {"joint_offset_sigma 0", "encoder_sigma: 0.001", "encoder_sigma: 0.001\n  joint_offset_sigma: 0",
       "robot.joint_offset_sigma", {"> 0"}},
      {"joint_offset_sigma negative", "encoder_sigma: 0.001", "encoder_sigma: 0.001\n  joint_offset_sigma: -0.01",
       "robot.joint_offset_sigma", {"> 0"}},
      {"joint_offset_sigma inf", "encoder_sigma: 0.001", "encoder_sigma: 0.001\n  joint_offset_sigma: .inf",
       "robot.joint_offset_sigma", {"finite"}},
      {"joint_offset_sigma nan in a map", "encoder_sigma: 0.001",
       "encoder_sigma: 0.001\n  joint_offset_sigma: {lf_hfe_joint: .nan}", "robot.joint_offset_sigma.lf_hfe_joint",
       {"finite"}},
      {"camera_model omni", "camera_model: pinhole", "camera_model: omni", "cameras[cam0].camera_model",
       {"pinhole", "'omni'"}},
      {"distortion_model fov", "distortion_model: radtan", "distortion_model: fov", "cameras[cam0].distortion_model",
       {"radtan, equidistant, none", "'fov'"}},
      {"intrinsics 3 numbers", "[600, 601, 320, 240]", "[600, 601, 320]", "cameras[cam0].intrinsics",
       {"4 numbers [fx, fy, cx, cy]", "got 3"}},
      {"intrinsics fx 0", "[600, 601, 320, 240]", "[0, 601, 320, 240]", "cameras[cam0].intrinsics[0]", {"> 0"}},
      {"intrinsics fy negative", "[600, 601, 320, 240]", "[600, -601, 320, 240]", "cameras[cam0].intrinsics[1]", {"> 0"}},
      {"intrinsics text", "[600, 601, 320, 240]", "[600, 601, abc, 240]", "cameras[cam0].intrinsics[2]",
       {"expected a number", "'abc'"}},
      {"intrinsics scalar", "[600, 601, 320, 240]", "600", "cameras[cam0].intrinsics", {"4 numbers", "'600'"}},
      {"resolution 1 value", "[640, 480]", "[640]", "cameras[cam0].resolution", {"2 integers", "got 1"}},
      {"resolution fractional", "[640, 480]", "[640.5, 480]", "cameras[cam0].resolution[0]", {"integer >= 1"}},
      {"resolution 0", "[640, 480]", "[640, 0]", "cameras[cam0].resolution[1]", {"integer >= 1"}},
      {"duplicate camera names", "name: cam1", "name: cam0", "cameras[cam0].name", {"unique", "the first is the camera at line"}},
      {"name with a slash", "name: cam1", "name: left/cam", "cameras[#2].name", {"folder name", "'left/cam'"}},
      {"name with a dot first", "name: cam1", "name: .hidden", "cameras[#2].name", {"folder name"}},
      {"name with a space", "name: cam1", "name: \"left cam\"", "cameras[#2].name", {"folder name"}},
      {"no cameras", "cameras:\n  - name: cam0", "cameras: []\nunused:\n  - name: cam0", "cameras",
       {"at least one camera"}},
      {"camera not a mapping", "  - name: cam0\n", "  - cam0\n  - name: cam0\n", "cameras[#1]",
       {"expected a mapping", "'cam0'"}},
      {"robot is a scalar", "robot:\n  urdf: robot.urdf", "robot: hyq\nold:\n  urdf: robot.urdf", "robot",
       {"expected a mapping", "'hyq'"}},
      {"urdf missing", "  urdf: robot.urdf\n", "", "robot.urdf", {"missing", "relative to the dataset folder"}},
      {"urdf a list", "urdf: robot.urdf", "urdf: [a, b]", "robot.urdf", {"text value", "a list of 2 items"}},
      {"sync tolerance negative", "sync_tolerance_ms: 2.5", "sync_tolerance_ms: -1", "sync_tolerance_ms",
       {">= 0"}},
  };
  for (const Case& c : cases) {
    SECTION(c.what) {
      const std::string text = replaced(kValidRig, c.from, c.to);
      const InputError e = expectInputError([&] { parse(text); });
      INFO(c.what << " -> " << e.what());
      CHECK(e.file() == "rig.yaml");
      CHECK(e.location() == c.location);
      for (const auto& p : c.parts) CHECK_THAT(std::string(e.what()), Catch::Contains(p));
    }
  }
}

TEST_CASE("rig.yaml: write -> parse gives back the same rig", "[apps][rig]") {
  const auto check_same = [](const RigConfig& a, const RigConfig& b) {
    CHECK(a.robot.urdf == b.robot.urdf);
    CHECK(a.robot.base_link == b.robot.base_link);
    CHECK(a.robot.marker_link == b.robot.marker_link);
    CHECK(a.robot.T_link_marker.matrix().isApprox(b.robot.T_link_marker.matrix(), 1e-15));
    CHECK(a.robot.mount_sigma_m == b.robot.mount_sigma_m);
    CHECK(a.robot.mount_sigma_rad == b.robot.mount_sigma_rad);
    CHECK(a.robot.encoder_sigma == b.robot.encoder_sigma);
    CHECK(a.robot.encoder_sigmas == b.robot.encoder_sigmas);
    CHECK(a.robot.joint_offset_sigma == b.robot.joint_offset_sigma);
    CHECK(a.robot.joint_offset_sigmas == b.robot.joint_offset_sigmas);
    CHECK(a.target.type == b.target.type);
    CHECK(a.target.squares_x == b.target.squares_x);
    CHECK(a.target.squares_y == b.target.squares_y);
    CHECK(a.target.square_size == b.target.square_size);
    CHECK(a.target.marker_size == b.target.marker_size);
    CHECK(a.target.dictionary == b.target.dictionary);
    REQUIRE(a.cameras.size() == b.cameras.size());
    for (std::size_t i = 0; i < a.cameras.size(); ++i) {
      const CameraConfig &x = a.cameras[i], &y = b.cameras[i];
      CHECK(x.name == y.name);
      CHECK(x.topic == y.topic);
      CHECK(x.camera_info_topic == y.camera_info_topic);
      CHECK(x.intrinsics_file == y.intrinsics_file);
      CHECK(x.intrinsics_from_bag == y.intrinsics_from_bag);
      CHECK(x.camera_model == y.camera_model);
      CHECK(x.distortion_model == y.distortion_model);
      CHECK(x.intrinsics == y.intrinsics);
      CHECK(x.distortion_coeffs == y.distortion_coeffs);
      CHECK(x.resolution == y.resolution);
      CHECK(x.pixel_sigma == y.pixel_sigma);
      CHECK(x.intrinsics_sigma == y.intrinsics_sigma);
      CHECK(x.distortion_coeffs_sigma == y.distortion_coeffs_sigma);
      REQUIRE(x.T_base_cam_guess.has_value() == y.T_base_cam_guess.has_value());
      if (x.T_base_cam_guess) CHECK(x.T_base_cam_guess->matrix().isApprox(y.T_base_cam_guess->matrix(), 1e-15));
    }
    CHECK(a.sync_tolerance_ms == b.sync_tolerance_ms);
    CHECK(a.joint_states_topic == b.joint_states_topic);
  };

  SECTION("the fixture") {
    const RigConfig rig = parse(kValidRig);
    const std::string text = writeRigConfig(rig);
    const RigConfig back = parseRigConfig(text, "written.yaml", "/elsewhere");
    check_same(rig, back);
    CHECK(back.warnings.empty());
  }
  SECTION("awkward values: a random mount, tiny sigmas, map form, name quoting, relative URDF") {
    RigConfig rig = parse(kValidRig);
    rig.robot.T_link_marker = SE3::exp((Vec6() << 0.3, -1.2, 2.9, 0.1234567890123, -1e-7, 3.3).finished());
    rig.robot.encoder_sigma = 0.0;
    rig.robot.encoder_sigmas = {{"lf_haa_joint", 1.0 / 3.0}, {"lf_hfe_joint", 1e-300}, {"yes", 0.1}};
    rig.robot.joint_offset_sigmas = {{"lf_kfe_joint", 0.1 + 0.2}, {"no", 1e-3}};
    rig.robot.mount_sigma_m = 0.1 + 0.2;
    rig.target.dictionary = "DICT_APRILTAG_36h11";
    rig.cameras[0].name = "123";
    rig.cameras[1].name = "null";
    rig.cameras[0].intrinsics = {600.123456789012345, 1e5, -0.5, 1234.5};
    rig.cameras[0].intrinsics_sigma = {6.0, 1.0 / 3.0, 2.5, 1e-9};
    rig.cameras[1].distortion_coeffs_sigma = {0.1, 0.01, 1e-3, 0.1 + 0.2};
    rig.sync_tolerance_ms = 0.0;
    const std::string text = writeRigConfig(rig, "/data/set");
    CHECK_THAT(text, Catch::Contains("urdf: \"robot.urdf\""));
    const RigConfig back = parseRigConfig(text, "written.yaml", "/data/set");
    check_same(rig, back);
  }
  SECTION("bag fields: topics, an intrinsics_file relative to the rig, intrinsics left to the bag") {
    TempDir tmp;
    writeFile(tmp / "calib/camchain.yaml", kCamchain);
    std::string text = replaced(kValidRig, "sync_tolerance_ms: 2.5\n", "joint_states_topic: /anymal/joints\n");
    text = replaced(text, "  - name: cam0\n", "  - name: cam0\n    topic: /cam0/image_raw\n");
    text = withoutGroup(text, "cam0", "    intrinsics_file: calib/camchain.yaml\n");
    text = withoutGroup(text, "cam1", "    topic: /cam1/image/compressed\n    camera_info_topic: /cam1/camera_info\n");
    writeFile(tmp / "rig.yaml", text);
    RigConfig rig = loadRigConfig(tmp / "rig.yaml");
    REQUIRE(rig.cameras[0].intrinsics_file == (tmp.path() / "calib/camchain.yaml").string());
    REQUIRE(rig.cameras[1].intrinsics_from_bag);
    rig.robot.urdf = (tmp.path() / "robot.urdf").string();
    const std::string written = writeRigConfig(rig, tmp.path().string());
    // Written relative to the rig's folder, so the dataset can be moved.
    CHECK_THAT(written, Catch::Contains("intrinsics_file: \"calib/camchain.yaml\""));
    CHECK_THAT(written, Catch::Contains("joint_states_topic: \"/anymal/joints\""));
    writeFile(tmp / "rig2.yaml", written);
    const RigConfig back = loadRigConfig(tmp / "rig2.yaml");
    check_same(rig, back);
    CHECK(back.warnings.empty());
  }
  SECTION("a camera left to the bag cannot be written without its camera_info_topic") {
    RigConfig rig = parse(kValidRig);
    rig.cameras[1].intrinsics_from_bag = true;
    CHECK_THROWS_WITH(writeRigConfig(rig), Catch::Contains("cam1") && Catch::Contains("camera_info_topic"));
  }
  SECTION("file on disk") {
    TempDir tmp;
    RigConfig rig = parse(kValidRig);
    rig.robot.urdf = (tmp.path() / "robot.urdf").string();
    writeFile(tmp / "rig.yaml", writeRigConfig(rig, tmp.path().string()));
    check_same(rig, loadRigConfig(tmp / "rig.yaml"));
  }
}

TEST_CASE("rig.yaml: bag topics and their defaults", "[apps][rig][bag]") {
  SECTION("absent: no camera topics, joint states on /joint_states") {
    const RigConfig rig = parse(kValidRig);
    CHECK(rig.joint_states_topic == "/joint_states");
    CHECK(rig.joint_states_topic == kDefaultJointStatesTopic);
    CHECK(rig.cameras[0].topic.empty());
    CHECK(rig.cameras[0].camera_info_topic.empty());
    CHECK(rig.cameras[0].intrinsics_file.empty());
    CHECK_FALSE(rig.cameras[0].intrinsics_from_bag);
    CHECK(rig.source == "rig.yaml");
    CHECK(rig.cameras[0].yaml_line == 17);
    CHECK(rig.cameras[1].yaml_line == 24);
  }
  SECTION("given") {
    std::string text = replaced(kValidRig, "sync_tolerance_ms: 2.5\n", "joint_states_topic: /robot/joint_states\n");
    text = replaced(text, "  - name: cam1\n",
                    "  - name: cam1\n    topic: /cam1/image_raw/compressed\n    camera_info_topic: /cam1/camera_info\n");
    const RigConfig rig = parse(text);
    CHECK(rig.joint_states_topic == "/robot/joint_states");
    CHECK(rig.cameras[1].topic == "/cam1/image_raw/compressed");
    CHECK(rig.cameras[1].camera_info_topic == "/cam1/camera_info");
    // intrinsics given too: they stay rig.yaml's, the topic is not needed for them
    CHECK_FALSE(rig.cameras[1].intrinsics_from_bag);
    CHECK(rig.cameras[1].intrinsics == std::array<double, 4>{400, 400, 330.5, 250.25});
    CHECK(rig.warnings.empty());
  }
  SECTION("errors name the field and line") {
    CHECK_INPUT_ERROR(parse(replaced(kValidRig, "  - name: cam1\n", "  - name: cam1\n    topic: [a, b]\n")),
                      "rig.yaml", "cameras[cam1].topic", "text value", "(line 25)");
    CHECK_INPUT_ERROR(parse(replaced(kValidRig, "  - name: cam1\n", "  - name: cam1\n    topic: \"/cam 1/image\"\n")),
                      "rig.yaml", "cameras[cam1].topic", "no spaces", "(line 25)");
    CHECK_INPUT_ERROR(parse(replaced(kValidRig, "  - name: cam0\n", "  - name: cam0\n    camera_info_topic: {a: 1}\n")),
                      "rig.yaml", "cameras[cam0].camera_info_topic", "text value");
    CHECK_INPUT_ERROR(parse(kValidRig + "joint_states_topic: [x]\n"), "rig.yaml", "joint_states_topic", "text value",
                      "(line 33)");
  }
}

TEST_CASE("rig.yaml: intrinsics from camera_info_topic are marked as not yet known", "[apps][rig][bag]") {
  const RigConfig rig = parse(withoutGroup(kValidRig, "cam1", "    camera_info_topic: /cam1/camera_info\n"));
  const CameraConfig& c = rig.cameras[1];
  CHECK(c.intrinsics_from_bag);
  CHECK(c.camera_info_topic == "/cam1/camera_info");
  CHECK(c.pixel_sigma == 0.7);
  CHECK(c.T_base_cam_guess.has_value());
  CHECK_FALSE(rig.cameras[0].intrinsics_from_bag);

  SECTION("camera_model may stay, but must still be a supported one") {
    std::string text = withoutGroup(kValidRig, "cam1", "    camera_info_topic: /cam1/camera_info\n");
    CHECK_INPUT_ERROR(parse(replaced(text, "    camera_model: pinhole\n    camera_info_topic",
                                     "    camera_model: omni\n    camera_info_topic")),
                      "rig.yaml", "cameras[cam1].camera_model", "pinhole", "'omni'");
  }
  SECTION("half of the group in rig.yaml is refused, naming the field") {
    const std::string text =
        withoutGroup(kValidRig, "cam1", "    camera_info_topic: /cam1/camera_info\n    resolution: [752, 480]\n");
    CHECK_INPUT_ERROR(parse(text), "rig.yaml", "cameras[cam1].resolution", "/cam1/camera_info", "give intrinsics too",
                      "(line 27)");
  }
}

TEST_CASE("rig.yaml: a camera without any intrinsics source names the three ways to give one", "[apps][rig][bag]") {
  CHECK_INPUT_ERROR(parse(withoutGroup(kValidRig, "cam0", "")), "rig.yaml", "cameras[cam0].intrinsics", "missing",
                    "[fx, fy, cx, cy]", "intrinsics_file", "camera_info_topic");
  // a topic for the images alone does not give intrinsics
  CHECK_INPUT_ERROR(parse(withoutGroup(kValidRig, "cam0", "    topic: /cam0/image_raw\n")), "rig.yaml",
                    "cameras[cam0].intrinsics", "missing", "intrinsics_file");
}

TEST_CASE("rig.yaml: intrinsics_file", "[apps][rig][bag]") {
  TempDir tmp;
  writeFile(tmp / "calib/camchain.yaml", kCamchain);
  const auto load = [&](const std::string& text) {
    writeFile(tmp / "rig.yaml", text);
    return loadRigConfig(tmp / "rig.yaml");
  };

  SECTION("relative to the rig.yaml's folder; a camchain camera picked by name") {
    std::string text = withoutGroup(kValidRig, "cam0", "    intrinsics_file: calib/camchain.yaml\n");
    text = withoutGroup(text, "cam1", "    intrinsics_file: ./calib/../calib/camchain.yaml\n");
    const RigConfig rig = load(text);
    const CameraConfig &c0 = rig.cameras[0], &c1 = rig.cameras[1];
    CHECK(c0.intrinsics_file == (tmp.path() / "calib/camchain.yaml").string());
    CHECK(c1.intrinsics_file == c0.intrinsics_file);
    CHECK_FALSE(c0.intrinsics_from_bag);
    CHECK(c0.distortion_model == "radtan");
    CHECK(c0.intrinsics == std::array<double, 4>{458.654, 457.296, 367.215, 248.375});
    CHECK(c0.distortion_coeffs == std::vector<double>{-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05});
    CHECK(c0.resolution == std::array<int, 2>{752, 480});
    CHECK(c0.pixel_sigma == 0.5);  // rig.yaml's own, not the importer's
    CHECK(c1.distortion_model == "equidistant");
    CHECK(c1.intrinsics[0] == 457.587);
    CHECK(c1.pixel_sigma == 0.7);
    CHECK(rig.warnings.empty());
  }
  SECTION("relative to the rig.yaml's folder, not the working directory") {
    writeFile(tmp / "sub/rig.yaml", withoutGroup(kValidRig, "cam0", "    intrinsics_file: ../calib/camchain.yaml\n"));
    CHECK(loadRigConfig(tmp / "sub/rig.yaml").cameras[0].intrinsics[0] == 458.654);
  }
  SECTION("absolute path") {
    const RigConfig rig = parse(
        withoutGroup(kValidRig, "cam1", "    intrinsics_file: " + (tmp.path() / "calib/camchain.yaml").string() + "\n"));
    CHECK(rig.cameras[1].intrinsics[0] == 457.587);
  }
  SECTION("a file with one camera is used whatever its name") {
    writeFile(tmp / "left.yaml", "cam3:\n  camera_model: pinhole\n  distortion_model: none\n  intrinsics: [300, 301, "
                                 "160, 120]\n  distortion_coeffs: []\n  resolution: [320, 240]\n");
    const RigConfig rig = load(withoutGroup(kValidRig, "cam1", "    intrinsics_file: left.yaml\n"));
    CHECK(rig.cameras[1].intrinsics == std::array<double, 4>{300, 301, 160, 120});
    CHECK(rig.cameras[1].distortion_model == "none");
    CHECK(rig.cameras[1].resolution == std::array<int, 2>{320, 240});
  }
  SECTION("a camchain with several cameras and none named like this one: an error listing them") {
    std::string text = withoutGroup(kValidRig, "cam1", "    intrinsics_file: calib/camchain.yaml\n");
    text = replaced(text, "name: cam1", "name: front");
    CHECK_INPUT_ERROR(load(text), "rig.yaml", "cameras[front].intrinsics_file", "2 cameras (cam0, cam1)", "'front'",
                      "(line 26)");
  }
  SECTION("both intrinsics and intrinsics_file: intrinsics win, with a warning; the file is not read") {
    const RigConfig rig =
        load(replaced(kValidRig, "    pixel_sigma: 0.5\n", "    pixel_sigma: 0.5\n    intrinsics_file: nowhere.yaml\n"));
    CHECK(rig.cameras[0].intrinsics == std::array<double, 4>{600, 601, 320, 240});
    CHECK(rig.cameras[0].intrinsics_file.empty());
    REQUIRE(rig.warnings.size() == 1);
    CHECK_THAT(rig.warnings[0], Catch::Contains("cameras[cam0].intrinsics_file") && Catch::Contains("ignored") &&
                                    Catch::Contains("precedence") && Catch::Contains("line 24"));
  }
  SECTION("intrinsics_file with part of the group in rig.yaml: refused, naming the field") {
    CHECK_INPUT_ERROR(
        load(withoutGroup(kValidRig, "cam0", "    intrinsics_file: calib/camchain.yaml\n    distortion_model: radtan\n")),
        "rig.yaml", "cameras[cam0].distortion_model", "intrinsics_file", "remove distortion_model");
  }
  SECTION("a missing file names rig.yaml, the field, the line and the resolved path") {
    CHECK_INPUT_ERROR(load(withoutGroup(kValidRig, "cam0", "    intrinsics_file: calib/missing.yaml\n")), "rig.yaml",
                      "cameras[cam0].intrinsics_file", (tmp.path() / "calib/missing.yaml").string(), "not found",
                      "(line 19)");
  }
  SECTION("a file fgcal cannot represent: the importer's reason, behind rig.yaml's field") {
    writeFile(tmp / "bad.yaml", replaced(kCamchain, "distortion_model: radtan", "distortion_model: fov"));
    CHECK_INPUT_ERROR(load(withoutGroup(kValidRig, "cam0", "    intrinsics_file: bad.yaml\n")), "rig.yaml",
                      "cameras[cam0].intrinsics_file", "bad.yaml", "cam0.distortion_model", "'fov'");
    writeFile(tmp / "notcam.yaml", "hello: world\n");
    CHECK_INPUT_ERROR(load(withoutGroup(kValidRig, "cam0", "    intrinsics_file: notcam.yaml\n")), "rig.yaml",
                      "cameras[cam0].intrinsics_file", "notcam.yaml", "Kalibr camchain");
  }
  SECTION("an empty value is missing, not a path") {
    CHECK_INPUT_ERROR(load(withoutGroup(kValidRig, "cam0", "    intrinsics_file: \"\"\n")), "rig.yaml",
                      "cameras[cam0].intrinsics_file", "text value");
  }
}

TEST_CASE("rig.yaml: intrinsics_file with the real Kalibr, ROS and OpenCV files", "[apps][rig][bag]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "intrinsics");
  SECTION("Kalibr EuRoC stereo: cam1 picked by name") {
    const RigConfig rig =
        parse(withoutGroup(kValidRig, "cam1", "    intrinsics_file: " + dir + "/kalibr_camchain_euroc_stereo_equidistant.yaml\n"));
    CHECK(rig.cameras[1].distortion_model == "equidistant");
    CHECK(rig.cameras[1].intrinsics[3] == 255.55347731935623);
  }
  SECTION("ROS camera_info: the only camera, whatever its name") {
    const RigConfig rig =
        parse(withoutGroup(kValidRig, "cam0", "    intrinsics_file: " + dir + "/ros_camera_info_plumb_bob.yaml\n"));
    CHECK(rig.cameras[0].intrinsics == std::array<double, 4>{438.783367, 437.302876, 305.593336, 243.738352});
    CHECK(rig.cameras[0].resolution == std::array<int, 2>{640, 480});
  }
  SECTION("OpenCV file with k3 != 0: the importer's reason") {
    CHECK_INPUT_ERROR(
        parse(withoutGroup(kValidRig, "cam0", "    intrinsics_file: " + dir + "/opencv_tutorial_camera_charuco.yml\n")),
        "rig.yaml", "cameras[cam0].intrinsics_file", "k3 = 2.954258940681008", "CALIB_FIX_K3");
  }
}

TEST_CASE("rig.yaml: the prior of estimated intrinsics", "[apps][rig]") {
  const std::string with = replaced(kValidRig, "    pixel_sigma: 0.5\n",
                                    "    pixel_sigma: 0.5\n    intrinsics_sigma: [6, 6, 3, 3]\n"
                                    "    distortion_coeffs_sigma: [0.05, 0.02, 0.001, 0.001]\n");
  const RigConfig rig = parse(with);
  CHECK(rig.cameras[0].intrinsics_sigma == std::vector<double>{6, 6, 3, 3});
  CHECK(rig.cameras[0].distortion_coeffs_sigma == std::vector<double>{0.05, 0.02, 0.001, 0.001});
  CHECK(rig.cameras[1].intrinsics_sigma.empty());  // absent: the default applies when estimating
  CHECK(rig.warnings.empty());
  CHECK(defaultDistortionSigma("radtan").size() == 4);
  CHECK(defaultDistortionSigma("equidistant").size() == 4);
  CHECK(defaultDistortionSigma("none").empty());

  // A zero, negative or non-finite sigma is an error naming the field.
  CHECK_INPUT_ERROR(parse(replaced(with, "intrinsics_sigma: [6, 6, 3, 3]", "intrinsics_sigma: [6, 0, 3, 3]")),
                    "rig.yaml", "cameras[cam0].intrinsics_sigma[1]", "> 0", "'0'");
  CHECK_INPUT_ERROR(parse(replaced(with, "intrinsics_sigma: [6, 6, 3, 3]", "intrinsics_sigma: [6, 6, -3, 3]")),
                    "rig.yaml", "cameras[cam0].intrinsics_sigma[2]", "> 0");
  CHECK_INPUT_ERROR(parse(replaced(with, "intrinsics_sigma: [6, 6, 3, 3]", "intrinsics_sigma: [6, 6, 3, .nan]")),
                    "rig.yaml", "cameras[cam0].intrinsics_sigma[3]", "finite");
  CHECK_INPUT_ERROR(
      parse(replaced(with, "distortion_coeffs_sigma: [0.05, 0.02, 0.001, 0.001]",
                     "distortion_coeffs_sigma: [0.05, 0.02, 0.001, .inf]")),
      "rig.yaml", "cameras[cam0].distortion_coeffs_sigma[3]", "finite");
  CHECK_INPUT_ERROR(
      parse(replaced(with, "distortion_coeffs_sigma: [0.05, 0.02, 0.001, 0.001]",
                     "distortion_coeffs_sigma: [0.05, 0, 0.001, 0.001]")),
      "rig.yaml", "cameras[cam0].distortion_coeffs_sigma[1]", "> 0");
  // Counts: 4 intrinsics, one sigma per coefficient of the model.
  CHECK_INPUT_ERROR(parse(replaced(with, "intrinsics_sigma: [6, 6, 3, 3]", "intrinsics_sigma: [6, 6, 3]")),
                    "rig.yaml", "cameras[cam0].intrinsics_sigma", "expected 4 numbers", "got 3");
  CHECK_INPUT_ERROR(
      parse(replaced(with, "distortion_coeffs_sigma: [0.05, 0.02, 0.001, 0.001]", "distortion_coeffs_sigma: [0.05]")),
      "rig.yaml", "cameras[cam0].distortion_coeffs_sigma", "4 numbers", "radtan", "got 1");
  CHECK_INPUT_ERROR(parse(replaced(with, "intrinsics_sigma: [6, 6, 3, 3]", "intrinsics_sigma: 3")), "rig.yaml",
                    "cameras[cam0].intrinsics_sigma", "4 numbers");
}

TEST_CASE("rig.yaml: an error found after reading names the file, the field by camera name and its line",
          "[rig][errors]") {
  const RigConfig rig = parseRigConfig(kValidRig, "rig.yaml", ".");
  REQUIRE(rig.cameras.size() == 2);
  // A camera's field has its own line; a field rig.yaml leaves out falls back to its camera's.
  const InputError topic = rigFieldError(rig, cameraField("cam1", "pixel_sigma"), "expected something");
  CHECK(topic.file() == "rig.yaml");
  CHECK(topic.location() == "cameras[cam1].pixel_sigma");
  CHECK_THAT(topic.what(), Catch::Contains("expected something (line "));
  CHECK(rig.lineSuffix("cameras[cam1].frame") == rig.lineSuffix("cameras[cam1]"));
  CHECK(rig.lineSuffix("cameras[cam1]") == " (line " + std::to_string(rig.cameras[1].yaml_line) + ")");
  CHECK(rig.lineSuffix("cameras[cam1].pixel_sigma") != rig.lineSuffix("cameras[cam1]"));
  CHECK(rig.lineSuffix("robot.base_link").find("(line ") != std::string::npos);
  CHECK(rig.lineSuffix("no_such_field").empty());
}

TEST_CASE("closest names are ranked by similarity, whatever their order in the file", "[rig][errors]") {
  std::vector<std::string> links;
  for (int i = 0; i < 20; ++i) links.push_back("link_" + std::to_string(i));
  links.push_back("front_camera_optical_frame");  // last in file order
  CHECK(closestNames("front_camra_optical_frame", links, 1) == std::vector<std::string>{"front_camera_optical_frame"});
  CHECK(closestNames("FRONT_CAMERA", links, 1) == std::vector<std::string>{"front_camera_optical_frame"});
  CHECK(closestNote("x", {}, "links").empty());
  CHECK(closestNote("lnk_3", links, "links", 1) == "; closest links: link_3");
}
