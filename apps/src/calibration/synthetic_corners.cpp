// The seeded corner-level problem of synthetic_corners.hpp.
#include "synthetic_corners.hpp"

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

}  // namespace

CornerProblem makeCornerProblem(const CornerProblemOptions& opt) {
  if (opt.cameras < 1 || opt.cameras > 4) throw std::invalid_argument("synthetic corner problem: 1..4 cameras");
  if (opt.instants < 3) throw std::invalid_argument("synthetic corner problem: at least 3 instants");
  if (opt.squares_x < 3 || opt.squares_y < 3) throw std::invalid_argument("synthetic corner problem: board >= 3x3");
  std::mt19937 gen(opt.seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  const bool fisheye = opt.distortion == "equidistant";

  CornerProblem out;
  CalibrationProblemInput& in = out.problem;
  CornerProblemInput& ci = out.corners;
  // Cameras at the front of the body, optical z forward and down.
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
  out.true_mount = SE3(SO3::fromRpy(0.1, -0.05, 0.2), Vec3(0.01, -0.02, 0.03));
  Vec6 mount_err;
  mount_err << opt.mount_error_rad, -opt.mount_error_rad, 0.5 * opt.mount_error_rad, opt.mount_error_m,
      0.5 * opt.mount_error_m, -opt.mount_error_m;
  in.mount_prior = out.true_mount.plus(mount_err);
  in.mount_sigma_m = 0.005;
  in.mount_sigma_rad = 0.03;
  in.fiducial_covariance_scale = 1.0;  // the corner errors drawn here are independent

  std::vector<Vec3> board;
  for (int y = 1; y < opt.squares_y; ++y)
    for (int x = 1; x < opt.squares_x; ++x) board.emplace_back(x * opt.square_size, y * opt.square_size, 0.0);
  const Vec3 centre(0.5 * opt.squares_x * opt.square_size, 0.5 * opt.squares_y * opt.square_size, 0.0);

  // Encoder noise through a 3-joint leg Jacobian: a rank-3 covariance, as the
  // kinematics module gives it.
  Eigen::Matrix<double, 6, 3> Jq;
  Jq << 0.9, 0.1, 0.0, 0.1, 1.0, 1.0, 0.2, 0.0, 0.1, 0.0, 0.35, 0.3, 0.4, 0.0, 0.05, 0.1, 0.6, 0.35;
  const Mat6 fk = opt.encoder_sigma * opt.encoder_sigma * Jq * Jq.transpose();
  const SE3& cam0 = out.true_cameras.front();
  const double lateral = fisheye ? 0.7 : 0.12;
  for (int j = 0; j < opt.instants; ++j) {
    // The board facing cam0 (its z along the optical axis), turned by up to
    // ~35 deg, its centre 0.45-0.9 m out along a ray near the view's centre.
    const double d = 0.45 + 0.225 * (u(gen) + 1.0);
    const Vec3 at = cam0 * Vec3(lateral * d * u(gen), lateral * d * u(gen), d);
    const SO3 R = cam0.so3() * SO3::exp(Vec3(0.6 * u(gen), 0.6 * u(gen), 0.6 * u(gen)));
    const SE3 L(R, at - R.matrix() * centre);
    const SE3 link_true = L * out.true_mount.inverse();
    VecX q(3);
    q << u(gen), u(gen), u(gen);
    const Eigen::Vector3d dq(opt.encoder_sigma * n(gen), opt.encoder_sigma * n(gen), opt.encoder_sigma * n(gen));
    const SE3 link_measured = link_true.plus(Jq * dq);
    const std::int64_t stamp = 1'000'000'000LL + j * 33'333'333LL;
    for (int c = 0; c < opt.cameras; ++c) {
      if (u(gen) > 2.0 * opt.see_probability - 1.0) continue;
      const SE3 T_cam_marker = out.true_cameras[static_cast<std::size_t>(c)].between(L);
      ImageCorners im;
      for (const Vec3& p : board) {
        const auto uv = truth[static_cast<std::size_t>(c)].project(T_cam_marker * p);
        if (!uv || uv->x() < 1.0 || uv->y() < 1.0 || uv->x() > truth[static_cast<std::size_t>(c)].width() - 2.0 ||
            uv->y() > truth[static_cast<std::size_t>(c)].height() - 2.0)
          continue;
        im.board_points.push_back(p);
        const double noise = opt.pixel_noise < 0.0 ? opt.pixel_sigma : opt.pixel_noise;
        im.pixels.push_back(*uv + noise * Eigen::Vector2d(n(gen), n(gen)));
      }
      if (im.pixels.size() < 6) continue;
      vision::PoseEstimate pose;
      try {
        vision::PnpOptions pnp;
        pnp.pixel_sigma = opt.pixel_sigma;
        pose = vision::estimatePose(ci.cameras[static_cast<std::size_t>(c)].model, im.board_points, im.pixels, pnp);
      } catch (const std::exception&) {
        continue;  // as the pipeline does: an image without a pose is skipped
      }
      BoardObservation o;
      o.camera = c;
      o.stamp_ns = stamp + c * 200'000;
      o.T_cam_marker = pose.T_cam_marker;
      o.covariance = pose.covariance;
      o.T_base_link = link_measured;
      o.link_covariance = fk;
      o.joint_positions = q;
      in.observations.push_back(std::move(o));
      ci.corners.push_back(std::move(im));
    }
  }
  return out;
}

}  // namespace fgcal::apps::synthetic
