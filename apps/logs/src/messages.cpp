// Message kinds and the one decoding of each message type (messages.hpp),
// written over the cursor vocabulary of wire_cursor.hpp that the ROS 1 wire
// format and CDR both implement: the fields and the checks on their values
// are the same whichever format carries them.
#include "fgcal/logs/messages.hpp"

#include <array>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "fgcal/logs/log_error.hpp"
#include "wire_cursor.hpp"

namespace fgcal::logs {

namespace {

std::string whereOf(const RawMessage& m) {
  return "topic " + (m.topic ? m.topic->name : std::string("?")) + ", message " + std::to_string(m.index);
}

void requireKind(const RawMessage& m, MessageKind want, const std::string& file) {
  const std::string type = m.topic ? m.topic->type : std::string();
  if (messageKind(type) != want)
    throw LogError(file, "topic " + (m.topic ? m.topic->name : std::string("?")),
                   std::string("expected messages of type ") + messageKindName(want) + ", but the topic's type is " +
                       (type.empty() ? std::string("unknown") : type));
}

/// The cursor of the topic's serialization.
std::unique_ptr<detail::WireCursor> cursorOf(const RawMessage& m, const std::string& file) {
  return m.topic->serialization == Serialization::Ros1 ? detail::ros1Cursor(m, file, whereOf(m))
                                                       : detail::cdrCursor(m, file, whereOf(m));
}

std::int64_t readStamp(detail::WireCursor& c) {
  const detail::WireCursor::Time t = c.headerTime();
  if (t.nsec >= 1000000000u)
    c.fail(c.name("header.stamp.nsec", "header.stamp.nanosec"),
           "expected less than 1000000000, found " + std::to_string(t.nsec));
  // A time before 1970 is no sensor time: a negative second count means a
  // damaged or garbage stamp, so it is refused rather than turned into a time
  // the calibration would trust.
  if (t.sec < 0) c.fail("header.stamp.sec", "expected a time since the epoch (>= 0), found " + std::to_string(t.sec));
  return t.sec * 1000000000 + t.nsec;
}

Header readHeader(detail::WireCursor& c) {
  Header h;
  h.stamp_ns = readStamp(c);
  h.frame_id = c.str("header.frame_id");
  return h;
}

/// Both formats store a bool as one byte; any other value than 0 or 1 means
/// the bytes are not this type (or are damaged).
bool readBool(detail::WireCursor& c, const char* field) {
  const std::uint8_t v = c.u8(field);
  if (v > 1) c.fail(field, "expected a bool (0 or 1), found " + std::to_string(v));
  return v == 1;
}

// One field, read as the type of the member that receives it.
void readField(detail::WireCursor& c, const char*, Header& v) { v = readHeader(c); }
void readField(detail::WireCursor& c, const char* field, bool& v) { v = readBool(c, field); }
void readField(detail::WireCursor& c, const char* field, std::uint32_t& v) { v = c.u32(field); }
void readField(detail::WireCursor& c, const char* field, std::string& v) { v = c.str(field); }
void readField(detail::WireCursor& c, const char* field, std::vector<std::uint8_t>& v) { v = c.bytes(field); }
void readField(detail::WireCursor& c, const char* field, std::vector<double>& v) { v = c.f64seq(field); }
void readField(detail::WireCursor& c, const char* field, std::vector<std::string>& v) { v = c.strseq(field); }
template <std::size_t N>
void readField(detail::WireCursor& c, const char* field, std::array<double, N>& v) {
  c.f64array(v, field);
}

void readFields(detail::WireCursor&) {}

/// The fields of a message in wire order, each its name and the member that
/// receives it: the decoders below read as the message definitions.
template <class T, class... Rest>
void readFields(detail::WireCursor& c, const char* field, T& member, Rest&&... rest) {
  readField(c, field, member);
  readFields(c, std::forward<Rest>(rest)...);
}

JointState readJointState(detail::WireCursor& c) {
  JointState js;
  readFields(c, "header", js.header, "name", js.name, "position", js.position, "velocity", js.velocity, "effort",
             js.effort);
  return js;
}

Image readImage(detail::WireCursor& c) {
  Image im;
  readFields(c, "header", im.header, "height", im.height, "width", im.width, "encoding", im.encoding, "is_bigendian",
             im.is_bigendian, "step", im.step, "data", im.data);
  return im;
}

CompressedImage readCompressedImage(detail::WireCursor& c) {
  CompressedImage ci;
  readFields(c, "header", ci.header, "format", ci.format, "data", ci.data);
  return ci;
}

CameraInfo readCameraInfo(detail::WireCursor& c) {
  CameraInfo ci;
  readFields(c, "header", ci.header, "height", ci.height, "width", ci.width, "distortion_model", ci.distortion_model,
             c.name("D", "d"), ci.d, c.name("K", "k"), ci.k, c.name("R", "r"), ci.r, c.name("P", "p"), ci.p,
             "binning_x", ci.binning_x, "binning_y", ci.binning_y);
  // roi (sensor_msgs/RegionOfInterest) is not kept, but it is read so that a
  // message cut inside it is refused like any other truncated message.
  std::uint32_t roi_offset_and_size[4];
  bool do_rectify = false;
  readFields(c, "roi.x_offset", roi_offset_and_size[0], "roi.y_offset", roi_offset_and_size[1], "roi.height",
             roi_offset_and_size[2], "roi.width", roi_offset_and_size[3], "roi.do_rectify", do_rectify);
  return ci;
}

/// Checks the topic's type, reads the message with `read` and lets the
/// format say whether anything may follow it.
template <class Read>
auto decodeAs(const RawMessage& m, const std::string& file, MessageKind kind, Read read) {
  requireKind(m, kind, file);
  const auto c = cursorOf(m, file);
  auto value = read(*c);
  c->finish(messageKindName(kind));
  return value;
}

}  // namespace

MessageKind messageKind(const std::string& type) {
  if (type == "sensor_msgs/JointState" || type == "sensor_msgs/msg/JointState") return MessageKind::JointState;
  if (type == "sensor_msgs/Image" || type == "sensor_msgs/msg/Image") return MessageKind::Image;
  if (type == "sensor_msgs/CompressedImage" || type == "sensor_msgs/msg/CompressedImage")
    return MessageKind::CompressedImage;
  if (type == "sensor_msgs/CameraInfo" || type == "sensor_msgs/msg/CameraInfo") return MessageKind::CameraInfo;
  return MessageKind::Other;
}

const char* messageKindName(MessageKind kind) {
  switch (kind) {
    case MessageKind::JointState: return "sensor_msgs/JointState";
    case MessageKind::Image: return "sensor_msgs/Image";
    case MessageKind::CompressedImage: return "sensor_msgs/CompressedImage";
    case MessageKind::CameraInfo: return "sensor_msgs/CameraInfo";
    case MessageKind::Other: break;
  }
  return "another type";
}

JointState decodeJointState(const RawMessage& m, const std::string& file) {
  return decodeAs(m, file, MessageKind::JointState, readJointState);
}

Image decodeImage(const RawMessage& m, const std::string& file) {
  return decodeAs(m, file, MessageKind::Image, readImage);
}

CompressedImage decodeCompressedImage(const RawMessage& m, const std::string& file) {
  return decodeAs(m, file, MessageKind::CompressedImage, readCompressedImage);
}

CameraInfo decodeCameraInfo(const RawMessage& m, const std::string& file) {
  return decodeAs(m, file, MessageKind::CameraInfo, readCameraInfo);
}

std::int64_t decodeHeaderStamp(const RawMessage& m, const std::string& file) {
  if (!m.topic) throw LogError(file, whereOf(m), "message without a topic");
  return readStamp(*cursorOf(m, file));
}

}  // namespace fgcal::logs
