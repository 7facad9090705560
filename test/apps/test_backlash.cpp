// Gear backlash (--estimate backlash) through the real fgcal command, on a
// simulated leg whose joints lag their motor-side encoders by half their play
// against the motion. Unmodelled, the lag moves the board by millimetres
// depending on the direction of motion, which neither the cameras nor the
// mount can absorb; estimated, every reversing joint's play is recovered
// within its sigma, the cameras come back to the accuracy of a leg without
// play, and calibration.yaml, the summary and the report say so. A joint that
// never moves both ways is a finding naming it, not a number. The lag the
// model gives a joint is the play operator's over the joint log's smooth fit:
// the simulator's dead zone, read from the motor side.

#include <cmath>
#include <random>
#include <sstream>

#include "apps_test_util.hpp"
#include "cli_test_util.hpp"
#include "commands/simulate/leg_motion.hpp"
#include "fgcal/apps/joint_trajectory.hpp"
#include "fgcal/apps/offset_estimation.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/simulator.hpp"
#include "fgcal_test/files.hpp"
#include "fgcal_test/pose_gap.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;
using fgcal::test::nees;
using fgcal::test::translationGapMm;

namespace {

constexpr double kChi2_6_999 = 22.4577;
constexpr double kPlay = 0.004;  // rad, every joint of the chain

}  // namespace

