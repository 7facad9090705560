// The format readers behind openBag (bag.cpp), each in its own file.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "fgcal/logs/bag.hpp"

namespace fgcal::logs::detail {

/// ROS 1 bag format 2.0 (ros1_bag.cpp).
std::unique_ptr<BagReader> openRos1Bag(const std::string& path, const ReadLimits& limits);
/// One MCAP file (mcap_reader.cpp).
std::unique_ptr<BagReader> openMcapFile(const std::string& path, const ReadLimits& limits);
/// One rosbag2 sqlite3 .db3 file (sqlite_reader.cpp).
std::unique_ptr<BagReader> openSqliteFile(const std::string& path, const ReadLimits& limits);
/// A rosbag2 folder: metadata.yaml and its storage files, split bags read
/// one file after the other (rosbag2_folder.cpp).
std::unique_ptr<BagReader> openRosbag2Folder(const std::string& path, const ReadLimits& limits);

/// What the four readers share: the path, the format line and the topics
/// they list, and the choice of the topics read() is asked for.
class BagReaderBase : public BagReader {
 public:
  const std::string& path() const override { return path_; }
  std::string format() const override { return format_; }
  const std::vector<TopicInfo>& topics() const override { return topics_; }

 protected:
  explicit BagReaderBase(std::string path) : path_(std::move(path)) {}

  /// The topics read() is asked for, as one flag per topics_ entry (every
  /// topic when `topic_names` is empty). A name the bag does not have is a
  /// LogError naming it and listing the topics the bag has (bag.cpp).
  std::vector<bool> selectTopics(const std::vector<std::string>& topic_names) const;

  std::string path_;
  std::string format_;
  std::vector<TopicInfo> topics_;  ///< sorted by name
};

}  // namespace fgcal::logs::detail
