// Importing intrinsics from the real Kalibr, ROS and OpenCV files in the shared
// data folder, and the errors for what fgcal's models cannot represent.
#include <catch2/catch.hpp>

#include "apps_test_util.hpp"
#include "fgcal/apps/intrinsics_import.hpp"
#include "fgcal_test/shared_data.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

TEST_CASE("intrinsics: Kalibr camchains", "[apps][intrinsics]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "intrinsics");
  SECTION("EuRoC stereo, equidistant") {
    const auto cams = importIntrinsics(dir + "/kalibr_camchain_euroc_stereo_equidistant.yaml", 0.5);
    REQUIRE(cams.size() == 2);
    CHECK(cams[0].name == "cam0");
    CHECK(cams[1].name == "cam1");
    CHECK(cams[0].camera_model == "pinhole");
    CHECK(cams[0].distortion_model == "equidistant");
    CHECK(cams[0].intrinsics[0] == 461.3418503026154);
    CHECK(cams[1].intrinsics[3] == 255.55347731935623);
    CHECK(cams[0].distortion_coeffs.size() == 4);
    CHECK(cams[0].distortion_coeffs[3] == 0.03666365316319072);
    CHECK(cams[0].resolution == std::array<int, 2>{752, 480});
    CHECK(cams[0].pixel_sigma == 0.5);
  }
  SECTION("mono files") {
    CHECK(importIntrinsics(dir + "/kalibr_camchain_imucam_mono_equidistant.yaml", 1.0).size() == 1);
    CHECK(importIntrinsics(dir + "/kalibr_camchain_mono_equidistant.yaml", 1.0)[0].intrinsics[1] == 278.4167467580337);
  }
  SECTION("OpenVINS RealSense file with a %YAML:1.0 line, radtan") {
    const auto cams = importIntrinsics(dir + "/kalibr_imucam_chain_rs_d455_radtan_openvins.yaml", 0.5);
    REQUIRE(cams.size() == 1);
    CHECK(cams[0].distortion_model == "radtan");
    CHECK(cams[0].distortion_coeffs ==
          std::vector<double>{-0.045761895748285604, 0.03423951132164367, -0.00040139057556727315, 0.000431371425853453});
    CHECK(cams[0].resolution == std::array<int, 2>{848, 480});
  }
}

TEST_CASE("intrinsics: ROS camera_info and OpenCV files", "[apps][intrinsics]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "intrinsics");
  SECTION("ROS plumb_bob with k3 = 0 -> radtan") {
    const auto cams = importIntrinsics(dir + "/ros_camera_info_plumb_bob.yaml", 0.5);
    REQUIRE(cams.size() == 1);
    CHECK(cams[0].name == "test_camera");
    CHECK(cams[0].distortion_model == "radtan");
    CHECK(cams[0].intrinsics == std::array<double, 4>{438.783367, 437.302876, 305.593336, 243.738352});
    CHECK(cams[0].distortion_coeffs == std::vector<double>{-0.361976, 0.110510, 0.001014, 0.000505});
    CHECK(cams[0].resolution == std::array<int, 2>{640, 480});
  }
  SECTION("OpenCV file with k3 != 0: refused with the reason") {
    CHECK_INPUT_ERROR(importIntrinsics(dir + "/opencv_tutorial_camera_charuco.yml", 0.5),
                      "opencv_tutorial_camera_charuco.yml", "distortion_coefficients", "k3 = 2.954258940681008",
                      "[k1, k2, p1, p2]", "CALIB_FIX_K3");
  }
  SECTION("OpenCV file without a resolution: refused with the reason") {
    CHECK_INPUT_ERROR(importIntrinsics(dir + "/opencv_tutorial_camera_params.yml", 0.5),
                      "opencv_tutorial_camera_params.yml", "", "image_width and image_height");
  }
}

TEST_CASE("intrinsics: synthetic cases and errors", "[apps][intrinsics]") {
  const std::string cv =
      "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n"
      "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n  data: [500., 0., 320., 0., 501., 240., 0., 0., 1.]\n"
      "distortion_coefficients: !!opencv-matrix\n  rows: 5\n  cols: 1\n  dt: d\n  data: [0.1, -0.2, 0.001, 0.002, 0.]\n";
  const auto cams = parseIntrinsics(cv, "calib.yml", 0.4, "front");
  REQUIRE(cams.size() == 1);
  CHECK(cams[0].name == "front");
  CHECK(cams[0].intrinsics == std::array<double, 4>{500, 501, 320, 240});
  CHECK(cams[0].distortion_coeffs == std::vector<double>{0.1, -0.2, 0.001, 0.002});

  CHECK_INPUT_ERROR(parseIntrinsics(replaced(cv, "0., 501.", "2., 501."), "calib.yml", 0.4), "calib.yml",
                    "camera_matrix", "no skew");
  CHECK_INPUT_ERROR(parseIntrinsics(replaced(cv, "rows: 5", "rows: 4"), "calib.yml", 0.4), "calib.yml",
                    "distortion_coefficients.data", "expected 4 numbers", "got 5");
  CHECK_INPUT_ERROR(parseIntrinsics("cam0:\n  camera_model: omni\n", "chain.yaml", 0.4), "chain.yaml",
                    "cam0.camera_model", "pinhole", "'omni'");
  CHECK_INPUT_ERROR(parseIntrinsics("foo: 1\n", "x.yaml", 0.4), "x.yaml", "", "Kalibr camchain", "found neither");
  CHECK_INPUT_ERROR(parseIntrinsics(cv, "calib.yml", 0.0), "calib.yml", "", "pixel_sigma");
}
