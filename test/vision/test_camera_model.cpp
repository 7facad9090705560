// Camera models: Jacobians against central differences, agreement with
// OpenCV's projectPoints / fisheye::projectPoints, unproject round trips and
// the errors for bad names and coefficient counts.
#include <random>

#include <catch2/catch.hpp>
#include <opencv2/calib3d.hpp>

#include "fgcal/vision/camera_model.hpp"
#include "fgcal/vision/vision_error.hpp"
#include "fgcal_test/jacobian_check.hpp"

using namespace fgcal;
using namespace fgcal::vision;

namespace {

std::vector<CameraModel> testCameras() {
  return {
      CameraModel(Projection::Pinhole, Distortion::None, 500, 505, 320, 240, {}, 640, 480),
      CameraModel(Projection::Pinhole, Distortion::RadTan, 500, 505, 321.5, 239.25,
                  {-0.28, 0.07, 1e-4, -2e-4}, 640, 480),
      CameraModel(Projection::Pinhole, Distortion::RadTan, 452.51, 456.77, 317.70, 277.75,
                  {0.12137, -1.08547, 1.1787e-4, -4.6241e-4, 2.95426}, 640, 480),
      CameraModel(Projection::Pinhole, Distortion::Equidistant, 380, 381, 322, 241,
                  {-0.01, 0.002, 0.0003, -0.0001}, 640, 480),
      CameraModel(Projection::Pinhole, Distortion::Equidistant, 280, 280, 320, 240,
                  {0.05, -0.01, 0.004, -0.0007}, 640, 480),
  };
}

// Points in front of the camera spanning roughly the field of view.
std::vector<Vec3> testPoints(const CameraModel& cam, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(0.0, cam.width()), uy(0.0, cam.height()), z(0.2, 3.0);
  std::vector<Vec3> pts;
  pts.push_back(Vec3(0, 0, 1.0));  // on the axis
  while (static_cast<int>(pts.size()) < n) {
    const auto ray = cam.unproject(Vec2(ux(rng), uy(rng)));
    if (!ray) continue;
    pts.push_back(*ray * z(rng) / ray->z());
  }
  return pts;
}

}  // namespace

TEST_CASE("camera model: Jacobian of project with respect to the point", "[vision][camera]") {
  for (const auto& cam : testCameras()) {
    INFO("distortion " << toString(cam.distortion()));
    for (const auto& p : testPoints(cam, 20, 3)) {
      Mat23 J;
      REQUIRE(cam.project(p, &J));
      CHECK_JACOBIAN(J, [&](const Eigen::Vector3d& q) -> Eigen::Vector2d { return *cam.project(q); },
                     Eigen::Vector3d(p));
    }
  }
}

TEST_CASE("camera model: agrees with OpenCV projectPoints and fisheye::projectPoints",
          "[vision][camera]") {
  for (const auto& cam : testCameras()) {
    INFO("distortion " << toString(cam.distortion()));
    const auto pts = testPoints(cam, 200, 11);
    std::vector<cv::Point3d> obj;
    for (const auto& p : pts) obj.emplace_back(p.x(), p.y(), p.z());
    cv::Mat K = (cv::Mat_<double>(3, 3) << cam.fx(), 0, cam.cx(), 0, cam.fy(), cam.cy(), 0, 0, 1);
    std::vector<cv::Point2d> img;
    const cv::Mat rvec = cv::Mat::zeros(3, 1, CV_64F), tvec = cv::Mat::zeros(3, 1, CV_64F);
    if (cam.distortion() == Distortion::Equidistant) {
      cv::fisheye::projectPoints(obj, img, rvec, tvec, K, cv::Mat(cam.coeffs()));
    } else {
      cv::projectPoints(obj, rvec, tvec, K, cv::Mat(cam.coeffs()), img);
    }
    double worst = 0.0;
    for (size_t i = 0; i < pts.size(); ++i) {
      const auto uv = cam.project(pts[i]);
      REQUIRE(uv);
      worst = std::max(worst, (*uv - Vec2(img[i].x, img[i].y)).norm());
    }
    INFO("worst difference " << worst << " px");
    CHECK(worst < 1e-9);
  }
}

TEST_CASE("camera model: unproject inverts project", "[vision][camera]") {
  for (const auto& cam : testCameras()) {
    INFO("distortion " << toString(cam.distortion()));
    for (const auto& p : testPoints(cam, 100, 5)) {
      const auto uv = cam.project(p);
      REQUIRE(uv);
      const auto ray = cam.unproject(*uv);
      REQUIRE(ray);
      CHECK((*ray - p.normalized()).norm() < 1e-10);
      const auto uv2 = cam.project(*ray);
      REQUIRE(uv2);
      CHECK((*uv2 - *uv).norm() < 1e-8);
    }
  }
}

