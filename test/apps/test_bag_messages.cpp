// The bag messages turned into the calibration's inputs, on synthetic
// messages: every image encoding to grey and to the pixels a dataset stores
// (Bayer patterns told apart by colour, rgb/bgr order, big-endian mono16,
// padded rows), the CompressedImage format strings image_transport writes,
// CameraInfo to intrinsics, JointState messages to a joints table (header
// stamp order, equal stamps, absent joints, NaN), and the streaming detection
// pool (results by slot, bounded queue, unreadable images).
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <thread>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bag/detection_pool.hpp"
#include "fgcal/apps/bag_messages.hpp"
#include "fgcal/apps/errors.hpp"
#include "fgcal/vision/board_renderer.hpp"
#include "fgcal/vision/camera_model.hpp"

using namespace fgcal;
using namespace fgcal::apps;

namespace {

/// An Image message of `mat`'s pixels (8-bit channels), rows padded to `step`.
logs::Image imageMessage(const cv::Mat& mat, const std::string& encoding, std::uint32_t step = 0) {
  logs::Image m;
  m.width = static_cast<std::uint32_t>(mat.cols);
  m.height = static_cast<std::uint32_t>(mat.rows);
  m.encoding = encoding;
  const std::size_t row = mat.cols * mat.elemSize();
  m.step = step ? step : static_cast<std::uint32_t>(row);
  m.data.assign(static_cast<std::size_t>(m.step) * m.height, 0xAB);  // padding bytes must be ignored
  for (int r = 0; r < mat.rows; ++r) std::memcpy(&m.data[r * m.step], mat.ptr(r), row);
  return m;
}

/// A Bayer mosaic of a uniform BGR colour. `pattern`: colours of the 2x2 cell, row-major ("rggb").
cv::Mat mosaic(const std::string& pattern, cv::Vec3b bgr, int w = 16, int h = 12) {
  cv::Mat m(h, w, CV_8UC1);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const char ch = pattern[(r % 2) * 2 + (c % 2)];
      m.at<std::uint8_t>(r, c) = ch == 'b' ? bgr[0] : ch == 'g' ? bgr[1] : bgr[2];
    }
  return m;
}

std::vector<std::uint8_t> rowsOf(const cv::Mat& m) {
  std::vector<std::uint8_t> v;
  for (int r = 0; r < m.rows; ++r) v.insert(v.end(), m.ptr(r), m.ptr(r) + m.cols * m.elemSize());
  return v;
}

}  // namespace

TEST_CASE("bag images: each Bayer pattern is demosaiced with its own colour order", "[bag]") {
  const cv::Vec3b red_ish(20, 60, 200);  // B, G, R: a wrong pattern swaps R and B or puts G where R is
  for (const std::string p : {"rggb", "bggr", "gbrg", "grbg"}) {
    INFO("bayer_" << p << "8");
    const logs::Image msg = imageMessage(mosaic(p, red_ish), "bayer_" + p + "8");
    REQUIRE(imageProblem(msg).empty());
    const cv::Mat bgr = imageForPng(msg);
    REQUIRE(bgr.type() == CV_8UC3);
    const cv::Vec3b inner = bgr.at<cv::Vec3b>(6, 8);  // away from the border's interpolation
    CHECK(std::abs(inner[0] - red_ish[0]) <= 2);
    CHECK(std::abs(inner[1] - red_ish[1]) <= 2);
    CHECK(std::abs(inner[2] - red_ish[2]) <= 2);
    cv::Mat want;
    cv::cvtColor(bgr, want, cv::COLOR_BGR2GRAY);
    const cv::Mat grey = imageToGray(msg);
    REQUIRE(grey.type() == CV_8UC1);
    CHECK(cv::norm(grey, want, cv::NORM_INF) == 0);  // the grey an imported PNG reads as
  }
}

