// Time offsets and joint zero offsets estimated with the camera poses
// (solveCalibration with an OffsetModel) on synthetic PnP observations of a
// real leg's kinematics with known truth: a camera's delay and the middle
// joint's offset recovered; the base-side and board-side offsets reported as
// not observed, with what they do to the cameras and the mount checked
// against the geometry; and the time offset's margin in the joint log.
#include <algorithm>
#include <cmath>
#include <random>

#include <catch2/catch.hpp>

#include "fgcal/apps/calibration_problem.hpp"
#include "fgcal/apps/corner_calibration.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/kinematics/default_robot.hpp"
#include "fgcal_test/pose_gap.hpp"

using namespace fgcal;
using namespace fgcal::apps;

namespace {

constexpr std::int64_t kT0 = 1'700'000'000'000'000'000LL;

struct Truth {
  std::vector<SE3> cameras;
  SE3 mount;
  VecX joint_offsets = VecX::Zero(3);
  std::vector<double> delays_s{0.0, 0.0};
};

struct Scene {
  CalibrationProblemInput input;
  CornerProblemInput corners;  ///< the same images' corners (0.5 px noise), for the corner graph
  JointLog log;
  Truth truth;
  kinematics::KinematicChain chain = kinematics::loadDefaultRobot().chain("base_link", "lf_foot");
};

/// The leg's true joints: smooth motions of 0.3-0.5 rad around a raised pose.
VecX trueJoints(double t) {
  VecX q(3);
  q << 0.15 + 0.25 * std::sin(1.3 * t), 0.9 + 0.5 * std::sin(0.9 * t + 1.0), -1.5 + 0.45 * std::sin(1.7 * t + 2.0);
  return q;
}

/// 20 s of a leg in front of two cameras: joints logged at 500 Hz (as read:
/// truth - joint offsets + noise), images at 30 Hz from 0.1 s to `last_image_s`,
/// camera c exposed delays_s[c] after its stamp, PnP with a camera-frame covariance.
Scene makeScene(const Truth& truth, unsigned seed, double last_image_s = 19.9, double encoder_sigma = 3e-4) {
  Scene s;
  s.truth = truth;
  std::mt19937 gen(seed);
  std::normal_distribution<double> n;
  const int samples = 10001;  // 20 s at 500 Hz
  s.log.names = s.chain.jointNames();
  s.log.positions.resize(samples, 3);
  for (int k = 0; k < samples; ++k) {
    const double t = 0.002 * k;
    s.log.stamps_ns.push_back(kT0 + 2'000'000LL * k);
    const VecX q = trueJoints(t) - truth.joint_offsets;
    for (int j = 0; j < 3; ++j) s.log.positions(k, j) = q[j] + encoder_sigma * n(gen);
  }
  auto& in = s.input;
  in.camera_names = {"cam0", "cam1"};
  in.camera_guesses = {std::nullopt, std::nullopt};
  in.mount_prior = truth.mount;
  in.mount_sigma_m = 0.005;
  in.mount_sigma_rad = 0.03;
  in.fiducial_covariance_scale = 1.0;
  Mat6 pnp = Mat6::Zero();
  pnp.diagonal() << 1e-6, 1e-6, 2.5e-7, 2.5e-8, 2.5e-8, 2.5e-7;  // 1 mrad, 0.16 mm lateral, 0.5 mm depth
  const Eigen::LLT<Mat6> pnp_llt(pnp);
  const VecX sigma_q = VecX::Constant(3, encoder_sigma);
  // The corner graph's view of the same images: a 5 x 7 board of 4 cm
  // squares, its 24 inner corners through a 640 x 480 pinhole camera.
  const auto model = vision::CameraModel::fromKalibr("pinhole", "none", {600, 600, 320, 240}, {}, {640, 480});
  for (int c = 0; c < 2; ++c) s.corners.cameras.push_back({model, 0.5, VecX()});
  std::vector<Vec3> board_points;
  for (int y = 1; y < 7; ++y)
    for (int x = 1; x < 5; ++x) board_points.push_back(Vec3(0.04 * x, 0.04 * y, 0.0));
  const std::vector<int> columns{0, 1, 2};
  for (double t = 0.1; t <= last_image_s; t += 1.0 / 30) {
    const auto stamp = kT0 + static_cast<std::int64_t>(std::llround(t * 1e9));
    const auto q = interpolate(s.log, stamp, columns);
    REQUIRE(q);
    for (int c = 0; c < 2; ++c) {
      BoardObservation o;
      o.camera = c;
      o.stamp_ns = stamp + c * 200'000;
      const SE3 seen = s.chain.forward(trueJoints(t + c * 2e-4 + truth.delays_s[c] )) * truth.mount;
      Vec6 z;
      for (int i = 0; i < 6; ++i) z[i] = n(gen);
      o.T_cam_marker = truth.cameras[c].between(seen).plus(pnp_llt.matrixL() * z);
      o.covariance = pnp;
      Mat6 link_covariance;
      o.T_base_link = s.chain.forwardWithCovariance(*q, sigma_q, &link_covariance);
      o.link_covariance = link_covariance;
      o.joint_positions = *q;
      in.observations.push_back(o);
      ImageCorners im;
      for (const Vec3& p : board_points)
        if (const auto uv = model.project(truth.cameras[c].between(seen) * p)) {
          im.pixels.push_back(*uv + 0.5 * Eigen::Vector2d(n(gen), n(gen)));
          im.board_points.push_back(p);
        }
      s.corners.corners.push_back(im);
    }
  }
  return s;
}

/// Two cameras 0.7 m in front of where the board goes, looking at it: the
/// board's mean centre and normal over the motion place them.
Truth defaultTruth() {
  Truth t;
  t.mount = SE3(SO3::fromRpy(0.0, -1.2, 0.3), Vec3(0.02, 0.0, -0.03));
  const auto chain = kinematics::loadDefaultRobot().chain("base_link", "lf_foot");
  Vec3 centre = Vec3::Zero(), normal = Vec3::Zero();
  int n = 0;
  for (double time = 0.0; time < 20.0; time += 0.1, ++n) {
    const SE3 board = chain.forward(trueJoints(time)) * t.mount;
    centre += board * Vec3(0.1, 0.14, 0.0);
    normal += board.rotation().col(2);
  }
  centre /= n;
  normal.normalize();
  for (const Vec3& side : {Vec3(0.0, 0.08, 0.0), Vec3(0.0, -0.1, 0.05)}) {
    const Vec3 p = centre + 0.7 * normal + side;
    const Vec3 z = (centre - p).normalized();
    const Vec3 x = z.cross(Vec3::UnitZ()).normalized();
    Mat3 R;
    R << x, z.cross(x), z;
    t.cameras.push_back(SE3(SO3(R), p));
  }
  return t;
}

OffsetModel model(const Scene& s, bool time, bool joints) {
  OffsetModel m;
  m.time_offsets = time;
  m.joint_offsets = joints;
  m.chain = std::make_shared<const kinematics::KinematicChain>(s.chain);
  m.trajectory = std::make_shared<const JointLogTrajectory>(s.log, std::vector<int>{0, 1, 2}, "joints.csv");
  m.joint_log_name = "joints.csv";
  m.joint_offset_sigma = VecX::Constant(3, 0.05);
  return m;
}

using fgcal::test::rotationGapDeg;
using fgcal::test::translationGapMm;

/// Distance of point p (base frame) from the axis of movable joint `k` of the
/// chain at q, the axis line in the base frame.
double distanceFromJointAxis(const kinematics::KinematicChain& chain, const VecX& q, int k, const Vec3& p) {
  // The axis: the chain's Jacobian column k at the base is [a; p_axis x a]
  // for a revolute joint in the base frame (left perturbation).
  kinematics::KinematicChain::Jacobian J;
  const SE3 T = chain.forward(q, &J);
  const Vec6 left = T.adjoint() * J.col(k);
  const Vec3 a = left.head<3>().normalized(), m = left.tail<3>();  // m = -a x c for a point c on the axis
  const Vec3 c = a.cross(m);                                       // closest point of the axis to the origin
  return a.cross(p - c).norm();
}

}  // namespace

