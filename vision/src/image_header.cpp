// Image sizes from PNG/JPEG headers, and decoding only after them (see image_header.hpp).
#include "fgcal/vision/image_header.hpp"

#include <algorithm>
#include <climits>
#include <fstream>
#include <iterator>
#include <vector>

#include <opencv2/imgcodecs.hpp>

namespace fgcal::vision {

namespace {

enum class Parse { Found, NeedMore, Invalid };

std::uint32_t be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}
std::uint32_t be16(const std::uint8_t* p) { return (std::uint32_t{p[0]} << 8) | p[1]; }

Parse parsePng(const std::uint8_t* d, std::size_t n, ImageHeader* out) {
  // Signature (8), IHDR length (4) = 13, "IHDR" (4), width (4), height (4).
  if (n < 24) return Parse::NeedMore;
  static const std::uint8_t kIhdr[8] = {0, 0, 0, 13, 'I', 'H', 'D', 'R'};
  if (!std::equal(kIhdr, kIhdr + 8, d + 8)) return Parse::Invalid;
  const std::uint32_t w = be32(d + 16), h = be32(d + 20);
  if (w == 0 || h == 0 || w > INT_MAX || h > INT_MAX) return Parse::Invalid;
  *out = {ImageHeader::Format::Png, static_cast<int>(w), static_cast<int>(h)};
  return Parse::Found;
}

Parse parseJpeg(const std::uint8_t* d, std::size_t n, ImageHeader* out) {
  std::size_t pos = 2;  // after SOI
  for (;;) {
    // As libjpeg's next_marker: bytes other than FF before a marker are
    // skipped (it warns of "extraneous bytes"), then FF fill bytes; FF 00 is
    // no marker.
    while (pos < n && d[pos] != 0xFF) ++pos;
    while (pos < n && d[pos] == 0xFF) ++pos;
    if (pos >= n) return Parse::NeedMore;
    const std::uint8_t marker = d[pos++];
    if (marker == 0x00 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // TEM, RSTn: no length
    if (marker == 0xD8 || marker == 0xD9 || marker == 0xDA)
      return Parse::Invalid;  // a second SOI, EOI or the scan before any frame header
    if (pos + 2 > n) return Parse::NeedMore;
    const std::uint32_t length = be16(d + pos);  // counts its own two bytes
    if (length < 2) return Parse::Invalid;
    const bool frame = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame) {
      // Length, precision (1), height (2), width (2), components...
      if (length < 8) return Parse::Invalid;
      if (pos + 7 > n) return Parse::NeedMore;
      const std::uint32_t h = be16(d + pos + 3), w = be16(d + pos + 5);
      if (w == 0 || h == 0) return Parse::Invalid;  // a height given later (DNL) is not supported
      *out = {ImageHeader::Format::Jpeg, static_cast<int>(w), static_cast<int>(h)};
      return Parse::Found;
    }
    pos += length;
  }
}

Parse parse(const std::uint8_t* d, std::size_t n, ImageHeader* out) {
  static const std::uint8_t kPng[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (n >= 1 && d[0] == 0x89) {
    if (n < 8) return Parse::NeedMore;
    return std::equal(kPng, kPng + 8, d) ? parsePng(d, n, out) : Parse::Invalid;
  }
  if (n >= 1 && d[0] == 0xFF) {
    if (n < 2) return Parse::NeedMore;
    return d[1] == 0xD8 ? parseJpeg(d, n, out) : Parse::Invalid;
  }
  return n == 0 ? Parse::NeedMore : Parse::Invalid;
}

std::string sizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

void checkSize(const ImageHeader& h, ExpectedSize expected, const std::string& what) {
  if (expected.width > 0) {
    if (h.width != expected.width || h.height != expected.height)
      throw ImageSizeMismatch(h.width, h.height,
                              what + ": its header says " + sizeText(h.width, h.height) + ", expected " +
                                  sizeText(expected.width, expected.height) + "; not decoded");
  } else if (std::int64_t{h.width} * h.height > kMaxUncheckedPixels) {
    throw ImageSizeMismatch(h.width, h.height,
                            what + ": its header says " + sizeText(h.width, h.height) +
                                ", more than the 8192x8192 pixels decoded before the camera's resolution is "
                                "known; not decoded");
  }
}

/// The header checked, then decoded from memory. Decoded as stored: OpenCV
/// would otherwise turn a JPEG by its Exif orientation, and the decoded
/// size would no longer be the header's (nor the sensor's).
cv::Mat decodeChecked(const std::uint8_t* data, std::size_t size, ExpectedSize expected, int flags,
                      const std::string& what) {
  const auto h = readImageHeader(data, size);
  if (!h) return cv::Mat();
  checkSize(*h, expected, what);
  if (size > static_cast<std::size_t>(INT_MAX)) return cv::Mat();
  const cv::Mat buf(1, static_cast<int>(size), CV_8UC1, const_cast<std::uint8_t*>(data));
  try {
    return cv::imdecode(buf, flags | cv::IMREAD_IGNORE_ORIENTATION);
  } catch (const cv::Exception&) {
    return cv::Mat();  // a damaged stream: unreadable
  }
}

/// The file read once, its header checked, then decoded from that buffer.
cv::Mat readChecked(const std::string& path, ExpectedSize expected, int flags) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return cv::Mat();
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  return decodeChecked(bytes.data(), bytes.size(), expected, flags, "image '" + path + "'");
}

}  // namespace

std::optional<ImageHeader> readImageHeader(const std::uint8_t* data, std::size_t size) {
  ImageHeader h;
  if (!data || parse(data, size, &h) != Parse::Found) return std::nullopt;
  return h;
}

std::optional<ImageHeader> readImageFileHeader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  // Most headers lie in the first few hundred bytes; JPEG APPn segments
  // (Exif, ICC profiles) may push the frame header further: read on, in
  // doubling steps, until it is found, the file ends, or 16 MiB were read
  // without one (a crafted file of filler bytes is not read whole).
  constexpr std::size_t kMaxHeaderBytes = std::size_t{16} << 20;
  std::vector<std::uint8_t> buf;
  std::size_t want = 4096;
  for (;;) {
    const std::size_t have = buf.size();
    buf.resize(want);
    in.read(reinterpret_cast<char*>(buf.data() + have), static_cast<std::streamsize>(want - have));
    buf.resize(have + static_cast<std::size_t>(in.gcount()));
    ImageHeader h;
    const Parse p = parse(buf.data(), buf.size(), &h);
    if (p == Parse::Found) return h;
    if (p == Parse::Invalid || !in || want >= kMaxHeaderBytes) return std::nullopt;  // malformed, cut short, too far
    want *= 2;
  }
}

cv::Mat decodeGrayChecked(const std::uint8_t* data, std::size_t size, ExpectedSize expected) {
  return decodeChecked(data, size, expected, cv::IMREAD_GRAYSCALE, "the image");
}

cv::Mat readGrayChecked(const std::string& path, ExpectedSize expected) {
  return readChecked(path, expected, cv::IMREAD_GRAYSCALE);
}

cv::Mat readColorChecked(const std::string& path, ExpectedSize expected) {
  return readChecked(path, expected, cv::IMREAD_COLOR);
}

}  // namespace fgcal::vision
