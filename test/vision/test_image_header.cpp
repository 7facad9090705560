// Image sizes read from PNG/JPEG headers without decoding, and the checked
// decoders that refuse an image of another size than expected (a
// decompression bomb declares gigapixels in a few bytes).
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <unistd.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "fgcal/vision/image_header.hpp"

using namespace fgcal::vision;
namespace fs = std::filesystem;

namespace {

std::vector<std::uint8_t> encode(const std::string& ext, int width, int height) {
  cv::Mat img(height, width, CV_8U);
  cv::randu(img, 0, 255);
  std::vector<std::uint8_t> bytes;
  REQUIRE(cv::imencode(ext, img, bytes));
  return bytes;
}

std::vector<std::uint8_t> bytesOf(const std::string& s) { return {s.begin(), s.end()}; }

std::optional<ImageHeader> headerOf(const std::vector<std::uint8_t>& b) { return readImageHeader(b.data(), b.size()); }

/// SOI, an APP1 segment of `app_bytes` payload, fill bytes, SOF2 (progressive) of w x h, EOI.
std::vector<std::uint8_t> jpegHeader(int w, int h, std::size_t app_bytes) {
  std::string s("\xFF\xD8\xFF\xE1", 4);
  const std::size_t len = app_bytes + 2;
  s += static_cast<char>(len >> 8);
  s += static_cast<char>(len & 0xFF);
  s += std::string(app_bytes, 'x');
  s += std::string("\xFF\xFF\xFF\xC2\x00\x0B\x08", 7);
  s += static_cast<char>(h >> 8);
  s += static_cast<char>(h & 0xFF);
  s += static_cast<char>(w >> 8);
  s += static_cast<char>(w & 0xFF);
  s += std::string("\x01\x01\x11\x00\xFF\xD9", 6);
  return bytesOf(s);
}

}  // namespace

TEST_CASE("image header: PNG and JPEG sizes as OpenCV writes them", "[vision][image_header]") {
  for (const char* ext : {".png", ".jpg"}) {
    INFO(ext);
    const auto b = encode(ext, 321, 123);
    const auto h = headerOf(b);
    REQUIRE(h);
    CHECK(h->width == 321);
    CHECK(h->height == 123);
    CHECK(h->format == (std::string(ext) == ".png" ? ImageHeader::Format::Png : ImageHeader::Format::Jpeg));
    const cv::Mat img = decodeGrayChecked(b.data(), b.size(), {321, 123});
    CHECK(img.cols == 321);
    CHECK(img.rows == 123);
    // Another expected size: not decoded, the header's size reported.
    try {
      decodeGrayChecked(b.data(), b.size(), {640, 480});
      FAIL("expected ImageSizeMismatch");
    } catch (const ImageSizeMismatch& e) {
      CHECK(e.width() == 321);
      CHECK(e.height() == 123);
      CHECK_THAT(std::string(e.what()), Catch::Contains("321x123") && Catch::Contains("expected 640x480"));
    }
  }
}

TEST_CASE("image header: JPEG markers before the frame header are skipped, bad headers refused",
          "[vision][image_header]") {
  const auto big = jpegHeader(32000, 32000, 20000);
  const auto h = headerOf(big);
  REQUIRE(h);
  CHECK(h->format == ImageHeader::Format::Jpeg);
  CHECK(h->width == 32000);
  CHECK(h->height == 32000);
  // Expected size unknown: over kMaxUncheckedPixels is still not decoded.
  CHECK_THROWS_AS(decodeGrayChecked(big.data(), big.size(), {}), ImageSizeMismatch);
  // Cut anywhere before the frame header's size: not a header.
  for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{3}, std::size_t{100}, big.size() - 8})
    CHECK_FALSE(readImageHeader(big.data(), n));
  CHECK(decodeGrayChecked(big.data(), 100, {}).empty());
  // Not an image, a PNG signature with no IHDR, a zero size, a scan before the frame header.
  CHECK_FALSE(headerOf(bytesOf("GIF89a.........................")));
  CHECK_FALSE(headerOf(bytesOf(std::string("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDX\0\0\0\x10\0\0\0\x10", 24))));
  CHECK_FALSE(headerOf(bytesOf(std::string("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\0\0\0\0\0\x10", 24))));
  CHECK_FALSE(headerOf(jpegHeader(0, 10, 4)));
  CHECK_FALSE(headerOf(bytesOf(std::string("\xFF\xD8\xFF\xDA\x00\x02", 6))));
  CHECK_FALSE(headerOf(bytesOf(std::string("\xFF\xD8\xFF\xE0\x00\x01", 6))));  // a length below 2
  // Stray bytes between segments are skipped, as libjpeg does (with a warning).
  {
    auto stray = big;
    stray.insert(stray.begin() + 2, {0x00, 0x12, 0x34});
    const auto s = headerOf(stray);
    REQUIRE(s);
    CHECK(s->width == 32000);
  }
  // DHT (C4) is not a frame header.
  CHECK_FALSE(headerOf(bytesOf(std::string("\xFF\xD8\xFF\xC4\x00\x0B\x08\x00\x10\x00\x10\x01\x01\x11\x00", 15))));
}

TEST_CASE("image header: read from a file, also past large JPEG segments, a missing file is empty",
          "[vision][image_header]") {
  const fs::path dir = fs::temp_directory_path() / ("fgcal_image_header_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto write = [&](const std::string& name, const std::vector<std::uint8_t>& b) {
    std::ofstream(dir / name, std::ios::binary).write(reinterpret_cast<const char*>(b.data()),
                                                      static_cast<std::streamsize>(b.size()));
    return (dir / name).string();
  };
  const std::string deep = write("deep.jpg", jpegHeader(640, 480, 60000));  // frame header after 60 kB
  const auto h = readImageFileHeader(deep);
  REQUIRE(h);
  CHECK(h->width == 640);
  CHECK(h->height == 480);
  const std::string png = write("small.png", encode(".png", 64, 48));
  CHECK(readGrayChecked(png, {64, 48}).size() == cv::Size(64, 48));
  CHECK(readColorChecked(png, {64, 48}).channels() == 3);
  CHECK_THROWS_AS(readGrayChecked(png, {640, 480}), ImageSizeMismatch);
  CHECK(readGrayChecked((dir / "missing.png").string(), {64, 48}).empty());
  CHECK_FALSE(readImageFileHeader((dir / "missing.png").string()));
  fs::remove_all(dir);
}
