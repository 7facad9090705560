// Cameras, workspace, board mount and view quality of the simulated scene.
#include "commands/simulate/scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace fgcal::apps::sim {

std::uint64_t mixSeed(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  auto splitmix = [](std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ULL;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
    return x ^ (x >> 31);
  };
  return splitmix(splitmix(splitmix(a) ^ b) ^ c);
}

void jointRanges(const kinematics::KinematicChain& chain, VecX* lower, VecX* upper) {
  const auto limits = chain.jointLimits();
  lower->resize(chain.numJoints());
  upper->resize(chain.numJoints());
  for (int i = 0; i < chain.numJoints(); ++i) {
    const auto& l = limits[static_cast<size_t>(i)];
    const bool limited = l.has_position_limits && std::isfinite(l.lower) && std::isfinite(l.upper) &&
                         l.upper > l.lower;
    (*lower)(i) = limited ? l.lower : -M_PI;
    (*upper)(i) = limited ? l.upper : M_PI;
  }
}

VecX sampleJoints(const kinematics::KinematicChain& chain, Rng& rng) {
  VecX lo, hi;
  jointRanges(chain, &lo, &hi);
  VecX q(chain.numJoints());
  for (int i = 0; i < q.size(); ++i) q(i) = rng.uniform(lo(i), hi(i));
  return q;
}

Workspace sampleWorkspace(const kinematics::KinematicChain& chain, const SE3& T_base_hip, Rng& rng,
                          int n_samples) {
  Workspace ws;
  ws.hip = T_base_hip.translation();
  ws.samples.reserve(static_cast<size_t>(n_samples));
  ws.T_base_link.reserve(static_cast<size_t>(n_samples));
  for (int k = 0; k < n_samples; ++k) {
    ws.samples.push_back(sampleJoints(chain, rng));
    ws.T_base_link.push_back(chain.forward(ws.samples.back()));
    ws.reach = std::max(ws.reach, (ws.T_base_link.back().translation() - ws.hip).norm());
  }
  // Raised forward: well in front of the hip (x forward, REP 103), not swung
  // out sideways (the leg is held in front of the body), upper half.
  std::vector<size_t> front;
  const double side = ws.hip.y() >= 0.0 ? 1.0 : -1.0;
  for (size_t k = 0; k < ws.samples.size(); ++k) {
    const Vec3 p = ws.T_base_link[k].translation();
    if (p.x() - ws.hip.x() > 0.4 * ws.reach && side * (p.y() - ws.hip.y()) < 0.1 * ws.reach) front.push_back(k);
  }
  if (front.size() < ws.samples.size() / 20) {  // an unusual leg: the most forward tenth
    std::vector<size_t> all(ws.samples.size());
    for (size_t k = 0; k < all.size(); ++k) all[k] = k;
    std::sort(all.begin(), all.end(), [&](size_t a, size_t b) {
      return ws.T_base_link[a].translation().x() > ws.T_base_link[b].translation().x();
    });
    front.assign(all.begin(), all.begin() + std::max<size_t>(1, all.size() / 10));
  }
  std::sort(front.begin(), front.end(), [&](size_t a, size_t b) {
    return ws.T_base_link[a].translation().z() > ws.T_base_link[b].translation().z();
  });
  front.resize(std::max<size_t>(1, front.size() / 2));
  ws.target.setZero();
  for (size_t k : front) ws.target += ws.T_base_link[k].translation();
  ws.target /= static_cast<double>(front.size());
  double best = std::numeric_limits<double>::infinity();
  for (size_t k : front) {
    const double d = (ws.T_base_link[k].translation() - ws.target).norm();
    if (d < best) {
      best = d;
      ws.q_typical = ws.samples[k];
    }
  }
  return ws;
}

