// The joint log as a smooth trajectory (what the time-offset factors
// evaluate): its value and velocity against the truth of a simulated leg
// motion with encoder noise, its derivative against its own values, gaps,
// the ends of the log, and the time-offset margin check.
#include <cmath>
#include <random>

#include <catch2/catch.hpp>

#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/joint_trajectory.hpp"

using namespace fgcal;
using namespace fgcal::apps;

namespace {

constexpr std::int64_t kT0 = 1'700'000'000'000'000'000LL;

/// Minimum-jerk segments between waypoints, as the simulator moves the leg.
struct MinJerk {
  std::vector<double> times{0.0, 0.8, 1.5, 2.7, 3.3, 4.0};
  std::vector<double> points{0.2, 1.1, 0.4, -0.3, 0.5, 0.6};
  void at(double t, double* q, double* v) const {
    std::size_t k = 1;
    while (k + 1 < times.size() && t > times[k]) ++k;
    const double T = times[k] - times[k - 1];
    const double tau = std::clamp((t - times[k - 1]) / T, 0.0, 1.0);
    const double s = tau * tau * tau * (10 - 15 * tau + 6 * tau * tau);
    const double ds = 30 * tau * tau * (1 - tau) * (1 - tau) / T;
    *q = points[k - 1] + s * (points[k] - points[k - 1]);
    *v = ds * (points[k] - points[k - 1]);
  }
};

JointLog sampled(const MinJerk& m, double period_s, double noise, unsigned seed, double span = 4.0) {
  std::mt19937 gen(seed);
  std::normal_distribution<double> n(0.0, noise);
  JointLog log;
  log.names = {"j0", "other"};
  const int samples = static_cast<int>(std::lround(span / period_s)) + 1;
  log.positions.resize(samples, 2);
  for (int s = 0; s < samples; ++s) {
    const double t = s * period_s;
    log.stamps_ns.push_back(kT0 + static_cast<std::int64_t>(std::llround(t * 1e9)));
    double q, v;
    m.at(t, &q, &v);
    log.positions(s, 0) = q + n(gen);
    log.positions(s, 1) = -1.0;
  }
  return log;
}

}  // namespace

TEST_CASE("joint trajectory follows a leg motion and its velocity through 500 Hz encoder noise") {
  const MinJerk m;
  const JointLog log = sampled(m, 0.002, 0.002, 1);
  const JointLogTrajectory traj(log, {0}, "joints.csv");
  CHECK(traj.numJoints() == 1);
  CHECK(traj.knotSpacing() > 0.03);  // wider knots average more of the noise
  double sq_q = 0, sq_v = 0, sq_v_linear = 0;
  int n = 0;
  VecX q, v;
  for (double t = 0.1; t < 3.9; t += 0.0037, ++n) {
    traj.evaluate(t, &q, &v);
    double qt, vt;
    m.at(t, &qt, &vt);
    sq_q += std::pow(q[0] - qt, 2);
    sq_v += std::pow(v[0] - vt, 2);
    // What linear interpolation's slope gives: the difference of two noisy samples.
    const auto s = static_cast<Eigen::Index>(std::floor(t / 0.002));
    sq_v_linear += std::pow((log.positions(s + 1, 0) - log.positions(s, 0)) / 0.002 - vt, 2);
  }
  const double rms_q = std::sqrt(sq_q / n), rms_v = std::sqrt(sq_v / n), rms_v_linear = std::sqrt(sq_v_linear / n);
  INFO("RMS position error " << rms_q << " rad, velocity " << rms_v << " rad/s (linear interpolation: "
                             << rms_v_linear << " rad/s)");
  CHECK(rms_q < 0.0008);              // the noise averaged: well below its 0.002 rad
  CHECK(rms_v < 0.06);                // against peak speeds of about 2 rad/s
  CHECK(rms_v_linear > 10 * rms_v);   // why a fit and not the samples' slopes
}

/// RMS error of the trajectory's change over `delay` seconds against the truth:
/// what a time-offset factor moves a delayed camera's board by.
double changeError(const JointLogTrajectory& traj, const MinJerk& m, double delay) {
  double sq = 0;
  int n = 0;
  VecX qa, qb;
  for (double t = 0.1; t + delay < 3.9; t += 0.0037, ++n) {
    traj.evaluate(t, &qa, nullptr);
    traj.evaluate(t + delay, &qb, nullptr);
    double ta, tb, v;
    m.at(t, &ta, &v);
    m.at(t + delay, &tb, &v);
    sq += std::pow((qb[0] - qa[0]) - (tb - ta), 2);
  }
  return std::sqrt(sq / n);
}

TEST_CASE("joint trajectory carries a noisy leg motion over a camera's delay far more precisely than the noise") {
  // The board a delayed camera saw is the board at the instant moved by the
  // trajectory's change over the delay; an error there is an error of that
  // camera's board which neither the kinematic factor nor the image covariance
  // accounts for. Knots every 20 ms average too few samples for it.
  const MinJerk m;
  for (unsigned seed : {1u, 2u, 3u}) {
    const JointLog log = sampled(m, 0.002, 0.002, seed);
    const JointLogTrajectory chosen(log, {0}, "joints.csv");
    const JointLogTrajectory fine(log, {0}, "joints.csv", 0.02);
    const double e_chosen = changeError(chosen, m, 0.015), e_fine = changeError(fine, m, 0.015);
    INFO("seed " << seed << ": knots every " << chosen.knotSpacing() << " s: change over 15 ms off by " << e_chosen
                 << " rad RMS; every 20 ms: " << e_fine << " rad");
    CHECK(e_fine > 5e-4);
    CHECK(e_chosen < 2.5e-4);
  }
  // Without noise the knots stay fine enough to follow the fastest segment.
  const JointLogTrajectory exact(sampled(m, 0.002, 0.0, 1), {0}, "joints.csv");
  CHECK(exact.knotSpacing() == Approx(0.02).epsilon(0.01));
  CHECK(changeError(exact, m, 0.015) < 1e-6);
}

