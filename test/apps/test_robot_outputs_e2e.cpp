// End to end through the fgcal command: a simulated ANYmal C dataset whose
// rig.yaml names each camera's URDF frame is calibrated with --urdf-out,
// --kalibr-out and --tf-out; the written URDF's chains give the calibrated
// poses (fgcal's walker and KDL), only the edited origins differ from the
// input URDF, the camchain gives the same relative poses, the launch files'
// numbers are the poses, and `fgcal evaluate` reads the camchain. Bad input
// is refused with exit 2 before the detection, leaving earlier outputs as
// they were.
#include <catch2/catch.hpp>


#include <cstdlib>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "apps_test_util.hpp"
#include "cli_test_util.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/simulator.hpp"
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

CliRun runFgcal(const std::string& args, const fs::path& scratch) {
  return runCommand(FGCAL_EXE, args, scratch);
}

using fgcal::test::rotationGap;
using fgcal::test::translationGap;

std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string l;
  while (std::getline(ss, l)) out.push_back(l);
  return out;
}

#ifdef FGCAL_HAVE_KDL
SE3 kdlPose(const std::string& urdf_text, const std::string& base, const std::string& frame) {
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE);
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

// The launch file's poses, in file order: 7 numbers each (x y z qx qy qz qw).
std::vector<SE3> launchPoses(const std::string& text, bool ros1) {
  const std::regex node = ros1 ? std::regex(R"re(args="(\S+) (\S+) (\S+) (\S+) (\S+) (\S+) (\S+) \S+ \S+")re")
                               : std::regex(R"re('--x', '([^']+)', '--y', '([^']+)', '--z', '([^']+)',\s*'--qx', '([^']+)', '--qy', '([^']+)', '--qz', '([^']+)', '--qw', '([^']+)')re");
  std::vector<SE3> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), node); it != std::sregex_iterator(); ++it) {
    double v[7];
    for (int g = 0; g < 7; ++g) v[g] = std::stod((*it)[g + 1].str());
    out.emplace_back(SO3(Eigen::Quaterniond(v[6], v[3], v[4], v[5])), Vec3(v[0], v[1], v[2]));
  }
  return out;
}

}  // namespace

