// End to end: `fgcal simulate` -> `fgcal calibrate` -> `fgcal evaluate`.
// 1. The promised accuracy on the default simulation: F2 within 1 mm / 0.1 deg of
//    the truth (cameras and mount), a fixed wrong CAD mount biases at least one
//    camera beyond that, F2 no worse than F1, the outputs are written and load.
// 2. Real robots' URDFs (ANYmal C, Unitree A1): calibration within 2 mm / 0.2 deg.
// 3. The fgcal command: exit codes (docs/design.md, Errors), the file/field named
//    on stderr, no partial or clobbered output, the evaluate table.
// Every dataset is simulated once per test case, in a temp folder removed at the end.
#include <catch2/catch.hpp>


#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "apps_test_util.hpp"
#include "cli_test_util.hpp"
#include "fgcal/apps/calibrate.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/evaluate.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/simulator.hpp"
#include "fgcal_test/shared_data.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {

bool within(const PoseError& e, double mm, double deg) { return e.translation_mm <= mm && e.rotation_deg <= deg; }

std::string describe(const PoseError& e) {
  std::ostringstream s;
  s << e.translation_mm << " mm, " << e.rotation_deg << " deg (x/y/z " << e.x_mm << "/" << e.y_mm << "/" << e.z_mm
    << " mm, NEES " << e.nees << ")";
  return s.str();
}

std::string describe(const Evaluation& ev) {
  std::ostringstream s;
  for (const auto& [name, e] : ev.cameras) s << "  " << name << ": " << describe(e) << "\n";
  if (ev.mount) s << "  mount: " << describe(*ev.mount) << "\n";
  return s.str();
}

double sumTranslationMm(const Evaluation& ev) {
  double s = 0.0;
  for (const auto& [name, e] : ev.cameras) s += e.translation_mm;
  return s;
}

double sumRotationDeg(const Evaluation& ev) {
  double s = 0.0;
  for (const auto& [name, e] : ev.cameras) s += e.rotation_deg;
  return s;
}

// ---- CLI helpers -------------------------------------------------------------

/// Runs FGCAL_EXE with `args` (already quoted), stdout and stderr captured.
CliRun runFgcal(const std::string& args, const fs::path& scratch) {
  return runCommand(FGCAL_EXE, args, scratch);
}

void copyDataset(const fs::path& from, const fs::path& to) {
  fs::copy(from, to, fs::copy_options::recursive);
  REQUIRE(fs::is_regular_file(to / "rig.yaml"));
}

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> f;
  std::stringstream ss(line);
  std::string item;
  while (std::getline(ss, item, ',')) f.push_back(item);
  return f;
}

std::string joinCsv(const std::vector<std::string>& f) {
  std::string s;
  for (std::size_t i = 0; i < f.size(); ++i) s += (i ? "," : "") + f[i];
  return s;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string l;
  while (std::getline(ss, l))
    if (!l.empty()) out.push_back(l);
  return out;
}

}  // namespace

