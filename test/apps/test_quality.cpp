// The quality verdict (docs/outputs.md, quality): the chi-square
// distribution its thresholds come from, the block in calibration.yaml, and
// set-up mistakes on one simulated dataset, each flagged with the input to
// fix while the correct dataset is not; an unusable result exits 1 and
// writes no calibration output, only the report that says why.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "apps_test_util.hpp"
#include "cli_test_util.hpp"
#include "commands/calibrate/calibrate_stages.hpp"
#include "fgcal/apps/calibrate.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/report.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/apps/simulator.hpp"
#include "quality/chi_square.hpp"
#include "quality/hypotheses.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {

/// One dataset for every case: fgcal's default robot, two cameras, 200 instants.
struct Fixture {
  TempDir tmp;
  std::string dataset;
  GroundTruth truth;
  Fixture() {
    SimulationOptions sim;
    sim.out_dir = tmp / "ds";
    sim.frames = 200;
    sim.seed = 3;
    sim.mount_error_m = 0.003;
    sim.mount_error_rad = 1.0 * M_PI / 180.0;
    simulateDataset(sim);
    dataset = sim.out_dir;
    truth = loadGroundTruth(dataset + "/ground_truth.yaml");
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

/// A copy of the fixture's dataset whose rig.yaml and joints.csv a case may edit.
std::string copyOf(const TempDir& tmp) {
  const fs::path to = tmp.path() / "ds";
  fs::copy(fixture().dataset, to, fs::copy_options::recursive);
  return to.string();
}

CalibrateResult calibrateQuiet(const std::string& dataset, const std::string& output = "") {
  CalibrateOptions o;
  o.dataset = dataset;
  o.output = output;
  o.report = false;
  std::ostringstream log;
  return runCalibrate(o, log);
}

const Finding* findingOf(const Quality& q, const std::string& check) {
  for (const Finding& f : q.findings)
    if (f.check == check) return &f;
  return nullptr;
}

bool names(const Finding& f, const std::string& field) {
  return std::find(f.fields.begin(), f.fields.end(), field) != f.fields.end();
}

std::string describe(const Quality& q) {
  std::ostringstream s;
  s << "verdict " << toString(q.verdict) << "\n";
  for (const Finding& f : q.findings) s << "  " << toString(f.severity) << " " << f.check << ": " << f.message << "\n";
  return s.str();
}

/// joints.csv with one column's values transformed.
void editJointColumn(const std::string& dataset, const std::string& joint, double (*change)(double)) {
  const std::string path = dataset + "/joints.csv";
  std::istringstream in(readFile(path));
  std::string header, line, out;
  std::getline(in, header);
  out = header + "\n";
  int column = -1, k = 0;
  std::stringstream hs(header);
  for (std::string name; std::getline(hs, name, ','); ++k)
    if (name == joint) column = k;
  REQUIRE(column > 0);
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::stringstream ls(line);
    std::string field, row;
    for (int i = 0; std::getline(ls, field, ','); ++i) {
      if (i == column) {
        std::ostringstream v;
        v.precision(17);
        v << change(std::stod(field));
        field = v.str();
      }
      row += (i ? "," : "") + field;
    }
    out += row + "\n";
  }
  writeFile(path, out);
}

/// The dataset's URDF with fgcal's robot's left front thigh (the origin of
/// lf_kfe_joint) 5 mm longer than the leg the images saw.
void lengthenThigh(const std::string& dataset) {
  std::string urdf = readFile(dataset + "/robot.urdf");
  const std::size_t joint = urdf.find("<joint name=\"lf_kfe_joint\"");
  REQUIRE(joint != std::string::npos);
  const std::string from = "<origin xyz=\"0 0 -0.35\"";
  const std::size_t origin = urdf.find(from, joint);
  REQUIRE(origin != std::string::npos);
  urdf.replace(origin, from.size(), "<origin xyz=\"0 0 -0.355\"");
  writeFile(dataset + "/robot.urdf", urdf);
}

}  // namespace

