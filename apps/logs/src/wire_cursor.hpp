// The reading vocabulary the message decoders (messages.cpp) are written in,
// and its two wire formats: the ROS 1 wire format (ros1_cursor.cpp) and CDR
// (cdr_cursor.cpp). A decoder says which field it reads next and of what
// kind; the cursor knows the format's byte order, alignment, string and
// sequence layout and its header.stamp, and words its own errors. Checks on
// the values read (a bool above 1, nanoseconds of a second above 1e9) belong
// to the decoders, so both formats make them alike.
//
// Every length is checked against the bytes that remain before anything is
// allocated, so a damaged message gives a LogError naming the file, topic,
// message and field, never a huge allocation or a read past the end.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "fgcal/logs/bag.hpp"

namespace fgcal::logs::detail {

class WireCursor {
 public:
  /// The element of a sequence, for the bound its count is checked against.
  enum class Element { Byte, Float64, String };
  /// header.stamp as the format stores it, not yet checked.
  struct Time {
    std::int64_t sec = 0;
    std::uint32_t nsec = 0;
  };

  virtual ~WireCursor() = default;

  virtual std::string str(const char* field) = 0;
  /// A sequence's element count, checked against the bytes left.
  virtual std::uint32_t count(const char* field, Element element) = 0;
  /// std_msgs/Header up to its stamp: ROS 1 has a seq before it, and its
  /// seconds are unsigned; ROS 2 has no seq and signed seconds.
  virtual Time headerTime() = 0;
  /// Called after a complete message of `type`: whether bytes may follow.
  virtual void finish(const char* type) const = 0;
  /// A field's name as the format's message definition spells it (ROS 1
  /// CameraInfo has D, K, R, P where ROS 2 has d, k, r, p).
  virtual const char* name(const char* ros1, const char* ros2) const = 0;
  /// A value that was read but is not what `field` may hold.
  [[noreturn]] virtual void fail(const std::string& field, const std::string& what) const = 0;

  /// The unsigned integer of `width` bytes (1, 4 or 8) that comes next, after
  /// the format's padding, in the format's byte order.
  std::uint64_t unsignedOf(std::size_t width, const char* field) {
    const std::size_t pad = padding(width);
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
  std::uint8_t u8(const char* field) { return static_cast<std::uint8_t>(unsignedOf(1, field)); }
  std::uint32_t u32(const char* field) { return static_cast<std::uint32_t>(unsignedOf(4, field)); }
  std::int32_t i32(const char* field) { return bitsAs<std::int32_t>(u32(field)); }
  double f64(const char* field) { return bitsAs<double>(unsignedOf(8, field)); }

  std::vector<std::uint8_t> bytes(const char* field) {
    const std::uint32_t n = count(field, Element::Byte);
    need(n, field);
    const std::uint8_t* p = data_ + pos_;
    pos_ += n;
    return std::vector<std::uint8_t>(p, p + n);
  }
  std::vector<double> f64seq(const char* field) {
    const std::uint32_t n = count(field, Element::Float64);
    std::vector<double> v;
    v.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i) v.push_back(f64(field));
    return v;
  }
  std::vector<std::string> strseq(const char* field) {
    const std::uint32_t n = count(field, Element::String);
    std::vector<std::string> v;
    v.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i) v.push_back(str(field));
    return v;
  }
  template <std::size_t N>
  void f64array(std::array<double, N>& out, const char* field) {
    for (auto& x : out) x = f64(field);
  }

 protected:
  WireCursor(const std::string& file, const std::string& where) : file_(file), where_(where) {}

  /// Throws the format's error when fewer than `n` bytes remain for `field`.
  virtual void need(std::uint64_t n, const char* field) const = 0;
  /// The bytes skipped before a primitive of `width` bytes.
  virtual std::size_t padding(std::size_t width) const = 0;
  std::size_t remaining() const { return size_ - pos_; }

  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0, pos_ = 0;
  bool little_ = true;
  const std::string& file_;
  const std::string where_;

 private:
  template <class T, class U>
  static T bitsAs(U u) {
    static_assert(sizeof(T) == sizeof(U), "same width");
    T v;
    std::memcpy(&v, &u, sizeof v);
    return v;
  }
};

/// `where` names the topic and message for errors; `file` must outlive the cursor.
std::unique_ptr<WireCursor> ros1Cursor(const RawMessage& m, const std::string& file, const std::string& where);
/// Refuses a topic whose MCAP message encoding is not CDR (mcap_encoding.hpp)
/// and a message without a plain CDR encapsulation header.
std::unique_ptr<WireCursor> cdrCursor(const RawMessage& m, const std::string& file, const std::string& where);

}  // namespace fgcal::logs::detail