// -----------------------------------------------------------------------------
TEST_CASE("e2e: the default simulation calibrates within 1 mm / 0.1 deg (F2, fixed mount, F1, outputs)",
          "[apps][e2e][calibrate][accuracy]") {
  TempDir tmp;
  SimulationOptions sim;
  sim.out_dir = tmp / "ds";
  sim.frames = 300;
  sim.pixel_noise = 0.5;
  sim.encoder_noise = 0.002;
  sim.mount_error_m = 0.003;
  sim.mount_error_rad = 1.0 * M_PI / 180.0;
  sim.seed = 1;
  const SimulationSummary s = simulateDataset(sim);
  REQUIRE(s.cameras.size() == 2);
  const GroundTruth truth = loadGroundTruth(sim.out_dir + "/ground_truth.yaml");
  REQUIRE(truth.T_link_marker.has_value());
  REQUIRE(truth.T_base_cam.size() == 2);

  std::ostringstream log;

  // F2, the default: every camera and the mount within 1 mm / 0.1 deg.
  CalibrateOptions f2;
  f2.dataset = sim.out_dir;
  f2.output = tmp / "out/calibration.yaml";
  fs::create_directories(tmp.path() / "out");
  const CalibrateResult r2 = runCalibrate(f2, log);
  const Evaluation e2 = evaluate(r2.output, truth);
  INFO("F2 errors:\n" << describe(e2));
  REQUIRE(e2.cameras.size() == 2);
  for (const auto& [name, e] : e2.cameras) {
    INFO("F2 camera " << name << ": " << describe(e) << " (limit 1 mm, 0.1 deg)");
    CHECK(e.translation_mm <= 1.0);
    CHECK(e.rotation_deg <= 0.1);
  }
  REQUIRE(e2.mount.has_value());
  {
    INFO("F2 board mount: " << describe(*e2.mount) << " (limit 1 mm, 0.1 deg)");
    CHECK(r2.output.mount.estimated);
    CHECK(e2.mount->translation_mm <= 1.0);
    CHECK(e2.mount->rotation_deg <= 0.1);
  }

  // Outputs: calibration.yaml and the URDF snippet beside it; the yaml reads back with every camera.
  {
    INFO("yaml " << r2.yaml_path << ", urdf " << r2.urdf_path);
    CHECK(r2.yaml_path == f2.output);
    CHECK(r2.urdf_path == (tmp / "out/calibration.urdf.xml"));
    REQUIRE(fs::is_regular_file(r2.yaml_path));
    REQUIRE(fs::is_regular_file(r2.urdf_path));
    const std::string urdf = readFile(r2.urdf_path);
    const CalibrationOutput loaded = loadCalibrationYaml(r2.yaml_path);
    REQUIRE(loaded.cameras.size() == truth.T_base_cam.size());
    for (const auto& [name, T] : truth.T_base_cam) {
      INFO("camera " << name);
      const auto it = std::find_if(loaded.cameras.begin(), loaded.cameras.end(),
                                   [&](const CameraResult& c) { return c.name == name; });
      REQUIRE(it != loaded.cameras.end());
      const auto in_mem = std::find_if(r2.output.cameras.begin(), r2.output.cameras.end(),
                                       [&](const CameraResult& c) { return c.name == name; });
      REQUIRE(in_mem != r2.output.cameras.end());
      CHECK(in_mem->T_base_cam.minus(it->T_base_cam).norm() < 1e-9);  // the file holds what was computed
      CHECK(it->images_used == in_mem->images_used);
      CHECK(urdf.find(name) != std::string::npos);
    }
    CHECK(urdf.find("<joint") != std::string::npos);
    CHECK(urdf.find("type=\"fixed\"") != std::string::npos);
    // The file evaluates like the in-memory result.
    const Evaluation e_file = evaluate(loaded, truth);
    for (const auto& [name, e] : e2.cameras) CHECK(e_file.cameras.at(name).translation_mm == Approx(e.translation_mm).margin(1e-6));
    // The report beside them, and no temporary file.
    CHECK(r2.report_path == (tmp.path() / "out/calibration_report/index.html").string());
    CHECK(fs::is_regular_file(r2.report_path));
    int files = 0;
    for (const auto& entry : fs::directory_iterator(tmp.path() / "out")) {
      INFO("output folder holds " << entry.path());
      ++files;
    }
    CHECK(files == 3);
  }

  // The wrong CAD mount held fixed biases the cameras: at least one is outside 1 mm / 0.1 deg.
  CalibrateOptions fixed = f2;
  fixed.fix_mount = true;
  fixed.write_files = false;
  const CalibrateResult rf = runCalibrate(fixed, log);
  const Evaluation ef = evaluate(rf.output, truth);
  {
    INFO("fixed (wrong, 3 mm / 1 deg off) mount errors:\n" << describe(ef));
    CHECK_FALSE(rf.output.mount.estimated);
    const bool any_outside = std::any_of(ef.cameras.begin(), ef.cameras.end(),
                                         [](const auto& kv) { return !within(kv.second, 1.0, 0.1); });
    CHECK(any_outside);
  }

  // F1: each camera alone. F2 shares the board pose between the cameras and must be no worse.
  CalibrateOptions f1 = f2;
  f1.single_camera = true;
  f1.write_files = false;
  const CalibrateResult r1 = runCalibrate(f1, log);
  const Evaluation e1 = evaluate(r1.output, truth);
  {
    INFO("F1 errors:\n" << describe(e1) << "F2 errors:\n" << describe(e2));
    const auto solve = [](const CalibrationOutput& out) {
      for (const auto& [k, v] : out.info)
        if (k == "solve") return v.substr(0, 2);
      return std::string("?");
    };
    CHECK(r1.output.method == "pnp");
    CHECK(solve(r1.output) == "F1");
    CHECK(solve(r2.output) == "F2");
    const double t1 = sumTranslationMm(e1), t2 = sumTranslationMm(e2);
    const double a1 = sumRotationDeg(e1), a2 = sumRotationDeg(e2);
    INFO("sum of camera translation errors: F1 " << t1 << " mm, F2 " << t2 << " mm; rotation: F1 " << a1
                                                 << " deg, F2 " << a2 << " deg");
    CHECK(t2 <= 1.05 * t1);
    CHECK(a2 <= 1.05 * a1);
    WARN("default simulation: F2 total " << t2 << " mm / " << a2 << " deg, F1 total " << t1 << " mm / " << a1
                               << " deg, fixed mount worst " << std::max_element(ef.cameras.begin(), ef.cameras.end(), [](const auto& a, const auto& b) { return a.second.translation_mm < b.second.translation_mm; })->second.translation_mm
                               << " mm");
  }
  // The corner method on the same images: the same promise, and its
  // covariance honest (NEES within the chi-square(6) 99.9 % point).
  CalibrateOptions fc = f2;
  fc.method = Method::Corners;
  fc.write_files = false;
  const CalibrateResult rc = runCalibrate(fc, log);
  const Evaluation ec = evaluate(rc.output, truth);
  {
    INFO("corners errors:\n" << describe(ec) << "F2 (pnp) errors:\n" << describe(e2));
    CHECK(rc.output.method == "corners");
    for (const auto& [name, e] : ec.cameras) {
      INFO("corners camera " << name << ": " << describe(e));
      CHECK(within(e, 1.0, 0.1));
      CHECK(e.nees < 22.46);
    }
    REQUIRE(ec.mount.has_value());
    CHECK(within(*ec.mount, 1.0, 0.1));
    CHECK(rc.solution.solve_labels.front().find("PnP start") == 0);
  }

}