TEST_CASE("chi-square distribution: the points the quality thresholds use", "[apps][quality]") {
  using namespace fgcal::apps::quality;
  CHECK(chiSquareQuantile(0.999, 6) == Approx(22.4577).epsilon(1e-5));   // the gate of kFiducialGate
  CHECK(chiSquareQuantile(0.999, 1) == Approx(10.8276).epsilon(1e-5));
  CHECK(chiSquareQuantile(0.95, 2) == Approx(5.99146).epsilon(1e-5));
  CHECK(chiSquareCdf(2.0, 2) == Approx(1.0 - std::exp(-1.0)).epsilon(1e-12));  // exponential
  // Far in the tail, no cancellation (the regularized upper gamma Q(500, 750)
  // and Q(3, 15), as mpmath computes them to 15 digits).
  CHECK(chiSquareSf(1500.0, 1000.0) == Approx(1.04546403859797e-22).epsilon(1e-9));
  CHECK(chiSquareSf(30.0, 6.0) == Approx(3.93084481844846e-5).epsilon(1e-9));
  for (double dof : {1.0, 6.0, 37.5, 1800.0})
    for (double x : {0.5 * dof, dof, 2.0 * dof}) {
      INFO("dof " << dof << " x " << x);
      CHECK(chiSquareCdf(x, dof) + chiSquareSf(x, dof) == Approx(1.0).epsilon(1e-12));
    }
  for (double dof : {1.0, 6.0, 37.5, 1800.0})
    for (double p : {0.01, 0.5, 0.999}) {
      INFO("dof " << dof << " p " << p);
      CHECK(chiSquareCdf(chiSquareQuantile(p, dof), dof) == Approx(p).epsilon(1e-9));
    }
}

// A test that assumes the rest of the model (the intrinsics' and the sizes'
// score tests) finds what another input's mistake causes: once an earlier
// finding named another input, its own is a note; a finding on the same
// input corroborates it; notes and findings made by the test itself name
// nothing.
TEST_CASE("a score test's finding after another input was named is a note, after the same input stays a check",
          "[apps][quality]") {
  using namespace fgcal::apps::quality;
  auto finding = [](const std::string& check, Severity severity, std::vector<std::string> fields) {
    Finding f;
    f.check = check;
    f.severity = severity;
    f.fields = std::move(fields);
    f.message = check;
    return f;
  };
  const std::string cam0 = "cameras[cam0].intrinsics", cam1 = "cameras[cam1].intrinsics";
  Quality q;
  q.add(finding("pixel_sigma", Severity::Note, {"cameras[cam0].pixel_sigma"}));
  q.add(finding("camera_scale", Severity::Check, {cam0}));
  const std::size_t earlier = q.findings.size();
  addAssumingTheRest(q, finding("intrinsics", Severity::Check, {cam0}), earlier);
  addAssumingTheRest(q, finding("intrinsics", Severity::Check, {cam1}), earlier);
  addAssumingTheRest(q, finding("leg_length", Severity::Check, {"robot.urdf"}), earlier);
  REQUIRE(q.findings.size() == 5);
  CHECK(q.findings[2].severity == Severity::Check);  // the same camera's intrinsics: corroborated
  CHECK(q.findings[3].severity == Severity::Note);   // another camera's
  CHECK(q.findings[3].message.find("camera_scale finding") != std::string::npos);
  CHECK(q.findings[4].severity == Severity::Note);
  CHECK(q.verdict == Verdict::Check);

  Quality alone;  // only notes before, and the test's own findings after
  alone.add(finding("pixel_sigma", Severity::Note, {"cameras[cam0].pixel_sigma"}));
  const std::size_t before = alone.findings.size();
  addAssumingTheRest(alone, finding("intrinsics", Severity::Check, {cam0}), before);
  addAssumingTheRest(alone, finding("intrinsics", Severity::Check, {cam1}), before);
  CHECK(alone.findings[1].severity == Severity::Check);
  CHECK(alone.findings[2].severity == Severity::Check);
  CHECK(namedCause(alone, alone.findings.size(), {"robot.urdf"}) == "intrinsics");
  CHECK(namedCause(alone, before, {"robot.urdf"}).empty());
}

