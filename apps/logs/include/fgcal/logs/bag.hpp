// Reading robot logs without ROS: ROS 1 bags (format 2.0), rosbag2 bags
// (a folder with metadata.yaml and one or more .db3 or .mcap files, split bags
// included) and single MCAP files. A reader lists the topics and streams the
// raw, still-serialized messages of the topics asked for; messages.hpp decodes
// the four message types the calibration needs.
//
//   auto bag = fgcal::logs::openBag("run.mcap");
//   for (const auto& t : bag->topics()) std::cout << t.name << " " << t.type << "\n";
//   bag->read({"/joint_states"}, [&](const fgcal::logs::RawMessage& m) {
//     const auto js = fgcal::logs::decodeJointState(m);
//     ...
//     return true;  // false stops the reading
//   });
//
// Messages come in storage order (the order of record time, which is not the
// order of header stamps). Errors are LogError (log_error.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace fgcal::logs {

/// How the bytes of a topic's messages are serialized.
enum class Serialization {
  Ros1,  ///< ROS 1 wire format (little-endian, uint32 lengths, no alignment)
  Cdr,   ///< ROS 2 CDR / XCDR1 with its 4-byte encapsulation header
};

struct TopicInfo {
  std::string name;        ///< "/cam0/image_raw"
  std::string type;        ///< as stored: "sensor_msgs/Image" (ROS 1) or "sensor_msgs/msg/Image" (ROS 2)
  Serialization serialization = Serialization::Cdr;
  std::string definition;  ///< the message definition text when the bag stores one, else empty
  std::uint64_t message_count = 0;
  std::int64_t first_record_ns = 0, last_record_ns = 0;  ///< record (receive) times; 0 when no message
};

/// One message, still serialized. `data` is valid only inside the callback.
struct RawMessage {
  const TopicInfo* topic = nullptr;
  std::int64_t record_ns = 0;  ///< receive time (bag time / db3 timestamp / MCAP log_time): order only
  std::uint64_t index = 0;     ///< 0-based index of this message among its topic's messages, in storage order
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};

/// Limits that keep a damaged or hostile file from exhausting memory.
struct ReadLimits {
  /// Largest decompressed chunk or single message accepted (bytes).
  std::size_t max_chunk_bytes = std::size_t{1} << 30;  // 1 GiB
};

class BagReader {
 public:
  virtual ~BagReader() = default;
  /// The path as given to openBag.
  virtual const std::string& path() const = 0;
  /// "ROS 1 bag 2.0", "rosbag2 sqlite3", "rosbag2 MCAP", "MCAP", with details
  /// such as the compression (for bag-info).
  virtual std::string format() const = 0;
  /// Every topic of the bag, sorted by name.
  virtual const std::vector<TopicInfo>& topics() const = 0;
  /// Calls `fn` for each message of the named topics (every topic when
  /// `topic_names` is empty) in storage order, until it returns false. A
  /// topic name not in the bag is a LogError listing those that are.
  virtual void read(const std::vector<std::string>& topic_names,
                    const std::function<bool(const RawMessage&)>& fn) = 0;

  /// The topic with that name, or nullptr.
  const TopicInfo* findTopic(const std::string& name) const;
  /// Record-time span of the whole bag (ns), from the topics.
  std::int64_t startNs() const;
  std::int64_t endNs() const;
};

/// Opens a ROS 1 .bag file, an .mcap file, a .db3 file or a rosbag2 folder
/// (metadata.yaml with its .db3 or .mcap files; a folder without
/// metadata.yaml but with .db3/.mcap files is read from those files alone).
/// Throws LogError when the path is none of these or the file is damaged.
std::unique_ptr<BagReader> openBag(const std::string& path, const ReadLimits& limits = {});

/// True when `path` looks like a bag openBag would take (a .bag/.mcap/.db3
/// file, or a folder holding metadata.yaml or .db3/.mcap files), without
/// reading it: used to tell a bag from a dataset folder.
bool looksLikeBag(const std::string& path);

}  // namespace fgcal::logs
