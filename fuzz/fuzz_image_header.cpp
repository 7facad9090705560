// Fuzz target: the PNG/JPEG header reader that decides, before any decoding,
// whether an image has the camera's size (vision/image_header.hpp). A header
// may lie about anything; the reader must never read past the bytes, and
// when it accepts a header that OpenCV then decodes, the decoded image must
// have the size the header declared: otherwise a decompression bomb could
// pass the check under another size.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "fgcal/vision/image_header.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // The oracle decodes what the header accepts: bound what a decoder allocates.
  setenv("OPENCV_IO_MAX_IMAGE_PIXELS", "4194304", 1);
  cv::setNumThreads(1);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fgcal::vision;
  if (size > 1 << 20) return 0;
  try {
    const auto header = readImageHeader(data, size);
    if (!header) {
      // Not PNG/JPEG to the reader: the checked decoder decodes nothing.
      if (!decodeGrayChecked(data, size, {}).empty()) std::abort();
      return 0;
    }
    if (header->width <= 0 || header->height <= 0) std::abort();
    // Another expected size: refused with the header's size, never decoded.
    try {
      // (another width that cannot overflow: the header's may be INT_MAX)
      decodeGrayChecked(data, size, {header->width == 1 ? 2 : header->width - 1, header->height});
      std::abort();
    } catch (const ImageSizeMismatch& e) {
      if (e.width() != header->width || e.height() != header->height) std::abort();
    }
    if (std::int64_t{header->width} * header->height > (std::int64_t{1} << 22)) return 0;
    const cv::Mat img = decodeGrayChecked(data, size, {header->width, header->height});
    if (!img.empty() && (img.cols != header->width || img.rows != header->height)) std::abort();
  } catch (const ImageSizeMismatch&) {
    std::abort();  // the expected size was the header's
  } catch (const std::exception& e) {
    fgcal::fuzz::unexpected(e);
  }
  return 0;
}
