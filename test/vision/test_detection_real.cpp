// Detection and pose on OpenCV's real ChArUco photos (../shared/data/charuco):
// every corner OpenCV 4.6 finds is found, and the pose reprojects to < 0.5 px RMS.
#include <fstream>
#include <map>
#include <sstream>

#include <catch2/catch.hpp>
#include <Eigen/Eigenvalues>
#include <opencv2/core/persistence.hpp>

#include "fgcal/vision/camera_io.hpp"
#include "fgcal/vision/charuco_detector.hpp"
#include "fgcal/vision/pnp.hpp"
#include "fgcal/vision/vision_error.hpp"
#include "fgcal_test/shared_data.hpp"

using namespace fgcal;
using namespace fgcal::vision;

namespace {

struct Expected {
  std::vector<int> marker_ids, corner_ids;
};

std::vector<int> parseIds(const std::string& s) {
  std::vector<int> v;
  std::istringstream in(s);
  for (int x; in >> x;) v.push_back(x);
  return v;
}

std::map<std::string, Expected> readExpected(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  std::map<std::string, Expected> out;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::vector<std::string> f;
    std::istringstream ls(line);
    for (std::string cell; std::getline(ls, cell, ',');) f.push_back(cell);
    REQUIRE(f.size() == 8);
    out[f[0]] = Expected{parseIds(f[5]), parseIds(f[7])};
  }
  return out;
}

// The tutorial intrinsics (OpenCV FileStorage): radtan with k3.
CameraModel tutorialCamera(const std::string& path) { return readOpenCvCamera(path); }

const CharucoTarget kTutorialBoard{5, 7, 0.04, 0.02, "DICT_6X6_250"};

}  // namespace

TEST_CASE("real photos: every expected corner found, reprojection RMS < 0.5 px",
          "[vision][detection][real]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "charuco");
  const auto expected = readExpected(dir + "/expected_detections_opencv46.csv");
  REQUIRE(expected.size() == 7);
  const CameraModel cam = tutorialCamera(dir + "/tutorial_camera_charuco.yml");
  const CharucoDetector detector(kTutorialBoard);
  for (const auto& [name, exp] : expected) {
    INFO(name);
    const auto det = detector.detectFile(dir + "/" + name);
    CHECK(det.marker_ids.size() == exp.marker_ids.size());
    auto markers = det.marker_ids;
    std::sort(markers.begin(), markers.end());
    CHECK(markers == exp.marker_ids);
    CHECK(det.ids == exp.corner_ids);
    if (name == "charucoboard.png") {
      // Drawn with marker/square 0.6, not this board's 0.5: no metric pose.
      continue;
    }
    REQUIRE(det.ok());
    const auto pose = estimatePose(cam, det);
    INFO("rms " << pose.rms_px << " px, distance " << pose.T_cam_marker.translation().norm() << " m");
    CHECK(pose.converged);
    CHECK(pose.rms_px < 0.5);
    CHECK(pose.T_cam_marker.translation().z() > 0.1);
    // Covariance: symmetric positive definite, sub-mm / sub-degree scale.
    const Mat6 C = pose.covariance;
    CHECK((C - C.transpose()).norm() < 1e-12 * C.norm());
    CHECK(Eigen::SelfAdjointEigenSolver<Mat6>(C).eigenvalues().minCoeff() > 0.0);
    CHECK(std::sqrt(C(5, 5)) < 0.01);
  }
}

TEST_CASE("real photos: the half-pixel refinement lowers the reprojection error",
          "[vision][detection][real]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "charuco");
  const CameraModel cam = tutorialCamera(dir + "/tutorial_camera_charuco.yml");
  double rms[3] = {0, 0, 0};
  const CornerRefinement modes[3] = {CornerRefinement::None, CornerRefinement::SubtractHalfPixel,
                                     CornerRefinement::CornerSubPix};
  for (int m = 0; m < 3; ++m) {
    DetectorOptions opt;
    opt.refinement = modes[m];
    const CharucoDetector detector(kTutorialBoard, opt);
    for (const char* name : {"img_00.jpg", "img_01.jpg", "img_02.jpg", "img_03.jpg"}) {
      const auto pose = estimatePose(cam, detector.detectFile(dir + "/" + name));
      rms[m] += pose.rms_px / 4.0;
    }
  }
  WARN("mean RMS reprojection on img_00..03 (px): OpenCV 4.6 raw " << rms[0] << ", -0.5 px "
                                                                   << rms[1] << ", cornerSubPix "
                                                                   << rms[2]);
  CHECK(rms[2] < 0.5);
  CHECK(rms[1] < 0.5);
}

TEST_CASE("detection errors: unreadable image, zero detections", "[vision][detection]") {
  const CharucoDetector detector(kTutorialBoard);
  const auto missing = detector.detectFile("/nonexistent/folder/frame_0001.png");
  CHECK(missing.status == DetectionStatus::UnreadableImage);
  CHECK_THAT(missing.message, Catch::Contains("/nonexistent/folder/frame_0001.png"));
  CHECK_THROWS_WITH(readGrayImage("/nonexistent/x.png"), Catch::Contains("/nonexistent/x.png"));

  const cv::Mat blank(480, 640, CV_8U, cv::Scalar(128));
  const auto none = detector.detect(blank);
  CHECK(none.status == DetectionStatus::NoMarkers);
  CHECK_THAT(none.message, Catch::Contains("no ArUco markers"));
  CHECK(none.ids.empty());
  CHECK_THROWS_WITH(estimatePose(CameraModel(Projection::Pinhole, Distortion::None, 500, 500, 320,
                                             240, {}, 640, 480),
                                 none),
                    Catch::Contains("no markers"));
  CHECK(detector.detect(cv::Mat()).status == DetectionStatus::UnreadableImage);
  CHECK_THROWS_AS(CharucoDetector(CharucoTarget{5, 7, 0.04, 0.02, "DICT_9X9_1"}), VisionError);
}

TEST_CASE("camera files: OpenCV FileStorage calibrations", "[vision][camera][real]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "intrinsics");
  const auto cam = readOpenCvCamera(dir + "/opencv_tutorial_camera_charuco.yml");
  CHECK(cam.distortion() == Distortion::RadTan);
  CHECK(cam.coeffs().size() == 5);
  CHECK(cam.fx() == Approx(452.5107).epsilon(1e-6));
  CHECK(cam.cy() == Approx(277.7516).epsilon(1e-6));
  CHECK(cam.width() == 640);
  // No image size in this one; its 5th coefficient (k3) is 0, a column vector.
  CHECK_THROWS_WITH(readOpenCvCamera(dir + "/opencv_tutorial_camera_params.yml"),
                    Catch::Contains("image_width"));
  const auto small = readOpenCvCamera(dir + "/opencv_tutorial_camera_params.yml", 640, 480);
  CHECK(small.coeffs().size() == 4);
  CHECK(small.coeffs()[2] == Approx(0.00754589));
  // Kalibr files are not FileStorage files.
  CHECK_THROWS_WITH(readOpenCvCamera(dir + "/kalibr_camchain_mono_equidistant.yaml"),
                    Catch::Contains("kalibr_camchain_mono_equidistant.yaml"));
  CHECK_THROWS_WITH(readOpenCvCamera(dir + "/no_such_file.yml"), Catch::Contains("no_such_file.yml"));
}
