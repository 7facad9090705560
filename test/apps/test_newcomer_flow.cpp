// The README's flow for a robot's own recording, as a new user runs it, on
// the shared ANYmal capture: `fgcal bag-info`, `fgcal init` from the bag, the one edit the docs
// ask for before --urdf-out (the capture's frame_ids are not links of
// anymal_c.urdf), `fgcal calibrate` with every output, then `fgcal evaluate`
// against the capture's ground truth. If any step needs more than the docs
// say, this test fails.

#include <array>
#include <filesystem>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>

#include "apps_test_util.hpp"
#include "cli_test_util.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal_test/shared_data.hpp"

using fgcal::apps::test::CliRun;
using fgcal::apps::test::quoted;
using fgcal::apps::test::readFile;
using fgcal::apps::test::TempDir;
using fgcal::apps::test::writeFile;

namespace {

CliRun runFgcal(const std::string& args, const TempDir& scratch) {
  return fgcal::apps::test::runCommand(FGCAL_EXE, args, scratch.path());
}

// The edit docs/formats.md and the README describe: remove the "# " in front
// of each camera's suggested "# frame: LINK" line. Returns the number of lines edited.
int uncommentSuggestedFrames(std::string& text) {
  const std::string commented = "\n    # frame: ", plain = "\n    frame: ";
  int n = 0;
  for (std::size_t pos; (pos = text.find(commented)) != std::string::npos; ++n)
    text.replace(pos, commented.size(), plain);
  return n;
}

// The |t| (mm) and angle (deg) columns of a camera's row of `fgcal evaluate`.
/// |t| mm, angle deg and NEES of `camera`'s row of evaluate's table (-1 when absent).
std::array<double, 3> poseError(const std::string& evaluate_out, const std::string& camera) {
  std::istringstream lines(evaluate_out);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream cols(line);
    std::string name;
    double v[9];
    if (!(cols >> name) || name != camera) continue;
    for (double& x : v)
      if (!(cols >> x)) return {-1.0, -1.0, -1.0};
    return {v[6], v[7], v[8]};
  }
  return {-1.0, -1.0, -1.0};
}

}  // namespace

