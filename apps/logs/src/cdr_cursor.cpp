// CDR (XCDR1, "plain CDR") under the decoders' vocabulary (wire_cursor.hpp),
// as ROS 2's rmw layers write it: a 4-byte encapsulation header (00 01 little
// endian, 00 00 big endian; two option bytes that carry nothing we need), then
// the fields, each primitive aligned to its own size counted from the byte
// after the encapsulation header (8 for float64). Strings are a uint32 length
// that counts the trailing NUL, then the bytes; sequences a uint32 count, then
// the elements; fixed arrays (k[9], r[9], p[12]) their elements alone. An
// empty sequence of float64 has no padding after its count (nothing is
// aligned when no element follows), as Fast-CDR and @foxglove/cdr write it.
// std_msgs/Header has no seq, and builtin_interfaces/Time signed seconds.
#include <cstdio>
#include <string>

#include "fgcal/logs/log_error.hpp"
#include "mcap_encoding.hpp"
#include "wire_cursor.hpp"

namespace fgcal::logs::detail {

namespace {

class CdrCursor final : public WireCursor {
 public:
  CdrCursor(const RawMessage& m, const std::string& file, const std::string& where) : WireCursor(file, where) {
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

  std::string str(const char* field) override {
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

  /// Checked against what remains when each element takes at least its
  /// smallest size (a string its 4-byte length).
  std::uint32_t count(const char* field, Element element) override {
    const std::uint32_t n = u32(field);
    const std::size_t min_element_bytes = element == Element::Byte ? 1 : element == Element::String ? 4 : 8;
    if (static_cast<std::uint64_t>(n) * min_element_bytes > remaining())
      fail(field, "sequence of " + std::to_string(n) + " elements needs at least " +
                      std::to_string(static_cast<std::uint64_t>(n) * min_element_bytes) + " bytes, but only " +
                      std::to_string(remaining()) + " remain");
    return n;
  }

  Time headerTime() override {
    Time t;
    t.sec = i32("header.stamp.sec");
    t.nsec = u32("header.stamp.nanosec");
    return t;
  }

  // A CDR payload may end in alignment padding (the encapsulation header's
  // option bytes can count it), so bytes after a complete message are not an
  // error here, unlike in ROS 1.
  void finish(const char*) const override {}

  const char* name(const char*, const char* ros2) const override { return ros2; }

  [[noreturn]] void fail(const std::string& field, const std::string& what) const override {
    throw LogError(file_, where_, "CDR field " + field + ": " + what);
  }

 private:
  void need(std::uint64_t n, const char* field) const override {
    if (n > remaining())
      fail(field, "expected " + std::to_string(n) + " more bytes, but the message ends after " +
                      std::to_string(remaining()) + " (truncated?)");
  }

  /// Each primitive is aligned to its own size, counted from the byte after
  /// the encapsulation header.
  std::size_t padding(std::size_t width) const override { return (width - (pos_ - 4) % width) % width; }
};

}  // namespace

std::unique_ptr<WireCursor> cdrCursor(const RawMessage& m, const std::string& file, const std::string& where) {
  return std::make_unique<CdrCursor>(m, file, where);
}

}  // namespace fgcal::logs::detail
