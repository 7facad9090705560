// The four sensor_msgs types the calibration reads, as plain structs, and
// their decoders from either serialization (ROS 1 or CDR, both endiannesses).
// A decoder checks the topic's type (ROS 1 "sensor_msgs/Image" and ROS 2
// "sensor_msgs/msg/Image" are the same type) and throws LogError naming the
// file, topic, message index and what was wrong (wrong type, truncated data,
// a length running past the end).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "fgcal/logs/bag.hpp"

namespace fgcal::logs {

struct Header {
  std::int64_t stamp_ns = 0;  ///< header.stamp as nanoseconds since the epoch
  std::string frame_id;
};

struct JointState {
  Header header;
  std::vector<std::string> name;
  std::vector<double> position, velocity, effort;
};

struct Image {
  Header header;
  std::uint32_t height = 0, width = 0;
  std::string encoding;  ///< "mono8", "rgb8", "bayer_rggb8", ...
  bool is_bigendian = false;
  std::uint32_t step = 0;  ///< bytes per row
  std::vector<std::uint8_t> data;
};

struct CompressedImage {
  Header header;
  std::string format;  ///< e.g. "jpeg", "png", "mono8; jpeg compressed "
  std::vector<std::uint8_t> data;
};

struct CameraInfo {
  Header header;
  std::uint32_t height = 0, width = 0;
  std::string distortion_model;  ///< "plumb_bob", "rational_polynomial", "equidistant", ...
  std::vector<double> d;
  std::array<double, 9> k{};   ///< row-major 3x3
  std::array<double, 9> r{};
  std::array<double, 12> p{};  ///< row-major 3x4
  std::uint32_t binning_x = 0, binning_y = 0;
};

enum class MessageKind { JointState, Image, CompressedImage, CameraInfo, Other };

/// The kind of a stored type name: "sensor_msgs/JointState" and
/// "sensor_msgs/msg/JointState" are both MessageKind::JointState.
MessageKind messageKind(const std::string& type);
/// "sensor_msgs/JointState" etc., for messages.
const char* messageKindName(MessageKind kind);

JointState decodeJointState(const RawMessage& m, const std::string& file);
Image decodeImage(const RawMessage& m, const std::string& file);
CompressedImage decodeCompressedImage(const RawMessage& m, const std::string& file);
CameraInfo decodeCameraInfo(const RawMessage& m, const std::string& file);

/// Reads only header.stamp of any message whose type starts with a
/// std_msgs/Header (all four above): cheap, for bag-info and planning.
std::int64_t decodeHeaderStamp(const RawMessage& m, const std::string& file);

}  // namespace fgcal::logs
