// The corner reprojection factor: Jacobians (camera pose, board pose,
// intrinsics) against central differences for every camera model, at poses
// away from zero residual; the prediction against CameraModel::project; the
// clamp behind the camera; and that evaluate() allocates nothing (the
// solver calls it some 10^5 times per iteration).
#include <random>

#include "fgcal/factors/corner_factor.hpp"
#include "fgcal_test/allocation_counter.hpp"
#include "fgcal_test/jacobian_check.hpp"


using namespace fgcal;
using vision::CameraModel;
using vision::Distortion;
using vision::Projection;

namespace {

std::vector<std::shared_ptr<const CameraModel>> cameras() {
  return {
      std::make_shared<CameraModel>(Projection::Pinhole, Distortion::None, 500, 505, 320, 240,
                                    std::vector<double>{}, 640, 480),
      std::make_shared<CameraModel>(Projection::Pinhole, Distortion::RadTan, 610, 612, 512.5, 271.25,
                                    std::vector<double>{-0.28, 0.07, 1e-4, -2e-4}, 1024, 544),
      std::make_shared<CameraModel>(Projection::Pinhole, Distortion::RadTan, 452.51, 456.77, 317.70, 277.75,
                                    std::vector<double>{0.12137, -1.08547, 1.1787e-4, -4.6241e-4, 2.95426}, 640,
                                    480),
      std::make_shared<CameraModel>(Projection::Pinhole, Distortion::Equidistant, 280, 281, 640, 512,
                                    std::vector<double>{0.05, -0.01, 0.004, -0.0007}, 1280, 1024),
  };
}

// A camera in the base frame and a board 0.4-1 m in front of it, turned
// towards it by up to ~50 deg, with a board point near its middle: the corner
// is in front of the camera and the detection u is off the prediction by a
// few pixels (a non-zero residual).
struct Scene {
  SE3 X, L;
  Vec3 p;
  Eigen::Vector2d u;
};

Scene randomScene(std::mt19937& rng, const CameraModel& cam) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> depth(0.4, 1.0);
  Scene s;
  s.X = SE3(SO3::exp(Vec3(n(rng), n(rng), n(rng))), Vec3(n(rng), n(rng), n(rng)) * 0.3);
  const SE3 T_cam_marker(SO3::exp(Vec3(M_PI + 0.5 * n(rng), 0.5 * n(rng), 0.5 * n(rng))),
                         Vec3(0.1 * n(rng), 0.1 * n(rng), depth(rng)));
  s.L = s.X * T_cam_marker;
  s.p = Vec3(0.1 + 0.05 * n(rng), 0.14 + 0.05 * n(rng), 0.0);
  s.u = *cam.project(T_cam_marker * s.p) + Eigen::Vector2d(3.0 * n(rng), 3.0 * n(rng));
  return s;
}

}  // namespace

TEST_CASE("corner factor: Jacobians by camera pose, board pose and intrinsics", "[factors][corner]") {
  std::mt19937 rng(11);
  const Key X = key('c', 0), L = key('b', 3), K = key('k', 0);
  for (const auto& cam : cameras()) {
    INFO("distortion " << vision::toString(cam->distortion()) << ", " << cam->intrinsicsSize() << " intrinsics");
    for (int i = 0; i < 20; ++i) {
      const Scene s = randomScene(rng, *cam);
      Values v;
      v.insert(X, s.X);
      v.insert(L, s.L);
      CornerFactor::insertIntrinsics(v, K, *cam);
      const CornerFactor fixed(X, L, cam, s.p, s.u, NoiseModel::isotropic(2, 0.5));
      const CornerFactor estimated(X, L, K, cam, s.p, s.u, NoiseModel::isotropic(2, 0.5));
      CHECK(fixed.error(v).norm() > 0.1);
      auto bad = checkFactorJacobians(fixed, v);
      INFO((bad.empty() ? "" : bad[0].message));
      CHECK(bad.empty());
      bad = checkFactorJacobians(estimated, v);
      INFO((bad.empty() ? "" : bad[0].message));
      CHECK(bad.empty());
      // Both predict what CameraModel::project predicts.
      const Eigen::Vector2d expected = *cam->project(s.X.inverse() * s.L * s.p) - s.u;
      CHECK((fixed.error(v) - expected).norm() < 1e-9);
      CHECK((estimated.error(v) - expected).norm() < 1e-9);
    }
  }
}