TEST_CASE("camera model: points behind the camera do not project", "[vision][camera]") {
  const auto cam = testCameras()[1];
  CHECK_FALSE(cam.project(Vec3(0.1, 0.2, -1.0)));
  CHECK_FALSE(cam.project(Vec3(0.1, 0.2, 0.0)));
}

TEST_CASE("camera model: Kalibr names and coefficient counts", "[vision][camera]") {
  const auto cam = CameraModel::fromKalibr("pinhole", "equidistant", {400, 401, 320, 240},
                                           {0.1, 0.01, -0.001, 0.0001}, {640, 480});
  CHECK(cam.distortion() == Distortion::Equidistant);
  CHECK(cam.width() == 640);
  CHECK_THROWS_WITH(CameraModel::fromKalibr("omni", "radtan", {1, 1, 0, 0}, {0, 0, 0, 0}, {640, 480}),
                    Catch::Contains("camera_model") && Catch::Contains("pinhole"));
  CHECK_THROWS_WITH(CameraModel::fromKalibr("pinhole", "fov", {1, 1, 0, 0}, {0}, {640, 480}),
                    Catch::Contains("distortion_model") && Catch::Contains("radtan") &&
                        Catch::Contains("equidistant"));
  CHECK_THROWS_WITH(CameraModel::fromKalibr("pinhole", "radtan", {1, 1, 0, 0}, {0, 0, 0}, {640, 480}),
                    Catch::Contains("distortion_coeffs") && Catch::Contains("got 3"));
  CHECK_THROWS_AS(CameraModel::fromKalibr("pinhole", "equidistant", {1, 1, 0, 0}, {0, 0, 0, 0, 0}, {640, 480}),
                  VisionError);
  CHECK_THROWS_AS(CameraModel::fromKalibr("pinhole", "none", {1, 1, 0, 0}, {0.1}, {640, 480}), VisionError);
  CHECK_THROWS_WITH(CameraModel::fromKalibr("pinhole", "none", {1, 1, 0}, {}, {640, 480}),
                    Catch::Contains("intrinsics"));
  CHECK_THROWS_WITH(CameraModel::fromKalibr("pinhole", "none", {-1, 1, 0, 0}, {}, {640, 480}),
                    Catch::Contains("fx"));
  CHECK_THROWS_WITH(CameraModel::fromKalibr("pinhole", "none", {1, 1, 0, 0}, {}, {640}),
                    Catch::Contains("resolution"));
}

// ---- intrinsics as a vector (what the corner factor estimates) ------------

namespace {

// d(uv)/d(intrinsics) by projectWith, as a matrix.
Eigen::MatrixXd intrinsicsJacobian(const CameraModel& cam, const Eigen::VectorXd& k, const Vec3& p) {
  Eigen::MatrixXd J(2, cam.intrinsicsSize());
  Vec2 uv;
  REQUIRE(cam.projectWith(k.data(), p, &uv, nullptr, J.data()));
  return J;
}

// Both Jacobians of projectWith at p against central differences, at the
// camera's own intrinsics moved off their values (so no coefficient is 0).
void checkBothJacobians(const CameraModel& cam, const Vec3& p) {
  Eigen::VectorXd k = cam.intrinsicsVector();
  for (Eigen::Index i = 0; i < k.size(); ++i) k[i] += (i < 4 ? 3.0 : 0.01) * std::sin(1.0 + i);
  const auto project_k = [&](const Eigen::VectorXd& kk) -> Eigen::Vector2d {
    Vec2 uv;
    REQUIRE(cam.projectWith(kk.data(), p, &uv));
    return uv;
  };
  const auto project_p = [&](const Eigen::Vector3d& q) -> Eigen::Vector2d {
    Vec2 uv;
    REQUIRE(cam.projectWith(k.data(), q, &uv));
    return uv;
  };
  Mat23 J_p;
  Vec2 uv;
  REQUIRE(cam.projectWith(k.data(), p, &uv, &J_p));
  CHECK_JACOBIAN(Eigen::MatrixXd(J_p), project_p, Eigen::Vector3d(p));
  CHECK_JACOBIAN(intrinsicsJacobian(cam, k, p), project_k, k);
}

}  // namespace

