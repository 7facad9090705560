// An image's width and height read from its header, before anything is
// decoded: a PNG or JPEG of a few kilobytes may declare 32000 x 32000 pixels
// (a "decompression bomb"), which a decoder would allocate gigabytes for.
// fgcal reads the size first, compares it with the camera's resolution and
// decodes only an image of the expected size (decodeGrayChecked,
// readGrayChecked); the calibration counts any other as "wrong image size".
//
// - PNG: the 8-byte signature, then the IHDR chunk (always first) holds the
//   width and height as big-endian 32-bit numbers.
// - JPEG: SOI (FF D8), then marker segments (APPn, COM, DQT, DHT, DRI, ...,
//   each with its 16-bit length) up to the first frame header SOF0..SOF15
//   (FFC0..FFCF except DHT FFC4, JPG FFC8 and DAC FFCC), which holds the
//   height and width as big-endian 16-bit numbers. Stray bytes and FF fill
//   bytes between segments are skipped, as libjpeg does.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <opencv2/core/mat.hpp>

#include "fgcal/vision/vision_error.hpp"

namespace fgcal::vision {

struct ImageHeader {
  enum class Format { Png, Jpeg };
  Format format = Format::Png;
  int width = 0, height = 0;  ///< > 0
};

/// The size a PNG or JPEG stream declares. nullopt when the bytes are
/// neither, or the header is cut short or malformed (a zero size, a segment
/// running past the end, no frame header before the image data).
std::optional<ImageHeader> readImageHeader(const std::uint8_t* data, std::size_t size);

/// The same from a file, reading only as much of it as the header needs.
/// nullopt too when the file cannot be opened.
std::optional<ImageHeader> readImageFileHeader(const std::string& path);

/// The largest image decoded when the expected size is not known yet (a bag
/// camera whose resolution comes from a camera_info not read yet): 2^26
/// pixels, 8192 x 8192.
constexpr std::int64_t kMaxUncheckedPixels = std::int64_t{1} << 26;

/// Thrown instead of decoding an image whose header declares another size
/// than the expected one (or, with no expected size, more than
/// kMaxUncheckedPixels): width and height are the header's.
class ImageSizeMismatch : public VisionError {
 public:
  ImageSizeMismatch(int width, int height, const std::string& what)
      : VisionError(what), width_(width), height_(height) {}
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int width_, height_;
};

/// The expected size of an image; width 0: not known.
struct ExpectedSize {
  int width = 0, height = 0;
};

/// 8-bit grey image of PNG/JPEG bytes, decoded only after the header was
/// read and matched `expected`: ImageSizeMismatch when it does not match; an
/// empty Mat when the bytes cannot be read (not PNG/JPEG, a damaged header or
/// data), as cv::imdecode gives.
cv::Mat decodeGrayChecked(const std::uint8_t* data, std::size_t size, ExpectedSize expected);

/// The same for an image file (an empty Mat also for a missing file, as
/// cv::imread gives); readColorChecked decodes to 8-bit BGR.
cv::Mat readGrayChecked(const std::string& path, ExpectedSize expected);
cv::Mat readColorChecked(const std::string& path, ExpectedSize expected);

}  // namespace fgcal::vision