TEST_CASE("calibration.yaml: the quality block comes first and reads back", "[apps][quality]") {
  CalibrationOutput out;
  CameraResult cam;
  cam.name = "cam0";
  out.cameras.push_back(cam);
  out.quality.add({"few_instants", Severity::Note, {}, "too few instants: 40", {}, {}});
  out.quality.add({"board_scale", Severity::Check, {"target.square_size", "target.marker_size"},
                   "the board's squares measure 42.0 mm \"(+-0.1)\"; rig.yaml says 40.0 mm",
                   {{"square_size", "0.042"}, {"marker_size", "0.0315"}},
                   "fgcal calibrate ds --estimate time-offset"});
  REQUIRE(out.quality.verdict == Verdict::Check);
  const std::string text = formatCalibrationYaml(out);
  CHECK(text.find("quality:") < text.find("cameras:"));
  CHECK(text.find("  verdict: check\n") != std::string::npos);
  const CalibrationOutput back = parseCalibrationYaml(text, "calibration.yaml");
  REQUIRE(back.quality.findings.size() == 2);
  CHECK(back.quality.verdict == Verdict::Check);
  const Finding& f = back.quality.findings[1];
  CHECK(f.check == "board_scale");
  CHECK(f.severity == Severity::Check);
  CHECK(f.fields == std::vector<std::string>{"target.square_size", "target.marker_size"});
  CHECK(f.message == out.quality.findings[1].message);
  REQUIRE(f.estimate.size() == 2);
  CHECK(f.estimate[0].first == "square_size");
  CHECK(std::stod(f.estimate[0].second) == 0.042);
  CHECK(f.command == "fgcal calibrate ds --estimate time-offset");
  // Unusable outranks check; a note leaves ok alone.
  Quality q;
  q.add({"few_instants", Severity::Note, {}, "", {}, {}});
  CHECK(q.verdict == Verdict::Ok);
  q.add({"joint_sign", Severity::Unusable, {"joints.csv:lf_hfe_joint"}, "", {}, {}});
  q.add({"mount_prior", Severity::Check, {}, "", {}, {}});
  CHECK(q.verdict == Verdict::Unusable);
  // A bad severity is named.
  const std::string bad = replaced(text, "severity: check", "severity: maybe");
  CHECK_THROWS_WITH(parseCalibrationYaml(bad, "calibration.yaml"),
                    Catch::Contains("calibration.yaml") && Catch::Contains("severity") &&
                        Catch::Contains("note, check or unusable"));
}