TEST_CASE("camera model: the intrinsics vector and its layout", "[vision][camera]") {
  const auto cams = testCameras();
  CHECK(cams[0].intrinsicsSize() == 4);
  CHECK(cams[1].intrinsicsSize() == 8);
  CHECK(cams[2].intrinsicsSize() == 9);  // radtan with k3
  CHECK(cams[3].intrinsicsSize() == 8);
  for (const auto& cam : cams) {
    const Eigen::VectorXd k = cam.intrinsicsVector();
    CHECK(k[0] == cam.fx());
    CHECK(k[3] == cam.cy());
    for (std::size_t i = 0; i < cam.coeffs().size(); ++i) CHECK(k[4 + static_cast<Eigen::Index>(i)] == cam.coeffs()[i]);
    // The same intrinsics through projectWith give project's pixels, bit for bit.
    for (const auto& p : testPoints(cam, 20, 9)) {
      Vec2 uv;
      REQUIRE(cam.projectWith(k.data(), p, &uv));
      CHECK(uv == *cam.project(p));
    }
    // withIntrinsics: another camera whose project() is projectWith of the vector.
    Eigen::VectorXd moved = k;
    moved[0] *= 1.01;
    moved[2] += 3.0;
    const CameraModel other = cam.withIntrinsics(moved);
    CHECK(other.intrinsicsVector() == moved);
    CHECK(other.width() == cam.width());
    const Vec3 p(0.1, -0.05, 1.0);
    Vec2 uv;
    REQUIRE(cam.projectWith(moved.data(), p, &uv));
    CHECK((*other.project(p) - uv).norm() < 1e-12);
  }
  CHECK_THROWS_WITH(cams[1].withIntrinsics(Eigen::VectorXd::Ones(4)),
                    Catch::Contains("expected 8") && Catch::Contains("radtan"));
  Eigen::VectorXd bad = cams[1].intrinsicsVector();
  bad[1] = -1.0;
  CHECK_THROWS_AS(cams[1].withIntrinsics(bad), VisionError);
  Vec2 uv(7, 7);
  CHECK_FALSE(cams[1].projectWith(cams[1].intrinsicsVector().data(), Vec3(0.1, 0.1, -1.0), &uv));
  CHECK(uv == Vec2(7, 7));
}

TEST_CASE("camera model: Jacobians by point and by intrinsics at random points", "[vision][camera]") {
  for (const auto& cam : testCameras()) {
    INFO("distortion " << toString(cam.distortion()) << ", " << cam.coeffs().size() << " coefficients");
    for (const auto& p : testPoints(cam, 25, 17)) checkBothJacobians(cam, p);
  }
}

TEST_CASE("camera model: Jacobians near the image edge", "[vision][camera]") {
  for (const auto& cam : testCameras()) {
    INFO("distortion " << toString(cam.distortion()));
    const double w = cam.width(), h = cam.height();
    // The four corners and edge midpoints, half a pixel inside.
    for (const Vec2& px : {Vec2(0.5, 0.5), Vec2(w - 0.5, 0.5), Vec2(0.5, h - 0.5), Vec2(w - 0.5, h - 0.5),
                          Vec2(w / 2, 0.5), Vec2(0.5, h / 2), Vec2(w - 0.5, h / 2), Vec2(w / 2, h - 0.5)}) {
      const auto ray = cam.unproject(px);
      REQUIRE(ray);
      INFO("pixel " << px.transpose());
      checkBothJacobians(cam, *ray * (0.7 / ray->z()));
    }
  }
}

TEST_CASE("camera model: equidistant Jacobians at wide angles", "[vision][camera]") {
  // A fisheye lens: 190 px focal length on 1280 x 1024, so that 85 deg off
  // the axis is about 280 px from the centre.
  const CameraModel fisheye(Projection::Pinhole, Distortion::Equidistant, 190, 191, 640.5, 511.5,
                            {-0.02, 0.004, -0.0012, 0.0002}, 1280, 1024);
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> azimuth(-M_PI, M_PI), range(0.3, 2.0);
  for (double deg : {0.0, 1e-6, 30.0, 60.0, 75.0, 80.0, 85.0, 88.0}) {
    for (int k = 0; k < 4; ++k) {
      const double th = deg * M_PI / 180.0, az = azimuth(rng), d = range(rng);
      const Vec3 p = d * Vec3(std::sin(th) * std::cos(az), std::sin(th) * std::sin(az), std::cos(th));
      INFO(deg << " deg off the axis, point " << p.transpose());
      checkBothJacobians(fisheye, p);
      // And it agrees with OpenCV's fisheye model there.
      std::vector<cv::Point3d> obj{{p.x(), p.y(), p.z()}};
      std::vector<cv::Point2d> img;
      const cv::Mat K = (cv::Mat_<double>(3, 3) << 190, 0, 640.5, 0, 191, 511.5, 0, 0, 1);
      cv::fisheye::projectPoints(obj, img, cv::Mat::zeros(3, 1, CV_64F), cv::Mat::zeros(3, 1, CV_64F), K,
                                 cv::Mat(fisheye.coeffs()));
      CHECK((*fisheye.project(p) - Vec2(img[0].x, img[0].y)).norm() < 1e-8);
    }
  }
}
