// openBag: tells the formats apart by name and magic bytes (bag.hpp).
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "readers.hpp"

namespace fs = std::filesystem;

namespace fgcal::logs {

namespace {

std::string compose(const std::string& file, const std::string& where, const std::string& detail) {
  std::string s = file;
  if (!where.empty()) s += (s.empty() ? "" : ": ") + where;
  if (!detail.empty()) s += (s.empty() ? "" : ": ") + detail;
  return s;
}

std::string lowerExtension(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

bool folderHoldsStorage(const fs::path& dir) {
  std::error_code ec;
  if (fs::is_regular_file(dir / "metadata.yaml", ec)) return true;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string e = lowerExtension(it->path());
    if (e == ".db3" || e == ".mcap") return true;
  }
  return false;
}

/// The first bytes of a file, or fewer when it is shorter.
std::string magic(const fs::path& p, std::size_t n) {
  std::ifstream in(p, std::ios::binary);
  std::string s(n, '\0');
  in.read(s.data(), static_cast<std::streamsize>(n));
  s.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return s;
}

}  // namespace

LogError::LogError(std::string file, std::string where, std::string detail)
    : std::runtime_error(compose(file, where, detail)),
      file_(std::move(file)),
      where_(std::move(where)),
      detail_(std::move(detail)) {}

const TopicInfo* BagReader::findTopic(const std::string& name) const {
  for (const auto& t : topics())
    if (t.name == name) return &t;
  return nullptr;
}

std::int64_t BagReader::startNs() const {
  std::int64_t v = 0;
  bool any = false;
  for (const auto& t : topics())
    if (t.message_count > 0 && (!any || t.first_record_ns < v)) v = t.first_record_ns, any = true;
  return v;
}

std::int64_t BagReader::endNs() const {
  std::int64_t v = 0;
  bool any = false;
  for (const auto& t : topics())
    if (t.message_count > 0 && (!any || t.last_record_ns > v)) v = t.last_record_ns, any = true;
  return v;
}

std::vector<bool> detail::BagReaderBase::selectTopics(const std::vector<std::string>& topic_names) const {
  std::vector<bool> wanted(topics_.size(), topic_names.empty());
  for (const auto& name : topic_names) {
    const auto it = std::find_if(topics_.begin(), topics_.end(), [&](const TopicInfo& t) { return t.name == name; });
    if (it == topics_.end()) {
      std::string list;
      for (const auto& t : topics_) list += (list.empty() ? "" : ", ") + t.name;
      throw LogError(path_, "topic " + name,
                     "not in the bag; its topics are: " + (list.empty() ? std::string("(none)") : list));
    }
    wanted[static_cast<std::size_t>(it - topics_.begin())] = true;
  }
  return wanted;
}

bool looksLikeBag(const std::string& path) {
  std::error_code ec;
  const fs::path p(path);
  if (fs::is_directory(p, ec)) return !fs::is_regular_file(p / "rig.yaml", ec) && folderHoldsStorage(p);
  const std::string e = lowerExtension(p);
  return e == ".bag" || e == ".mcap" || e == ".db3";
}

std::unique_ptr<BagReader> openBag(const std::string& path, const ReadLimits& limits) {
  std::error_code ec;
  const fs::path p(path);
  if (!fs::exists(p, ec))
    throw LogError(path, "", "not found; expected a ROS 1 .bag file, a ROS 2 bag folder or an .mcap file");
  if (fs::is_directory(p, ec)) {
    if (!folderHoldsStorage(p))
      throw LogError(path, "",
                     "expected a ROS 2 bag folder (metadata.yaml with .db3 or .mcap files), but it holds neither");
    return detail::openRosbag2Folder(path, limits);
  }
  const std::string head = magic(p, 16);  // the longest magic: "SQLite format 3\0"
  if (head.rfind("#ROSBAG V", 0) == 0) {
    if (head.rfind("#ROSBAG V2.0\n", 0) != 0)
      throw LogError(path, "offset 0",
                     "ROS 1 bag version '" + head.substr(0, head.find('\n')) + "' is not supported; expected #ROSBAG V2.0");
    return detail::openRos1Bag(path, limits);
  }
  if (head.size() >= 8 && std::memcmp(head.data(), "\x89MCAP0\r\n", 8) == 0) return detail::openMcapFile(path, limits);
  if (head.rfind("SQLite format 3", 0) == 0) return detail::openSqliteFile(path, limits);
  const std::string e = lowerExtension(p);
  if (e == ".bag") throw LogError(path, "offset 0", "expected a ROS 1 bag ('#ROSBAG V2.0' at the start of the file)");
  if (e == ".mcap") throw LogError(path, "offset 0", "expected an MCAP file (magic '\\x89MCAP0\\r\\n' at the start)");
  if (e == ".db3") throw LogError(path, "offset 0", "expected a rosbag2 sqlite3 file ('SQLite format 3' header)");
  throw LogError(path, "", "not a bag: expected a ROS 1 .bag, an .mcap or .db3 file, or a ROS 2 bag folder");
}

}  // namespace fgcal::logs