TEST_CASE("the README flow on a real capture: init, the documented frame edit, calibrate with every output, evaluate",
          "[newcomer][bag][shared][cli]") {
  FGCAL_REQUIRE_SHARED_DATA(bags, "bags/anymal_small");
  FGCAL_REQUIRE_SHARED_DATA(urdf, "urdf/anymal_c.urdf");
  const std::string bag = bags + "/anymal_small.mcap";
  TempDir dir;
  const std::string rig = dir / "rig.yaml";

  // 0. bag-info: what the bag holds.
  const CliRun info = runFgcal("bag-info " + quoted(bag), dir);
  INFO(info.out << info.err);
  REQUIRE(info.exit_code == 0);
  CHECK_THAT(info.out, Catch::Contains("/cam0/camera_info") && Catch::Contains("/joint_states"));

  // 1. init, as the README writes it.
  const CliRun init = runFgcal("init --urdf " + quoted(urdf) + " --base-link base --marker-link LF_FOOT "
                               "--board 5x7:0.04:0.03:DICT_4X4_50 --bag " + quoted(bag) + " -o " + quoted(rig),
                               dir);
  INFO(init.out << init.err);
  REQUIRE(init.exit_code == 0);
  CHECK_THAT(init.out, Catch::Contains("before calibrate --urdf-out: edit rig.yaml"));

  // 2. Without the edit --urdf-out cannot work: it says so, names the field, and writes nothing.
  const std::string out = dir / "out";
  std::filesystem::create_directories(out);  // the README's `mkdir -p out`
  const std::string outputs = " -o " + quoted(out + "/calibration.yaml") + " --urdf-out " +
                              quoted(out + "/robot.urdf") + " --kalibr-out " + quoted(out + "/camchain.yaml") +
                              " --tf-out " + quoted(out + "/cameras.launch.py");
  const CliRun unedited = runFgcal("calibrate " + quoted(bag) + " --rig " + quoted(rig) + outputs, dir);
  INFO(unedited.out << unedited.err);
  CHECK(unedited.exit_code == 2);
  CHECK_THAT(unedited.err, Catch::Contains("frame"));
  CHECK(!std::filesystem::exists(out + "/calibration.yaml"));
  CHECK(!std::filesystem::exists(out + "/robot.urdf"));

  // 3. The documented edit, one line per camera, and nothing else.
  std::string text = readFile(rig);
  REQUIRE(uncommentSuggestedFrames(text) == 2);
  writeFile(rig, text);
  const fgcal::apps::RigConfig edited = fgcal::apps::loadRigConfig(rig);
  REQUIRE(edited.cameras.size() == 2);
  CHECK(!edited.cameras[0].frame.empty());
  CHECK(!edited.cameras[1].frame.empty());
  CHECK(edited.cameras[0].frame != edited.cameras[1].frame);
  CHECK(edited.warnings.empty());

  // 4. calibrate with every output of the README's command, and the report.
  const CliRun cal = runFgcal("calibrate " + quoted(bag) + " --rig " + quoted(rig) + outputs, dir);
  INFO(cal.out << cal.err);
  REQUIRE(cal.exit_code == 0);
  const std::string calibration = readFile(out + "/calibration.yaml");
  CHECK_THAT(calibration, Catch::Contains("cam0"));
  CHECK_THAT(calibration, Catch::Contains("cam1"));
  CHECK_THAT(calibration, Catch::Contains("T_base_cam"));
  const std::string robot = readFile(out + "/robot.urdf");
  CHECK_THAT(robot, Catch::Contains("<robot"));
  CHECK_THAT(robot, Catch::Contains(edited.cameras[0].frame));
  CHECK(robot != readFile(urdf));  // the cameras' joints were rewritten
  CHECK_THAT(cal.out + cal.err, Catch::Contains("URDF check: "));
  CHECK_THAT(cal.out + cal.err, Catch::Contains("joints updated: cam0 -> "));
  const std::string camchain = readFile(out + "/camchain.yaml");
  CHECK_THAT(camchain, Catch::Contains("cam0:"));
  CHECK_THAT(camchain, Catch::Contains("cam1:"));
  CHECK_THAT(camchain, Catch::Contains("T_cn_cnm1"));
  const std::string launch = readFile(out + "/cameras.launch.py");
  CHECK_THAT(launch, Catch::Contains("static_transform_publisher"));
  CHECK_THAT(launch, Catch::Contains(edited.cameras[1].frame));
  const std::string report = readFile(out + "/calibration_report/index.html");
  CHECK_THAT(report, Catch::Contains("cam0"));
  CHECK_THAT(report, Catch::Contains("cam1"));

  // 5. evaluate against the capture's ground truth: both cameras within a few millimetres (40 images
  // and a mount left at init's identity), and their covariance, with init's kinematic_sigma, honest.
  const CliRun eval =
      runFgcal("evaluate " + quoted(out + "/calibration.yaml") + " " + quoted(bags + "/ground_truth.yaml"), dir);
  INFO(eval.out << eval.err);
  REQUIRE(eval.exit_code == 0);
  for (const std::string camera : {"cam0", "cam1"}) {
    INFO(camera);
    const auto [t_mm, angle_deg, nees] = poseError(eval.out, camera);
    CHECK(t_mm >= 0.0);
    CHECK(t_mm < 8.0);
    CHECK(angle_deg >= 0.0);
    CHECK(angle_deg < 1.0);
    CHECK(nees >= 0.0);
    CHECK(nees < 22.4577);  // chi-square(6) at 0.999
  }
  const CliRun eval_chain =
      runFgcal("evaluate " + quoted(out + "/camchain.yaml") + " " + quoted(bags + "/ground_truth.yaml"), dir);
  INFO(eval_chain.out << eval_chain.err);
  CHECK(eval_chain.exit_code == 0);
  CHECK_THAT(eval_chain.out, Catch::Contains("T_cam0_cam1"));
}
