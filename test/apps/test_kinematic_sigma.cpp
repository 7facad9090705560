// The URDF's tolerance (robot.kinematic_sigma) through the real fgcal
// command, on a simulated leg whose joint origins differ from its URDF. The
// images cannot see such an error (the origin nearest the base moves every
// board pose, and the cameras with it), so without the tolerance the cameras'
// covariance is far too small; with it, each camera's NEES against the truth
// is within chi-square(6)'s 0.999 point, calibration.yaml says how much of
// each sigma the URDF adds and which origin corrections the data observe, and
// a bad tolerance is an exit-2 error naming its field.

#include <cmath>
#include <fstream>
#include <regex>

#include "apps_test_util.hpp"
#include "cli_test_util.hpp"
#include "fgcal_test/pose_gap.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/simulator.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;
using fgcal::test::nees;

namespace {

constexpr double kChi2_6_999 = 22.4577;

void writeAll(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

/// rig.yaml with its robot.kinematic_sigma line replaced by `line` (empty: removed).
void setKinematicSigma(const fs::path& rig, const std::string& line) {
  const std::string text = readFile(rig);
  writeAll(rig, std::regex_replace(text, std::regex("  kinematic_sigma: [^\n]*\n"), line.empty() ? "" : line + "\n"));
}

}  // namespace

TEST_CASE("kinematic_sigma: the URDF's tolerance enters the cameras' covariance and is reported",
          "[apps][e2e][kinematic_sigma]") {
  TempDir tmp;
  const fs::path data = tmp.path() / "sim";
  SimulationOptions sim;
  sim.out_dir = data.string();
  sim.frames = 90;
  sim.supersampling = 2;
  sim.seed = 4;
  sim.leg_origin_error_m = 0.001;
  sim.leg_origin_error_rad = 0.15 * M_PI / 180.0;
  simulateDataset(sim);
  const GroundTruth truth = loadGroundTruth((data / "ground_truth.yaml").string());
  REQUIRE(truth.kinematic_origins.size() == 3);
  const fs::path rig = data / "rig.yaml";
  REQUIRE(readFile(rig).find("kinematic_sigma: [0.001, ") != std::string::npos);

  const auto calibrate = [&](const std::string& name, const std::string& extra = "") {
    const fs::path out = tmp.path() / (name + ".yaml");
    const CliRun r = runCommand(FGCAL_EXE, "calibrate " + quoted(data.string()) + " --method corners -o " +
                                               quoted(out.string()) + extra, tmp.path());
    INFO(r.command << "\nstderr:\n" << r.err);
    REQUIRE(r.exit_code == 0);
    return std::make_pair(loadCalibrationYaml(out.string()), r.err);
  };
  {
    INFO("with the tolerance: every camera's NEES within chi2(6) 0.999, the URDF's share and the origins written");
    const auto [cal, log] = calibrate("with");
    for (const CameraResult& c : cal.cameras) {
      INFO("camera " << c.name);
      const double n = nees(truth.T_base_cam.at(c.name), c.T_base_cam, c.covariance);
      CHECK(n < kChi2_6_999);
      REQUIRE(c.sigma_from_urdf_mm_deg);
      // The URDF's millimetre moves the camera by about as much: most of its sigma.
      const Vec6 sigma = sigmaMmDeg(c.T_base_cam, c.covariance);
      CHECK(c.sigma_from_urdf_mm_deg->head<3>().norm() > 0.5 * sigma.head<3>().norm());
      CHECK(c.sigma_from_urdf_mm_deg->head<3>().norm() > 0.5);
    }
    REQUIRE(cal.kinematic_origins.size() == 3);
    CHECK(cal.kinematic_origins[0].joint == "lf_haa_joint");
    for (int k = 0; k < 6; ++k) {
      INFO("component " << k << " of the origin nearest the base: moves every board rigidly, never observed");
      CHECK(!cal.kinematic_origins[0].observed[static_cast<std::size_t>(k)]);
      CHECK(cal.kinematic_origins[0].sigma[k] > 0.5 * (k < 3 ? sim.leg_origin_error_rad : sim.leg_origin_error_m));
    }
    CHECK(log.find("URDF tolerance (robot.kinematic_sigma)") != std::string::npos);
    // Each unobserved component is named with what it would move: a millimetre
    // of the base-side origin moves every camera by about a millimetre.
    std::smatch moved;
    const std::string line = "not observed, translation x: a true 1 mm moves " + cal.cameras[0].name + " ([0-9.]+) mm";
    REQUIRE(std::regex_search(log, moved, std::regex(line)));
    CHECK(std::stod(moved[1]) > 0.5);
    CHECK(std::stod(moved[1]) < 1.5);
    // The relative pose of the two cameras does not depend on the leg: its
    // own covariance is honest and far tighter than either camera's.
    const SE3 rel_true = truth.T_base_cam.at(cal.cameras[0].name).inverse() * truth.T_base_cam.at(cal.cameras[1].name);
    REQUIRE(cal.relative_poses.size() == 1);
    const RelativePoseResult& rel = cal.relative_poses[0];
    CHECK(rel_true.between(rel.T_a_b).translation().norm() < 0.001);
    CHECK(nees(rel_true, rel.T_a_b, rel.covariance) < kChi2_6_999);
    CHECK(rel.covariance.bottomRightCorner<3, 3>().trace() <
          0.25 * cal.cameras[1].covariance.bottomRightCorner<3, 3>().trace());
  }
  {
    INFO("with joint offsets estimated too: the URDF's share is read from the reported marginals, whose unobserved "
         "offsets are held, so it is not lost to the free base-side offset");
    const auto [cal, log] = calibrate("with_offsets", " --estimate joint-offsets");
    for (const CameraResult& c : cal.cameras) {
      INFO("camera " << c.name);
      CHECK(nees(truth.T_base_cam.at(c.name), c.T_base_cam, c.covariance) < kChi2_6_999);
      REQUIRE(c.sigma_from_urdf_mm_deg);
      CHECK(c.sigma_from_urdf_mm_deg->head<3>().norm() > 0.5);
    }
    CHECK(cal.kinematic_origins.size() == 3);
    CHECK(cal.joint_offsets.size() == 3);
  }
  {
    INFO("without it (the URDF taken as exact) the same data give a covariance far too small");
    setKinematicSigma(rig, "");
    const auto [cal, log] = calibrate("without");
    double worst = 0.0;
    for (const CameraResult& c : cal.cameras) {
      worst = std::max(worst, nees(truth.T_base_cam.at(c.name), c.T_base_cam, c.covariance));
      CHECK(!c.sigma_from_urdf_mm_deg);
    }
    CHECK(worst > kChi2_6_999);
    CHECK(cal.kinematic_origins.empty());
  }
  const auto refused = [&](const std::string& line, const std::string& field, const std::string& also = "(line ") {
    INFO("rig.yaml robot line: " << line);
    setKinematicSigma(rig, "");
    std::string text = readFile(rig);
    text.insert(text.find("  encoder_sigma:"), line + "\n");
    writeAll(rig, text);
    const CliRun r = runCommand(FGCAL_EXE, "calibrate " + quoted(data.string()) + " -o " +
                                               quoted((tmp.path() / "bad.yaml").string()), tmp.path());
    INFO(r.err);
    CHECK(r.exit_code == 2);
    CHECK(r.err.find(field) != std::string::npos);
    CHECK(r.err.find(also) != std::string::npos);  // the line, or what else the message must say
    CHECK(!fs::exists(tmp.path() / "bad.yaml"));
  };
  refused("  kinematic_sigma: [0, 0.001]", "robot.kinematic_sigma");
  refused("  kinematic_sigma: [0.001, .nan]", "robot.kinematic_sigma");
  refused("  kinematic_sigma: [0.001]", "robot.kinematic_sigma");
  refused("  kinematic_sigma: {lf_haa_joint: [0.001, 0.002]}", "lf_hfe_joint");       // every chain joint needs one
  refused("  kinematic_sigma: {lf_haa_joint: [0.001, 0.002], lf_hfe_joint: [0.001, 0.002], lf_kfe_joint: "
          "[0.001, 0.002], rf_haa_joint: [0.001, 0.002]}",
          "robot.kinematic_sigma.rf_haa_joint", "closest joints: lf_haa_joint");
}
