#include "calibration_problem.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/factors/relative_pose_factor.hpp"

namespace fgcal::bench {

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kMm = 1e-3;

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : gen_(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(gen_); }
  double normal() { return normal_(gen_); }
  bool bernoulli(double p) { return uniform(0.0, 1.0) < p; }
  int index(int n) { return std::uniform_int_distribution<int>(0, n - 1)(gen_); }
  Vec3 normal3() { return Vec3(normal(), normal(), normal()); }
  Vec6 normal6() {
    Vec6 x;
    for (int i = 0; i < 6; ++i) x[i] = normal();
    return x;
  }

 private:
  std::mt19937_64 gen_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

// Rotation whose z axis (optical axis, or the board normal) points along
// `forward`, x to the right of it, y down: OpenCV's camera convention.
Mat3 lookAlong(const Vec3& forward) {
  const Vec3 z = forward.normalized();
  Vec3 x = z.cross(Vec3::UnitZ());
  if (x.norm() < 1e-6) x = Vec3::UnitY();
  x.normalize();
  const Vec3 y = z.cross(x);
  Mat3 R;
  R << x, y, z;
  return R;
}

// A full 6x6 covariance with the given per-axis sigmas and random correlations.
Mat6 correlatedCovariance(Rng& rng, const Vec6& sigmas, double spread) {
  Mat6 A;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) A(i, j) = rng.normal();
  const Mat6 Q = Eigen::HouseholderQR<Mat6>(A).householderQ();
  Vec6 lambda;
  for (int i = 0; i < 6; ++i) lambda[i] = rng.uniform(1.0 - spread, 1.0 + spread);
  const Mat6 C = Q * lambda.asDiagonal() * Q.transpose();
  // Normalize to a correlation matrix, then scale by the sigmas.
  const Vec6 d = C.diagonal().cwiseSqrt().cwiseInverse();
  const Mat6 corr = d.asDiagonal() * C * d.asDiagonal();
  return sigmas.asDiagonal() * corr * sigmas.asDiagonal();
}

// Measured = truth * Exp(noise) with noise ~ N(0, covariance); returns the
// measurement with W (upper triangular, W^T W = covariance^-1).
PoseMeasurement measure(Rng& rng, const SE3& truth, const Mat6& covariance) {
  const Eigen::LLT<Mat6> llt(covariance);
  const Vec6 xi = llt.matrixL() * rng.normal6();
  const Mat6 information = covariance.inverse();
  const Eigen::LLT<Mat6> llt_info(0.5 * (information + information.transpose()));
  return {truth.plus(xi), Mat6(llt_info.matrixU())};
}

}  // namespace

