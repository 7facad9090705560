// One rosbag2 sqlite3 storage file (.db3), read through libsqlite3 without
// ROS. The layouts rosbag2 wrote from Foxy to Jazzy are accepted:
//   topics(id, name, type, serialization_format[, offered_qos_profiles][, type_description_hash])
//   messages(id, topic_id, timestamp, data)
//   optional: schema(schema_version[, ros_distro]), metadata(...),
//             message_definitions(topic_type, encoding, encoded_message_definition, ...)
// Counts and record-time spans come from SQL at open; read() streams the rows
// of the asked topics in rosbag2's read order (timestamp, then id), one row
// at a time, never loading the table.
//
// Reading never writes into the bag's folder. When no -wal or -journal file
// lies beside the file, it is opened read-only with the "immutable" URI flag:
// no lock, no -shm file, so a bag on a read-only file system opens too; a bag
// still being written is not supported. When such a file exists, sqlite must
// see it (a recording that was not closed keeps messages in its -wal), but
// opening it in place would create a -shm file beside it (or roll a -journal
// back into it): the .db3 and its -wal/-journal are then copied into a
// private temporary folder, the copy is opened, and the folder is removed
// when the reader closes.
#include <sqlite3.h>
#include <stdlib.h>

#include <algorithm>
#include <cstdint>
#include <climits>
#include <filesystem>
#include <map>
#include <set>
#include <tuple>
#include <string>
#include <vector>

#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "readers.hpp"

namespace fs = std::filesystem;

namespace fgcal::logs::detail {

namespace {

struct DbCloser {
  void operator()(sqlite3* db) const { sqlite3_close_v2(db); }
};
struct StmtFinalizer {
  void operator()(sqlite3_stmt* s) const { sqlite3_finalize(s); }
};
using Db = std::unique_ptr<sqlite3, DbCloser>;
using Stmt = std::unique_ptr<sqlite3_stmt, StmtFinalizer>;

/// A file path as an SQLite URI ("file:" + percent-encoded path).
std::string fileUri(const std::string& path, bool immutable) {
  static const char* hex = "0123456789ABCDEF";
  std::string uri = "file:";
  std::error_code ec;
  fs::path abs = fs::absolute(path, ec);
  if (ec) abs = path;  // sqlite takes a relative file: URI too
  for (unsigned char c : abs.string()) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    if (plain || c == '/' || c == '-' || c == '_' || c == '.' || c == '~') {
      uri += static_cast<char>(c);
    } else {
      uri += '%';
      uri += hex[c >> 4];
      uri += hex[c & 15];
    }
  }
  if (immutable) uri += "?immutable=1";
  return uri;
}

bool nonEmptyFile(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec) && fs::file_size(path, ec) > 0 && !ec;
}

