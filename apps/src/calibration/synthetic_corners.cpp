// The seeded corner-level problem of synthetic_corners.hpp.
#include "calibration/synthetic_corners.hpp"

#include <cmath>
#include <random>
#include <stdexcept>

#include "fgcal/vision/pnp.hpp"

namespace fgcal::apps::synthetic {

namespace {

vision::CameraModel trueModel(const std::string& distortion, int c) {
  using vision::CameraModel;
  using vision::Distortion;
  using vision::Projection;
  const double s = 1.0 + 0.03 * c;  // cameras differ a little
  if (distortion == "equidistant")
    return CameraModel(Projection::Pinhole, Distortion::Equidistant, 300 * s, 301 * s, 641.5, 509.25,
                       {0.021, -0.006, 0.0012, -0.0002}, 1280, 1024);
  if (distortion == "radtan")
    return CameraModel(Projection::Pinhole, Distortion::RadTan, 560 * s, 562 * s, 515.5, 268.25,
                       {-0.21, 0.045, 2e-4, -3e-4}, 1024, 544);
  if (distortion == "none")
    return CameraModel(Projection::Pinhole, Distortion::None, 560 * s, 562 * s, 515.5, 268.25, {}, 1024, 544);
  throw std::invalid_argument("synthetic corner problem: distortion '" + distortion +
                              "' (expected none, radtan or equidistant)");
}

// The problem's random draws, in the order they are made: one generator for
// all, so that a seed gives one problem.
struct Random {
  std::mt19937 gen;
  std::uniform_real_distribution<double> u{-1.0, 1.0};
  std::normal_distribution<double> n{0.0, 1.0};
};

// The cameras at the front of the body, optical z forward and down, each with
// its true model (returned) and the rig's, off the truth as `opt` says.
std::vector<vision::CameraModel> addCameras(const CornerProblemOptions& opt, Random& rnd, CornerProblem& out) {
  std::mt19937& gen = rnd.gen;
  auto& u = rnd.u;
  CalibrationProblemInput& in = out.problem;
  CornerProblemInput& ci = out.corners;
  const SO3 look = SO3::fromRpy(-M_PI / 2 - 0.4, 0.0, -M_PI / 2);
  const Vec3 places[4] = {Vec3(0.55, 0.05, 0.05), Vec3(0.52, -0.06, 0.0), Vec3(0.55, -0.17, 0.05),
                          Vec3(0.5, 0.16, 0.1)};
  std::vector<vision::CameraModel> truth;
  for (int c = 0; c < opt.cameras; ++c) {
    out.true_cameras.push_back(SE3(look * SO3::exp(Vec3(0.02 * c, 0.1 * c, -0.03 * c)), places[c]));
    truth.push_back(trueModel(opt.distortion, c));
    out.true_intrinsics.push_back(truth.back().intrinsicsVector());
    VecX rig = truth.back().intrinsicsVector();
    const auto sign = [&] { return u(gen) < 0.0 ? -1.0 : 1.0; };
    rig[0] *= 1.0 + sign() * opt.intrinsics_error_pct / 100.0;
    rig[1] *= 1.0 + sign() * opt.intrinsics_error_pct / 100.0;
    rig[2] += sign() * opt.intrinsics_error_px;
    rig[3] += sign() * opt.intrinsics_error_px;
    CornerCamera cam{truth.back().withIntrinsics(rig), opt.pixel_sigma, VecX()};
    cam.intrinsics_sigma = VecX::Constant(rig.size(), 0.01);
    cam.intrinsics_sigma.head<4>() << 0.02 * rig[0], 0.02 * rig[1], 0.02 * cam.model.width(),
        0.02 * cam.model.height();
    ci.cameras.push_back(cam);
    in.camera_names.push_back("cam" + std::to_string(c));
    in.camera_guesses.push_back(std::nullopt);
  }
  return truth;
}

// The true mount, and the rig's prior on it, off the truth as `opt` says.
void setMount(const CornerProblemOptions& opt, CornerProblem& out) {
  CalibrationProblemInput& in = out.problem;
  out.true_mount = SE3(SO3::fromRpy(0.1, -0.05, 0.2), Vec3(0.01, -0.02, 0.03));
  Vec6 mount_err;
  mount_err << opt.mount_error_rad, -opt.mount_error_rad, 0.5 * opt.mount_error_rad, opt.mount_error_m,
      0.5 * opt.mount_error_m, -opt.mount_error_m;
  in.mount_prior = out.true_mount.plus(mount_err);
  in.mount_sigma_m = 0.005;
  in.mount_sigma_rad = 0.03;
  in.fiducial_covariance_scale = 1.0;  // the corner errors drawn here are independent
}

// The board's inner corners, in its frame.
std::vector<Vec3> boardCorners(const CornerProblemOptions& opt) {
  std::vector<Vec3> board;
  for (int y = 1; y < opt.squares_y; ++y)
    for (int x = 1; x < opt.squares_x; ++x) board.emplace_back(x * opt.square_size, y * opt.square_size, 0.0);
  return board;
}

// One instant's board and leg: the board's true pose and the link's pose as
// the encoders measure it, with their covariance.
struct Instant {
  SE3 T_base_marker;  // true
  SE3 link_measured;
  VecX q;
  std::int64_t stamp_ns = 0;
};

// Encoder noise through a 3-joint leg Jacobian: a rank-3 covariance, as the
// kinematics module gives it.
Eigen::Matrix<double, 6, 3> legJacobian() {
  Eigen::Matrix<double, 6, 3> Jq;
  Jq << 0.9, 0.1, 0.0, 0.1, 1.0, 1.0, 0.2, 0.0, 0.1, 0.0, 0.35, 0.3, 0.4, 0.0, 0.05, 0.1, 0.6, 0.35;
  return Jq;
}

// The board facing cam0 (its z along the optical axis), turned by up to
// ~35 deg, its centre 0.45-0.9 m out along a ray near the view's centre.
Instant drawInstant(const CornerProblemOptions& opt, const CornerProblem& out, int j, Random& rnd) {
  std::mt19937& gen = rnd.gen;
  auto& u = rnd.u;
  auto& n = rnd.n;
  const Eigen::Matrix<double, 6, 3> Jq = legJacobian();
  const Vec3 centre(0.5 * opt.squares_x * opt.square_size, 0.5 * opt.squares_y * opt.square_size, 0.0);
  const SE3& cam0 = out.true_cameras.front();
  const double lateral = opt.distortion == "equidistant" ? 0.7 : 0.12;
  const double d = 0.45 + 0.225 * (u(gen) + 1.0);
  const Vec3 at = cam0 * Vec3(lateral * d * u(gen), lateral * d * u(gen), d);
  const SO3 R = cam0.so3() * SO3::exp(Vec3(0.6 * u(gen), 0.6 * u(gen), 0.6 * u(gen)));
  const SE3 L(R, at - R.matrix() * centre);
  const SE3 link_true = L * out.true_mount.inverse();
  Instant inst;
  inst.T_base_marker = L;
  inst.q.resize(3);
  inst.q << u(gen), u(gen), u(gen);
  const Eigen::Vector3d dq(opt.encoder_sigma * n(gen), opt.encoder_sigma * n(gen), opt.encoder_sigma * n(gen));
  inst.link_measured = link_true.plus(Jq * dq);
  inst.stamp_ns = 1'000'000'000LL + j * 33'333'333LL;
  return inst;
}

// Camera c's detected corners of the board at T_cam_marker: those inside the
// image, with pixel noise.
ImageCorners imageCorners(const CornerProblemOptions& opt, const vision::CameraModel& truth, const SE3& T_cam_marker,
                          const std::vector<Vec3>& board, Random& rnd) {
  std::mt19937& gen = rnd.gen;
  auto& n = rnd.n;
  ImageCorners im;
  for (const Vec3& p : board) {
    const auto uv = truth.project(T_cam_marker * p);
    if (!uv || uv->x() < 1.0 || uv->y() < 1.0 || uv->x() > truth.width() - 2.0 || uv->y() > truth.height() - 2.0)
      continue;
    im.board_points.push_back(p);
    const double noise = opt.pixel_noise < 0.0 ? opt.pixel_sigma : opt.pixel_noise;
    im.pixels.push_back(*uv + noise * Eigen::Vector2d(n(gen), n(gen)));
  }
  return im;
}

// Adds camera c's image of the instant, as the pipeline would: skipped with
// fewer than 6 corners or without a PnP pose.
void addImage(const CornerProblemOptions& opt, const Instant& inst, int c, ImageCorners im, const Mat6& fk,
              CornerProblem& out) {
  if (im.pixels.size() < 6) return;
  vision::PoseEstimate pose;
  try {
    vision::PnpOptions pnp;
    pnp.pixel_sigma = opt.pixel_sigma;
    pose = vision::estimatePose(out.corners.cameras[static_cast<std::size_t>(c)].model, im.board_points, im.pixels,
                                pnp);
  } catch (const std::exception&) {
    return;
  }
  BoardObservation o;
  o.camera = c;
  o.stamp_ns = inst.stamp_ns + c * 200'000;
  o.T_cam_marker = pose.T_cam_marker;
  o.covariance = pose.covariance;
  o.T_base_link = inst.link_measured;
  o.link_covariance = fk;
  o.joint_positions = inst.q;
  out.problem.observations.push_back(std::move(o));
  out.corners.corners.push_back(std::move(im));
}

}  // namespace

CornerProblem makeCornerProblem(const CornerProblemOptions& opt) {
  if (opt.cameras < 1 || opt.cameras > 4) throw std::invalid_argument("synthetic corner problem: 1..4 cameras");
  if (opt.instants < 3) throw std::invalid_argument("synthetic corner problem: at least 3 instants");
  if (opt.squares_x < 3 || opt.squares_y < 3) throw std::invalid_argument("synthetic corner problem: board >= 3x3");
  Random rnd{std::mt19937(opt.seed)};
  CornerProblem out;
  const std::vector<vision::CameraModel> truth = addCameras(opt, rnd, out);
  setMount(opt, out);
  const std::vector<Vec3> board = boardCorners(opt);
  const Eigen::Matrix<double, 6, 3> Jq = legJacobian();
  const Mat6 fk = opt.encoder_sigma * opt.encoder_sigma * Jq * Jq.transpose();
  for (int j = 0; j < opt.instants; ++j) {
    const Instant inst = drawInstant(opt, out, j, rnd);
    for (int c = 0; c < opt.cameras; ++c) {
      if (rnd.u(rnd.gen) > 2.0 * opt.see_probability - 1.0) continue;
      const SE3 T_cam_marker = out.true_cameras[static_cast<std::size_t>(c)].between(inst.T_base_marker);
      addImage(opt, inst, c, imageCorners(opt, truth[static_cast<std::size_t>(c)], T_cam_marker, board, rnd), fk,
               out);
    }
  }
  return out;
}

}  // namespace fgcal::apps::synthetic