// -----------------------------------------------------------------------------
TEST_CASE("e2e: real robots' URDFs (ANYmal C, Unitree A1) calibrate within 2 mm / 0.2 deg",
          "[apps][e2e][calibrate][shared_data][accuracy]") {
  FGCAL_REQUIRE_SHARED_DATA(urdf_dir, "urdf");
  struct Robot {
    const char* file;
    const char* base;
    const char* foot;
  };
  for (const Robot& r : {Robot{"anymal_c.urdf", "base", "LF_FOOT"}, Robot{"a1.urdf", "trunk", "FL_foot"}}) {
    INFO(r.file << ": " << r.base << " -> " << r.foot);
    TempDir tmp;
    SimulationOptions sim;
    sim.urdf_path = urdf_dir + "/" + r.file;
    sim.base_link = r.base;
    sim.marker_link = r.foot;
    sim.frames = 120;
    sim.mount_error_m = 0.003;
    sim.mount_error_rad = 1.0 * M_PI / 180.0;
    sim.out_dir = tmp / "ds";
    simulateDataset(sim);
    const GroundTruth truth = loadGroundTruth(sim.out_dir + "/ground_truth.yaml");

    CalibrateOptions opt;
    opt.dataset = sim.out_dir;
    opt.output = tmp / "calibration.yaml";
    std::ostringstream log;
    CalibrateResult res;
    try {
      res = runCalibrate(opt, log);
    } catch (const std::exception& e) {
      FAIL("calibrate failed on " << r.file << ": " << e.what() << "\nlog:\n" << log.str());
    }
    const Evaluation ev = evaluate(res.output, truth);
    INFO("errors:\n" << describe(ev));
    REQUIRE(ev.cameras.size() == truth.T_base_cam.size());
    for (const auto& [name, e] : ev.cameras) {
      INFO("camera " << name << ": " << describe(e) << " (limit 2 mm, 0.2 deg)");
      CHECK(e.translation_mm <= 2.0);
      CHECK(e.rotation_deg <= 0.2);
    }
    CHECK(fs::is_regular_file(opt.output));
    WARN(r.file << ":\n" << describe(ev));
  }
}

