// `fgcal bag-info BAG`: what a robot log holds, without ROS (the counterpart of
// `rosbag info` / `ros2 bag info`), so a user can write rig.yaml's topics and
// check that a recording is complete before calibrating from it.
//
// summarizeBag opens the bag through fgcal::logs and collects, per topic, the
// type, count, record-time span, rate and serialization; with read_stamps it
// also reads header.stamp of every message of the four types the calibration
// uses (JointState, Image, CompressedImage, CameraInfo), which reads the whole
// of those topics (all image bytes), hence opt-in. formatBagInfo prints it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace fgcal::apps {

struct BagTopicSummary {
  std::string name;           ///< "/cam0/image_raw"
  std::string type;           ///< as stored: "sensor_msgs/Image" or "sensor_msgs/msg/Image"
  std::string serialization;  ///< "ros1" or "cdr"
  std::uint64_t message_count = 0;
  /// Record (receive) times of the first and last message; 0 when none.
  std::int64_t first_record_ns = 0, last_record_ns = 0;
  /// (count - 1) / (last - first record time), Hz; 0 with fewer than two
  /// messages or a zero span.
  double rate_hz = 0.0;
  /// One of the four types the calibration reads (so header stamps can be read).
  bool known_type = false;
  /// Filled by summarizeBag(..., read_stamps = true) for known types with
  /// messages: the smallest and largest header.stamp, and how many messages
  /// have a header stamp earlier than the one stored before them.
  bool stamps_read = false;
  std::int64_t min_stamp_ns = 0, max_stamp_ns = 0;
  std::uint64_t stamps_out_of_order = 0;
};

struct BagSummary {
  std::string path;    ///< as given
  std::string format;  ///< BagReader::format(), e.g. "ROS 1 bag 2.0 (lz4 chunks)"
  std::uint64_t size_bytes = 0;  ///< the file, or every file under the bag folder
  std::uint64_t message_count = 0;
  /// Record-time span of the whole bag; 0 when it holds no message.
  std::int64_t start_ns = 0, end_ns = 0;
  std::vector<BagTopicSummary> topics;  ///< sorted by name
};

/// Opens and summarizes the bag at `path` (a ROS 1 .bag, a rosbag2 folder or
/// .db3, an .mcap). A missing, unrecognized or damaged bag is an InputError
/// (exit 2) carrying the reader's LogError message (file, offset or topic and
/// message, what was expected).
BagSummary summarizeBag(const std::string& path, bool read_stamps = false);

/// The human-readable report: path, format, duration, start and end (seconds
/// since the epoch and UTC date), size, message count, then one row per topic
/// (name, type, count, rate, serialization, and the header-stamp span when
/// read).
std::string formatBagInfo(const BagSummary& summary);

/// "2023-11-25 02:04:33.968399947 UTC" for nanoseconds since the epoch.
std::string formatUtc(std::int64_t ns);

}  // namespace fgcal::apps