TEST_CASE("quality: the correct dataset is ok, and each mistake names its input", "[apps][quality][e2e]") {
  SECTION("correct: no check fires") {
    const CalibrateResult r = calibrateQuiet(fixture().dataset);
    INFO(describe(r.output.quality));
    CHECK(r.output.quality.verdict == Verdict::Ok);
  }
  SECTION("a board entered 5 % too large: board_scale, with the size the data give") {
    TempDir tmp;
    const std::string ds = copyOf(tmp);
    RigConfig cfg = loadRigConfig(ds + "/rig.yaml");
    const double true_square = cfg.target.square_size;
    cfg.target.square_size *= 1.05;
    cfg.target.marker_size *= 1.05;
    writeFile(ds + "/rig.yaml", writeRigConfig(cfg, ds));
    const CalibrateResult r = calibrateQuiet(ds);
    INFO(describe(r.output.quality));
    const Finding* f = findingOf(r.output.quality, "board_scale");
    REQUIRE(f != nullptr);
    CHECK(f->severity == Severity::Check);
    CHECK(names(*f, "target.square_size"));
    REQUIRE(!f->estimate.empty());
    CHECK(std::stod(f->estimate[0].second) == Approx(true_square).epsilon(0.01));
    CHECK(r.output.quality.verdict != Verdict::Ok);
  }
  // A principal point off by a few pixels looks to PnP like a turned
  // camera, which the solution takes up (0.8 deg off here) without a misfit
  // in any family; only the kinematics tell the two apart.
  SECTION("one camera's principal point 8 px off: intrinsics names that camera, with the cx the data give") {
    TempDir tmp;
    const std::string ds = copyOf(tmp);
    RigConfig cfg = loadRigConfig(ds + "/rig.yaml");
    const double true_cx = cfg.cameras[1].intrinsics[2];
    cfg.cameras[1].intrinsics[2] += 8.0;
    writeFile(ds + "/rig.yaml", writeRigConfig(cfg, ds));
    const CalibrateResult r = calibrateQuiet(ds);
    INFO(describe(r.output.quality));
    CHECK(r.output.quality.verdict != Verdict::Ok);
    const Finding* f = findingOf(r.output.quality, "intrinsics");
    REQUIRE(f != nullptr);
    CHECK(f->severity == Severity::Check);
    CHECK(f->fields == std::vector<std::string>{"cameras[" + cfg.cameras[1].name + "].intrinsics"});
    REQUIRE(f->estimate.size() == 1);
    CHECK(f->estimate[0].first == "cx");
    CHECK(std::stod(f->estimate[0].second) == Approx(true_cx).margin(3.0));
  }
  // A thigh 5 mm shorter than the URDF moves the board as a board of another
  // size would; the images still tell the two apart.
  SECTION("the URDF's thigh 5 mm longer than the leg: leg_length names the URDF, with the length the data give") {
    TempDir tmp;
    const std::string ds = copyOf(tmp);
    lengthenThigh(ds);
    const CalibrateResult r = calibrateQuiet(ds);
    INFO(describe(r.output.quality));
    CHECK(r.output.quality.verdict != Verdict::Ok);
    const Finding* f = findingOf(r.output.quality, "leg_length");
    REQUIRE(f != nullptr);
    CHECK(names(*f, "robot.urdf"));
    REQUIRE(!f->estimate.empty());
    CHECK(f->estimate[0].first == "lf_kfe_joint_origin_scale");
    CHECK(std::stod(f->estimate[0].second) == Approx(0.35 / 0.355).margin(0.004));
  }
  // On this dataset the thigh misfits the kinematic family, and the link's
  // refit explains all of it: the misfit is not reported beside it (it was,
  // as kinematic_fit naming encoder_sigma, when only the board's and the
  // cameras' scales and the joints counted as explanations).
  SECTION("a refitted link that explains the misfit: leg_length alone, no kinematic_fit") {
    TempDir tmp;
    const std::string ds = tmp / "leg";
    const CliRun sim = runCommand(FGCAL_EXE, "simulate -o " + quoted(ds) + " --seed 1", tmp.path());
    REQUIRE(sim.exit_code == 0);
    lengthenThigh(ds);
    const CalibrateResult r = calibrateQuiet(ds);
    INFO(describe(r.output.quality));
    const Finding* f = findingOf(r.output.quality, "leg_length");
    REQUIRE(f != nullptr);
    CHECK(f->severity == Severity::Check);
    CHECK(findingOf(r.output.quality, "kinematic_fit") == nullptr);
  }
  SECTION("the mount left at the identity: mount_prior, with the mount the data give") {
    TempDir tmp;
    const std::string ds = copyOf(tmp);
    RigConfig cfg = loadRigConfig(ds + "/rig.yaml");
    cfg.robot.T_link_marker = SE3();
    writeFile(ds + "/rig.yaml", writeRigConfig(cfg, ds));
    const CalibrateResult r = calibrateQuiet(ds);
    INFO(describe(r.output.quality));
    const Finding* f = findingOf(r.output.quality, "mount_prior");
    REQUIRE(f != nullptr);
    CHECK(names(*f, "robot.T_link_marker"));
    CHECK(r.output.quality.verdict != Verdict::Ok);
  }
  // Encoders 200 times noisier than rig.yaml says misfit every family, and
  // then almost any change removes some chi-square: on this dataset the
  // board's scale removed more than chi-square(6) at 10^-3, and was named.
  // Judged against the variance factor it leaves, it is not, and the misfit
  // names encoder_sigma.
  SECTION("encoder_sigma far too small: kinematic_fit names it and no alternative is offered") {
    TempDir tmp;
    const std::string ds = tmp / "enc";
    const CliRun sim = runCommand(FGCAL_EXE, "simulate -o " + quoted(ds) + " --seed 6", tmp.path());
    REQUIRE(sim.exit_code == 0);
    RigConfig cfg = loadRigConfig(ds + "/rig.yaml");
    cfg.robot.encoder_sigma = 1e-5;
    writeFile(ds + "/rig.yaml", writeRigConfig(cfg, ds));
    const CalibrateResult r = calibrateQuiet(ds);
    INFO(describe(r.output.quality));
    const Finding* f = findingOf(r.output.quality, "kinematic_fit");
    REQUIRE(f != nullptr);
    CHECK(f->severity == Severity::Check);
    CHECK(names(*f, "robot.encoder_sigma"));
    for (const char* alternative : {"board_scale", "camera_scale", "joint_sign", "joint_swap"})
      CHECK(findingOf(r.output.quality, alternative) == nullptr);
  }
  // These two contradict the images so much that no image of a camera
  // survives the gate: the run fails (DataError) with the diagnosis.
  SECTION("a joint logged with the wrong sign: joint_sign names its column") {
    TempDir tmp;
    const std::string ds = copyOf(tmp);
    editJointColumn(ds, "lf_hfe_joint", [](double q) { return -q; });
    // One run: the exception's type and its text.
    try {
      calibrateQuiet(ds);
      FAIL("calibrate succeeded on a sign-flipped joint");
    } catch (const DataError& e) {
      CHECK_THAT(e.what(), Catch::Contains("unusable [joint_sign] fields: joints.csv:lf_hfe_joint"));
    }
  }
  SECTION("two joints' columns swapped: joint_swap names both") {
    TempDir tmp;
    const std::string ds = copyOf(tmp);
    std::string csv = readFile(ds + "/joints.csv");
    csv = replaced(csv, "lf_hfe_joint", "@");
    csv = replaced(csv, "lf_kfe_joint", "lf_hfe_joint");
    csv = replaced(csv, "@", "lf_kfe_joint");
    writeFile(ds + "/joints.csv", csv);
    CHECK_THROWS_WITH(calibrateQuiet(ds), Catch::Contains("[joint_swap]") &&
                                              Catch::Contains("joints.csv:lf_hfe_joint") &&
                                              Catch::Contains("joints.csv:lf_kfe_joint"));
  }
  SECTION("joints logged in degrees: joint_units names the columns") {
    TempDir tmp;
    const std::string ds = copyOf(tmp);
    for (const char* j : {"lf_haa_joint", "lf_hfe_joint", "lf_kfe_joint"})
      editJointColumn(ds, j, [](double q) { return q * 180.0 / M_PI; });
    CHECK_THROWS_WITH(calibrateQuiet(ds), Catch::Contains("unusable [joint_units]") &&
                                              Catch::Contains("joints.csv:lf_kfe_joint") &&
                                              Catch::Contains("in degrees"));
  }
  SECTION("the board's rows and columns swapped in rig.yaml: board_layout names the target") {
    TempDir tmp;
    const std::string ds = copyOf(tmp);
    RigConfig cfg = loadRigConfig(ds + "/rig.yaml");
    std::swap(cfg.target.squares_x, cfg.target.squares_y);
    writeFile(ds + "/rig.yaml", writeRigConfig(cfg, ds));
    // The gate rejects most images and never settles: the result is judged
    // as a failed solve is, and comes out unusable (exit 1 on the command).
    const CalibrateResult r = calibrateQuiet(ds);
    INFO(describe(r.output.quality));
    CHECK(r.output.quality.verdict == Verdict::Unusable);
    const Finding* f = findingOf(r.output.quality, "board_layout");
    REQUIRE(f != nullptr);
    CHECK(f->severity == Severity::Unusable);
    CHECK(names(*f, "target.squares_x"));
    CHECK(names(*f, "target.squares_y"));
  }
  SECTION("two cameras' intrinsics swapped in rig.yaml: intrinsics names both cameras") {
    TempDir tmp;
    const std::string ds = copyOf(tmp);
    RigConfig cfg = loadRigConfig(ds + "/rig.yaml");
    REQUIRE(cfg.cameras.size() == 2);
    CameraConfig& a = cfg.cameras[0];
    CameraConfig& b = cfg.cameras[1];
    std::swap(a.intrinsics, b.intrinsics);
    std::swap(a.distortion_model, b.distortion_model);
    std::swap(a.distortion_coeffs, b.distortion_coeffs);
    writeFile(ds + "/rig.yaml", writeRigConfig(cfg, ds));
    CHECK_THROWS_WITH(calibrateQuiet(ds), Catch::Contains("unusable [intrinsics]") &&
                                              Catch::Contains("cameras[" + a.name + "].intrinsics") &&
                                              Catch::Contains("cameras[" + b.name + "].intrinsics") &&
                                              Catch::Contains("intrinsics swapped"));
  }
  SECTION("the board on another foot than rig.yaml says: marker_link names the foot it is on") {
    TempDir tmp;
    const std::string ds = copyOf(tmp);
    RigConfig cfg = loadRigConfig(ds + "/rig.yaml");
    cfg.robot.marker_link = "rf_foot";
    writeFile(ds + "/rig.yaml", writeRigConfig(cfg, ds));
    CHECK_THROWS_WITH(calibrateQuiet(ds), Catch::Contains("[marker_link] fields: robot.marker_link") &&
                                              Catch::Contains("with the board on lf_foot"));
  }
  SECTION("the command: a failed solve exits 1, writes no calibration output, and its report says why") {
    TempDir tmp;
    const std::string ds = copyOf(tmp);
    editJointColumn(ds, "lf_hfe_joint", [](double q) { return -q; });
    fs::create_directories(tmp.path() / "out");
    const std::string out = tmp / "out/calibration.yaml";
    const CliRun run = runCommand(FGCAL_EXE, "calibrate " + quoted(ds) + " -o " + quoted(out) + " --kalibr-out " +
                                                 quoted(tmp / "out/camchain.yaml"), tmp.path());
    INFO(run.err);
    CHECK(run.exit_code == 1);
    CHECK(run.err.find("verdict: UNUSABLE") != std::string::npos);
    CHECK(run.err.find("joints.csv:lf_hfe_joint") != std::string::npos);
    CHECK_FALSE(fs::exists(out));
    CHECK_FALSE(fs::exists(tmp / "out/camchain.yaml"));
    CHECK_FALSE(fs::exists(tmp / "out/calibration.urdf.xml"));
    // The report is written, titled as a failed calibration, with the finding and the input.
    const fs::path report = tmp.path() / "out/calibration_report/index.html";
    REQUIRE(fs::exists(report));
    CHECK(run.err.find("the report of the failed calibration: ") != std::string::npos);
    CHECK(run.err.find("calibration_report/index.html") != std::string::npos);
    const std::string html = readFile(report.string());
    CHECK(html.find("<title>fgcal: failed calibration") != std::string::npos);
    CHECK(html.find("Verdict: UNUSABLE") != std::string::npos);
    CHECK(html.find("joints.csv:lf_hfe_joint") != std::string::npos);
    CHECK(html.find(ds) != std::string::npos);
  }
}