TEST_CASE("bag images: rgb8 and bgr8 keep their colours, padded rows are cut", "[bag]") {
  cv::Mat rgb(5, 7, CV_8UC3);
  cv::randu(rgb, 0, 256);
  const logs::Image m_rgb = imageMessage(rgb, "rgb8", 7 * 3 + 5);
  REQUIRE(imageProblem(m_rgb).empty());
  // The PNG's decoded RGB rows are exactly the message's rows.
  std::vector<std::uint8_t> png;
  REQUIRE(cv::imencode(".png", imageForPng(m_rgb), png));
  cv::Mat back = cv::imdecode(png, cv::IMREAD_UNCHANGED);
  cv::cvtColor(back, back, cv::COLOR_BGR2RGB);
  CHECK(rowsOf(back) == rowsOf(rgb));
  cv::Mat grey_want;
  cv::cvtColor(rgb, grey_want, cv::COLOR_RGB2GRAY);
  CHECK(cv::norm(imageToGray(m_rgb), grey_want, cv::NORM_INF) == 0);
  // The same pixels as bgr8 are another image: R and B swap.
  const logs::Image m_bgr = imageMessage(rgb, "bgr8");
  cv::Mat grey_bgr;
  cv::cvtColor(rgb, grey_bgr, cv::COLOR_BGR2GRAY);
  CHECK(cv::norm(imageToGray(m_bgr), grey_bgr, cv::NORM_INF) == 0);
  CHECK(rowsOf(imageForPng(m_bgr)) == rowsOf(rgb));
  // rgba8: alpha kept in the PNG, ignored for grey.
  cv::Mat rgba(4, 3, CV_8UC4, cv::Scalar(10, 20, 30, 77));
  const logs::Image m_rgba = imageMessage(rgba, "rgba8");
  CHECK(imageForPng(m_rgba).at<cv::Vec4b>(0, 0) == cv::Vec4b(30, 20, 10, 77));
  cv::Mat grey_rgba;
  cv::cvtColor(rgba, grey_rgba, cv::COLOR_RGBA2GRAY);
  CHECK(cv::norm(imageToGray(m_rgba), grey_rgba, cv::NORM_INF) == 0);
}

TEST_CASE("bag images: mono16 in either byte order; grey is its high byte, the PNG keeps all 16 bits", "[bag]") {
  logs::Image m;
  m.width = 2;
  m.height = 1;
  m.encoding = "mono16";
  m.step = 4;
  m.is_bigendian = true;
  m.data = {0x12, 0x34, 0xFE, 0x01};
  REQUIRE(imageProblem(m).empty());
  const cv::Mat png = imageForPng(m);
  REQUIRE(png.type() == CV_16UC1);
  CHECK(png.at<std::uint16_t>(0, 0) == 0x1234);
  CHECK(png.at<std::uint16_t>(0, 1) == 0xFE01);
  const cv::Mat grey = imageToGray(m);
  CHECK(grey.at<std::uint8_t>(0, 0) == 0x12);
  CHECK(grey.at<std::uint8_t>(0, 1) == 0xFE);
  // A 16-bit PNG read as grey gives the same 8 bits (so an imported folder detects the same).
  std::vector<std::uint8_t> bytes;
  REQUIRE(cv::imencode(".png", png, bytes));
  CHECK(cv::norm(cv::imdecode(bytes, cv::IMREAD_GRAYSCALE), grey, cv::NORM_INF) == 0);
  m.is_bigendian = false;
  CHECK(imageForPng(m).at<std::uint16_t>(0, 0) == 0x3412);
}

TEST_CASE("bag images: what cannot be read is said, not guessed", "[bag]") {
  logs::Image m = imageMessage(cv::Mat(4, 4, CV_8UC1, cv::Scalar(0)), "yuv422");
  CHECK_THAT(imageProblem(m), Catch::Contains("yuv422") && Catch::Contains("mono8"));
  m.encoding = "32FC1";
  CHECK_THAT(imageProblem(m), Catch::Contains("32FC1"));
  m.encoding = "mono8";
  m.step = 3;
  CHECK_THAT(imageProblem(m), Catch::Contains("step 3"));
  m.step = 4;
  m.data.resize(15);
  CHECK_THAT(imageProblem(m), Catch::Contains("15 bytes"));
  m.data.resize(16);
  CHECK(imageProblem(m).empty());
}

TEST_CASE("bag images: CompressedImage format strings as image_transport writes them", "[bag]") {
  CHECK(compressedImageFormat("jpeg") == "jpeg");
  CHECK(compressedImageFormat("png") == "png");
  CHECK(compressedImageFormat("mono8; jpeg compressed ") == "jpeg");
  CHECK(compressedImageFormat("bgr8; jpeg compressed bgr8") == "jpeg");
  CHECK(compressedImageFormat("rgb8; png compressed") == "png");
  CHECK(compressedImageFormat("JPEG") == "jpeg");
  CHECK(compressedImageFormat("16UC1; compressedDepth png").empty());
  CHECK(compressedImageFormat("tiff").empty());
  CHECK(compressedImageFormat("").empty());
  // Decoding: grey from a colour PNG; garbage is an empty image, not an exception.
  logs::CompressedImage c;
  c.format = "png";
  cv::Mat colour(3, 4, CV_8UC3, cv::Scalar(10, 200, 30));
  REQUIRE(cv::imencode(".png", colour, c.data));
  CHECK(compressedToGray(c).type() == CV_8UC1);
  CHECK(compressedToGray(c).size() == cv::Size(4, 3));
  c.data = {1, 2, 3};
  CHECK(compressedToGray(c).empty());
}

