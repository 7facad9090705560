// A rosbag2 bag folder: metadata.yaml (versions 1 to 9, Dashing to Jazzy) and
// the storage files it lists in relative_file_paths, .db3 (sqlite3) or .mcap,
// read as ONE bag: topics merged by name, counts summed, the files of a split
// bag read one after the other, and each topic's message index continuing
// from one file to the next. A folder without metadata.yaml (a recording that
// was never closed) is read from its .db3/.mcap files in natural name order
// (bag_2 before bag_10).
//
// What metadata.yaml may and may not contradict:
//  - a file it lists that is missing, a storage it names that we cannot read,
//    a topic whose type differs from the storage's, or compression_mode FILE
//    are errors: reading on would give a different bag than the one recorded;
//  - message counts (total, per topic, per file) that differ from the storage
//    are NOT errors: the storage is what is read and what topics() reports
//    (rosbag2 itself never reads those counts back, and a recorder that
//    stopped uncleanly leaves them stale). The disagreement is reported in
//    format(), which bag-info prints;
//  - storage files in the folder that metadata.yaml does not list are not
//    read (rosbag2 reads only the listed ones too).
// compression_mode MESSAGE with zstd (each message compressed on its own) is
// decompressed here, so either storage reader sees plain CDR.
#include <yaml-cpp/yaml.h>
#include <zstd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "readers.hpp"

namespace fs = std::filesystem;