TEST_CASE("corner factor: the intrinsics variable moves the prediction as another camera would",
          "[factors][corner]") {
  std::mt19937 rng(13);
  for (const auto& cam : cameras()) {
    const Scene s = randomScene(rng, *cam);
    VecX k = cam->intrinsicsVector();
    k[0] *= 1.01;
    k[3] -= 3.0;
    if (k.size() > 4) k[4] += 0.01;  // a distortion coefficient, when the model has one
    const CameraModel other = cam->withIntrinsics(k);
    Values v;
    v.insert(key('c', 0), s.X);
    v.insert(key('b', 0), s.L);
    CornerFactor::insertIntrinsics(v, key('k', 0), other);
    CHECK(CornerFactor::intrinsicsAt(v, key('k', 0)) == k);
    const CornerFactor f(key('c', 0), key('b', 0), key('k', 0), cam, s.p, s.u, NoiseModel::isotropic(2, 1.0));
    CHECK((f.error(v) - (*other.project(s.X.inverse() * s.L * s.p) - s.u)).norm() < 1e-9);
    // Jacobians where the intrinsics are away from the camera's own.
    const auto bad = checkFactorJacobians(f, v);
    INFO((bad.empty() ? "" : bad[0].message));
    CHECK(bad.empty());
  }
}

TEST_CASE("corner factor: a point behind the camera gives a huge finite residual", "[factors][corner]") {
  const auto cam = cameras()[1];
  Values v;
  v.insert(key('c', 0), SE3::identity());
  v.insert(key('b', 0), SE3(SO3::identity(), Vec3(0.05, 0.02, -0.5)));  // the board behind the camera
  const CornerFactor f(key('c', 0), key('b', 0), cam, Vec3(0.01, 0.02, 0.0), Eigen::Vector2d(500, 270),
                       NoiseModel::isotropic(2, 0.5));
  std::vector<MatX> J;
  const VecX r = f.error(v, &J);
  CHECK(r.allFinite());
  CHECK(r.norm() > 1e6);
  CHECK(J[0].allFinite());
  CHECK(J[1].allFinite());
}

TEST_CASE("corner factor: wrong intrinsics variable, noise or model are errors", "[factors][corner]") {
  const auto cam = cameras()[1];
  Values v;
  v.insert(key('c', 0), SE3::identity());
  v.insert(key('b', 0), SE3(SO3::identity(), Vec3(0, 0, 1)));
  v.insert(key('k', 0), Eigen::Vector4d(600, 600, 512, 272));  // radtan wants 8 entries
  const CornerFactor f(key('c', 0), key('b', 0), key('k', 0), cam, Vec3::Zero(), Eigen::Vector2d(512, 272),
                       NoiseModel::isotropic(2, 0.5));
  CHECK_THROWS_WITH(f.error(v), Catch::Contains("8 entries"));
  CHECK_THROWS_WITH(CornerFactor(key('c', 0), key('b', 0), cam, Vec3::Zero(), Eigen::Vector2d::Zero(),
                                 NoiseModel::isotropic(6, 0.5)),
                    Catch::Contains("dimension 2"));
  CHECK_THROWS_AS(CornerFactor(key('c', 0), key('b', 0), nullptr, Vec3::Zero(), Eigen::Vector2d::Zero(),
                               NoiseModel::isotropic(2, 0.5)),
                  std::invalid_argument);
}

TEST_CASE("corner factor: evaluate allocates nothing", "[factors][corner]") {
  std::mt19937 rng(17);
  const auto cam = cameras()[3];
  const Scene s = randomScene(rng, *cam);
  Values v;
  v.insert(key('c', 0), s.X);
  v.insert(key('b', 0), s.L);
  CornerFactor::insertIntrinsics(v, key('k', 0), *cam);
  const CornerFactor fixed(key('c', 0), key('b', 0), cam, s.p, s.u, NoiseModel::isotropic(2, 0.5));
  const CornerFactor estimated(key('c', 0), key('b', 0), key('k', 0), cam, s.p, s.u, NoiseModel::isotropic(2, 0.5));
  const Variable* vars[3] = {&v.variable(key('c', 0)), &v.variable(key('b', 0)), &v.variable(key('k', 0))};
  double r[2], Jx[12], Jl[12], Jk[16];
  double* jac[3] = {Jx, Jl, Jk};
  const long before = fgcal_test::heap_allocations.load();
  for (int i = 0; i < 100; ++i) {
    fixed.evaluate(vars, r, jac);
    estimated.evaluate(vars, r, jac);
    estimated.evaluate(vars, r, nullptr);
  }
  CHECK(fgcal_test::heap_allocations.load() - before == 0);
  CHECK(std::isfinite(r[0]));
}
