// Message kinds and the decoders' dispatch on the serialization (messages.hpp).
#include "fgcal/logs/messages.hpp"

#include "fgcal/logs/log_error.hpp"
#include "message_decoders.hpp"

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
  requireKind(m, MessageKind::JointState, file);
  return m.topic->serialization == Serialization::Ros1 ? detail::decodeRos1JointState(m, file, whereOf(m))
                                                       : detail::decodeCdrJointState(m, file, whereOf(m));
}

Image decodeImage(const RawMessage& m, const std::string& file) {
  requireKind(m, MessageKind::Image, file);
  return m.topic->serialization == Serialization::Ros1 ? detail::decodeRos1Image(m, file, whereOf(m))
                                                       : detail::decodeCdrImage(m, file, whereOf(m));
}

CompressedImage decodeCompressedImage(const RawMessage& m, const std::string& file) {
  requireKind(m, MessageKind::CompressedImage, file);
  return m.topic->serialization == Serialization::Ros1 ? detail::decodeRos1CompressedImage(m, file, whereOf(m))
                                                       : detail::decodeCdrCompressedImage(m, file, whereOf(m));
}

CameraInfo decodeCameraInfo(const RawMessage& m, const std::string& file) {
  requireKind(m, MessageKind::CameraInfo, file);
  return m.topic->serialization == Serialization::Ros1 ? detail::decodeRos1CameraInfo(m, file, whereOf(m))
                                                       : detail::decodeCdrCameraInfo(m, file, whereOf(m));
}

std::int64_t decodeHeaderStamp(const RawMessage& m, const std::string& file) {
  if (!m.topic) throw LogError(file, whereOf(m), "message without a topic");
  return m.topic->serialization == Serialization::Ros1 ? detail::decodeRos1HeaderStamp(m, file, whereOf(m))
                                                       : detail::decodeCdrHeaderStamp(m, file, whereOf(m));
}

}  // namespace fgcal::logs