TEST_CASE("a 15 ms camera delay is recovered with the camera poses") {
  Truth truth = defaultTruth();
  truth.delays_s = {0.0, 0.015};
  Scene s = makeScene(truth, 1);
  CalibrationProblemInput without = s.input;
  s.input.offsets = model(s, true, false);
  const CalibrationSolution sol = solveCalibration(s.input);
  REQUIRE(sol.offsets.time_offsets.size() == 2);
  const auto& t0 = sol.offsets.time_offsets[0];
  const auto& t1 = sol.offsets.time_offsets[1];
  INFO("cam0 " << t0.offset_s * 1e3 << " +- " << t0.sigma_s * 1e3 << " ms, cam1 " << t1.offset_s * 1e3 << " +- "
               << t1.sigma_s * 1e3 << " ms");
  CHECK(t0.observed);
  CHECK(t1.observed);
  CHECK(std::abs(t0.offset_s) < 3e-4);
  CHECK(std::abs(t1.offset_s - 0.015) < 3e-4);
  // Honest sigma: the error within 4 sigma, the sigma well below the 0.3 ms target.
  CHECK(std::abs(t1.offset_s - 0.015) < 4 * t1.sigma_s);
  CHECK(t1.sigma_s < 1e-4);
  const CalibrationSolution plain = solveCalibration(without);
  for (int c = 0; c < 2; ++c) {
    INFO("camera " << c << ": with " << translationGapMm(sol.cameras[c].T_base_cam, truth.cameras[c]) << " mm, without "
                   << translationGapMm(plain.cameras[c].T_base_cam, truth.cameras[c]) << " mm");
    CHECK(translationGapMm(sol.cameras[c].T_base_cam, truth.cameras[c]) < 0.5);
    CHECK(rotationGapDeg(sol.cameras[c].T_base_cam, truth.cameras[c]) < 0.05);
  }
  // Without the estimate the delayed camera's images disagree with the kinematics.
  CHECK(translationGapMm(plain.cameras[1].T_base_cam, truth.cameras[1]) >
        2 * translationGapMm(sol.cameras[1].T_base_cam, truth.cameras[1]));
}

