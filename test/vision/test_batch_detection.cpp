// Detection over many images on all cores: input order kept, bad files are a
// per-image status naming the file, results equal the sequential ones.
#include <catch2/catch.hpp>

#include "fgcal/vision/batch_detection.hpp"
#include "fgcal/vision/board_renderer.hpp"
#include "fgcal_test/shared_data.hpp"
#include "render_fixtures.hpp"

using namespace fgcal;
using namespace fgcal::vision;
using namespace fgcal::vision::testing;

TEST_CASE("batch: rendered images on all cores equal sequential detection", "[vision][batch]") {
  const CharucoTarget board = testBoard();
  const CameraModel cam = equidistantCamera();
  const BoardRenderer renderer(cam, board, 2);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 8; ++i)
    images.push_back(renderer.render(boardPose(board, Vec3(0.01 * i, 0.0, 0.4 + 0.05 * i), 0.2, -0.1 * i, 0.3 * i)));
  images.push_back(cv::Mat());  // an image that failed to load
  const CharucoDetector detector(board);
  const auto loader = [&](std::size_t i) { return images[i]; };
  const auto par = processImages(detector, images.size(), loader, &cam, {}, 0);
  const auto seq = processImages(detector, images.size(), loader, &cam, {}, 1);
  REQUIRE(par.size() == images.size());
  for (size_t i = 0; i + 1 < images.size(); ++i) {
    INFO("image " << i);
    REQUIRE(par[i].detection.ok());
    CHECK(par[i].detection.ids == seq[i].detection.ids);
    REQUIRE(par[i].pose);
    CHECK((par[i].pose->T_cam_marker.matrix() - seq[i].pose->T_cam_marker.matrix()).norm() == 0.0);
  }
  CHECK(par.back().detection.status == DetectionStatus::UnreadableImage);
  CHECK_FALSE(par.back().pose);
}

TEST_CASE("batch: files, with a missing one in the middle", "[vision][batch][real]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "charuco");
  const CharucoTarget board{5, 7, 0.04, 0.02, "DICT_6X6_250"};
  const std::vector<std::string> paths = {dir + "/img_00.jpg", dir + "/no_such_image.png",
                                          dir + "/img_02.jpg", dir + "/SOURCES.md",
                                          dir + "/chocclusion_original.jpg"};
  const auto res = processFiles(CharucoDetector(board), paths);
  REQUIRE(res.size() == paths.size());
  CHECK(res[0].detection.ok());
  CHECK(res[0].detection.ids.size() == 24);
  CHECK(res[1].detection.status == DetectionStatus::UnreadableImage);
  CHECK_THAT(res[1].detection.message, Catch::Contains("no_such_image.png"));
  CHECK(res[2].detection.ids.size() == 22);
  CHECK(res[3].detection.status == DetectionStatus::UnreadableImage);
  CHECK(res[4].detection.ids.size() == 16);
  for (size_t i = 0; i < paths.size(); ++i) CHECK(res[i].detection.source == paths[i]);
}