// -----------------------------------------------------------------------------
TEST_CASE("e2e: the fgcal command's exit codes, messages and outputs", "[apps][e2e][cli]") {
  TempDir tmp;
  const fs::path base = tmp.path() / "base";
  {
    SimulationOptions sim;
    sim.out_dir = base.string();
    sim.frames = 40;
    sim.supersampling = 2;
    sim.mount_error_m = 0.003;
    sim.mount_error_rad = 1.0 * M_PI / 180.0;
    simulateDataset(sim);
  }
  const fs::path scratch = tmp.path() / "scratch";
  fs::create_directories(scratch);
  auto fresh = [&](const std::string& name) {
    const fs::path d = tmp.path() / name;
    copyDataset(base, d);
    return d;
  };

  {  // one case; sections would re-run the simulation
    INFO("case: success, then evaluate prints a table with every camera");
    const fs::path out = tmp.path() / "ok.yaml";
    const CliRun cal = runFgcal("calibrate " + quoted(base.string()) + " -o " + quoted(out.string()), scratch);
    INFO(cal.command << "\nstderr:\n" << cal.err);
    CHECK(cal.exit_code == 0);
    CHECK(fs::is_regular_file(out));
    CHECK(fs::is_regular_file(tmp.path() / "ok.urdf.xml"));
    CHECK_THAT(cal.err, Catch::Contains("wrote"));
    const CliRun ev =
        runFgcal("evaluate " + quoted(out.string()) + " " + quoted((base / "ground_truth.yaml").string()), scratch);
    INFO(ev.command << "\nstdout:\n" << ev.out << "\nstderr:\n" << ev.err);
    CHECK(ev.exit_code == 0);
    for (const auto& [name, T] : loadGroundTruth((base / "ground_truth.yaml").string()).T_base_cam) {
      INFO("camera " << name);
      CHECK(ev.out.find(name) != std::string::npos);
    }
  }

  {  // one case; sections would re-run the simulation
    INFO("case: a missing dataset folder: exit 2 naming it");
    const std::string missing = (tmp.path() / "no_such_dataset").string();
    const CliRun r = runFgcal("calibrate " + quoted(missing) + " -o " + quoted(tmp / "x.yaml"), scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains(missing));
    CHECK_FALSE(fs::exists(tmp / "x.yaml"));
  }

  {  // one case; sections would re-run the simulation
    INFO("case: a bad dictionary in rig.yaml: exit 2 naming rig.yaml and the field");
    const fs::path d = fresh("bad_dict");
    writeFile((d / "rig.yaml").string(), replaced(readFile((d / "rig.yaml").string()), "DICT_4X4_50", "DICT_NOPE"));
    const CliRun r = runFgcal("calibrate " + quoted(d.string()) + " -o " + quoted(tmp / "x.yaml"), scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("rig.yaml"));
    CHECK_THAT(r.err, Catch::Contains("dictionary"));
    CHECK_THAT(r.err, Catch::Contains("DICT_NOPE"));
    CHECK_FALSE(fs::exists(tmp / "x.yaml"));
  }

  {  // one case; sections would re-run the simulation
    INFO("case: --pnp-covariance-scale reaches the solve: recorded in info, every covariance larger than the default's");
    const fs::path out = tmp.path() / "scale2.yaml";
    const CliRun r = runFgcal("calibrate " + quoted(base.string()) + " -o " + quoted(out.string()) +
                                  " --pnp-covariance-scale 2 --no-report",
                              scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    REQUIRE(r.exit_code == 0);
    const CalibrationOutput two = loadCalibrationYaml(out.string());
    const CalibrationOutput dflt = loadCalibrationYaml((tmp.path() / "ok.yaml").string());
    std::map<std::string, std::string> info(two.info.begin(), two.info.end());
    CHECK(info["pnp_covariance_scale"] == "2.000000");
    REQUIRE(two.cameras.size() == dflt.cameras.size());
    for (std::size_t c = 0; c < two.cameras.size(); ++c) {
      INFO("camera " << two.cameras[c].name);
      const double ratio = two.cameras[c].covariance.trace() / dflt.cameras[c].covariance.trace();
      CHECK(ratio > 1.05);  // less weight on the images (2 against the default) ...
      CHECK(ratio < 2.0 / kDefaultFiducialCovarianceScale);  // ... but the kinematics keep theirs
    }
  }

  {  // one case; sections would re-run the simulation
    INFO("case: --method corners with intrinsics estimated: calibration.yaml says so and holds them");
    const fs::path out = tmp.path() / "corners.yaml";
    const CliRun r = runFgcal("calibrate " + quoted(base.string()) + " -o " + quoted(out.string()) +
                                  " --method corners --estimate intrinsics --no-report",
                              scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 0);
    const CalibrationOutput back = loadCalibrationYaml(out.string());
    CHECK(back.method == "corners");
    CHECK(back.estimated == std::vector<std::string>{"intrinsics"});
    for (const CameraResult& c : back.cameras) {
      INFO("camera " << c.name);
      CHECK(c.intrinsics.size() == 4);
      CHECK(c.intrinsics_sigma.size() == 4);
      CHECK(c.distortion_coeffs.size() == c.distortion_coeffs_sigma.size());
    }
    // rig.yaml has no intrinsics_sigma: the default prior, said in a warning naming the field.
    CHECK_THAT(r.err, Catch::Contains("intrinsics_sigma") && Catch::Contains("default"));
    CHECK_THAT(r.err, Catch::Contains("Calibration (corners, F2"));
  }

  {  // one case; sections would re-run the simulation
    INFO("case: --estimate intrinsics without --method selects corners; with --method pnp it is exit 2 saying why");
    const fs::path out = tmp.path() / "implied.yaml";
    const CliRun r = runFgcal("calibrate " + quoted(base.string()) + " -o " + quoted(out.string()) +
                                  " --estimate intrinsics --no-report",
                              scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 0);
    CHECK(loadCalibrationYaml(out.string()).method == "corners");
    const CliRun bad = runFgcal("calibrate " + quoted(base.string()) + " -o " + quoted(tmp / "x.yaml") +
                                    " --method pnp --estimate intrinsics",
                                scratch);
    INFO(bad.command << "\nstderr:\n" << bad.err);
    CHECK(bad.exit_code == 2);
    CHECK_THAT(bad.err, Catch::Contains("--estimate") && Catch::Contains("--method corners") &&
                            Catch::Contains("focal length"));
    CHECK_FALSE(fs::exists(tmp / "x.yaml"));
  }

  {  // one case; sections would re-run the simulation
    INFO("case: an unknown --method or --estimate name: exit 2 listing the valid ones");
    const CliRun m = runFgcal("calibrate " + quoted(base.string()) + " -o " + quoted(tmp / "x.yaml") +
                                  " --method bundle",
                              scratch);
    INFO(m.command << "\nstderr:\n" << m.err);
    CHECK(m.exit_code == 2);
    CHECK_THAT(m.err, Catch::Contains("--method") && Catch::Contains("pnp") && Catch::Contains("corners"));
    const CliRun e = runFgcal("calibrate " + quoted(base.string()) + " -o " + quoted(tmp / "x.yaml") +
                                  " --estimate intrinsics,focal",
                              scratch);
    INFO(e.command << "\nstderr:\n" << e.err);
    CHECK(e.exit_code == 2);
    CHECK_THAT(e.err, Catch::Contains("'focal'") && Catch::Contains("time-offset") &&
                          Catch::Contains("joint-offsets") && Catch::Contains("intrinsics"));
    CHECK_FALSE(fs::exists(tmp / "x.yaml"));
  }

  {  // one case; sections would re-run the simulation
    INFO("case: a PnP covariance scale below 1: exit 2 naming the option, nothing written");
    const CliRun r = runFgcal("calibrate " + quoted(base.string()) + " -o " + quoted(tmp / "x.yaml") +
                                  " --pnp-covariance-scale 0.5",
                              scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("--pnp-covariance-scale"));
    CHECK_THAT(r.err, Catch::Contains(">= 1"));
    CHECK_FALSE(fs::exists(tmp / "x.yaml"));
  }

  {  // one case; sections would re-run the simulation
    INFO("case: an output path in a folder that does not exist: exit 2 naming the folder, nothing created");
    const fs::path missing_dir = tmp.path() / "no_such_out_dir";
    const fs::path out = missing_dir / "calibration.yaml";
    const CliRun r = runFgcal("calibrate " + quoted(base.string()) + " -o " + quoted(out.string()), scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains(missing_dir.string()));
    CHECK_THAT(r.err, Catch::Contains("-o: the output folder"));
    CHECK_THAT(r.err, Catch::Contains("create it first"));  // as --urdf-out and init say it
    CHECK_FALSE(fs::exists(missing_dir));
    CHECK_FALSE(fs::exists(out));
  }

  {  // one case; sections would re-run the simulation
    INFO("case: joints.csv without a chain joint's column: exit 2 naming the column");
    const fs::path d = fresh("no_kfe");
    const auto ls = lines(readFile((d / "joints.csv").string()));
    REQUIRE(ls.size() > 2);
    const auto header = splitCsv(ls[0]);
    const auto col = std::find(header.begin(), header.end(), "lf_kfe_joint");
    REQUIRE(col != header.end());
    const auto k = static_cast<std::size_t>(col - header.begin());
    std::string text;
    for (const auto& l : ls) {
      auto f = splitCsv(l);
      REQUIRE(f.size() == header.size());
      f.erase(f.begin() + static_cast<std::ptrdiff_t>(k));
      text += joinCsv(f) + "\n";
    }
    writeFile((d / "joints.csv").string(), text);
    const CliRun r = runFgcal("calibrate " + quoted(d.string()) + " -o " + quoted(tmp / "x.yaml"), scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains("joints.csv"));
    CHECK_THAT(r.err, Catch::Contains("lf_kfe_joint"));
    CHECK_FALSE(fs::exists(tmp / "x.yaml"));
  }

  {  // one case; sections would re-run the simulation
    INFO("case: a camera folder with every image deleted: exit 2 naming the folder");
    const fs::path d = fresh("empty_cam");
    const auto cams = loadGroundTruth((d / "ground_truth.yaml").string()).T_base_cam;
    REQUIRE(cams.size() == 2);
    const std::string cam = std::prev(cams.end())->first;
    const fs::path folder = d / cam;
    REQUIRE(fs::is_directory(folder));
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(folder)) files.push_back(e.path());
    REQUIRE(!files.empty());
    for (const auto& f : files) fs::remove(f);
    const CliRun r = runFgcal("calibrate " + quoted(d.string()) + " -o " + quoted(tmp / "x.yaml"), scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 2);
    CHECK_THAT(r.err, Catch::Contains(folder.string()));
    CHECK_FALSE(fs::exists(tmp / "x.yaml"));
  }

  {  // one case; sections would re-run the simulation
    INFO("case: degenerate motion (every joints.csv row identical): exit 1 saying so; an existing output is kept");
    const fs::path d = fresh("degenerate");
    const auto ls = lines(readFile((d / "joints.csv").string()));
    REQUIRE(ls.size() > 2);
    const auto first = splitCsv(ls[1]);
    std::string text = ls[0] + "\n";
    for (std::size_t i = 1; i < ls.size(); ++i) {
      auto f = splitCsv(ls[i]);
      REQUIRE(f.size() == first.size());
      for (std::size_t j = 1; j < f.size(); ++j) f[j] = first[j];  // keep the stamp, freeze the joints
      text += joinCsv(f) + "\n";
    }
    writeFile((d / "joints.csv").string(), text);
    const std::string out = tmp / "existing.yaml";
    writeFile(out, "sentinel");
    const CliRun r = runFgcal("calibrate " + quoted(d.string()) + " -o " + quoted(out), scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 1);
    CHECK_THAT(r.err, Catch::Contains("degenerate"));
    CHECK(readFile(out) == "sentinel");
    CHECK_FALSE(fs::exists(tmp / "existing.urdf.xml"));
    // No temporary file left beside it either.
    int entries = 0;
    for (const auto& e : fs::directory_iterator(tmp.path()))
      if (e.path().filename().string().rfind("existing", 0) == 0) ++entries;
    CHECK(entries == 1);
  }

  {  // one case; sections would re-run the simulation
    INFO("case: an existing output survives an input error too");
    const std::string out = tmp / "existing2.yaml";
    writeFile(out, "sentinel");
    const CliRun r =
        runFgcal("calibrate " + quoted((tmp.path() / "no_such_dataset").string()) + " -o " + quoted(out), scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 2);
    CHECK(readFile(out) == "sentinel");
  }

  {  // one case; sections would re-run the simulation
    INFO("case: an unknown subcommand: exit 2");
    const CliRun r = runFgcal("frobnicate", scratch);
    INFO(r.command << "\nstderr:\n" << r.err);
    CHECK(r.exit_code == 2);
    const CliRun none = runFgcal("", scratch);
    INFO(none.command << "\nstderr:\n" << none.err);
    CHECK(none.exit_code == 2);
  }
}