TEST_CASE("a time offset past the joint log's end is an input error naming the log and the camera") {
  Truth truth = defaultTruth();
  truth.delays_s = {0.0, 0.015};
  Scene s = makeScene(truth, 2);
  // The log cut 4 ms after cam1's last image: less than its 15 ms delay.
  std::int64_t last = 0;
  for (const auto& o : s.input.observations) last = std::max(last, o.stamp_ns);
  Eigen::Index keep = 0;
  while (keep < static_cast<Eigen::Index>(s.log.stamps_ns.size()) &&
         s.log.stamps_ns[static_cast<std::size_t>(keep)] <= last + 4'000'000)
    ++keep;
  s.log.stamps_ns.resize(static_cast<std::size_t>(keep));
  s.log.positions.conservativeResize(keep, Eigen::NoChange);
  s.input.offsets = model(s, true, false);
  try {
    solveCalibration(s.input);
    FAIL("expected an InputError");
  } catch (const InputError& e) {
    const std::string w = e.what();
    INFO(w);
    CHECK(e.file() == "joints.csv");
    CHECK(w.find("cam1") != std::string::npos);
    CHECK(w.find("after the joint log's last sample") != std::string::npos);
  }
}

TEST_CASE("joint offsets: the middle joint is recovered, the base-side and board-side ones are reported unobserved") {
  Truth truth = defaultTruth();
  truth.joint_offsets << 0.0, 0.01, 0.0;
  Scene s = makeScene(truth, 3);
  s.input.offsets = model(s, false, true);
  const CalibrationSolution sol = solveCalibration(s.input);
  const auto& jo = sol.offsets.joint_offsets;
  REQUIRE(jo.size() == 3);
  CHECK(jo[0].joint == "lf_haa_joint");
  CHECK(jo[1].joint == "lf_hfe_joint");
  CHECK(jo[2].joint == "lf_kfe_joint");
  INFO("hfe " << jo[1].offset_rad * 1e3 << " +- " << jo[1].sigma_rad * 1e3 << " mrad; eigenvalues "
              << sol.offsets.joint_offset_eigenvalues.transpose());
  CHECK(jo[1].observed);
  CHECK(jo[1].offset_rad == Approx(0.01).margin(1e-3));
  CHECK(!jo[0].observed);
  CHECK(!jo[2].observed);
  // Each unobserved offset warned about by name with its smallest eigenvalue.
  for (int k : {0, 2}) {
    bool named = false;
    for (const auto& w : sol.warnings) named = named || (w.find(jo[k].joint) != std::string::npos &&
                                                         w.find("not observed") != std::string::npos &&
                                                         w.find("mrad^-2") != std::string::npos);
    CHECK(named);
    CHECK(jo[k].eigenvalue < 1e-6 / (0.05 * 0.05));
  }
  for (int c = 0; c < 2; ++c) {
    CHECK(translationGapMm(sol.cameras[c].T_base_cam, truth.cameras[c]) < 0.5);
    CHECK(rotationGapDeg(sol.cameras[c].T_base_cam, truth.cameras[c]) < 0.05);
  }
  // What they do per mrad, against the geometry. The base-side joint turns
  // the board poses, and so the cameras, about its axis: 1 mrad of rotation,
  // and each camera moves by its distance from that axis; the mount stays.
  const VecX q_mean = s.input.observations[0].joint_positions;
  REQUIRE(jo[0].absorbed.size() == 3);
  for (int c = 0; c < 2; ++c) {
    const Absorption& a = jo[0].absorbed[static_cast<std::size_t>(c)];
    CHECK(a.estimate == s.input.camera_names[static_cast<std::size_t>(c)]);
    CHECK(a.deg_per_mrad == Approx(0.180 / M_PI).epsilon(0.02));
    CHECK(a.mm_per_mrad ==
          Approx(distanceFromJointAxis(s.chain, q_mean, 0, truth.cameras[static_cast<std::size_t>(c)].translation()))
              .epsilon(0.02));
  }
  CHECK(jo[0].absorbed[2].estimate == "mount");
  CHECK(jo[0].absorbed[2].deg_per_mrad < 0.002);
  // The board-side joint folds into the mount: the cameras stay.
  REQUIRE(jo[2].absorbed.size() == 3);
  for (int c = 0; c < 2; ++c) {
    CHECK(jo[2].absorbed[static_cast<std::size_t>(c)].mm_per_mrad < 0.01);
    CHECK(jo[2].absorbed[static_cast<std::size_t>(c)].deg_per_mrad < 0.001);
  }
  CHECK(jo[2].absorbed[2].deg_per_mrad == Approx(0.180 / M_PI).epsilon(0.02));
}