namespace {

struct CameraSpec {
  const char* name;
  int width, height;
  double fx, fy, cx, cy;
  std::array<double, 4> radtan, equidistant;
  Vec3 offset;       // from the head point, metres at the default robot's scale
  Vec3 look_offset;  // from the workspace target
  double roll_deg;
  bool stereo_partner;  // same orientation as cam0
};

// cam0/cam1 as on HyQ (Multisense SL left camera, ASUS Xtion RGB camera below
// it); cam2 the Multisense right camera (7 cm baseline); cam3 a wide camera.
const std::array<CameraSpec, 4>& cameraSpecs() {
  static const std::array<CameraSpec, 4> specs{{
      {"multisense_left", 1024, 544, 590.0, 590.0, 514.3, 270.6, {-0.05, 0.01, 1e-4, -1e-4},
       {-0.01, 0.003, -0.001, 0.0002}, Vec3(0.0, 0.035, 0.0), Vec3::Zero(), 0.0, false},
      {"xtion_rgb", 640, 480, 525.0, 525.0, 319.2, 241.7, {0.03, -0.08, 2e-4, 1e-4},
       {0.02, -0.01, 0.002, -0.0005}, Vec3(0.03, -0.03, -0.10), Vec3(0.0, 0.0, -0.04), 1.5, false},
      {"multisense_right", 1024, 544, 591.5, 591.5, 510.8, 272.9, {-0.048, 0.009, -1e-4, 1e-4},
       {-0.011, 0.0028, -0.0009, 0.00018}, Vec3(0.0, -0.035, 0.0), Vec3::Zero(), 0.0, true},
      {"head_wide", 800, 600, 430.0, 430.0, 402.5, 297.1, {-0.12, 0.025, 3e-4, -2e-4},
       {-0.03, 0.006, -0.002, 0.0004}, Vec3(-0.03, 0.11, 0.04), Vec3(0.0, 0.03, 0.0), -2.0, false},
  }};
  return specs;
}

// Camera frame (x right, y down, z along the optical axis) looking from `eye`
// at `at`, image x towards the robot's right, then rolled about its axis.
// The rotation whose columns are x, z x x and z, for unit z and a unit x
// orthogonal to it.
SO3 frameFromZX(const Vec3& z, const Vec3& x) {
  Mat3 R;
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  return SO3(R);
}

SO3 lookAt(const Vec3& eye, const Vec3& at, double roll_rad) {
  const Vec3 z = (at - eye).normalized();
  Vec3 x = z.cross(Vec3::UnitZ());
  if (x.norm() < 1e-6) x = -Vec3::UnitY();
  return frameFromZX(z, x.normalized()) * SO3::exp(Vec3(0, 0, roll_rad));
}

void fieldOfView(SimCamera* cam) {
  const auto& m = cam->model;
  cam->x_min = cam->y_min = std::numeric_limits<double>::infinity();
  cam->x_max = cam->y_max = -std::numeric_limits<double>::infinity();
  auto add = [&](double u, double v) {
    const auto ray = m.unproject(vision::Vec2(u, v));
    if (!ray || ray->z() <= 1e-6) return;
    cam->x_min = std::min(cam->x_min, ray->x() / ray->z());
    cam->x_max = std::max(cam->x_max, ray->x() / ray->z());
    cam->y_min = std::min(cam->y_min, ray->y() / ray->z());
    cam->y_max = std::max(cam->y_max, ray->y() / ray->z());
  };
  const int W = m.width(), H = m.height();
  for (int i = 0; i <= 32; ++i) {
    const double u = (W - 1) * i / 32.0, v = (H - 1) * i / 32.0;
    add(u, 0);
    add(u, H - 1);
    add(0, v);
    add(W - 1, v);
  }
}

}  // namespace

std::vector<std::string> cameraNames(int count) {
  std::vector<std::string> names;
  for (int i = 0; i < count && i < static_cast<int>(cameraSpecs().size()); ++i)
    names.emplace_back(cameraSpecs()[static_cast<size_t>(i)].name);
  return names;
}

vision::CameraModel withFieldOfView(const vision::CameraModel& m, double fov_deg) {
  const double half = 0.5 * fov_deg * M_PI / 180.0;
  const double r = m.distort(vision::Vec2(std::tan(half), 0.0)).x();
  const double fx = 0.5 * m.width() / r;
  return vision::CameraModel(m.projection(), m.distortion(), fx, fx * m.fy() / m.fx(), m.cx(), m.cy(), m.coeffs(),
                             m.width(), m.height());
}

std::string projectionFolds(const vision::CameraModel& m) {
  const vision::Vec2 c(m.cx(), m.cy());
  const double W = m.width() - 1.0, H = m.height() - 1.0;
  const std::array<vision::Vec2, 8> border{{{0, 0}, {W, 0}, {0, H}, {W, H}, {0.5 * W, 0}, {0.5 * W, H}, {0, 0.5 * H},
                                            {W, 0.5 * H}}};
  for (const vision::Vec2& end : border) {
    double last_angle = -1.0;
    for (int i = 1; i <= 64; ++i) {
      const vision::Vec2 uv = c + (end - c) * (i / 64.0);
      const auto ray = m.unproject(uv);
      const auto back = ray && ray->z() > 0.02 ? m.project(*ray) : std::nullopt;
      const std::string where = "pixel (" + std::to_string(static_cast<int>(uv.x())) + ", " +
                                std::to_string(static_cast<int>(uv.y())) + ")";
      if (!back || (*back - uv).norm() > 1e-3) return "no viewing ray in front of the camera at " + where;
      const double angle = std::acos(std::clamp(ray->z(), -1.0, 1.0));
      if (angle <= last_angle) return "the distortion folds back at " + where;
      last_angle = angle;
    }
  }
  return "";
}