namespace fgcal::logs::detail {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

/// Natural order: runs of digits compare by value, so bag_2 < bag_10.
bool naturalLess(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
      std::size_t i2 = i, j2 = j;
      while (i2 < a.size() && std::isdigit(static_cast<unsigned char>(a[i2]))) ++i2;
      while (j2 < b.size() && std::isdigit(static_cast<unsigned char>(b[j2]))) ++j2;
      std::string x = a.substr(i, i2 - i), y = b.substr(j, j2 - j);
      x.erase(0, std::min(x.find_first_not_of('0'), x.size()));
      y.erase(0, std::min(y.find_first_not_of('0'), y.size()));
      if (x.size() != y.size()) return x.size() < y.size();
      if (x != y) return x < y;
      i = i2, j = j2;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i, ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

/// metadata.yaml's content, as far as reading needs it.
struct Metadata {
  int version = 0;
  std::string storage_identifier;
  std::vector<std::string> files;  // relative_file_paths
  bool has_total = false;
  std::uint64_t message_count = 0;
  struct Topic {
    std::string name, type;
    std::uint64_t count = 0;
  };
  std::vector<Topic> topics;
  std::map<std::string, std::uint64_t> file_counts;  // files: path -> message_count
  std::string compression_format, compression_mode;
};

class MetadataParser {
 public:
  explicit MetadataParser(std::string file) : file_(std::move(file)) {}

  Metadata parse() {
    YAML::Node root;
    try {
      root = YAML::LoadFile(file_);
    } catch (const YAML::ParserException& e) {
      throw LogError(file_, "line " + std::to_string(e.mark.line + 1), "not valid YAML: " + e.msg);
    } catch (const YAML::Exception& e) {
      throw LogError(file_, "", std::string("cannot be read: ") + e.what());
    }
    const YAML::Node info = root.IsMap() ? root["rosbag2_bagfile_information"] : YAML::Node();
    if (!info || !info.IsMap())
      throw LogError(file_, "rosbag2_bagfile_information",
                     "missing: expected rosbag2's metadata.yaml with a rosbag2_bagfile_information map");
    Metadata m;
    const std::string top = "rosbag2_bagfile_information.";
    m.version = static_cast<int>(integer(required(info, "version", top), top + "version"));
    if (m.version < 1)
      throw LogError(file_, top + "version", "is " + std::to_string(m.version) + ", expected 1 or more");
    if (info["storage_identifier"]) m.storage_identifier = text(info["storage_identifier"], top + "storage_identifier");
    const YAML::Node paths = required(info, "relative_file_paths", top);
    if (!paths.IsSequence() || paths.size() == 0)
      throw LogError(file_, top + "relative_file_paths", "expected a list of one or more storage file names");
    for (std::size_t i = 0; i < paths.size(); ++i)
      m.files.push_back(text(paths[i], top + "relative_file_paths[" + std::to_string(i) + "]"));
    if (info["message_count"]) {
      m.has_total = true;
      m.message_count = integer(info["message_count"], top + "message_count");
    }
    if (const YAML::Node topics = info["topics_with_message_count"]; topics && !topics.IsNull()) {
      if (!topics.IsSequence())
        throw LogError(file_, top + "topics_with_message_count", "expected a list of topics");
      for (std::size_t i = 0; i < topics.size(); ++i) {
        const std::string at = top + "topics_with_message_count[" + std::to_string(i) + "]";
        if (!topics[i].IsMap()) throw LogError(file_, at, "expected a map with topic_metadata and message_count");
        const YAML::Node meta = required(topics[i], "topic_metadata", at + ".");
        if (!meta.IsMap()) throw LogError(file_, at + ".topic_metadata", "expected a map with name and type");
        Metadata::Topic t;
        t.name = text(required(meta, "name", at + ".topic_metadata."), at + ".topic_metadata.name");
        t.type = text(required(meta, "type", at + ".topic_metadata."), at + ".topic_metadata.type");
        // offered_qos_profiles is a YAML string up to version 8 and a list in
        // version 9; reading needs neither, so both are accepted untouched.
        t.count = integer(required(topics[i], "message_count", at + "."), at + ".message_count");
        m.topics.push_back(std::move(t));
      }
    }
    if (const YAML::Node files = info["files"]; files && !files.IsNull()) {
      if (!files.IsSequence()) throw LogError(file_, top + "files", "expected a list of files");
      for (std::size_t i = 0; i < files.size(); ++i) {
        const std::string at = top + "files[" + std::to_string(i) + "]";
        if (!files[i].IsMap()) throw LogError(file_, at, "expected a map with path and message_count");
        const std::string path = text(required(files[i], "path", at + "."), at + ".path");
        if (files[i]["message_count"]) m.file_counts[path] = integer(files[i]["message_count"], at + ".message_count");
      }
    }
    if (info["compression_format"]) m.compression_format = text(info["compression_format"], top + "compression_format");
    if (info["compression_mode"]) m.compression_mode = text(info["compression_mode"], top + "compression_mode");
    return m;
  }

 private:
  YAML::Node required(const YAML::Node& map, const std::string& key, const std::string& prefix) const {
    const YAML::Node n = map[key];
    if (!n) throw LogError(file_, prefix + key, "missing");
    return n;
  }

  std::string text(const YAML::Node& n, const std::string& field) const {
    if (!n.IsScalar()) throw LogError(file_, field, "expected a text value");
    return n.Scalar();
  }

  std::uint64_t integer(const YAML::Node& n, const std::string& field) const {
    const std::string s = n.IsScalar() ? n.Scalar() : std::string();
    if (s.empty() || s.size() > 19 || s.find_first_not_of("0123456789") != std::string::npos)
      throw LogError(file_, field, "is '" + s + "', expected a whole number >= 0");
    return std::stoull(s);
  }

  std::string file_;
};

/// How one storage file is opened: by its extension, else by the storage
/// identifier of metadata.yaml.
std::unique_ptr<BagReader> openStorage(const fs::path& p, const std::string& storage_identifier,
                                       const std::string& metadata_file, const ReadLimits& limits) {
  const std::string ext = lower(p.extension().string());
  const std::string id = lower(storage_identifier);
  if ((ext == ".db3" && !id.empty() && id != "sqlite3") || (ext == ".mcap" && !id.empty() && id != "mcap"))
    throw LogError(metadata_file, "rosbag2_bagfile_information.storage_identifier",
                   "is '" + storage_identifier + "', but the storage file " + p.filename().string() +
                       " is " + (ext == ".db3" ? "sqlite3" : "mcap"));
  if (ext == ".db3" || (ext != ".mcap" && id == "sqlite3")) return openSqliteFile(p.string(), limits);
  if (ext == ".mcap" || id == "mcap") return openMcapFile(p.string(), limits);
  throw LogError(metadata_file, "rosbag2_bagfile_information.storage_identifier",
                 "is '" + storage_identifier + "' for " + p.filename().string() +
                     "; expected sqlite3 (.db3 files) or mcap (.mcap files)");
}

class Rosbag2Folder final : public BagReaderBase {
 public:
  Rosbag2Folder(std::string path, const ReadLimits& limits) : BagReaderBase(std::move(path)), limits_(limits) {
    const fs::path dir(path_);
    const fs::path yaml = dir / "metadata.yaml";
    std::error_code ec;
    std::vector<fs::path> files;
    std::string storage_identifier;
    Metadata meta;
    const bool has_meta = fs::is_regular_file(yaml, ec);
    if (has_meta) {
      meta = MetadataParser(yaml.string()).parse();
      storage_identifier = meta.storage_identifier;
      for (std::size_t i = 0; i < meta.files.size(); ++i) {
        fs::path p = dir / meta.files[i];
        // Before version 4, rosbag2 wrote the paths relative to the folder's parent.
        if (!fs::exists(p, ec) && meta.version < 4) p = dir.parent_path() / meta.files[i];
        if (!fs::is_regular_file(p, ec))
          throw LogError(yaml.string(), "rosbag2_bagfile_information.relative_file_paths[" + std::to_string(i) + "]",
                         "names " + meta.files[i] + ", which is not a file in " + path_ +
                             " (a split bag copied without all its files?)");
        for (std::size_t j = 0; j < i; ++j)
          if (meta.files[j] == meta.files[i])
            throw LogError(yaml.string(), "rosbag2_bagfile_information.relative_file_paths[" + std::to_string(i) + "]",
                           "names " + meta.files[i] + " a second time (also entry " + std::to_string(j) +
                               "); expected each storage file once");
        files.push_back(p);
      }
      compression_ = lower(meta.compression_mode);
      const std::string fmt = lower(meta.compression_format);
      if (compression_ == "file")
        throw LogError(yaml.string(), "rosbag2_bagfile_information.compression_mode",
                       "is FILE (whole storage files compressed with " + meta.compression_format +
                           "); decompress the bag first (ros2 bag decompress, or zstd -d on each file and "
                           "metadata.yaml updated)");
      if (compression_ == "message" && fmt != "zstd")
        throw LogError(yaml.string(), "rosbag2_bagfile_information.compression_format",
                       "is '" + meta.compression_format + "' with compression_mode MESSAGE; expected zstd");
      if (compression_ != "message" && compression_ != "none" && !compression_.empty())
        throw LogError(yaml.string(), "rosbag2_bagfile_information.compression_mode",
                       "is '" + meta.compression_mode + "'; expected empty, NONE, MESSAGE or FILE");
    } else {
      for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string e = lower(it->path().extension().string());
        if ((e == ".db3" || e == ".mcap") && it->is_regular_file(ec)) files.push_back(it->path());
      }
      if (ec) throw LogError(path_, "", "cannot list the folder: " + ec.message());
      std::sort(files.begin(), files.end(),
                [](const fs::path& a, const fs::path& b) { return naturalLess(a.filename().string(), b.filename().string()); });
      if (files.empty())
        throw LogError(path_, "", "expected metadata.yaml or .db3/.mcap storage files in the folder, found neither");
    }

    for (const auto& f : files) {
      Part part;
      part.reader = openStorage(f, storage_identifier, yaml.string(), limits_);
      parts_.push_back(std::move(part));
    }
    merge();
    describe(has_meta, meta, files);
  }

  void read(const std::vector<std::string>& topic_names, const std::function<bool(const RawMessage&)>& fn) override {
    (void)selectTopics(topic_names);  // each file selects its own share below
    bool go_on = true;
    std::vector<std::uint8_t> plain;  // a decompressed message
    for (std::size_t k = 0; k < parts_.size() && go_on; ++k) {
      Part& part = parts_[k];
      const auto& own = part.reader->topics();
      std::vector<std::string> names;  // the asked topics this file has
      for (const auto& name : topic_names)
        if (part.reader->findTopic(name)) names.push_back(name);
      if (!topic_names.empty() && names.empty()) continue;  // an empty list would mean every topic
      part.reader->read(names, [&](const RawMessage& m) {
        const std::less<const TopicInfo*> before;
        std::size_t own_pos = 0;
        if (!before(m.topic, own.data()) && before(m.topic, own.data() + own.size())) {
          own_pos = static_cast<std::size_t>(m.topic - own.data());
        } else {  // a reader that points elsewhere: find the topic by name
          const auto it = std::find_if(own.begin(), own.end(), [&](const TopicInfo& t) { return t.name == m.topic->name; });
          if (it == own.end()) throw LogError(part.reader->path(), "topic " + m.topic->name, "delivered but not listed");
          own_pos = static_cast<std::size_t>(it - own.begin());
        }
        const std::size_t t = part.merged[own_pos];
        RawMessage out = m;
        out.topic = &topics_[t];
        out.index = part.offset[own_pos] + m.index;
        if (compression_ == "message") {
          decompress(m, out, plain);
          out.data = plain.data();
          out.size = plain.size();
        }
        go_on = fn(out);
        return go_on;
      });
    }
  }

 private:
  struct Part {
    std::unique_ptr<BagReader> reader;
    std::vector<std::size_t> merged;    // the file's topic position -> position in topics_
    std::vector<std::uint64_t> offset;  // the file's topic position -> messages of that topic in earlier files
  };

  void merge() {
    std::map<std::string, TopicInfo> all;
    std::map<std::string, std::string> first_file;
    for (const auto& part : parts_) {
      for (const auto& t : part.reader->topics()) {
        auto [it, fresh] = all.emplace(t.name, t);
        if (fresh) {
          first_file[t.name] = part.reader->path();
          continue;
        }
        TopicInfo& m = it->second;
        if (m.type != t.type || m.serialization != t.serialization)
          throw LogError(part.reader->path(), "topic " + t.name,
                         "has type " + t.type + ", but " + first_file[t.name] + " stores it as " + m.type +
                             "; expected one type per topic across the files of a split bag");
        if (m.definition.empty()) m.definition = t.definition;
        if (t.message_count > 0) {
          if (m.message_count == 0 || t.first_record_ns < m.first_record_ns) m.first_record_ns = t.first_record_ns;
          if (m.message_count == 0 || t.last_record_ns > m.last_record_ns) m.last_record_ns = t.last_record_ns;
        }
        m.message_count += t.message_count;
      }
    }
    for (auto& [name, t] : all) {
      position_[name] = topics_.size();
      topics_.push_back(std::move(t));
    }
    std::vector<std::uint64_t> seen(topics_.size(), 0);
    for (auto& part : parts_) {
      for (const auto& t : part.reader->topics()) {
        const std::size_t pos = position_.at(t.name);
        part.merged.push_back(pos);
        part.offset.push_back(seen[pos]);
        seen[pos] += t.message_count;
      }
    }
  }

  void describe(bool has_meta, const Metadata& meta, const std::vector<fs::path>& files) {
    const std::string yaml = (fs::path(path_) / "metadata.yaml").string();
    std::string kinds;
    for (const auto& part : parts_) {
      const std::string f = part.reader->format();
      if (kinds.find(f) == std::string::npos) kinds += (kinds.empty() ? "" : " + ") + f;
    }
    format_ = kinds + ", " + std::to_string(parts_.size()) + (parts_.size() == 1 ? " file" : " files");
    if (!has_meta) {
      format_ += ", no metadata.yaml (files read in name order)";
      return;
    }
    format_ += ", metadata version " + std::to_string(meta.version);
    if (compression_ == "message") format_ += ", messages compressed with zstd";

    // A type that differs is an error; a count that differs is a note.
    std::vector<std::string> notes;
    std::uint64_t total = 0;
    for (const auto& t : topics_) total += t.message_count;
    if (meta.has_total && meta.message_count != total)
      notes.push_back("metadata.yaml states " + std::to_string(meta.message_count) + " messages, the files hold " +
                      std::to_string(total));
    for (const auto& mt : meta.topics) {
      const auto it = position_.find(mt.name);
      if (it == position_.end()) {
        if (mt.count > 0)
          notes.push_back("metadata.yaml lists topic " + mt.name + " with " + std::to_string(mt.count) +
                          " messages, the files do not have it");
        continue;
      }
      const TopicInfo& t = topics_[it->second];
      if (t.type != mt.type)
        throw LogError(yaml, "topic " + mt.name,
                       "metadata.yaml gives the type " + mt.type + ", the storage " + t.type +
                           "; expected the same type");
      if (t.message_count != mt.count)
        notes.push_back("topic " + mt.name + ": metadata.yaml states " + std::to_string(mt.count) +
                        " messages, the files hold " + std::to_string(t.message_count));
    }
    for (std::size_t k = 0; k < parts_.size(); ++k) {
      const auto it = meta.file_counts.find(meta.files[k]);
      if (it == meta.file_counts.end()) continue;
      std::uint64_t n = 0;
      for (const auto& t : parts_[k].reader->topics()) n += t.message_count;
      if (n != it->second)
        notes.push_back(files[k].filename().string() + ": metadata.yaml states " + std::to_string(it->second) +
                        " messages, the file holds " + std::to_string(n));
    }
    if (!notes.empty()) {
      format_ += "; WARNING, metadata.yaml disagrees with the storage, whose counts are used: ";
      for (std::size_t i = 0; i < notes.size(); ++i) format_ += (i ? "; " : "") + notes[i];
    }
  }

  void decompress(const RawMessage& in, const RawMessage& out, std::vector<std::uint8_t>& plain) const {
    const std::string where = "topic " + out.topic->name + ", message " + std::to_string(out.index);
    const unsigned long long size = ZSTD_getFrameContentSize(in.data, in.size);
    if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN)
      throw LogError(path_, where,
                     "expected a zstd frame with its content size (compression_mode MESSAGE), found none");
    if (size > limits_.max_chunk_bytes)
      throw LogError(path_, where,
                     "decompresses to " + std::to_string(size) + " bytes, more than the limit of " +
                         std::to_string(limits_.max_chunk_bytes) + " bytes (ReadLimits::max_chunk_bytes)");
    plain.resize(static_cast<std::size_t>(size));
    const std::size_t got = ZSTD_decompress(plain.data(), plain.size(), in.data, in.size);
    if (ZSTD_isError(got) || got != size)
      throw LogError(path_, where,
                     std::string("the zstd frame is damaged: ") +
                         (ZSTD_isError(got) ? ZSTD_getErrorName(got) : "it decompresses to fewer bytes than it declares"));
  }

  ReadLimits limits_;
  std::vector<Part> parts_;
  std::string compression_;  // lower-case compression_mode
  std::map<std::string, std::size_t> position_;
};

}  // namespace

std::unique_ptr<BagReader> openRosbag2Folder(const std::string& path, const ReadLimits& limits) {
  return std::make_unique<Rosbag2Folder>(path, limits);
}

}  // namespace fgcal::logs::detail