TEST_CASE("e2e: unusable frames are skipped and counted, not fatal", "[apps][e2e]") {
  TempDir tmp;
  const fs::path d = tmp.path() / "ds";
  SimulationOptions sim;
  sim.out_dir = d.string();
  sim.frames = 40;
  sim.supersampling = 2;
  simulateDataset(sim);

  std::vector<fs::path> cam0;
  for (const auto& e : fs::directory_iterator(d / "multisense_left")) cam0.push_back(e.path());
  std::sort(cam0.begin(), cam0.end());
  REQUIRE(cam0.size() >= 10);
  // One image replaced by text, one truncated to a third of its bytes.
  { std::ofstream(cam0[3], std::ios::trunc) << "not a png"; }
  fs::resize_file(cam0[5], fs::file_size(cam0[5]) / 3);
  // A NaN reading of a leg joint at the sample of another image (cam0 is on the joint clock).
  const std::string stamp = cam0[7].stem().string();
  std::string csv = readTextFile((d / "joints.csv").string());
  std::vector<std::string> rows = lines(csv);
  const auto header = splitCsv(rows[0]);
  const auto col = std::find(header.begin(), header.end(), "lf_kfe_joint") - header.begin();
  REQUIRE(col < static_cast<long>(header.size()));
  bool replaced = false;
  for (auto& row : rows) {
    auto f = splitCsv(row);
    if (!f.empty() && f[0] == stamp) {
      f[static_cast<std::size_t>(col)] = "nan";
      row = joinCsv(f);
      replaced = true;
    }
  }
  REQUIRE(replaced);
  std::string out;
  for (const auto& row : rows) out += row + "\n";
  writeFileAtomically((d / "joints.csv").string(), out);

  CalibrateOptions c;
  c.dataset = d.string();
  c.output = (tmp.path() / "cal.yaml").string();
  std::ostringstream log;
  const CalibrateResult r = runCalibrate(c, log);
  INFO(log.str());
  const auto cam = std::find_if(r.output.cameras.begin(), r.output.cameras.end(),
                                [](const CameraResult& cr) { return cr.name == "multisense_left"; });
  REQUIRE(cam != r.output.cameras.end());
  auto count = [&](const std::string& reason) {
    const auto it = cam->images_skipped.find(reason);
    return it == cam->images_skipped.end() ? 0 : it->second;
  };
  CHECK(count("unreadable image") >= 1);                           // the text file at least
  CHECK(count("unreadable image") + count("no board") + count("too few corners") >= 2);  // and the truncated one
  CHECK(count("invalid joint values") >= 1);
  int skipped = 0;
  for (const auto& [reason, k] : cam->images_skipped) skipped += k;
  CHECK(cam->images_used + skipped == static_cast<int>(cam0.size()));
  CHECK(r.summary.find("unreadable image") != std::string::npos);
  CHECK(r.summary.find("invalid joint values") != std::string::npos);
  // Each warning once.
  for (std::size_t i = 0; i < r.warnings.size(); ++i)
    for (std::size_t k = i + 1; k < r.warnings.size(); ++k) CHECK(r.warnings[i] != r.warnings[k]);
  // The calibration itself goes on: 40 instants give a few mm, and the
  // reported covariance says so (NEES within chi-square(6) 99.9 %).
  const Evaluation ev = evaluate(r.output, loadGroundTruth((d / "ground_truth.yaml").string()));
  REQUIRE(ev.cameras.size() == 2);
  for (const auto& [name, e] : ev.cameras) {
    INFO(name << " " << describe(e));
    CHECK(within(e, 10.0, 1.0));
    CHECK(e.nees < 22.46);
  }
}
