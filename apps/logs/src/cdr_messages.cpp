// CDR (XCDR1, "plain CDR") decoding of the four sensor_msgs types, as ROS 2's
// rmw layers write them: a 4-byte encapsulation header (00 01 little endian,
// 00 00 big endian; two option bytes that carry nothing we need), then the
// fields, each primitive aligned to its own size counted from the byte after
// the encapsulation header (8 for float64). Strings are a uint32 length that
// counts the trailing NUL, then the bytes; sequences a uint32 count, then the
// elements; fixed arrays (k[9], r[9], p[12]) their elements alone. An empty
// sequence of float64 has no padding after its count (nothing is aligned when
// no element follows), as Fast-CDR and @foxglove/cdr write it.
//
// Every length is checked against the bytes that remain before anything is
// allocated, so a damaged message gives a LogError naming the file, topic,
// message and field, never a huge allocation or a read past the end.
#include <array>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "fgcal/logs/log_error.hpp"
#include "mcap_encoding.hpp"
#include "message_decoders.hpp"

namespace fgcal::logs::detail {

namespace {

class CdrCursor {
 public:
  CdrCursor(const RawMessage& m, const std::string& file, const std::string& where) : file_(file), where_(where) {
    if (m.topic) {
      const std::string enc = foreignEncodingOf(m.topic->type);
      if (!enc.empty())
        throw LogError(file_, where_, "the topic's messages are " + enc + "-encoded; only CDR messages can be decoded");
    }
    if (m.size > 0 && m.data == nullptr) fail("message", "no data");
    data_ = m.data;
    size_ = m.size;
    if (size_ < 4)
      fail("encapsulation header",
           "expected 4 bytes (00 01 for little-endian CDR), but the message has " + std::to_string(size_));
    if (data_[0] != 0 || data_[1] > 1) {
      char hex[16];
      std::snprintf(hex, sizeof hex, "%02x %02x", data_[0], data_[1]);
      fail("encapsulation header",
           std::string("expected plain CDR (00 01 little endian or 00 00 big endian), found ") + hex +
               (data_[0] == 0 && (data_[1] == 2 || data_[1] == 3) ? " (parameter-list CDR, not supported)"
                : data_[0] == 0 && data_[1] >= 6                  ? " (XCDR2, not supported)"
                                                                  : ""));
    }
    little_ = data_[1] == 1;
    pos_ = 4;
  }

  std::uint8_t u8(const char* field) {
    need(1, field);
    return data_[pos_++];
  }
  std::uint32_t u32(const char* field) { return static_cast<std::uint32_t>(unsignedOf(4, field)); }
  std::int32_t i32(const char* field) {
    const std::uint32_t u = u32(field);
    std::int32_t v;
    std::memcpy(&v, &u, sizeof v);
    return v;
  }
  double f64(const char* field) {
    const std::uint64_t u = unsignedOf(8, field);
    double v;
    std::memcpy(&v, &u, sizeof v);
    return v;
  }

  std::string str(const char* field) {
    const std::uint32_t n = u32(field);
    if (n == 0) return {};  // Fast-CDR reads a zero length as the empty string
    if (n > remaining())
      fail(field, "string length " + std::to_string(n) + " runs past the end of the message (" +
                      std::to_string(remaining()) + " bytes remain)");
    if (data_[pos_ + n - 1] != 0) fail(field, "string of " + std::to_string(n) + " bytes does not end with a NUL");
    std::string s(reinterpret_cast<const char*>(data_ + pos_), n - 1);
    pos_ += n;
    return s;
  }

  /// A sequence's element count, checked against what remains when each
  /// element takes at least `min_element_bytes`.
  std::uint32_t count(const char* field, std::size_t min_element_bytes) {
    const std::uint32_t n = u32(field);
    if (static_cast<std::uint64_t>(n) * min_element_bytes > remaining())
      fail(field, "sequence of " + std::to_string(n) + " elements needs at least " +
                      std::to_string(static_cast<std::uint64_t>(n) * min_element_bytes) + " bytes, but only " +
                      std::to_string(remaining()) + " remain");
    return n;
  }

  std::vector<double> f64seq(const char* field) {
    const std::uint32_t n = count(field, 8);
    std::vector<double> v;
    v.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i) v.push_back(f64(field));
    return v;
  }
  template <std::size_t N>
  void f64array(std::array<double, N>& out, const char* field) {
    for (auto& x : out) x = f64(field);
  }
  std::vector<std::uint8_t> bytes(const char* field) {
    const std::uint32_t n = count(field, 1);
    std::vector<std::uint8_t> v(data_ + pos_, data_ + pos_ + n);
    pos_ += n;
    return v;
  }
  std::vector<std::string> strseq(const char* field) {
    const std::uint32_t n = count(field, 4);
    std::vector<std::string> v;
    v.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i) v.push_back(str(field));
    return v;
  }