TEST_CASE("bag camera_info: plumb_bob, rational_polynomial and equidistant to fgcal's models", "[bag]") {
  logs::CameraInfo info;
  info.width = 640;
  info.height = 480;
  info.k = {444.6, 0, 324.8, 0, 444.4, 240.9, 0, 0, 1};
  info.distortion_model = "plumb_bob";
  info.d = {-0.22, 0.088, -0.00045, -0.0004, 0.0};
  CameraConfig c;
  REQUIRE(intrinsicsFromCameraInfo(info, &c).empty());
  CHECK(c.distortion_model == "radtan");
  CHECK(c.intrinsics == std::array<double, 4>{444.6, 444.4, 324.8, 240.9});
  CHECK(c.distortion_coeffs == std::vector<double>{-0.22, 0.088, -0.00045, -0.0004});
  CHECK(c.resolution == std::array<int, 2>{640, 480});

  info.d = {-0.22, 0.088, -0.00045, -0.0004, 0.01};
  CHECK_THAT(intrinsicsFromCameraInfo(info, &c), Catch::Contains("k3"));
  info.distortion_model = "rational_polynomial";
  info.d = {-0.22, 0.088, -0.00045, -0.0004, 0, 0, 0, 0};
  CHECK(intrinsicsFromCameraInfo(info, &c).empty());
  info.d[6] = 0.5;
  CHECK_THAT(intrinsicsFromCameraInfo(info, &c), Catch::Contains("k5"));
  info.distortion_model = "equidistant";
  info.d = {0.1, 0.01, -0.002, 0.0003};
  REQUIRE(intrinsicsFromCameraInfo(info, &c).empty());
  CHECK(c.distortion_model == "equidistant");
  CHECK(c.distortion_coeffs == info.d);
  info.distortion_model = "fisheye_weird";
  CHECK_THAT(intrinsicsFromCameraInfo(info, &c), Catch::Contains("fisheye_weird"));
  info.distortion_model = "plumb_bob";
  info.d = {};
  info.k = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  CHECK_THAT(intrinsicsFromCameraInfo(info, &c), Catch::Contains("skew") || Catch::Contains("fx > 0"));
  info.k = {444.6, 0, 324.8, 0, 444.4, 240.9, 0, 0, 1};
  info.binning_x = 2;
  CHECK_THAT(intrinsicsFromCameraInfo(info, &c), Catch::Contains("binning"));
}

namespace {

logs::JointState js(std::int64_t stamp, std::vector<std::string> names, std::vector<double> pos) {
  logs::JointState m;
  m.header.stamp_ns = stamp;
  m.name = std::move(names);
  m.position = std::move(pos);
  return m;
}

}  // namespace

TEST_CASE("bag joint states: header-stamp order, equal stamps merged, absent joints held, NaN kept", "[bag]") {
  JointStateCollector col;
  // Storage (record) order differs from header-stamp order.
  REQUIRE(col.add(js(300, {"a", "b"}, {3.0, 30.0}), 0).empty());
  REQUIRE(col.add(js(100, {"a", "b"}, {1.0, 10.0}), 1).empty());
  REQUIRE(col.add(js(200, {"b"}, {20.0}), 2).empty());                // a absent: keeps 1.0
  REQUIRE(col.add(js(400, {"a", "b"}, {4.0, 40.0}), 3).empty());
  REQUIRE(col.add(js(400, {"b", "c"}, {41.0, 7.0}), 4).empty());     // same stamp: merged, later wins for b
  REQUIRE(col.add(js(500, {"a"}, {std::nan("")}), 5).empty());
  REQUIRE(col.add(js(600, {"a"}, {}), 6).empty());                   // no positions: ignored
  CHECK(col.withoutPositions() == 1);
  CHECK_THAT(col.add(js(700, {"a", "b"}, {1.0}), 7), Catch::Contains("2 names and 1 positions"));
  CHECK_THAT(col.add(js(700, {"a", "a"}, {1.0, 2.0}), 8), Catch::Contains("named twice"));
  std::size_t dup = 0;
  const JointLog log = col.finish(&dup);
  CHECK(dup == 1);
  CHECK(log.names == std::vector<std::string>{"a", "b", "c"});
  REQUIRE(log.stamps_ns == std::vector<std::int64_t>{100, 200, 300, 400, 500});
  CHECK(log.positions(1, 0) == 1.0);
  CHECK(log.positions(1, 1) == 20.0);
  CHECK(std::isnan(log.positions(0, 2)));  // c not seen yet
  CHECK(log.positions(3, 0) == 4.0);
  CHECK(log.positions(3, 1) == 41.0);
  CHECK(log.positions(3, 2) == 7.0);
  CHECK(std::isnan(log.positions(4, 0)));
  CHECK(log.positions(4, 1) == 41.0);
}