/// A private folder (mode 0700) under the system's temporary folder, with a
/// copy of a .db3 and the -wal/-journal files beside it; removed with its
/// contents (and the -shm sqlite makes there) on destruction.
class PrivateCopy {
 public:
  PrivateCopy(const std::string& db3, const std::vector<std::string>& suffixes) {
    std::error_code ec;
    std::string tmpl = (fs::temp_directory_path(ec) / "fgcal-db3-XXXXXX").string();
    if (ec) tmpl = "/tmp/fgcal-db3-XXXXXX";
    if (!mkdtemp(tmpl.data()))
      throw LogError(db3, "", "cannot create a private temporary folder (" + tmpl +
                                  ") to read the file with its -wal/-journal without writing beside it; set "
                                  "TMPDIR to a writable folder");
    dir_ = tmpl;
    path_ = dir_ + "/bag.db3";
    for (const std::string& suffix : suffixes) {
      fs::copy_file(db3 + suffix, path_ + suffix, ec);
      if (ec) {
        std::error_code ignored;
        fs::remove_all(dir_, ignored);
        throw LogError(db3 + suffix, "",
                       "cannot copy it to " + dir_ + " to read it without writing beside it: " + ec.message() +
                           " (the copy needs as much free space there as the file's size; set TMPDIR to another "
                           "folder)");
      }
    }
  }
  ~PrivateCopy() {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  PrivateCopy(const PrivateCopy&) = delete;
  PrivateCopy& operator=(const PrivateCopy&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string dir_, path_;
};

std::string columnText(sqlite3_stmt* s, int i) {
  const unsigned char* t = sqlite3_column_text(s, i);
  return t ? std::string(reinterpret_cast<const char*>(t), static_cast<std::size_t>(sqlite3_column_bytes(s, i)))
           : std::string();
}

const char* typeName(int sqlite_type) {
  switch (sqlite_type) {
    case SQLITE_INTEGER: return "an integer";
    case SQLITE_FLOAT: return "a real number";
    case SQLITE_TEXT: return "text";
    case SQLITE_BLOB: return "a blob";
    default: return "NULL";
  }
}

class SqliteBag final : public BagReaderBase {
 public:
  SqliteBag(std::string path, const ReadLimits& limits) : BagReaderBase(std::move(path)), limits_(limits) {
    open();
    readSchemaInfo();
    readTopics();
    readCounts();
  }

  void read(const std::vector<std::string>& topic_names, const std::function<bool(const RawMessage&)>& fn) override {
    const std::vector<bool> wanted = selectTopics(topic_names);
    const std::string ids = topicIds(wanted, topic_names);
    if (ids.empty()) return;  // a bag without topics

    // The row order is rosbag2's; the blob is fetched by rowid in a second
    // statement so that the ordering step (an index walk, or a sort when the
    // file has no timestamp index) never carries message data.
    Stmt order = prepare(std::string("SELECT rowid, topic_id, timestamp FROM messages") +
                             " WHERE topic_id IN (" + ids + ")" +
                             " ORDER BY timestamp, id",
                         "table messages");
    Stmt blob = prepare(
        "SELECT typeof(data), length(data), CASE WHEN typeof(data) = 'blob' AND length(data) <= ?2 THEN data END "
        "FROM messages WHERE rowid = ?1",
        "table messages");
    std::vector<std::uint64_t> next_index(topics_.size(), 0);
    for (;;) {
      const int rc = sqlite3_step(order.get());
      if (rc == SQLITE_DONE) break;
      if (rc != SQLITE_ROW) fail(rc, "table messages", "reading the messages in timestamp order");
      const sqlite3_int64 rowid = sqlite3_column_int64(order.get(), 0);
      std::string where;
      RawMessage m = messageOfRow(order.get(), rowid, wanted, next_index, &where);
      fetchData(blob.get(), rowid, where, m);
      if (!fn(m)) return;
    }
    for (std::size_t i = 0; i < topics_.size(); ++i)
      if (wanted[i] && next_index[i] != topics_[i].message_count)
        throw LogError(path_, "topic " + topics_[i].name,
                       "the file is damaged: " + std::to_string(topics_[i].message_count) +
                           " messages counted, but reading in timestamp order found " + std::to_string(next_index[i]));
  }

 private:
  /// The wanted topics' ids, comma-separated. A topic whose serialization no
  /// decoder knows is listed by topics() but never delivered: asking for it,
  /// or reading every topic while it has messages, is an error rather than a
  /// silent gap.
  std::string topicIds(const std::vector<bool>& wanted, const std::vector<std::string>& topic_names) const {
    std::string ids;
    for (std::size_t i = 0; i < topics_.size(); ++i) {
      if (!wanted[i]) continue;
      if (!cdr_[i] && (!topic_names.empty() || topics_[i].message_count > 0))
        throw LogError(path_, "topic " + topics_[i].name,
                       "serialization_format '" + format_of_[i] +
                           "' cannot be read; expected 'cdr' (ask for the other topics by name)");
      ids += (ids.empty() ? "" : ",") + std::to_string(ids_[i]);
    }
    return ids;
  }

  /// The message of the ordering statement's current row (its topic, record
  /// time and index; no data yet), checked against the topic's counts; *where
  /// names it for messages.
  RawMessage messageOfRow(sqlite3_stmt* order, sqlite3_int64 rowid, const std::vector<bool>& wanted,
                          std::vector<std::uint64_t>& next_index, std::string* where) const {
    const sqlite3_int64 topic_id = sqlite3_column_int64(order, 1);
    const auto pos = position_.find(topic_id);
    if (sqlite3_column_type(order, 1) != SQLITE_INTEGER || pos == position_.end() || !wanted[pos->second])
      throw LogError(path_, "table messages, row " + std::to_string(rowid),
                     "topic_id is not the id of a topic asked for (the table changed while reading?)");
    const std::size_t t = pos->second;
    const std::uint64_t index = next_index[t]++;
    *where = "topic " + topics_[t].name + ", message " + std::to_string(index);
    if (sqlite3_column_type(order, 2) != SQLITE_INTEGER)
      throw LogError(path_, *where, std::string("timestamp is ") + typeName(sqlite3_column_type(order, 2)) +
                                        ", expected an integer (nanoseconds)");
    RawMessage m;
    m.topic = &topics_[t];
    m.record_ns = sqlite3_column_int64(order, 2);
    m.index = index;
    // The walk in timestamp order may go through the timestamp index, the
    // counts through the table: a damaged index makes them disagree.
    if (index >= topics_[t].message_count || m.record_ns < topics_[t].first_record_ns ||
        m.record_ns > topics_[t].last_record_ns)
      throw LogError(path_, *where + " (record time " + std::to_string(m.record_ns) + ")",
                     "the file is damaged: reading in timestamp order finds a message outside the topic's " +
                         std::to_string(topics_[t].message_count) + " counted messages (record times " +
                         std::to_string(topics_[t].first_record_ns) + " to " +
                         std::to_string(topics_[t].last_record_ns) + ")");
    return m;
  }

  /// The message's data by rowid: a blob within ReadLimits::max_chunk_bytes.
  /// m.data points into the statement's row until its next step.
  void fetchData(sqlite3_stmt* blob, sqlite3_int64 rowid, const std::string& where, RawMessage& m) const {
    static const std::uint8_t empty = 0;
    const sqlite3_int64 max_bytes =
        static_cast<sqlite3_int64>(std::min<std::size_t>(limits_.max_chunk_bytes, std::size_t{INT64_MAX}));
    sqlite3_reset(blob);
    sqlite3_bind_int64(blob, 1, rowid);
    sqlite3_bind_int64(blob, 2, max_bytes);
    const int brc = sqlite3_step(blob);
    if (brc == SQLITE_DONE)
      throw LogError(path_, where,
                     "the file is damaged: row " + std::to_string(rowid) +
                         " of table messages, listed in timestamp order, is not in the table");
    if (brc != SQLITE_ROW) fail(brc, where, "reading the message data");
    const std::string kind = columnText(blob, 0);
    if (kind != "blob")
      throw LogError(path_, where + " (record time " + std::to_string(m.record_ns) + ")",
                     "data is " + (kind == "null" ? std::string("NULL") : kind) + ", expected a blob of serialized " +
                         m.topic->type);
    const sqlite3_int64 bytes = sqlite3_column_int64(blob, 1);
    if (bytes > max_bytes)
      throw LogError(path_, where + " (record time " + std::to_string(m.record_ns) + ")",
                     "data is " + std::to_string(bytes) + " bytes, more than the limit of " +
                         std::to_string(limits_.max_chunk_bytes) + " bytes (ReadLimits::max_chunk_bytes)");
    const void* p = sqlite3_column_blob(blob, 2);
    const int n = sqlite3_column_bytes(blob, 2);
    if (!p && n > 0) fail(sqlite3_errcode(db_.get()), where, "reading the message data");
    m.data = p ? static_cast<const std::uint8_t*>(p) : &empty;
    m.size = static_cast<std::size_t>(n);
  }

  [[noreturn]] void fail(int rc, const std::string& where, const std::string& doing) const {
    std::string what = sqlite3_errstr(rc);
    const char* msg = db_ ? sqlite3_errmsg(db_.get()) : nullptr;
    if (msg && what != msg) what += std::string(" (") + msg + ")";
    if ((rc & 0xff) == SQLITE_NOTADB)
      throw LogError(path_, where, "not an SQLite database: expected a rosbag2 sqlite3 (.db3) file (" + what + ")");
    if ((rc & 0xff) == SQLITE_CORRUPT)
      throw LogError(path_, where, "the SQLite file is damaged while " + doing + " (" + what + ")");
    throw LogError(path_, where, "SQLite failed while " + doing + ": " + what);
  }

  Stmt prepare(const std::string& sql, const std::string& where) const {
    sqlite3_stmt* s = nullptr;
    const int rc = sqlite3_prepare_v2(db_.get(), sql.c_str(), -1, &s, nullptr);
    Stmt stmt(s);
    if (rc != SQLITE_OK) fail(rc, where, "preparing '" + sql + "'");
    return stmt;
  }

  void open() {
    std::vector<std::string> journals;
    for (const char* suffix : {"-wal", "-journal"})
      if (nonEmptyFile(path_ + suffix)) journals.push_back(suffix);
    const bool journal = !journals.empty();
    sqlite3* raw = nullptr;
    int rc = SQLITE_OK;
    if (!journal) {
      rc = sqlite3_open_v2(fileUri(path_, true).c_str(), &raw, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr);
    } else {
      // The copy is ours: opened read-write, so that sqlite may build its
      // -shm and roll a -journal back there, not in the bag's folder.
      journals.insert(journals.begin(), "");
      copy_ = std::make_unique<PrivateCopy>(path_, journals);
      rc = sqlite3_open_v2(fileUri(copy_->path(), false).c_str(), &raw, SQLITE_OPEN_READWRITE | SQLITE_OPEN_URI,
                           nullptr);
    }
    db_.reset(raw);
    if (rc != SQLITE_OK) {
      if (!raw) throw LogError(path_, "", "cannot open the SQLite file: out of memory");
      fail(rc, "", journal ? "opening it with its -wal/-journal file" : "opening it read-only");
    }
    sqlite3_extended_result_codes(db_.get(), 1);
    // A bag is data, not code: no triggers, views or schema functions run.
    sqlite3_db_config(db_.get(), SQLITE_DBCONFIG_DEFENSIVE, 1, nullptr);
    sqlite3_db_config(db_.get(), SQLITE_DBCONFIG_TRUSTED_SCHEMA, 0, nullptr);
    sqlite3_db_config(db_.get(), SQLITE_DBCONFIG_ENABLE_TRIGGER, 0, nullptr);
    sqlite3_db_config(db_.get(), SQLITE_DBCONFIG_ENABLE_VIEW, 0, nullptr);
  }

  /// The tables of the file and the columns of those we read.
  void readSchemaInfo() {
    Stmt s = prepare("SELECT name FROM sqlite_master WHERE type = 'table'", "");
    for (int rc; (rc = sqlite3_step(s.get())) != SQLITE_DONE;) {
      if (rc != SQLITE_ROW) fail(rc, "", "listing its tables");
      tables_.insert(columnText(s.get(), 0));
    }
    std::string found;
    for (const auto& t : tables_) found += (found.empty() ? "" : ", ") + t;
    for (const char* need : {"topics", "messages"})
      if (!tables_.count(need))
        throw LogError(path_, std::string("table ") + need,
                       "not found: a rosbag2 sqlite3 file has the tables topics and messages (found: " +
                           (found.empty() ? std::string("no tables") : found) + ")");
    requireColumns("topics", {"id", "name", "type", "serialization_format"});
    requireColumns("messages", {"id", "topic_id", "timestamp", "data"});

    format_ = "rosbag2 sqlite3";
    if (tables_.count("schema")) {
      const auto cols = columns("schema");
      const bool distro = cols.count("ros_distro") > 0;
      Stmt v = prepare(std::string("SELECT schema_version") + (distro ? ", ros_distro" : "") + " FROM schema", "table schema");
      const int rc = sqlite3_step(v.get());
      if (rc == SQLITE_ROW) {
        format_ += " (schema " + columnText(v.get(), 0);
        if (distro) {
          const std::string d = columnText(v.get(), 1);
          format_ += d.empty() ? std::string() : ", " + d;
        }
        format_ += ")";
      } else if (rc != SQLITE_DONE) {
        fail(rc, "table schema", "reading the schema version");
      }
    } else {
      format_ += " (no schema table: the Foxy layout)";
    }
  }

  std::set<std::string> columns(const std::string& table) const {
    std::set<std::string> out;
    Stmt s = prepare("SELECT name FROM pragma_table_info('" + table + "')", "table " + table);
    for (int rc; (rc = sqlite3_step(s.get())) != SQLITE_DONE;) {
      if (rc != SQLITE_ROW) fail(rc, "table " + table, "listing its columns");
      out.insert(columnText(s.get(), 0));
    }
    return out;
  }

  void requireColumns(const std::string& table, const std::vector<std::string>& need) const {
    const auto have = columns(table);
    for (const auto& c : need)
      if (!have.count(c)) {
        std::string list;
        for (const auto& h : have) list += (list.empty() ? "" : ", ") + h;
        throw LogError(path_, "table " + table,
                       "has no column " + c + " (expected rosbag2's columns; found: " + list + ")");
      }
  }

  void readTopics() {
    // Definitions by type (message_definitions exists from Iron/Jazzy on).
    std::map<std::string, std::string> definitions;
    if (tables_.count("message_definitions")) {
      requireColumns("message_definitions", {"topic_type", "encoding", "encoded_message_definition"});
      Stmt s = prepare("SELECT topic_type, encoding, encoded_message_definition FROM message_definitions",
                       "table message_definitions");
      for (int rc; (rc = sqlite3_step(s.get())) != SQLITE_DONE;) {
        if (rc != SQLITE_ROW) fail(rc, "table message_definitions", "reading the message definitions");
        // rosbag2 stores encoding 'unknown' with an empty text when it had no definition.
        if (columnText(s.get(), 1) == "unknown") continue;
        definitions[columnText(s.get(), 0)] = columnText(s.get(), 2);
      }
    }

    Stmt s = prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id", "table topics");
    std::vector<std::tuple<TopicInfo, sqlite3_int64, std::string>> rows;
    for (int rc; (rc = sqlite3_step(s.get())) != SQLITE_DONE;) {
      if (rc != SQLITE_ROW) fail(rc, "table topics", "reading the topics");
      if (sqlite3_column_type(s.get(), 0) != SQLITE_INTEGER)
        throw LogError(path_, "table topics", std::string("a topic's id is ") + typeName(sqlite3_column_type(s.get(), 0)) +
                                                  ", expected an integer");
      const sqlite3_int64 id = sqlite3_column_int64(s.get(), 0);
      const std::string row = "table topics, id " + std::to_string(id);
      for (int c = 1; c <= 3; ++c)
        if (sqlite3_column_type(s.get(), c) != SQLITE_TEXT)
          throw LogError(path_, row, std::string(sqlite3_column_name(s.get(), c)) + " is " +
                                         typeName(sqlite3_column_type(s.get(), c)) + ", expected text");
      TopicInfo t;
      t.name = columnText(s.get(), 1);
      t.type = columnText(s.get(), 2);
      const std::string serialization = columnText(s.get(), 3);
      if (t.name.empty() || t.type.empty())
        throw LogError(path_, row, "empty topic name or type; expected e.g. /cam0/image_raw, sensor_msgs/msg/Image");
      t.serialization = Serialization::Cdr;
      auto d = definitions.find(t.type);
      // A service-event topic (pkg/srv/X_Event) has the service's definition (pkg/srv/X).
      const std::string event = "_Event";
      if (d == definitions.end() && t.type.find("/srv/") != std::string::npos && t.type.size() > event.size() &&
          t.type.compare(t.type.size() - event.size(), event.size(), event) == 0)
        d = definitions.find(t.type.substr(0, t.type.size() - event.size()));
      if (d != definitions.end()) t.definition = d->second;
      rows.emplace_back(std::move(t), id, serialization);
    }
    std::sort(rows.begin(), rows.end(),
              [](const auto& a, const auto& b) { return std::get<0>(a).name < std::get<0>(b).name; });
    for (std::size_t i = 0; i < rows.size(); ++i) {
      auto& [t, id, serialization] = rows[i];
      if (i > 0 && t.name == topics_.back().name)
        throw LogError(path_, "table topics, id " + std::to_string(id),
                       "topic " + t.name + " is listed twice (also as id " + std::to_string(ids_.back()) +
                           "); expected one row per topic");
      position_[id] = topics_.size();
      topics_.push_back(std::move(t));
      ids_.push_back(id);
      cdr_.push_back(serialization == "cdr");
      format_of_.push_back(serialization);
    }
  }

  void readCounts() {
    Stmt s = prepare(
        "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp), SUM(typeof(timestamp) <> 'integer'), MIN(id) "
        "FROM messages GROUP BY topic_id",
        "table messages");
    for (int rc; (rc = sqlite3_step(s.get())) != SQLITE_DONE;) {
      if (rc != SQLITE_ROW) fail(rc, "table messages", "counting the messages of each topic");
      const auto pos = sqlite3_column_type(s.get(), 0) == SQLITE_INTEGER
                           ? position_.find(sqlite3_column_int64(s.get(), 0))
                           : position_.end();
      if (pos == position_.end()) {
        std::string ids;
        for (const auto& [id, pos_] : position_) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
        throw LogError(path_, "table messages, id " + columnText(s.get(), 5),
                       std::to_string(sqlite3_column_int64(s.get(), 1)) + " message(s) have topic_id " +
                           (sqlite3_column_type(s.get(), 0) == SQLITE_NULL ? std::string("NULL")
                                                                            : "'" + columnText(s.get(), 0) + "'") +
                           ", which is no topic of table topics (its ids: " + (ids.empty() ? "none" : ids) + ")");
      }
      TopicInfo& t = topics_[pos->second];
      if (sqlite3_column_int64(s.get(), 4) != 0)
        throw LogError(path_, "topic " + t.name,
                       std::to_string(sqlite3_column_int64(s.get(), 4)) +
                           " message(s) have a timestamp that is not an integer; expected nanoseconds");
      t.message_count = static_cast<std::uint64_t>(sqlite3_column_int64(s.get(), 1));
      t.first_record_ns = sqlite3_column_int64(s.get(), 2);
      t.last_record_ns = sqlite3_column_int64(s.get(), 3);
    }
  }

  ReadLimits limits_;
  std::unique_ptr<PrivateCopy> copy_;  // with a -wal/-journal: what db_ opened (outlives db_)
  Db db_;
  std::set<std::string> tables_;
  std::vector<sqlite3_int64> ids_;         // topics.id of each
  std::vector<bool> cdr_;                  // serialization_format is cdr
  std::vector<std::string> format_of_;     // serialization_format as stored
  std::map<sqlite3_int64, std::size_t> position_;  // topics.id -> position in topics_
};

}  // namespace

std::unique_ptr<BagReader> openSqliteFile(const std::string& path, const ReadLimits& limits) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw LogError(path, "", "not found or not a file; expected a rosbag2 .db3 file");
  return std::make_unique<SqliteBag>(path, limits);
}

}  // namespace fgcal::logs::detail
