// A rolling shutter (rig.yaml readout_ms, --estimate rolling-shutter) through
// the real fgcal command, on a simulated rig whose second camera exposes its
// rows one after another over 25 ms while the leg moves. A time offset alone
// takes up the mean row's delay; the skew within each image stays, and only
// reading every corner at its own row's time removes it. Estimated, the
// readout comes back within its sigma and the camera is right again; held at
// a datasheet's value it serves as well; a readout longer than the camera's
// frame period is refused naming the camera's field.

#include <cmath>
#include <fstream>
#include <regex>

#include "apps_test_util.hpp"
#include "cli_test_util.hpp"
#include "fgcal_test/files.hpp"
#include "fgcal_test/pose_gap.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/simulator.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;
using fgcal::test::nees;
using fgcal::test::translationGapMm;

namespace {

constexpr double kChi2_6_999 = 22.4577;
constexpr double kReadoutMs = 25.0;
const std::string kRolling = "xtion_rgb";

const CameraResult& camera(const CalibrationOutput& out, const std::string& name) {
  for (const CameraResult& c : out.cameras)
    if (c.name == name) return c;
  FAIL("no camera " << name);
  return out.cameras.front();
}

}  // namespace

TEST_CASE("rolling shutter: the readout is estimated at corner level, held from rig.yaml, or refused when too long",
          "[apps][e2e][rolling-shutter]") {
  TempDir tmp;
  const fs::path data = tmp.path() / "sim";
  SimulationOptions sim;
  sim.out_dir = data.string();
  sim.frames = 120;
  sim.seed = 3;
  // No exposure: its blur costs the simulation 5x (test_simulator_effects has it).
  sim.readout_ms[kRolling] = kReadoutMs;
  simulateDataset(sim);
  const GroundTruth truth = loadGroundTruth((data / "ground_truth.yaml").string());
  REQUIRE(truth.readout_ms.at(kRolling) == kReadoutMs);

  const auto calibrate = [&](const std::string& name, const std::string& extra, int expected_exit = 0) {
    const fs::path out = tmp.path() / (name + ".yaml");
    const CliRun r = runCommand(FGCAL_EXE, "calibrate " + quoted(data.string()) + " -o " + quoted(out.string()) +
                                               " --method corners" + extra, tmp.path());
    INFO(r.command << "\nstderr:\n" << r.err);
    REQUIRE(r.exit_code == expected_exit);
    return std::make_pair(expected_exit == 0 ? loadCalibrationYaml(out.string()) : CalibrationOutput(), r.out + r.err);
  };
  const auto [offset_only, offset_log] = calibrate("offset", " --no-report --estimate time-offset");
  const auto [estimated, log] = calibrate("rolling", " --report " + quoted((tmp.path() / "report").string()) +
                                                         " --estimate time-offset,rolling-shutter");
  const SE3& T = truth.T_base_cam.at(kRolling);
  const CameraResult& a = camera(offset_only, kRolling);
  const CameraResult& b = camera(estimated, kRolling);
  INFO(kRolling << ": " << translationGapMm(T, a.T_base_cam) << " mm, NEES " << nees(T, a.T_base_cam, a.covariance)
                << " with a time offset alone; " << translationGapMm(T, b.T_base_cam) << " mm, NEES "
                << nees(T, b.T_base_cam, b.covariance) << " with the readout");
  REQUIRE(b.readout_ms);
  REQUIRE(b.readout_sigma_ms);
  CHECK(b.readout_observed);
  CHECK(std::abs(*b.readout_ms - kReadoutMs) < 3.0 * *b.readout_sigma_ms);
  CHECK(*b.readout_sigma_ms < 2.0);
  CHECK(std::abs(*b.time_offset_ms) < 3.0 * *b.time_offset_sigma_ms + 0.5);  // the first row is at the stamp
  // The global-shutter camera's readout is estimated too, and comes out near 0.
  const CameraResult& g = camera(estimated, "multisense_left");
  REQUIRE(g.readout_ms);
  CHECK(std::abs(*g.readout_ms) < 3.0 * *g.readout_sigma_ms + 0.5);
  CHECK(translationGapMm(T, b.T_base_cam) < 0.6);
  CHECK(nees(T, b.T_base_cam, b.covariance) < kChi2_6_999);
  CHECK(nees(T, b.T_base_cam, b.covariance) < nees(T, a.T_base_cam, a.covariance));
  // Unmodelled, the quality block names the readout with the command that estimates it; modelled, it does not.
  const auto flagged = [&](const CalibrationOutput& out) {
    for (const Finding& f : out.quality.findings)
      if (f.check == "rolling_shutter")
        return f.fields == std::vector<std::string>{"cameras[" + kRolling + "].readout_ms"} &&
               f.command.find("rolling-shutter") != std::string::npos;
    return false;
  };
  CHECK(flagged(offset_only));
  CHECK_FALSE(flagged(estimated));
  CHECK(log.find("rolling-shutter readout " + kRolling) != std::string::npos);
  CHECK(fgcal::test::readFile(tmp.path() / "report" / "index.html").find("rolling-shutter readout") !=
        std::string::npos);

  // rig.yaml's readout (a datasheet's), held: written back without a sigma.
  std::string rig = fgcal::test::readFile(data / "rig.yaml");
  const std::string anchor = "  - name: " + kRolling + "\n";
  REQUIRE(rig.find(anchor) != std::string::npos);
  const fs::path held_rig = data / "rig_readout.yaml";  // beside robot.urdf, which it names relatively
  std::ofstream(held_rig) << std::regex_replace(rig, std::regex(anchor), anchor + "    readout_ms: 25\n");
  const auto [held, held_log] =
      calibrate("held", " --no-report --rig " + quoted(held_rig.string()) + " --estimate time-offset");
  const CameraResult& h = camera(held, kRolling);
  REQUIRE(h.readout_ms);
  CHECK(*h.readout_ms == 25.0);
  CHECK_FALSE(h.readout_sigma_ms);
  CHECK(translationGapMm(T, h.T_base_cam) < 0.6);
  CHECK(nees(T, h.T_base_cam, h.covariance) < kChi2_6_999);

  // Longer than the frame period: the simulated images come tens of ms apart.
  const fs::path long_rig = data / "rig_long.yaml";
  std::ofstream(long_rig) << std::regex_replace(rig, std::regex(anchor), anchor + "    readout_ms: 400\n");
  const auto [none, long_log] = calibrate("long", " --no-report --rig " + quoted(long_rig.string()), 2);
  INFO(long_log);
  CHECK(long_log.find("cameras[" + kRolling + "].readout_ms") != std::string::npos);
  CHECK(long_log.find("frame period") != std::string::npos);
  CHECK_FALSE(fs::exists(tmp.path() / "long.yaml"));
}
