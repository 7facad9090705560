// Decoders of the ROS 1 wire format (message_decoders.hpp): little-endian,
// no alignment, strings and variable arrays prefixed by a uint32 count,
// fixed arrays (CameraInfo's K, R, P) without one. Every length is checked
// against the bytes left before anything is allocated, and a full decoder
// insists on consuming the message exactly, so a wrong or damaged type is
// reported instead of decoded into nonsense.
#include <cstring>

#include "fgcal/logs/log_error.hpp"
#include "message_decoders.hpp"

namespace fgcal::logs::detail {

namespace {

class Ros1Reader {
 public:
  Ros1Reader(const RawMessage& m, const std::string& file, const std::string& where)
      : p_(m.data), n_(m.data ? m.size : 0), file_(file), where_(where) {}

  std::uint8_t u8(const char* field) {
    need(1, field);
    return p_[i_++];
  }

  std::uint32_t u32(const char* field) {
    need(4, field);
    const std::uint8_t* p = p_ + i_;
    i_ += 4;
    return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24;
  }

  double f64(const char* field) {
    need(8, field);
    std::uint64_t bits = 0;
    for (int k = 7; k >= 0; --k) bits = bits << 8 | p_[i_ + static_cast<std::size_t>(k)];
    i_ += 8;
    double v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }

  std::string str(const char* field) {
    const std::uint32_t len = u32(field);
    need(len, field, "string of ", " bytes");
    std::string s(reinterpret_cast<const char*>(p_ + i_), len);
    i_ += len;
    return s;
  }

  std::vector<std::uint8_t> bytes(const char* field) {
    const std::uint32_t len = u32(field);
    need(len, field, "array of ", " bytes");
    std::vector<std::uint8_t> v(p_ + i_, p_ + i_ + len);
    i_ += len;
    return v;
  }

  std::vector<double> f64s(const char* field) {
    const std::uint32_t count = u32(field);
    need(std::uint64_t{count} * 8, field, "array of " + std::to_string(count) + " float64 (", " bytes)");
    std::vector<double> v(count);
    for (auto& x : v) x = f64(field);
    return v;
  }

  std::vector<std::string> strs(const char* field) {
    const std::uint32_t count = u32(field);
    // each string needs at least its 4-byte length: a cheap bound before reserving
    need(std::uint64_t{count} * 4, field, "array of " + std::to_string(count) + " strings (at least ", " bytes)");
    std::vector<std::string> v;
    v.reserve(count);
    for (std::uint32_t k = 0; k < count; ++k) v.push_back(str(field));
    return v;
  }

  template <std::size_t N>
  void fixed(std::array<double, N>& a, const char* field) {
    need(N * 8, field, "float64[" + std::to_string(N) + "] (", " bytes)");
    for (auto& x : a) x = f64(field);
  }

  Header header() {
    Header h;
    (void)u32("header.seq");
    const std::uint32_t sec = u32("header.stamp.sec");
    const std::uint32_t nsec = u32("header.stamp.nsec");
    if (nsec >= 1000000000u)
      throw LogError(file_, where_, "header.stamp.nsec is " + std::to_string(nsec) + "; expected less than 1000000000");
    h.stamp_ns = std::int64_t{sec} * 1000000000 + nsec;
    h.frame_id = str("header.frame_id");
    return h;
  }

  void end(const char* type) const {
    if (i_ != n_)
      throw LogError(file_, where_, std::to_string(n_ - i_) + " byte(s) left over after a complete " + type + " of " +
                                        std::to_string(i_) + " bytes; expected the message to end there");
  }

 private:
  void need(std::uint64_t k, const char* field, const std::string& pre = "", const std::string& post = " bytes") const {
    if (k > n_ - i_)
      throw LogError(file_, where_, std::string("field ") + field + " needs " +
                                        (pre.empty() ? std::to_string(k) + post
                                                     : pre + std::to_string(k) + post) +
                                        " at byte " + std::to_string(i_) + " but only " + std::to_string(n_ - i_) +
                                        " of the message's " + std::to_string(n_) + " remain");
  }

  const std::uint8_t* p_;
  std::size_t n_, i_ = 0;
  const std::string& file_;
  const std::string& where_;
};

}  // namespace

JointState decodeRos1JointState(const RawMessage& m, const std::string& file, const std::string& where) {
  Ros1Reader r(m, file, where);
  JointState js;
  js.header = r.header();
  js.name = r.strs("name");
  js.position = r.f64s("position");
  js.velocity = r.f64s("velocity");
  js.effort = r.f64s("effort");
  r.end("sensor_msgs/JointState");
  return js;
}

Image decodeRos1Image(const RawMessage& m, const std::string& file, const std::string& where) {
  Ros1Reader r(m, file, where);
  Image im;
  im.header = r.header();
  im.height = r.u32("height");
  im.width = r.u32("width");
  im.encoding = r.str("encoding");
  im.is_bigendian = r.u8("is_bigendian") != 0;
  im.step = r.u32("step");
  im.data = r.bytes("data");
  r.end("sensor_msgs/Image");
  return im;
}

CompressedImage decodeRos1CompressedImage(const RawMessage& m, const std::string& file, const std::string& where) {
  Ros1Reader r(m, file, where);
  CompressedImage ci;
  ci.header = r.header();
  ci.format = r.str("format");
  ci.data = r.bytes("data");
  r.end("sensor_msgs/CompressedImage");
  return ci;
}

CameraInfo decodeRos1CameraInfo(const RawMessage& m, const std::string& file, const std::string& where) {
  Ros1Reader r(m, file, where);
  CameraInfo ci;
  ci.header = r.header();
  ci.height = r.u32("height");
  ci.width = r.u32("width");
  ci.distortion_model = r.str("distortion_model");
  ci.d = r.f64s("D");
  r.fixed(ci.k, "K");
  r.fixed(ci.r, "R");
  r.fixed(ci.p, "P");
  ci.binning_x = r.u32("binning_x");
  ci.binning_y = r.u32("binning_y");
  // roi (sensor_msgs/RegionOfInterest): x_offset, y_offset, height, width, do_rectify
  (void)r.u32("roi.x_offset");
  (void)r.u32("roi.y_offset");
  (void)r.u32("roi.height");
  (void)r.u32("roi.width");
  (void)r.u8("roi.do_rectify");
  r.end("sensor_msgs/CameraInfo");
  return ci;
}

std::int64_t decodeRos1HeaderStamp(const RawMessage& m, const std::string& file, const std::string& where) {
  Ros1Reader r(m, file, where);
  return r.header().stamp_ns;
}

}  // namespace fgcal::logs::detail