// A result that kept a minority of a camera's images rests on too little to
// be trusted; correct data never come near (the gate rejects about one image
// in a thousand), so it is judged as a failed solve.
TEST_CASE("a result is judged as a failed solve when the gate rejected more than half of a camera's images",
          "[apps][quality]") {
  CalibrationProblemInput problem;
  problem.camera_names = {"a", "b"};
  for (int k = 0; k < 10; ++k) problem.observations.push_back(BoardObservation{});
  for (int k = 0; k < 10; ++k) problem.observations[static_cast<std::size_t>(k)].camera = k < 6 ? 0 : 1;
  CalibrationSolution sol;
  for (std::size_t k : {0, 1, 2}) sol.rejected.push_back({k, "outlier"});  // a: 3 of 6
  CHECK_FALSE(stages::mostImagesRejected(problem, sol));
  sol.rejected.push_back({3, "outlier"});  // a: 4 of 6
  CHECK(stages::mostImagesRejected(problem, sol));
  sol.rejected = {{6, "outlier"}, {7, "outlier"}};  // b: 2 of 4, half is not most
  CHECK_FALSE(stages::mostImagesRejected(problem, sol));
  sol.rejected.push_back({8, "outlier"});
  CHECK(stages::mostImagesRejected(problem, sol));
}

TEST_CASE("report: an unusable result is titled a failed calibration and opens with its findings",
          "[apps][quality][report]") {
  ReportData d;
  d.dataset = "ds";
  d.quality.add({"joint_units", Severity::Unusable, {"joints.csv:lf_kfe_joint"}, "the log is in degrees <here>",
                 {{"unit", "degrees"}}, {}});
  d.warnings = {"the log is in degrees <here>", "an input's own warning"};
  const std::string html = formatReportHtml(d);
  CHECK(html.find("<title>fgcal: failed calibration") != std::string::npos);
  CHECK(html.find("Verdict: UNUSABLE") != std::string::npos);
  CHECK(html.find("Verdict: UNUSABLE") < html.find("id=\"quality\""));
  CHECK(html.find("joints.csv:lf_kfe_joint") != std::string::npos);
  CHECK(html.find("the log is in degrees &lt;here&gt;") != std::string::npos);
  // a warning that is a finding's message is shown once, the other apart
  CHECK(html.find("1 warning: read before trusting the result") != std::string::npos);
  CHECK(html.find("an input&#39;s own warning") != std::string::npos);
}
