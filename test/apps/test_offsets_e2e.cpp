// Time offsets and joint zero offsets through the real fgcal command: what
// calibration.yaml, the summary and the report say, and every bad input of
// theirs answered with exit code 2 naming the field (the prior's sigma in
// rig.yaml, a time offset past the joint log, an unknown --estimate name).

#include <cstdlib>
#include <sstream>

#include "apps_test_util.hpp"
#include "cli_test_util.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/simulator.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {

CliRun runFgcal(const std::string& args, const fs::path& scratch) {
  return runCommand(FGCAL_EXE, args, scratch);
}

fs::path copyOf(const fs::path& base, const fs::path& to) {
  fs::copy(base, to, fs::copy_options::recursive);
  return to;
}

/// Every line of `text` but those after the first whose stamp exceeds `last_ns`.
std::string cutJoints(const std::string& text, std::int64_t last_ns) {
  std::stringstream in(text);
  std::string line, out;
  std::getline(in, line);
  out = line + "\n";
  while (std::getline(in, line)) {
    if (std::stoll(line.substr(0, line.find(','))) > last_ns) break;
    out += line + "\n";
  }
  return out;
}

}  // namespace

TEST_CASE("offsets e2e: calibration.yaml, the summary and the report say what was estimated and observed",
          "[apps][e2e][offsets]") {
  TempDir tmp;
  const fs::path base = tmp.path() / "base";
  SimulationOptions sim;
  sim.out_dir = base.string();
  sim.frames = 60;
  sim.supersampling = 2;
  simulateDataset(sim);
  const fs::path scratch = tmp.path() / "scratch";
  fs::create_directories(scratch);

  {
    INFO("case: both estimated: exit 0, every key written, the unobserved offsets warned about by name");
    const fs::path out = tmp.path() / "both.yaml";
    const CliRun r = runFgcal("calibrate " + quoted(base.string()) + " -o " + quoted(out.string()) +
                                  " --estimate time-offset,joint-offsets",
                              scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    REQUIRE(r.exit_code == 0);
    const CalibrationOutput cal = loadCalibrationYaml(out.string());
    for (const CameraResult& c : cal.cameras) {
      INFO("camera " << c.name);
      REQUIRE(c.time_offset_ms);
      CHECK(std::abs(*c.time_offset_ms) < 1.0);  // no delay was simulated
      CHECK(*c.time_offset_sigma_ms > 0.0);
      CHECK(*c.time_offset_sigma_ms < 0.5);
    }
    REQUIRE(cal.joint_offsets.size() == 3);
    CHECK(cal.joint_offsets[0].joint == "lf_haa_joint");
    CHECK(!cal.joint_offsets[0].observed);
    CHECK(cal.joint_offsets[0].offset_rad == 0.0);   // the prior's, not the solver's near-zero number
    CHECK(cal.joint_offsets[0].sigma_rad == 0.05);   // the documented default prior
    CHECK(cal.joint_offsets[1].observed);
    CHECK(std::abs(cal.joint_offsets[1].offset_rad) < 5 * cal.joint_offsets[1].sigma_rad);
    CHECK(!cal.joint_offsets[2].observed);
    // The warnings name each unobserved joint, its smallest eigenvalue, and what it does to the cameras.
    CHECK_THAT(r.err, Catch::Contains("joint lf_haa_joint's zero offset is not observed"));
    CHECK_THAT(r.err, Catch::Contains("joint lf_kfe_joint's zero offset is not observed"));
    CHECK_THAT(r.err, Catch::Contains("mrad^-2 (its smallest eigenvalue)"));
    CHECK_THAT(r.err, Catch::Contains("per mrad: multisense_left"));
    CHECK_THAT(r.err, Catch::Contains("time offset multisense_left:"));
    // The report: the table of what --estimate added and each camera's time-offset sweep.
    const std::string html = readFile((tmp.path() / "both_report" / "index.html").string());
    CHECK_THAT(html, Catch::Contains("id=\"estimates-table\""));
    CHECK_THAT(html, Catch::Contains("id=\"time-offset-sweep-0\""));
    CHECK_THAT(html, Catch::Contains("id=\"time-offset-sweep-1\""));
    CHECK_THAT(html, Catch::Contains("lf_hfe_joint"));
  }

  for (const auto& [what, value, detail] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"zero", "0", "> 0"}, {"negative", "-0.01", "> 0"}, {"not finite", ".nan", "finite"}}) {
    INFO("case: joint_offset_sigma " << what << ": exit 2 naming the field, nothing written");
    const fs::path d = copyOf(base, tmp.path() / ("sigma_" + what));
    const std::string rig = readFile((d / "rig.yaml").string());
    writeFile((d / "rig.yaml").string(),
              replaced(rig, "  encoder_sigma:", "  joint_offset_sigma: " + value + "\n  encoder_sigma:"));
    const fs::path out = tmp.path() / ("sigma_" + what + ".yaml");
    const CliRun r = runFgcal("calibrate " + quoted(d.string()) + " -o " + quoted(out.string()) +
                                  " --estimate joint-offsets",
                              scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("robot.joint_offset_sigma"));
    CHECK_THAT(r.err, Catch::Contains(detail));
    CHECK(!fs::exists(out));
  }

  {
    INFO("case: a time offset past the joint log's end: exit 2 naming joints.csv and the camera");
    // xtion_rgb's images stamped 15 ms early (renamed): exposed at stamp + 15 ms.
    const fs::path d = copyOf(base, tmp.path() / "late");
    std::int64_t last = 0;
    for (const auto& e : fs::directory_iterator(d / "xtion_rgb")) {
      const std::int64_t stamp = std::stoll(e.path().stem().string()) - 15'000'000;
      fs::rename(e.path(), d / "xtion_rgb" / (std::to_string(stamp) + ".png"));
      last = std::max(last, stamp);
    }
    // The log ends 5 ms after that camera's last image, less than its 15 ms delay.
    writeFile((d / "joints.csv").string(), cutJoints(readFile((d / "joints.csv").string()), last + 5'000'000));
    const fs::path out = tmp.path() / "late.yaml";
    const CliRun r =
        runFgcal("calibrate " + quoted(d.string()) + " -o " + quoted(out.string()) + " --estimate time-offset", scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("joints.csv"));
    CHECK_THAT(r.err, Catch::Contains("time offset of camera xtion_rgb"));
    CHECK_THAT(r.err, Catch::Contains("after the joint log's last sample"));
    CHECK(!fs::exists(out));
  }

  {
    INFO("case: an unknown name in --estimate: exit 2 naming the option and the valid names");
    const CliRun r = runFgcal("calibrate " + quoted(base.string()) + " -o " + quoted(tmp / "x.yaml") +
                                  " --estimate time-offset,zero-offsets",
                              scratch);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("--estimate"));
    CHECK_THAT(r.err, Catch::Contains("joint-offsets"));
  }
}