  Header header() {
    Header h;
    h.stamp_ns = stamp();
    h.frame_id = str("header.frame_id");
    return h;
  }

  std::int64_t stamp() {
    const std::int32_t sec = i32("header.stamp.sec");
    const std::uint32_t nsec = u32("header.stamp.nanosec");
    if (nsec >= 1000000000u)
      fail("header.stamp.nanosec", "expected less than 1000000000, found " + std::to_string(nsec));
    // builtin_interfaces/Time before 1970 is no sensor time: a negative
    // second count means a damaged or garbage stamp, so it is refused rather
    // than turned into a time the calibration would trust.
    if (sec < 0) fail("header.stamp.sec", "expected a time since the epoch (>= 0), found " + std::to_string(sec));
    return static_cast<std::int64_t>(sec) * 1000000000 + nsec;
  }

  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw LogError(file_, where_, "CDR field " + field + ": " + what);
  }

 private:
  std::size_t remaining() const { return size_ - pos_; }

  void need(std::size_t n, const char* field) const {
    if (n > remaining())
      fail(field, "expected " + std::to_string(n) + " more bytes, but the message ends after " +
                      std::to_string(remaining()) + " (truncated?)");
  }

  std::uint64_t unsignedOf(std::size_t width, const char* field) {
    const std::size_t rel = pos_ - 4;  // alignment counts from after the encapsulation header
    const std::size_t pad = (width - rel % width) % width;
    need(pad + width, field);
    pos_ += pad;
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < width; ++i) {
      const std::uint64_t b = data_[pos_ + (little_ ? i : width - 1 - i)];
      v |= b << (8 * i);
    }
    pos_ += width;
    return v;
  }

  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0, pos_ = 0;
  bool little_ = true;
  const std::string& file_;
  const std::string& where_;
};

}  // namespace

std::int64_t decodeCdrHeaderStamp(const RawMessage& m, const std::string& file, const std::string& where) {
  CdrCursor c(m, file, where);
  return c.stamp();
}

JointState decodeCdrJointState(const RawMessage& m, const std::string& file, const std::string& where) {
  CdrCursor c(m, file, where);
  JointState js;
  js.header = c.header();
  js.name = c.strseq("name");
  js.position = c.f64seq("position");
  js.velocity = c.f64seq("velocity");
  js.effort = c.f64seq("effort");
  return js;
}

Image decodeCdrImage(const RawMessage& m, const std::string& file, const std::string& where) {
  CdrCursor c(m, file, where);
  Image im;
  im.header = c.header();
  im.height = c.u32("height");
  im.width = c.u32("width");
  im.encoding = c.str("encoding");
  const std::uint8_t be = c.u8("is_bigendian");
  if (be > 1) c.fail("is_bigendian", "expected 0 or 1, found " + std::to_string(be));
  im.is_bigendian = be == 1;
  im.step = c.u32("step");
  im.data = c.bytes("data");
  return im;
}

CompressedImage decodeCdrCompressedImage(const RawMessage& m, const std::string& file, const std::string& where) {
  CdrCursor c(m, file, where);
  CompressedImage ci;
  ci.header = c.header();
  ci.format = c.str("format");
  ci.data = c.bytes("data");
  return ci;
}

CameraInfo decodeCdrCameraInfo(const RawMessage& m, const std::string& file, const std::string& where) {
  CdrCursor c(m, file, where);
  CameraInfo ci;
  ci.header = c.header();
  ci.height = c.u32("height");
  ci.width = c.u32("width");
  ci.distortion_model = c.str("distortion_model");
  ci.d = c.f64seq("d");
  c.f64array(ci.k, "k");
  c.f64array(ci.r, "r");
  c.f64array(ci.p, "p");
  ci.binning_x = c.u32("binning_x");
  ci.binning_y = c.u32("binning_y");
  // roi (sensor_msgs/RegionOfInterest) is not kept, but it is read so that a
  // message cut inside it is refused like any other truncated message.
  for (const char* f : {"roi.x_offset", "roi.y_offset", "roi.height", "roi.width"}) (void)c.u32(f);
  const std::uint8_t rect = c.u8("roi.do_rectify");
  if (rect > 1) c.fail("roi.do_rectify", "expected a bool (0 or 1), found " + std::to_string(rect));
  return ci;
}

}  // namespace fgcal::logs::detail