TEST_CASE("bag joint states: only the joints asked for are kept, with what they would be in the whole table",
          "[bag]") {
  const std::vector<logs::JointState> messages = {
      js(300, {"a", "b", "c"}, {3.0, 30.0, 300.0}), js(100, {"a", "b"}, {1.0, 10.0}), js(200, {"b"}, {20.0}),
      js(400, {"c", "a"}, {400.0, 4.0}), js(400, {"b"}, {41.0}), js(500, {"a"}, {std::nan("")})};
  JointStateCollector all, some({"c", "a", "z"});
  for (std::size_t k = 0; k < messages.size(); ++k) {
    REQUIRE(all.add(messages[k], k).empty());
    REQUIRE(some.add(messages[k], k).empty());
  }
  CHECK_THAT(some.add(js(600, {"b", "b"}, {1.0, 2.0}), 9), Catch::Contains("named twice"));  // checked all the same
  const JointLog whole = all.finish(), kept = some.finish();
  CHECK(kept.names == std::vector<std::string>{"c", "a"});  // z never seen: missing, as from a joints.csv
  CHECK(kept.source_names == whole.names);
  REQUIRE(kept.stamps_ns == whole.stamps_ns);
  for (std::size_t r = 0; r < whole.stamps_ns.size(); ++r)
    for (const std::string name : {"a", "c"}) {
      INFO("row " << r << ", " << name);
      const double w = whole.positions(static_cast<Eigen::Index>(r), whole.column(name));
      const double k = kept.positions(static_cast<Eigen::Index>(r), kept.column(name));
      CHECK((std::isnan(w) ? std::isnan(k) : w == k));
    }
  CHECK_THROWS_AS(columnIndices(kept, {"a", "z"}, "bag"), InputError);
}

TEST_CASE("detection pool: results by slot as they come, at most `capacity` images waiting, unreadable ones named",
          "[bag]") {
  const vision::CharucoTarget target;
  const vision::CharucoDetector detector(target);
  const auto cam = vision::CameraModel::fromKalibr("pinhole", "none", {500, 500, 320, 240}, {}, {640, 480});
  const cv::Mat board = vision::renderBoard(cam, target, SE3(SO3::identity(), Vec3(-0.1, -0.14, 0.6)));
  std::atomic<int> alive{0}, peak{0};
  constexpr std::size_t kCapacity = 3;
  constexpr int kImages = 24;
  std::mutex mutex;
  std::vector<StreamedDetection> results(kImages);
  std::vector<int> handed(kImages, 0);
  {
    DetectionPool pool(detector, 2, [&](std::size_t slot, StreamedDetection&& r) {
      std::lock_guard<std::mutex> lock(mutex);
      REQUIRE(slot < results.size());
      results[slot] = std::move(r);
      ++handed[slot];
    }, kCapacity);
    for (int i = 0; i < kImages; ++i) {
      // A decoded message lives from submit until its worker has decoded it.
      auto token = std::shared_ptr<int>(new int(i), [&](int* p) { --alive; delete p; });
      peak = std::max(peak.load(), ++alive);
      const std::size_t slot = pool.submit(
          [token, i, &board]() -> cv::Mat {
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
            if (i % 3 == 1) return cv::Mat(480, 640, CV_8UC1, cv::Scalar(255));
            if (i % 3 == 2) throw std::runtime_error("truncated JPEG");
            return board;
          },
          "image " + std::to_string(i));
      CHECK(slot == static_cast<std::size_t>(i));
    }
    pool.finish();
  }
  for (int i = 0; i < kImages; ++i) {
    INFO("image " << i);
    CHECK(handed[i] == 1);
    if (i % 3 == 0) {
      CHECK(results[i].detection.ok());
      CHECK(results[i].width == 640);
    } else if (i % 3 == 1) {
      CHECK(results[i].detection.status == vision::DetectionStatus::NoMarkers);
    } else {
      CHECK(results[i].detection.status == vision::DetectionStatus::UnreadableImage);
      CHECK_THAT(results[i].detection.message, Catch::Contains("image " + std::to_string(i)) &&
                                                   Catch::Contains("truncated JPEG"));
    }
  }
  CHECK(alive == 0);
  // The queue's bound plus one image per worker being decoded, plus the one being submitted.
  CHECK(peak <= static_cast<int>(kCapacity) + 2 + 1);
}

TEST_CASE("detection pool: an exception of the result's taker comes out of finish", "[bag]") {
  const vision::CharucoDetector detector{vision::CharucoTarget{}};
  DetectionPool pool(detector, 2, [](std::size_t slot, StreamedDetection&&) {
    if (slot == 1) throw std::runtime_error("taker failed");
  });
  for (int i = 0; i < 3; ++i) pool.submit([] { return cv::Mat(); }, "image");
  CHECK_THROWS_WITH(pool.finish(), Catch::Contains("taker failed"));
}
