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