TEST_CASE("the corner graph recovers a camera delay and the middle joint's offset together") {
  Truth truth = defaultTruth();
  truth.delays_s = {0.0, 0.015};
  truth.joint_offsets << 0.0, 0.01, 0.0;
  Scene s = makeScene(truth, 5);
  s.input.offsets = model(s, true, true);
  const CalibrationSolution pnp = solveCalibration(s.input);
  const CornerSolution sol = solveCornerCalibration(s.input, s.corners, pnp);
  const OffsetEstimates& est = sol.solution.offsets;
  REQUIRE(est.time_offsets.size() == 2);
  REQUIRE(est.joint_offsets.size() == 3);
  INFO("delays " << est.time_offsets[0].offset_s * 1e3 << ", " << est.time_offsets[1].offset_s * 1e3 << " +- "
                 << est.time_offsets[1].sigma_s * 1e3 << " ms (PnP " << pnp.offsets.time_offsets[0].offset_s * 1e3
                 << ", " << pnp.offsets.time_offsets[1].offset_s * 1e3 << " +- "
                 << pnp.offsets.time_offsets[1].sigma_s * 1e3 << "); hfe " << est.joint_offsets[1].offset_rad * 1e3 << " +- "
                 << est.joint_offsets[1].sigma_rad * 1e3 << " mrad (PnP: " << pnp.offsets.joint_offsets[1].offset_rad * 1e3
                 << " +- " << pnp.offsets.joint_offsets[1].sigma_rad * 1e3 << ")");
  CHECK(std::abs(est.time_offsets[0].offset_s) < 3e-4);
  CHECK(std::abs(est.time_offsets[1].offset_s - 0.015) < 3e-4);
  CHECK(est.joint_offsets[1].observed);
  CHECK(est.joint_offsets[1].offset_rad == Approx(0.01).margin(1e-3));
  CHECK(!est.joint_offsets[0].observed);
  CHECK(!est.joint_offsets[2].observed);
  for (int c = 0; c < 2; ++c) {
    CHECK(translationGapMm(sol.solution.cameras[c].T_base_cam, truth.cameras[c]) < 0.5);
    CHECK(rotationGapDeg(sol.solution.cameras[c].T_base_cam, truth.cameras[c]) < 0.05);
  }
}

TEST_CASE("a base-side joint offset goes into the cameras as much as reported") {
  Truth truth = defaultTruth();
  truth.joint_offsets << 0.01, 0.0, 0.0;
  Scene s = makeScene(truth, 4);
  s.input.offsets = model(s, false, true);
  const CalibrationSolution sol = solveCalibration(s.input);
  const auto& haa = sol.offsets.joint_offsets[0];
  REQUIRE(!haa.observed);
  for (int c = 0; c < 2; ++c) {
    const Absorption& a = haa.absorbed[static_cast<std::size_t>(c)];
    INFO("camera " << c << " absorbed " << translationGapMm(sol.cameras[c].T_base_cam, truth.cameras[c]) << " mm, "
                   << rotationGapDeg(sol.cameras[c].T_base_cam, truth.cameras[c]) << " deg; predicted "
                   << 10 * a.mm_per_mrad << " mm, " << 10 * a.deg_per_mrad << " deg");
    CHECK(rotationGapDeg(sol.cameras[c].T_base_cam, truth.cameras[c]) == Approx(10 * a.deg_per_mrad).epsilon(0.05));
    CHECK(translationGapMm(sol.cameras[c].T_base_cam, truth.cameras[c]) == Approx(10 * a.mm_per_mrad).epsilon(0.1));
  }
}