TEST_CASE("e2e: calibrate --urdf-out --kalibr-out --tf-out on ANYmal C, and the refusals",
          "[apps][e2e][urdf_out][shared_data]") {
  FGCAL_REQUIRE_SHARED_DATA(urdf_dir, "urdf");
  TempDir tmp;
  SimulationOptions sim;
  sim.urdf_path = urdf_dir + "/anymal_c.urdf";
  sim.base_link = "base";
  sim.marker_link = "LF_FOOT";
  sim.frames = 40;
  sim.cameras = 2;
  sim.out_dir = tmp / "ds";
  simulateDataset(sim);
  // The simulator places its own cameras; name URDF frames for them. The
  // write-back must make the chains give the CALIBRATED poses, whatever they are.
  const std::string rig_path = tmp / "ds/rig.yaml";
  const std::string rig0 = readFile(rig_path);
  const std::vector<std::string> frames{"depth_camera_front_depth_optical_frame",
                                        "wide_angle_camera_front_camera"};
  std::string rig = rig0;
  {
    std::size_t pos = 0;
    for (const auto& f : frames) {
      pos = rig.find("    pixel_sigma:", pos);
      REQUIRE(pos != std::string::npos);
      pos = rig.find('\n', pos) + 1;
      const std::string line = "    frame: " + f + "\n";
      rig.insert(pos, line);
      pos += line.size();
    }
  }
  writeFile(rig_path, rig);
  fs::create_directories(tmp / "out");
  const std::string outs = "-o " + quoted(tmp / "out/calibration.yaml") + " --urdf-out " +
                           quoted(tmp / "out/robot.urdf") + " --kalibr-out " + quoted(tmp / "out/camchain.yaml") +
                           " --no-report --threads 2";

  const CliRun ok = runFgcal("calibrate " + quoted(tmp / "ds") + " " + outs + " --tf-out " +
                                 quoted(tmp / "out/cameras.launch.py"),
                             tmp.path());
  INFO(ok.err);
  REQUIRE(ok.exit_code == 0);
  CHECK(ok.err.find("URDF check: ") != std::string::npos);
  CHECK(ok.err.find("tolerance 1e-09") != std::string::npos);

  const CalibrationOutput cal = loadCalibrationYaml(tmp / "out/calibration.yaml");
  REQUIRE(cal.cameras.size() == 2);
  const std::string urdf_in = readFile(tmp / "ds/robot.urdf");
  const std::string urdf_out = readFile(tmp / "out/robot.urdf");
  const auto model = kinematics::RobotModel::fromString(urdf_out, "robot.urdf (written)");
  for (std::size_t i = 0; i < 2; ++i) {
    INFO(cal.cameras[i].name << " at " << frames[i]);
    const SE3& want = cal.cameras[i].T_base_cam;
    const SE3 walker = model.chain("base", frames[i]).forward(VecX());
    CHECK(translationGap(walker, want) <= 1e-9);
    CHECK(rotationGap(walker, want) <= 1e-9);
#ifdef FGCAL_HAVE_KDL
    const SE3 kdl = kdlPose(urdf_out, "base", frames[i]);
    CHECK(translationGap(kdl, want) <= 1e-9);
    CHECK(rotationGap(kdl, want) <= 1e-9);
#endif
  }
  // Input and output URDF differ in two <origin> lines only.
  {
    const auto a = splitLines(urdf_in), b = splitLines(urdf_out);
    REQUIRE(a.size() == b.size());
    int changed = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (a[i] != b[i]) {
        ++changed;
        INFO(a[i] << "\n" << b[i]);
        CHECK(a[i].find("<origin") != std::string::npos);
      }
    CHECK(changed == 2);
  }
  // The camchain read back with yaml-cpp: T_cn_cnm1 = T_base_c1^-1 T_base_c0.
  {
    const YAML::Node chain = YAML::LoadFile(tmp / "out/camchain.yaml");
    CHECK(chain.size() == 2);
    CHECK(chain["cam0"]["fgcal_camera"].as<std::string>() == cal.cameras[0].name);
    Eigen::Matrix4d M;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) M(r, c) = chain["cam1"]["T_cn_cnm1"][r][c].as<double>();
    const Eigen::Matrix4d want = (cal.cameras[1].T_base_cam.inverse() * cal.cameras[0].T_base_cam).matrix();
    CHECK((M - want).cwiseAbs().maxCoeff() < 1e-12);
  }
  // The ROS 2 launch file's numbers.
  {
    const auto poses = launchPoses(readFile(tmp / "out/cameras.launch.py"), false);
    REQUIRE(poses.size() == 2);
    for (std::size_t i = 0; i < 2; ++i) {
      CHECK(translationGap(poses[i], cal.cameras[i].T_base_cam) < 1e-12);
      CHECK(rotationGap(poses[i], cal.cameras[i].T_base_cam) < 1e-12);
    }
    CHECK(readFile(tmp / "out/cameras.launch.py").find("'--child-frame-id', '" + frames[0] + "'") !=
          std::string::npos);
  }
  // evaluate reads the camchain: relative poses only, and says so.
  {
    const CliRun ev = runFgcal("evaluate " + quoted(tmp / "out/camchain.yaml") + " " + quoted(tmp / "ds/ground_truth.yaml"),
                               tmp.path());
    INFO(ev.err << ev.out);
    CHECK(ev.exit_code == 0);
    CHECK(ev.out.find("T_" + cal.cameras[0].name + "_" + cal.cameras[1].name) != std::string::npos);
    CHECK(ev.out.find("no base frame") != std::string::npos);
  }

  // ---- Refusals: exit 2, before the detection, earlier outputs untouched ----
  const std::vector<std::string> files{"calibration.yaml", "calibration.urdf.xml", "robot.urdf", "camchain.yaml",
                                       "cameras.launch.py"};
  std::vector<std::string> before;
  for (const auto& f : files) before.push_back(readFile(tmp / ("out/" + f)));
  const auto refused = [&](const std::string& rig_text, const std::string& extra, const std::vector<std::string>& words) {
    writeFile(rig_path, rig_text);
    const CliRun r = runFgcal("calibrate " + quoted(tmp / "ds") + " " + outs + " " + extra, tmp.path());
    INFO(r.err);
    CHECK(r.exit_code == 2);
    for (const auto& w : words) CHECK(r.err.find(w) != std::string::npos);
    CHECK(r.err.find("images from") == std::string::npos);  // stopped before the detection
    for (std::size_t i = 0; i < files.size(); ++i) CHECK(readFile(tmp / ("out/" + files[i])) == before[i]);
    for (const auto& e : fs::directory_iterator(tmp / "out"))
      CHECK(e.path().filename().string().find(".tmp.") == std::string::npos);
  };
  refused(replaced(rig, "frame: wide_angle_camera_front_camera", "frame: wide_angle_camera_front_camra"), "",
          {"rig.yaml", ".frame:", "wide_angle_camera_front_camera", "(line "});
  refused(replaced(rig, "frame: wide_angle_camera_front_camera\n",
                   "frame: wide_angle_camera_front_camera\n    urdf_joint: LF_HAA\n"),
          "", {"urdf_joint", "LF_HAA", "expected a joint above"});
  refused(replaced(rig, "frame: wide_angle_camera_front_camera", "frame: LF_SHANK"), "", {"revolute", "LF_SHANK", "pan-tilt"});
  refused(rig, "--tf-out " + quoted(tmp / "no_such_folder/tf.launch"), {"no_such_folder", "does not exist"});
  refused(rig0, "", {".frame: missing; --urdf-out expected at least one camera with a frame:", "(line ",
                     "remove the '# '"});

  refused(rig, "--tf-out " + quoted(tmp / "out/cameras.txt"), {"cameras.txt", "--tf-out", ".launch.xml (ROS 2 XML)"});
  refused(rig, "--tf-out " + quoted(tmp / "out/cameras.launch") + " --tf-out " + quoted(tmp / "out/../out/cameras.launch"),
          {"--tf-out " + (tmp / "out/cameras.launch"), "out/../out/cameras.launch", "written there too"});

  // The ROS 1 form, chosen by the .launch suffix, and the ROS 2 XML form in the same run.
  writeFile(rig_path, rig);
  const CliRun ros1 = runFgcal("calibrate " + quoted(tmp / "ds") + " " + outs + " --tf-out " +
                                   quoted(tmp / "out/cameras.launch") + " --tf-out " +
                                   quoted(tmp / "out/cameras.launch.xml"),
                               tmp.path());
  INFO(ros1.err);
  REQUIRE(ros1.exit_code == 0);
  CHECK(ros1.err.find("cameras.launch (ROS 1 roslaunch XML") != std::string::npos);
  CHECK(ros1.err.find("cameras.launch.xml (ROS 2 XML launch file") != std::string::npos);
  const std::string xml = readFile(tmp / "out/cameras.launch");
  CHECK(xml.find("pkg=\"tf2_ros\" type=\"static_transform_publisher\"") != std::string::npos);
  const auto poses = launchPoses(xml, true);
  const CalibrationOutput cal2 = loadCalibrationYaml(tmp / "out/calibration.yaml");
  REQUIRE(poses.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) CHECK(translationGap(poses[i], cal2.cameras[i].T_base_cam) < 1e-12);
  const std::string xml2 = readFile(tmp / "out/cameras.launch.xml");
  CHECK(xml2.find("pkg=\"tf2_ros\" exec=\"static_transform_publisher\"") != std::string::npos);
  CHECK(xml2.find("--frame-id base --child-frame-id " + frames[0] + "\"") != std::string::npos);
}