std::vector<SimCamera> makeCameras(int count, const std::string& distortion, const Workspace& ws, int width,
                                   int height, double fov_deg) {
  // Head point: the cameras look down 30 degrees at the workspace target from
  // 0.55 m (the middle of the 0.3-0.9 m working range for a 20 x 28 cm board),
  // from the robot's centre line when the leg's reach allows.
  const double D = 0.55, elevation = 30.0 * M_PI / 180.0;
  const double hd = D * std::cos(elevation), vd = D * std::sin(elevation);
  // The cameras look straight ahead more than a leg's sideways offset would
  // ask for (as on HyQ): at a point halfway between the workspace and the
  // centre line.
  const Vec3 P(ws.target.x(), 0.5 * ws.target.y(), ws.target.z());
  const double head_y = std::abs(P.y()) < 0.8 * hd ? 0.0 : P.y() - std::copysign(0.8 * hd, P.y());
  const double dy = P.y() - head_y;
  const Vec3 head(P.x() - std::sqrt(std::max(0.0, hd * hd - dy * dy)), head_y, P.z() + vd);
  // Offsets between the cameras scale with the leg (1 at the default robot's reach).
  const double scale = std::clamp(ws.reach / 0.78, 0.5, 1.5);

  std::vector<SimCamera> cams;
  for (int i = 0; i < count; ++i) {
    const CameraSpec& s = cameraSpecs()[static_cast<size_t>(i)];
    std::vector<double> coeffs;
    if (distortion == "radtan") coeffs.assign(s.radtan.begin(), s.radtan.end());
    if (distortion == "equidistant") coeffs.assign(s.equidistant.begin(), s.equidistant.end());
    SimCamera cam;
    cam.name = s.name;
    if (width > 0 && height > 0) {
      const double k = std::min(static_cast<double>(width) / s.width, static_cast<double>(height) / s.height);
      cam.model = vision::CameraModel::fromKalibr(
          "pinhole", distortion,
          {k * s.fx, k * s.fy, 0.5 * width + k * (s.cx - 0.5 * s.width), 0.5 * height + k * (s.cy - 0.5 * s.height)},
          coeffs, {width, height});
    } else {
      cam.model = vision::CameraModel::fromKalibr("pinhole", distortion, {s.fx, s.fy, s.cx, s.cy}, coeffs,
                                                  {s.width, s.height});
    }
    if (fov_deg > 0.0) cam.model = withFieldOfView(cam.model, fov_deg);
    const Vec3 eye = head + scale * s.offset;
    const SO3 R = s.stereo_partner && !cams.empty()
                      ? cams.front().T_base_cam.so3()
                      : lookAt(eye, P + scale * s.look_offset, s.roll_deg * M_PI / 180.0);
    cam.T_base_cam = SE3(R, eye);
    fieldOfView(&cam);
    cams.push_back(std::move(cam));
  }
  return cams;
}

SE3 designMount(const Workspace& ws, const kinematics::KinematicChain& chain,
                const std::vector<SimCamera>& cameras, const vision::CharucoTarget& target) {
  const SE3 T_base_link = chain.forward(ws.q_typical);
  Vec3 eye = Vec3::Zero();
  for (const auto& c : cameras) eye += c.T_base_cam.translation();
  eye /= static_cast<double>(cameras.size());
  const Vec3 foot = T_base_link.translation();
  // Board z points away from the viewer (OpenCV's board frame): from the cameras to the foot.
  const Vec3 z = (foot - eye).normalized();
  Vec3 x = -Vec3::UnitY() - (-Vec3::UnitY()).dot(z) * z;  // image right = robot's right
  if (x.norm() < 1e-6) x = Vec3::UnitX() - Vec3::UnitX().dot(z) * z;
  const SO3 R = frameFromZX(z, x.normalized());
  // Board centre 3 cm in front of the link origin, towards the cameras.
  const Vec3 centre = foot - 0.03 * z;
  const Vec3 half(0.5 * target.squares_x * target.square_size, 0.5 * target.squares_y * target.square_size, 0.0);
  const SE3 T_base_marker(R, centre - R * half);
  return T_base_link.inverse() * T_base_marker;
}

ViewQuality viewQuality(const SimCamera& camera, const SE3& T_base_marker, const vision::CharucoTarget& target,
                        double margin_px) {
  ViewQuality q;
  const SE3 T_cam_marker = camera.T_base_cam.inverse() * T_base_marker;
  const double W = target.squares_x * target.square_size, H = target.squares_y * target.square_size;
  const Vec3 centre = T_cam_marker * Vec3(0.5 * W, 0.5 * H, 0.0);
  q.distance = centre.norm();
  // The board faces the camera along -z_board; the ray from the board to the camera is -centre.
  const double c = T_cam_marker.rotation().col(2).dot(centre) / std::max(q.distance, 1e-12);
  q.angle = std::acos(std::clamp(c, -1.0, 1.0));
  const auto& m = camera.model;
  auto inside = [&](const Vec3& corner) {
    const Vec3 p = T_cam_marker * corner;
    if (p.z() < 0.05) return false;
    const double xn = p.x() / p.z(), yn = p.y() / p.z();
    if (xn < camera.x_min || xn > camera.x_max || yn < camera.y_min || yn > camera.y_max) return false;
    const auto uv = m.project(p);
    return uv && uv->x() >= margin_px && uv->y() >= margin_px && uv->x() <= m.width() - 1 - margin_px &&
           uv->y() <= m.height() - 1 - margin_px;
  };
  q.in_image = inside(Vec3(0, 0, 0)) && inside(Vec3(W, 0, 0)) && inside(Vec3(0, H, 0)) && inside(Vec3(W, H, 0));
  return q;
}

}  // namespace fgcal::apps::sim
