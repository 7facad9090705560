// The format readers behind openBag (bag.cpp), each in its own file.
#pragma once

#include <memory>
#include <string>
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

/// The topics BagReader::read is asked for, as one flag per bag.topics()
/// entry (every topic when `topic_names` is empty). A name the bag does not
/// have is a LogError naming it and listing the topics the bag has (bag.cpp).
std::vector<bool> selectTopics(const BagReader& bag, const std::vector<std::string>& topic_names);

}  // namespace fgcal::logs::detail