TEST_CASE("e2e: cameras simulated at ANYmal C's URDF frames; the written URDF moves them to the truth",
          "[apps][e2e][urdf_out][shared_data]") {
  FGCAL_REQUIRE_SHARED_DATA(urdf_dir, "urdf");
  TempDir tmp;
  SimulationOptions sim;
  sim.urdf_path = urdf_dir + "/anymal_c.urdf";
  sim.base_link = "base";
  sim.marker_link = "LF_FOOT";
  sim.frames = 80;
  sim.cameras = 2;
  // The depth and colour frames of ANYmal C's front RealSense: both see the raised foot.
  sim.camera_frames = {"depth_camera_front_depth_optical_frame", "depth_camera_front_color_optical_frame"};
  sim.camera_frame_offset_m = 0.006;
  sim.camera_frame_offset_rad = 0.6 * M_PI / 180.0;
  sim.out_dir = tmp / "ds";
  const SimulationSummary s = simulateDataset(sim);
  for (const auto& c : s.per_camera) INFO(c.name << ": board in view in " << c.board_in_view << " of " << c.images);
  const GroundTruth truth = loadGroundTruth(tmp / "ds/ground_truth.yaml");
  const RigConfig rig = loadRigConfig(tmp / "ds/rig.yaml");
  REQUIRE(rig.cameras.size() == 2);
  CHECK(rig.cameras[0].frame == sim.camera_frames[0]);
  CHECK(rig.cameras[1].frame == sim.camera_frames[1]);
  const std::string urdf_in = readFile(tmp / "ds/robot.urdf");
  const auto cad = kinematics::RobotModel::fromString(urdf_in, "cad");
  for (std::size_t i = 0; i < 2; ++i) {  // the truth is the CAD pose moved by the offset
    const SE3 T_cad = cad.chain("base", sim.camera_frames[i]).forward(VecX());
    const SE3& T_true = truth.T_base_cam.at(rig.cameras[i].name);
    CHECK(translationGap(T_cad, T_true) == Approx(0.006).epsilon(1e-9));
    CHECK(rotationGap(T_cad, T_true) == Approx(0.6 * M_PI / 180.0).epsilon(1e-9));
  }

  const std::string args = "calibrate " + quoted(tmp / "ds") + " -o " + quoted(tmp / "calibration.yaml") +
                           " --urdf-out " + quoted(tmp / "robot_calibrated.urdf") + " --no-report --threads 2";
  // By default the depth frame's joint is the camera body's, which carries the
  // colour frame too: refused, naming the way out.
  const CliRun shared = runFgcal(args, tmp.path());
  INFO(shared.err);
  CHECK(shared.exit_code == 2);
  CHECK(shared.err.find("depth_camera_front_camera_to_camera_parent") != std::string::npos);
  CHECK(shared.err.find("would move camera " + rig.cameras[1].name) != std::string::npos);
  CHECK_FALSE(fs::exists(tmp / "robot_calibrated.urdf"));
  // Naming the depth frame's own joint separates them.
  const std::string rig_text = readFile(tmp / "ds/rig.yaml");
  writeFile(tmp / "ds/rig.yaml",
            replaced(rig_text, "frame: depth_camera_front_depth_optical_frame",
                     "frame: depth_camera_front_depth_optical_frame\n    urdf_joint: "
                     "depth_camera_front_camera_parent_to_depth_optical_frame"));
  const CliRun r = runFgcal(args, tmp.path());
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const auto model = kinematics::RobotModel::fromString(readFile(tmp / "robot_calibrated.urdf"), "calibrated");
  for (std::size_t i = 0; i < 2; ++i) {
    const SE3 T_urdf = model.chain("base", sim.camera_frames[i]).forward(VecX());
    const SE3& T_true = truth.T_base_cam.at(rig.cameras[i].name);
    INFO(rig.cameras[i].name << ": URDF after calibration " << translationGap(T_urdf, T_true) * 1e3 << " mm, "
                             << rotationGap(T_urdf, T_true) * 180 / M_PI << " deg from the truth (CAD: 6 mm, 0.6 deg)");
    CHECK(translationGap(T_urdf, T_true) < 0.003);
    CHECK(rotationGap(T_urdf, T_true) < 0.3 * M_PI / 180.0);
  }
}

TEST_CASE("simulate --camera-frames: bad links are refused before anything is written", "[apps][simulate][shared_data]") {
  FGCAL_REQUIRE_SHARED_DATA(urdf_dir, "urdf");
  TempDir tmp;
  SimulationOptions sim;
  sim.urdf_path = urdf_dir + "/anymal_d.urdf";
  sim.base_link = "base";
  sim.marker_link = "LF_FOOT";
  sim.cameras = 1;
  sim.out_dir = tmp / "ds";
  const auto fails = [&](const std::vector<std::string>& frames, const std::string& word) {
    sim.camera_frames = frames;
    try {
      simulateDataset(sim);
      FAIL("expected an InputError");
    } catch (const InputError& e) {
      INFO(e.what());
      CHECK(e.location() == "--camera-frames");
      CHECK(std::string(e.what()).find(word) != std::string::npos);
    }
    CHECK_FALSE(fs::exists(tmp / "ds/rig.yaml"));
  };
  fails({"no_such_link"}, "no_such_link");
  fails({"inspection_payload_camera"}, "inspection_payload_");  // behind the pan-tilt joints
  fails({"depth_camera_left_depth_optical_frame", "depth_camera_right_depth_optical_frame"}, "one link per camera");
}