TEST_CASE("joint trajectory without noise reproduces the motion") {
  const MinJerk m;
  const JointLogTrajectory traj(sampled(m, 0.002, 0.0, 1), {0, 1}, "joints.csv");
  VecX q, v;
  double worst_q = 0, worst_v = 0;
  for (double t = 0.05; t < 3.95; t += 0.0011) {
    traj.evaluate(t, &q, &v);
    double qt, vt;
    m.at(t, &qt, &vt);
    worst_q = std::max(worst_q, std::abs(q[0] - qt));
    worst_v = std::max(worst_v, std::abs(v[0] - vt));
    CHECK(q[1] == Approx(-1.0).margin(1e-9));
    CHECK(v[1] == Approx(0.0).margin(1e-7));
  }
  INFO("worst position error " << worst_q << " rad, velocity " << worst_v << " rad/s");
  CHECK(worst_q < 2e-5);
  CHECK(worst_v < 3e-3);
}

TEST_CASE("joint trajectory velocity is the derivative of its position, also past the log's ends") {
  const MinJerk m;
  const JointLogTrajectory traj(sampled(m, 0.002, 0.002, 2), {0}, "joints.csv");
  VecX q, v, qp, qm;
  for (double t : {-0.3, -1e-3, 0.0, 0.0123, 0.02, 0.5, 1.9999, 3.98, 4.0, 4.001, 4.5}) {
    traj.evaluate(t, &q, &v);
    const double e = 1e-6;
    traj.evaluate(t + e, &qp, nullptr);
    traj.evaluate(t - e, &qm, nullptr);
    INFO("t = " << t);
    CHECK(v[0] == Approx((qp[0] - qm[0]) / (2 * e)).margin(1e-5));
  }
  // Past the end it continues at the end velocity.
  VecX q_end, v_end;
  traj.evaluate(traj.duration(), &q_end, &v_end);
  traj.evaluate(traj.duration() + 0.1, &q, &v);
  CHECK(q[0] == Approx(q_end[0] + 0.1 * v_end[0]).margin(1e-12));
  CHECK(v[0] == Approx(v_end[0]).margin(1e-12));
}

TEST_CASE("joint trajectory bridges NaN samples and a gap in the log") {
  const MinJerk m;
  JointLog log = sampled(m, 0.002, 0.0, 1);
  for (Eigen::Index s = 900; s < 960; ++s) log.positions(s, 0) = std::nan("");  // 120 ms without a reading
  const JointLogTrajectory traj(log, {0}, "joints.csv");
  VecX q, v;
  for (double t = 1.80; t < 1.92; t += 0.01) {
    traj.evaluate(t, &q, &v);
    double qt, vt;
    m.at(t, &qt, &vt);
    INFO("t = " << t);
    CHECK(std::isfinite(q[0]));
    CHECK(q[0] == Approx(qt).margin(0.01));
  }
}

TEST_CASE("joint trajectory refuses a log it cannot fit") {
  JointLog one;
  one.names = {"j0"};
  one.stamps_ns = {kT0};
  one.positions = Eigen::MatrixXd::Zero(1, 1);
  CHECK_THROWS_AS(JointLogTrajectory(one, {0}, "joints.csv"), InputError);
  JointLog nan = sampled(MinJerk(), 0.01, 0.0, 1);
  nan.positions.col(0).setConstant(std::nan(""));
  try {
    JointLogTrajectory(nan, {0}, "joints.csv");
    FAIL("expected an InputError");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("j0") != std::string::npos);
  }
}

TEST_CASE("time offset past the joint log's margin is an error naming the log, the camera and the end") {
  const JointLog log = sampled(MinJerk(), 0.002, 0.0, 1);  // 4 s
  const JointLogTrajectory traj(log, {0}, "joints.csv");
  // Images from 0.1 s to 3.99 s: 100 ms of log before, 10 ms after.
  const TimeOffsetMargin images{"cam1", kT0 + 100'000'000, kT0 + 3'990'000'000};
  CHECK_NOTHROW(checkTimeOffsetMargin(images, 0.009, traj, "joints.csv"));
  CHECK_NOTHROW(checkTimeOffsetMargin(images, -0.099, traj, "joints.csv"));
  try {
    checkTimeOffsetMargin(images, 0.015, traj, "joints.csv");
    FAIL("expected an InputError");
  } catch (const InputError& e) {
    const std::string w = e.what();
    INFO(w);
    CHECK(e.file() == "joints.csv");
    CHECK(w.find("cam1") != std::string::npos);
    CHECK(w.find("+15.00 ms") != std::string::npos);
    CHECK(w.find("last image") != std::string::npos);
    CHECK(w.find("margin at that end is 10.00 ms") != std::string::npos);
  }
  CHECK_THROWS_AS(checkTimeOffsetMargin(images, -0.12, traj, "joints.csv"), InputError);
  // A rolling shutter's last row comes a readout after its first: 5 ms of
  // offset fit, 5 ms + a 30 ms readout do not, and the message says both.
  CHECK_NOTHROW(checkTimeOffsetMargin(images, 0.005, traj, "joints.csv", 0.004));
  try {
    checkTimeOffsetMargin(images, 0.005, traj, "joints.csv", 0.030);
    FAIL("expected an InputError");
  } catch (const InputError& e) {
    const std::string w = e.what();
    INFO(w);
    CHECK(w.find("readout 30.00 ms") != std::string::npos);
    CHECK(w.find("last image") != std::string::npos);
  }
}