TEST_CASE("backlash: a joint moving both ways shows its play, one moving one way or standing still does not",
          "[apps][backlash]") {
  // Three joints sampled at 500 Hz for 6 s: one oscillating, one ramping one
  // way, one standing still under encoder noise (which turns a smooth fit to
  // and fro by itself).
  JointLog log;
  log.names = {"swing", "ramp", "still"};
  const int n = 3000;
  log.positions.resize(n, 3);
  std::mt19937 gen(3);
  std::normal_distribution<double> noise(0.0, 0.002);
  for (int i = 0; i < n; ++i) {
    const double t = 0.002 * i;
    log.stamps_ns.push_back(static_cast<std::int64_t>(1'000'000'000 + 2'000'000LL * i));
    log.positions(i, 0) = 0.4 * std::sin(2.0 * t) + noise(gen);
    log.positions(i, 1) = 0.1 * t + noise(gen);
    log.positions(i, 2) = 0.3 + noise(gen);
  }
  const auto trajectory = std::make_shared<const JointLogTrajectory>(log, std::vector<int>{0, 1, 2}, "joints.csv");
  const std::vector<bool> reversing = backlashReversing(*motorPath(trajectory, log), Eigen::VectorXd::Constant(3, 0.002));
  CHECK(reversing == std::vector<bool>{true, false, false});
}

TEST_CASE("backlash: estimated through the command, the play is recovered and the cameras are right again",
          "[apps][e2e][backlash]") {
  TempDir tmp;
  const fs::path data = tmp.path() / "sim";
  SimulationOptions sim;
  sim.out_dir = data.string();
  sim.frames = 120;
  sim.supersampling = 2;
  sim.seed = 11;
  sim.backlash_rad = kPlay;
  simulateDataset(sim);
  const GroundTruth truth = loadGroundTruth((data / "ground_truth.yaml").string());
  REQUIRE(truth.backlash_rad.size() == 3);

  const auto calibrate = [&](const std::string& name, const std::string& extra) {
    const fs::path out = tmp.path() / (name + ".yaml");
    const CliRun r = runCommand(FGCAL_EXE, "calibrate " + quoted(data.string()) + " -o " + quoted(out.string()) +
                                               " --report " + quoted((tmp.path() / (name + "_report")).string()) +
                                               extra, tmp.path());
    INFO(r.command << "\nstderr:\n" << r.err);
    REQUIRE(r.exit_code == 0);
    return std::make_pair(loadCalibrationYaml(out.string()), r.out + r.err);
  };
  const auto [plain, plain_log] = calibrate("plain", "");
  const auto [cal, log] = calibrate("backlash", " --estimate backlash");
  REQUIRE(cal.backlash.size() == 3);
  int observed = 0;
  for (const JointOffsetResult& b : cal.backlash) {
    INFO("joint " << b.joint << ": " << b.offset_rad << " +- " << b.sigma_rad);
    if (!b.observed) continue;
    ++observed;
    CHECK(std::abs(b.offset_rad - truth.backlash_rad.at(b.joint)) < 3.0 * b.sigma_rad + 2e-4);
    CHECK(b.sigma_rad < 0.5 * kPlay);
  }
  CHECK(observed >= 2);  // a 3-joint leg moved both ways: the play of its joints shows
  for (const CameraResult& c : cal.cameras) {
    const CameraResult* p = nullptr;
    for (const CameraResult& q : plain.cameras)
      if (q.name == c.name) p = &q;
    REQUIRE(p);
    const SE3& T = truth.T_base_cam.at(c.name);
    INFO("camera " << c.name << ": " << translationGapMm(T, p->T_base_cam) << " mm without the model, "
                   << translationGapMm(T, c.T_base_cam) << " mm with it");
    // 120 frames: a leg without play gives 0.36 - 0.46 mm here.
    CHECK(nees(T, c.T_base_cam, c.covariance) < kChi2_6_999);
    CHECK(translationGapMm(T, c.T_base_cam) < 0.9);
    CHECK(translationGapMm(T, c.T_base_cam) < 0.85 * translationGapMm(T, p->T_base_cam));
    CHECK(nees(T, p->T_base_cam, p->covariance) > nees(T, c.T_base_cam, c.covariance));
  }
  // Unmodelled, the play is named with the command that estimates it; modelled, nothing is left to name.
  bool named = false;
  for (const Finding& f : plain.quality.findings)
    if (f.check == "backlash") named = f.command.find("--estimate backlash") != std::string::npos && !f.fields.empty();
  CHECK(named);
  CHECK(cal.quality.verdict == Verdict::Ok);
  CHECK(log.find("backlash lf_") != std::string::npos);        // the summary's lines
  CHECK(log.find("backlash_not_reversing") == std::string::npos);
  CHECK(fgcal::test::readFile(tmp.path() / "backlash_report" / "index.html").find("backlash") != std::string::npos);
  CHECK(fgcal::test::readFile(tmp.path() / "backlash.yaml").find("backlash:") != std::string::npos);
}

namespace {

/// The joint log of `motor` at 500 Hz for its duration, encoder noise `sigma`.
JointLog motorLog(const sim::LegTrajectory& motor, double sigma, unsigned seed) {
  JointLog log;
  const auto n = static_cast<Eigen::Index>(motor.waypoints().front().size());
  for (Eigen::Index k = 0; k < n; ++k) log.names.push_back("j" + std::to_string(k));
  const int samples = static_cast<int>(motor.duration() / 0.002) + 1;
  log.positions.resize(samples, n);
  std::mt19937 gen(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (int i = 0; i < samples; ++i) {
    log.stamps_ns.push_back(1'000'000'000 + 2'000'000LL * i);
    const VecX q = motor.at(0.002 * i);
    for (Eigen::Index k = 0; k < n; ++k) log.positions(i, k) = q[k] + (sigma > 0.0 ? noise(gen) : 0.0);
  }
  return log;
}

}  // namespace

TEST_CASE("backlash: the play operator's lag over the joint log is the simulator's dead zone", "[apps][backlash]") {
  // Joint 0 swings like a sinusoid of varying amplitude, with one turn back
  // by less than its play (the joint does not move) and a pause; joint 1
  // rises, pauses and falls with a larger play; joint 2 never moves.
  const std::vector<double> swing{0.0, 0.3, -0.2, 0.25, 0.248, 0.248, -0.1, 0.2, 0.2};
  const std::vector<double> rise{0.5, 0.6, 0.7, 0.7, 0.4, 0.3, 0.45, 0.5, 0.5};
  std::vector<double> times;
  std::vector<VecX> waypoints;
  for (std::size_t k = 0; k < swing.size(); ++k) {
    times.push_back(0.8 * static_cast<double>(k));
    waypoints.push_back((VecX(3) << swing[k], rise[k], -0.4).finished());
  }
  const sim::LegTrajectory motor(times, waypoints);
  const VecX b = (VecX(3) << 0.004, 0.01, 0.004).finished();
  const sim::JointPlay joint(motor, b);

  for (const double sigma : {0.0, 0.002}) {
    const JointLog log = motorLog(motor, sigma, 7);
    const auto trajectory = std::make_shared<const JointLogTrajectory>(log, std::vector<int>{0, 1, 2}, "joints.csv");
    const auto path = motorPath(trajectory, log);
    const std::vector<bool> reversing = backlashReversing(*path, VecX::Constant(3, 0.002));
    CHECK(reversing == std::vector<bool>{true, true, false});
    const BacklashLag lag(path, (VecX(3) << b[0], b[1], 0.0).finished());
    // At the log's stamps and between them: the model's lag times b against
    // where the joint stood relative to its motor, and the fit against the motor.
    double worst = 0.0, sum = 0.0, fit = 0.0;
    int n = 0;
    for (std::int64_t ns = log.stamps_ns.front(); ns <= log.stamps_ns.back(); ns += 700'000) {
      const double t = 1e-9 * static_cast<double>(ns - log.stamps_ns.front());
      const VecX m = motor.at(t), truth = joint.at(t) - m, lambda = lag.at(ns);
      VecX x;
      trajectory->evaluate(t, &x, nullptr);
      for (int k = 0; k < 2; ++k) {
        REQUIRE(std::abs(lambda[k]) <= 0.5 + 1e-12);
        worst = std::max(worst, std::abs(lambda[k] * b[k] - truth[k]));
        sum += std::abs(lambda[k] * b[k] - truth[k]);
        fit = std::max(fit, std::abs(x[k] - m[k]));
        ++n;
      }
      CHECK(lambda[2] == 0.0);  // no play given: no lag
    }
    INFO("encoder noise " << sigma << ": |lambda b - (joint - motor)| at most " << worst << " rad, mean " << sum / n
                          << "; the fit off the motor by at most " << fit << " rad");
    // The play operator is 1-Lipschitz in the largest deviation: run over a
    // fit off the motor by at most e, the joint is off by at most e, its lag
    // by 2 e. Without noise the fit is the motor to ~1e-6 rad; with 2 mrad of
    // noise at 500 Hz the fit strays by a few tenths of a mrad where the leg
    // is slow, which the operator holds through a pause or a turn.
    CHECK(worst <= 2.0 * fit + 1e-12);
    if (sigma == 0.0) {
      CHECK(worst < 1e-5);
    } else {
      CHECK(sum / n < 0.25e-3);  // against lags of +-2 and +-5 mrad
    }
  }
}