CalibrationProblem makeCalibrationProblem(const CalibrationProblemOptions& opt) {
  Rng rng(opt.seed);
  CalibrationProblem p;
  p.cameras = opt.cameras;
  p.frames = opt.frames;

  // Cameras on the front half of a 1.0 x 0.4 x 0.25 m body (base frame: x
  // forward, z up), each looking at a point of the workspace in front and
  // below, where the foot carrying the board moves.
  for (int i = 0; i < opt.cameras; ++i) {
    const Vec3 position(rng.uniform(0.1, 0.5), rng.uniform(-0.2, 0.2), rng.uniform(-0.12, 0.12));
    const Vec3 target(0.9 + rng.uniform(-0.2, 0.2), rng.uniform(-0.25, 0.25), -0.3 + rng.uniform(-0.15, 0.15));
    const SE3 T_base_cam(SO3(lookAlong(target - position)), position);
    p.true_cameras.push_back(T_base_cam);
    // Start: a few cm and a few degrees off.
    Vec6 perturbation;
    perturbation << 3.0 * kDeg * rng.normal3(), 0.03 * rng.normal3();
    p.initial_cameras.push_back(T_base_cam.plus(perturbation));
  }

  p.board_priors.reserve(static_cast<std::size_t>(opt.frames));
  p.observations.reserve(static_cast<std::size_t>(opt.frames * opt.cameras * opt.see_probability * 1.05) + 16);
  std::vector<int> seen;
  for (int j = 0; j < opt.frames; ++j) {
    // Board in the workspace, facing the robot with up to ~25 deg of tilt.
    const Vec3 position(rng.uniform(0.6, 1.3), rng.uniform(-0.5, 0.5), rng.uniform(-0.6, 0.1));
    const Mat3 R_face = lookAlong(position - Vec3(0.3, 0.0, 0.0));
    const SE3 T_base_marker(SO3(R_face * SO3::exp(0.25 * rng.normal3()).matrix()), position);
    p.true_boards.push_back(T_base_marker);

    // Kinematic prior: ~1.5 mm and ~0.3 deg, correlated.
    Vec6 prior_sigmas;
    prior_sigmas << Vec3::Constant(0.3 * kDeg), Vec3::Constant(1.5 * kMm);
    p.board_priors.push_back(measure(rng, T_base_marker, correlatedCovariance(rng, prior_sigmas, 0.7)));
    p.initial_boards.push_back(p.board_priors.back().measured);

    seen.clear();
    for (int i = 0; i < opt.cameras; ++i)
      if (rng.bernoulli(opt.see_probability)) seen.push_back(i);
    if (seen.empty()) seen.push_back(rng.index(opt.cameras));
    for (int i : seen) {
      const SE3 T_cam_marker = p.true_cameras[static_cast<std::size_t>(i)].inverse() * T_base_marker;
      // PnP-like covariance in the camera frame (left perturbation): precise
      // across the image (0.5 mm, 0.05 deg in-plane), worse in depth and tilt,
      // with the tilt/lateral-shift correlation of a planar target.
      // Visibility is drawn at random, not from geometry: clamp the depth so
      // that a board beside or behind a camera still gets a sane covariance.
      const double depth = std::clamp(std::abs(T_cam_marker.translation().z()), 0.3, 2.5) / 0.8;
      Vec6 s;
      s << 0.2 * kDeg, 0.2 * kDeg, 0.05 * kDeg, 0.5 * kMm * depth, 0.5 * kMm * depth, 2.0 * kMm * depth * depth;
      Mat6 corr = Mat6::Identity();
      corr(1, 3) = corr(3, 1) = 0.6;   // rotation about y <-> shift along x
      corr(0, 4) = corr(4, 0) = -0.6;  // rotation about x <-> shift along y
      const Mat6 cov_cam = s.asDiagonal() * corr * s.asDiagonal();
      // To the right perturbation of T_cam_marker: xi_marker = Ad(Z^-1) xi_cam.
      const Mat6 Ad = T_cam_marker.inverse().adjoint();
      Mat6 cov = Ad * cov_cam * Ad.transpose();
      cov = 0.5 * (cov + cov.transpose());
      p.observations.push_back({i, j, measure(rng, T_cam_marker, cov)});
    }
  }
  return p;
}

void buildFgcalProblem(const CalibrationProblem& p, FactorGraph& graph, Values& initial) {
  graph.reserve(p.numFactors());
  for (int i = 0; i < p.cameras; ++i) initial.insert(cameraKey(i), p.initial_cameras[static_cast<std::size_t>(i)]);
  for (int j = 0; j < p.frames; ++j) initial.insert(boardKey(j), p.initial_boards[static_cast<std::size_t>(j)]);
  auto noise = [](const Mat6& W) { return NoiseModel::fromInformation(MatX(W.transpose() * W)); };
  std::size_t o = 0;
  for (int j = 0; j < p.frames; ++j) {
    const PoseMeasurement& prior = p.board_priors[static_cast<std::size_t>(j)];
    graph.emplace<PriorFactorSE3>(boardKey(j), prior.measured, noise(prior.sqrt_information));
    for (; o < p.observations.size() && p.observations[o].frame == j; ++o) {
      const Observation& ob = p.observations[o];
      graph.emplace<RelativePoseFactor>(cameraKey(ob.camera), boardKey(j), ob.z.measured, noise(ob.z.sqrt_information));
    }
  }
}

}  // namespace fgcal::bench
