// The ROS 1 wire format under the decoders' vocabulary (wire_cursor.hpp):
// little-endian, no alignment, strings and variable arrays prefixed by a
// uint32 count (strings without a trailing NUL), fixed arrays (CameraInfo's
// K, R, P) without one. Nothing pads a ROS 1 message, so a full decoder
// insists on consuming it exactly: a wrong or damaged type is reported
// instead of decoded into nonsense.
#include "fgcal/logs/log_error.hpp"
#include "wire_cursor.hpp"

namespace fgcal::logs::detail {

namespace {

class Ros1Cursor final : public WireCursor {
 public:
  Ros1Cursor(const RawMessage& m, const std::string& file, const std::string& where) : WireCursor(file, where) {
    data_ = m.data;
    size_ = m.data ? m.size : 0;
  }

  std::string str(const char* field) override {
    const std::uint32_t len = u32(field);
    need(len, field, "string of ", " bytes");
    std::string s(reinterpret_cast<const char*>(data_ + pos_), len);
    pos_ += len;
    return s;
  }

  std::uint32_t count(const char* field, Element element) override {
    const std::uint32_t n = u32(field);
    const std::string ns = std::to_string(n);
    switch (element) {
      case Element::Byte: need(n, field, "array of ", " bytes"); break;
      case Element::Float64: need(std::uint64_t{n} * 8, field, "array of " + ns + " float64 (", " bytes)"); break;
      // each string needs at least its 4-byte length: a cheap bound before reserving
      case Element::String:
        need(std::uint64_t{n} * 4, field, "array of " + ns + " strings (at least ", " bytes)");
        break;
    }
    return n;
  }

  Time headerTime() override {
    (void)u32("header.seq");
    Time t;
    t.sec = u32("header.stamp.sec");
    t.nsec = u32("header.stamp.nsec");
    return t;
  }

  void finish(const char* type) const override {
    if (pos_ != size_)
      throw LogError(file_, where_, std::to_string(remaining()) + " byte(s) left over after a complete " + type +
                                        " of " + std::to_string(pos_) + " bytes; expected the message to end there");
  }

  const char* name(const char* ros1, const char*) const override { return ros1; }

  [[noreturn]] void fail(const std::string& field, const std::string& what) const override {
    throw LogError(file_, where_, "field " + field + ": " + what);
  }

 private:
  void need(std::uint64_t n, const char* field) const override { need(n, field, "", " bytes"); }
  std::size_t padding(std::size_t) const override { return 0; }

  void need(std::uint64_t k, const char* field, const std::string& pre, const std::string& post) const {
    if (k > remaining())
      throw LogError(file_, where_, std::string("field ") + field + " needs " +
                                        (pre.empty() ? std::to_string(k) + post
                                                     : pre + std::to_string(k) + post) +
                                        " at byte " + std::to_string(pos_) + " but only " +
                                        std::to_string(remaining()) + " of the message's " + std::to_string(size_) +
                                        " remain");
  }
};

}  // namespace

std::unique_ptr<WireCursor> ros1Cursor(const RawMessage& m, const std::string& file, const std::string& where) {
  return std::make_unique<Ros1Cursor>(m, file, where);
}

}  // namespace fgcal::logs::detail
