// The ChArUco target: OpenCV 4.6's board frame, dictionary names and field checks.
#include <catch2/catch.hpp>

#include "fgcal/vision/charuco_target.hpp"
#include "fgcal/vision/vision_error.hpp"

using namespace fgcal;
using namespace fgcal::vision;

TEST_CASE("target: corner positions are OpenCV 4.6's board frame", "[vision][target]") {
  CharucoTarget t{5, 7, 0.04, 0.02, "DICT_6X6_250"};
  REQUIRE_NOTHROW(t.validate());
  CHECK(t.cornerCount() == 24);
  CHECK(t.markerCount() == 17);
  // SOURCES.md: corner 0 at (0.04, 0.04), corner 3 at (0.16, 0.04), corner 4 at (0.04, 0.08).
  CHECK((t.cornerPosition(0) - Vec3(0.04, 0.04, 0)).norm() < 1e-15);
  CHECK((t.cornerPosition(3) - Vec3(0.16, 0.04, 0)).norm() < 1e-15);
  CHECK((t.cornerPosition(4) - Vec3(0.04, 0.08, 0)).norm() < 1e-15);
  for (const auto& target : {t, CharucoTarget{5, 7, 0.04, 0.03, "DICT_4X4_50"},
                             CharucoTarget{8, 6, 0.025, 0.018, "DICT_5X5_100"}}) {
    const auto ours = target.cornerPositions();
    const auto theirs = openCvCornerPositions(target);
    REQUIRE(ours.size() == theirs.size());
    for (size_t i = 0; i < ours.size(); ++i) CHECK((ours[i] - theirs[i]).norm() < 1e-7);
  }
  CHECK_THROWS_AS(t.cornerPosition(24), VisionError);
}

TEST_CASE("target: unknown dictionary lists the valid names", "[vision][target]") {
  CharucoTarget t{5, 7, 0.04, 0.02, "DICT_6X6_25"};
  try {
    t.validate();
    FAIL("no exception");
  } catch (const VisionError& e) {
    const std::string msg = e.what();
    CHECK_THAT(msg, Catch::Contains("DICT_6X6_25'") && Catch::Contains("target.dictionary"));
    for (const auto& name : dictionaryNames()) CHECK_THAT(msg, Catch::Contains(name));
  }
  CHECK(dictionaryNames().size() == 21);
}

TEST_CASE("target: field checks name the field", "[vision][target]") {
  CHECK_THROWS_WITH((CharucoTarget{1, 7, 0.04, 0.02, "DICT_6X6_250"}.validate()),
                    Catch::Contains("squares_x"));
  CHECK_THROWS_WITH((CharucoTarget{5, 7, 0.0, 0.02, "DICT_6X6_250"}.validate()),
                    Catch::Contains("square_size"));
  CHECK_THROWS_WITH((CharucoTarget{5, 7, 0.04, -0.02, "DICT_6X6_250"}.validate()),
                    Catch::Contains("marker_size"));
  CHECK_THROWS_WITH((CharucoTarget{5, 7, 0.04, 0.04, "DICT_6X6_250"}.validate()),
                    Catch::Contains("marker_size"));
  // 10x10 board needs 50 markers: DICT_APRILTAG_16h5 has 30.
  CHECK_THROWS_WITH((CharucoTarget{10, 10, 0.04, 0.03, "DICT_APRILTAG_16h5"}.validate()),
                    Catch::Contains("needs 50"));
}

TEST_CASE("target: OpenCV's drawing puts corner 0 where the mapping says", "[vision][target]") {
  CharucoTarget t{5, 7, 0.04, 0.02, "DICT_6X6_250"};
  const cv::Mat img = drawTarget(t, 100, 50);
  REQUIRE(img.cols == 600);
  REQUIRE(img.rows == 800);
  // Top-left square black (docs/toolchain.md, gotcha 2), margin white.
  CHECK(img.at<uchar>(50 + 50, 50 + 50) == 0);
  CHECK(img.at<uchar>(25, 25) == 255);
  // Corner 0 at pixel edge 50 + 100 = 150: square (0,0) black to its top-left,
  // square (1,0) white (with a marker inside) to its top-right.
  CHECK(img.at<uchar>(149, 149) == 0);
  CHECK(img.at<uchar>(149, 150) == 255);
  CHECK(img.at<uchar>(150, 150) == 0);
}
