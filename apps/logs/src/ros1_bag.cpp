// The ROS 1 bag (format 2.0) reader behind openBag (readers.hpp).
//
// A bag is "#ROSBAG V2.0\n" then records <header_len><header><data_len><data>,
// the header being <field_len><name>=<value> fields (ROS wiki, Bags/Format/2.0):
//   0x03 bag header  index_pos, conn_count, chunk_count (data: padding)
//   0x05 chunk       compression (none | bz2 | lz4), size (uncompressed bytes);
//                    data: connection (0x07) and message data (0x02) records
//   0x04 index data  after each chunk, one per connection: (time, offset) entries
//   0x07 connection  conn, topic; data: the connection header (type, md5sum, ...)
//   0x06 chunk info  after index_pos, one per chunk: its position and per-connection counts
// A closed bag is read through its index (connections and chunk infos at
// index_pos, then the index data records after each chunk for exact counts and
// record times); a bag whose recording was killed (index_pos 0 or past the
// end) is read by a linear scan of its chunks. Either way the messages are read
// one decompressed chunk at a time, into buffers reused from chunk to chunk.
// roslz4 writes standard LZ4 frames (magic 04 22 4D 18), read with LZ4F.
#include <bzlib.h>
#include <fcntl.h>
#include <lz4frame.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iterator>
#include <limits>
#include <map>
#include <set>
#include <string_view>
#include <unordered_map>

#include "fgcal/logs/log_error.hpp"
#include "readers.hpp"

namespace fgcal::logs::detail {

namespace {

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr std::uint64_t kMagicSize = 13;

enum Op : std::uint8_t {
  kOpMessageData = 0x02,
  kOpBagHeader = 0x03,
  kOpIndexData = 0x04,
  kOpChunk = 0x05,
  kOpChunkInfo = 0x06,
  kOpConnection = 0x07,
};

std::uint32_t le32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24;
}

std::uint64_t le64(const std::uint8_t* p) { return std::uint64_t{le32(p)} | std::uint64_t{le32(p + 4)} << 32; }

std::string at(std::uint64_t offset) { return "offset " + std::to_string(offset); }

std::string inChunk(std::uint64_t chunk_offset, std::uint64_t inner) {
  return "chunk at offset " + std::to_string(chunk_offset) + ", uncompressed offset " + std::to_string(inner);
}

/// A byte for humans: printable as is, else as \xNN.
std::string printable(std::string_view s) {
  std::string out;
  for (const char c : s) {
    if (c >= 0x20 && c < 0x7f) {
      out += c;
    } else {
      static const char* hex = "0123456789abcdef";
      const auto u = static_cast<unsigned char>(c);
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15];
    }
  }
  return out;
}

/// The name=value fields of one record header. Values point into the caller's buffer.
class RecordHeader {
 public:
  /// Parses `n` bytes; `where` names the record for errors.
  RecordHeader(const std::string& file, std::string where, const std::uint8_t* p, std::size_t n)
      : file_(file), where_(std::move(where)) {
    std::size_t i = 0;
    while (i < n) {
      if (n - i < 4)
        throw LogError(file_, where_, "record header ends inside a field length (" + std::to_string(n - i) +
                                          " byte(s) left of " + std::to_string(n) + ")");
      const std::uint32_t len = le32(p + i);
      i += 4;
      if (len > n - i)
        throw LogError(file_, where_, "record header field declares " + std::to_string(len) +
                                          " bytes but only " + std::to_string(n - i) + " remain in the header");
      const std::string_view field(reinterpret_cast<const char*>(p + i), len);
      i += len;
      const std::size_t eq = field.find('=');
      if (eq == std::string_view::npos)
        throw LogError(file_, where_, "record header field '" + printable(field.substr(0, 40)) +
                                          "' has no '='; expected name=value");
      fields_.emplace_back(field.substr(0, eq), field.substr(eq + 1));
    }
  }

  const std::string_view* find(std::string_view name) const {
    for (const auto& f : fields_)
      if (f.first == name) return &f.second;
    return nullptr;
  }

  std::string_view bytes(std::string_view name) const {
    const auto* v = find(name);
    if (!v) throw LogError(file_, where_, "record header has no '" + std::string(name) + "' field");
    return *v;
  }

  std::uint8_t op() const {
    const auto v = bytes("op");
    if (v.size() != 1) throw LogError(file_, where_, "field 'op' has " + std::to_string(v.size()) + " bytes; expected 1");
    return static_cast<std::uint8_t>(v[0]);
  }

  std::uint32_t u32(std::string_view name) const {
    const auto v = bytes(name);
    if (v.size() != 4)
      throw LogError(file_, where_, "field '" + std::string(name) + "' has " + std::to_string(v.size()) +
                                        " bytes; expected a 4-byte integer");
    return le32(reinterpret_cast<const std::uint8_t*>(v.data()));
  }

  std::uint64_t u64(std::string_view name) const {
    const auto v = bytes(name);
    if (v.size() != 8)
      throw LogError(file_, where_, "field '" + std::string(name) + "' has " + std::to_string(v.size()) +
                                        " bytes; expected an 8-byte integer");
    return le64(reinterpret_cast<const std::uint8_t*>(v.data()));
  }

  /// A ROS time (sec uint32, nsec uint32) as nanoseconds.
  std::int64_t time(std::string_view name) const {
    const std::uint64_t raw = u64(name);
    const std::uint32_t sec = static_cast<std::uint32_t>(raw), nsec = static_cast<std::uint32_t>(raw >> 32);
    if (nsec >= 1000000000u)
      throw LogError(file_, where_, "field '" + std::string(name) + "' has nsec " + std::to_string(nsec) +
                                        "; expected less than 1000000000");
    return std::int64_t{sec} * 1000000000 + nsec;
  }

  std::string str(std::string_view name) const { return std::string(bytes(name)); }

 private:
  const std::string& file_;
  std::string where_;
  std::vector<std::pair<std::string_view, std::string_view>> fields_;
};

/// Reads at given offsets; no state between reads.
class BagFile {
 public:
  explicit BagFile(const std::string& path) : path_(path) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) throw LogError(path, "", std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd_, &st) != 0) {
      const int e = errno;
      ::close(fd_);
      throw LogError(path, "", std::string("cannot stat: ") + std::strerror(e));
    }
    size_ = static_cast<std::uint64_t>(st.st_size);
  }
  ~BagFile() { ::close(fd_); }
  BagFile(const BagFile&) = delete;
  BagFile& operator=(const BagFile&) = delete;

  std::uint64_t size() const { return size_; }

  /// Exactly `n` bytes at `offset`; the caller has checked they lie in the file.
  void read(std::uint64_t offset, void* dst, std::size_t n) const {
    auto* out = static_cast<char*>(dst);
    while (n > 0) {
      const ssize_t got = ::pread(fd_, out, n, static_cast<off_t>(offset));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0)
        throw LogError(path_, at(offset),
                       got < 0 ? std::string("read failed: ") + std::strerror(errno)
                               : std::string("the file ended early (was it truncated while being read?)"));
      out += got, n -= static_cast<std::size_t>(got), offset += static_cast<std::uint64_t>(got);
    }
  }

 private:
  std::string path_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

/// Where one record's parts lie in the file.
struct RecordSpan {
  std::uint64_t pos = 0;         ///< the record's first byte (its header_len)
  std::uint64_t data_pos = 0;    ///< first byte of its data
  std::uint32_t data_len = 0;
  std::uint64_t end() const { return data_pos + data_len; }
};

enum class Compression { None, Bz2, Lz4 };

const char* compressionName(Compression c) {
  switch (c) {
    case Compression::None: return "none";
    case Compression::Bz2: return "bz2";
    case Compression::Lz4: return "lz4";
  }
  return "?";
}

struct Chunk {
  RecordSpan span;
  Compression compression = Compression::None;
  std::uint32_t size = 0;  ///< uncompressed bytes
  /// Messages per connection id in this chunk (from its chunk info, or counted by the scan).
  std::map<std::uint32_t, std::uint32_t> counts;
};

struct Lz4Free {
  void operator()(LZ4F_dctx* c) const { LZ4F_freeDecompressionContext(c); }
};

struct Connection {
  std::string topic, type, md5sum, definition;
};

class Ros1Bag final : public BagReaderBase {
 public:
  Ros1Bag(const std::string& path, const ReadLimits& limits) : BagReaderBase(path), limits_(limits), file_(path) {
    open();
  }

  void read(const std::vector<std::string>& topic_names, const std::function<bool(const RawMessage&)>& fn) override {
    const std::vector<bool> wanted = selectTopics(topic_names);
    std::vector<std::uint64_t> next_index(topics_.size(), 0);
    for (const Chunk& chunk : chunks_) {
      bool any = false;
      for (const auto& [conn, count] : chunk.counts) any = any || (count > 0 && wanted[topicOf(conn)]);
      if (!any) {  // nothing asked for here: skip the chunk, keep the per-topic numbering
        for (const auto& [conn, count] : chunk.counts) next_index[topicOf(conn)] += count;
        continue;
      }
      loadChunk(chunk);
      std::map<std::uint32_t, std::uint32_t> seen;
      bool stop = false;
      walkChunk(chunk, [&](std::uint8_t op, const RecordHeader& h, std::uint64_t inner, const std::uint8_t* data,
                           std::uint32_t len) {
        if (op != kOpMessageData) return true;
        const std::uint32_t conn = h.u32("conn");
        const auto c = conn_topic_.find(conn);
        if (c == conn_topic_.end())
          throw LogError(path_, inChunk(chunk.span.pos, inner),
                         "message of connection " + std::to_string(conn) + ", which no connection record declares");
        const std::int64_t t = h.time("time");
        ++seen[conn];
        const std::size_t ti = c->second;
        const std::uint64_t index = next_index[ti]++;
        if (!wanted[ti]) return true;
        RawMessage m;
        m.topic = &topics_[ti];
        m.record_ns = t;
        m.index = index;
        m.data = data;
        m.size = len;
        if (!fn(m)) stop = true;
        return !stop;
      });
      if (stop) return;
      if (seen != chunk.counts)
        throw LogError(path_, at(chunk.span.pos),
                       "the chunk's messages per connection (" + describe(seen) +
                           ") differ from its index (" + describe(chunk.counts) + ")");
    }
  }

 private:
  static std::string describe(const std::map<std::uint32_t, std::uint32_t>& counts) {
    std::string s;
    for (const auto& [conn, n] : counts) s += (s.empty() ? "" : ", ") + std::string("conn ") + std::to_string(conn) + ": " + std::to_string(n);
    return s.empty() ? "none" : s;
  }

  std::size_t topicOf(std::uint32_t conn) const { return conn_topic_.at(conn); }

  /// Reads the record at `pos` (which must be below `limit`), its header into
  /// `header_buf`; the data stays in the file.
  RecordSpan readRecord(std::uint64_t pos, std::uint64_t limit, std::vector<std::uint8_t>& header_buf) const {
    if (limit - pos < 4)
      throw LogError(path_, at(pos), "a record starts here but only " + std::to_string(limit - pos) +
                                         " byte(s) remain in the file; expected at least 8 (the bag was cut short?)");
    std::uint8_t len[4];
    file_.read(pos, len, 4);
    const std::uint32_t header_len = le32(len);
    if (header_len > limits_.max_chunk_bytes)
      throw LogError(path_, at(pos), "record header declares " + std::to_string(header_len) +
                                         " bytes, more than the limit of " + std::to_string(limits_.max_chunk_bytes));
    if (header_len > limit - pos - 4)
      throw LogError(path_, at(pos), "record header declares " + std::to_string(header_len) + " bytes but only " +
                                         std::to_string(limit - pos - 4) + " remain in the file (the bag was cut short?)");
    if (limit - pos - 4 - header_len < 4)
      throw LogError(path_, at(pos), "the file ends before the record's data length (the bag was cut short?)");
    header_buf.resize(header_len);
    file_.read(pos + 4, header_buf.data(), header_len);
    file_.read(pos + 4 + header_len, len, 4);
    RecordSpan s;
    s.pos = pos;
    s.data_pos = pos + 8 + header_len;
    s.data_len = le32(len);
    if (s.data_len > limit - s.data_pos)
      throw LogError(path_, at(pos), "record declares " + std::to_string(s.data_len) + " data bytes but only " +
                                         std::to_string(limit - s.data_pos) +
                                         " remain in the file (the bag was cut short?)");
    return s;
  }

  void open() {
    const std::uint64_t size = file_.size();
    char magic[kMagicSize] = {};
    if (size < kMagicSize) throw LogError(path_, at(0), "too short for a ROS 1 bag; expected '#ROSBAG V2.0' and records");
    file_.read(0, magic, kMagicSize);
    if (std::memcmp(magic, kMagic, kMagicSize) != 0)
      throw LogError(path_, at(0), "expected a ROS 1 bag ('#ROSBAG V2.0' at the start of the file)");

    std::vector<std::uint8_t> hb;
    const RecordSpan bh = readRecord(kMagicSize, size, hb);
    const RecordHeader bag_header(path_, at(kMagicSize), hb.data(), hb.size());
    if (bag_header.op() != kOpBagHeader)
      throw LogError(path_, at(kMagicSize), "expected the bag header record (op 0x03) first, found op " +
                                                std::to_string(bag_header.op()));
    if (const auto* enc = bag_header.find("encryptor"))
      throw LogError(path_, at(kMagicSize), "the bag is encrypted (encryptor '" + printable(*enc) +
                                                "'); expected an unencrypted bag (rosbag decrypt writes one)");
    const std::uint64_t index_pos = bag_header.u64("index_pos");
    const std::uint32_t conn_count = bag_header.u32("conn_count");
    const std::uint32_t chunk_count = bag_header.u32("chunk_count");
    first_record_ = bh.end();

    if (index_pos == 0 || index_pos >= size) {
      indexed_ = false;
      scan();
    } else {
      if (index_pos < first_record_)
        throw LogError(path_, at(kMagicSize), "index_pos " + std::to_string(index_pos) +
                                                  " points inside the bag header; expected 0 or an offset after " +
                                                  std::to_string(first_record_));
      indexed_ = true;
      readIndex(index_pos, conn_count, chunk_count);
    }
    buildTopics();

    std::set<std::string> used;
    for (const auto& c : chunks_) used.insert(compressionName(c.compression));
    std::string comp;
    for (const auto& u : used) comp += (comp.empty() ? "" : "+") + u;
    format_ = "ROS 1 bag 2.0, " + std::to_string(chunks_.size()) + " chunk(s), compression " +
              (comp.empty() ? std::string("none") : comp) +
              (indexed_ ? ", indexed" : ", no index (the recording was not closed; read by a linear scan)");
  }

  Compression parseCompression(const RecordHeader& h, std::uint64_t pos) const {
    const auto* v = h.find("compression");
    const std::string name = v ? std::string(*v) : std::string("none");
    if (name == "none") return Compression::None;
    if (name == "bz2") return Compression::Bz2;
    if (name == "lz4") return Compression::Lz4;
    throw LogError(path_, at(pos), "chunk compression '" + printable(name) + "' is not supported; expected none, bz2 or lz4");
  }

  /// The chunk record at `pos`: its span, compression and size, checked against the limits.
  Chunk readChunkRecord(std::uint64_t pos, std::vector<std::uint8_t>& hb) const {
    Chunk c;
    c.span = readRecord(pos, file_.size(), hb);
    const RecordHeader h(path_, at(pos), hb.data(), hb.size());
    if (h.op() != kOpChunk)
      throw LogError(path_, at(pos), "expected a chunk record (op 0x05), found op " + std::to_string(h.op()));
    c.compression = parseCompression(h, pos);
    c.size = h.u32("size");
    if (c.size > limits_.max_chunk_bytes)
      throw LogError(path_, at(pos), "chunk declares " + std::to_string(c.size) +
                                         " uncompressed bytes, more than the limit of " +
                                         std::to_string(limits_.max_chunk_bytes));
    if (c.span.data_len > limits_.max_chunk_bytes)
      throw LogError(path_, at(pos), "chunk holds " + std::to_string(c.span.data_len) +
                                         " compressed bytes, more than the limit of " +
                                         std::to_string(limits_.max_chunk_bytes));
    if (c.compression == Compression::None && c.size != c.span.data_len)
      throw LogError(path_, at(pos), "uncompressed chunk declares size " + std::to_string(c.size) + " but holds " +
                                         std::to_string(c.span.data_len) + " bytes");
    return c;
  }

  void addConnection(std::uint32_t id, const RecordHeader& h, const std::uint8_t* data, std::uint32_t len,
                     const std::string& where) {
    const RecordHeader ch(path_, where + ", connection header", data, len);
    Connection c;
    c.topic = h.str("topic");
    c.type = ch.str("type");
    if (const auto* v = ch.find("md5sum")) c.md5sum = std::string(*v);
    if (const auto* v = ch.find("message_definition")) c.definition = std::string(*v);
    if (c.topic.empty()) throw LogError(path_, where, "connection " + std::to_string(id) + " has an empty topic name");
    const auto it = connections_.find(id);
    if (it != connections_.end()) {
      if (it->second.topic != c.topic || it->second.type != c.type)
        throw LogError(path_, where, "connection " + std::to_string(id) + " is declared twice, as " +
                                         it->second.topic + " (" + it->second.type + ") and as " + c.topic + " (" +
                                         c.type + ")");
      return;
    }
    connections_.emplace(id, std::move(c));
  }

  /// A chunk info record of the index section (its position `pos`, its span
  /// and header): the chunk's offset and its message count per connection.
  Chunk readChunkInfo(std::uint64_t pos, const RecordSpan& s, const RecordHeader& h, std::uint64_t index_pos,
                      std::vector<std::uint8_t>& data) const {
    const std::uint32_t ver = h.u32("ver");
    if (ver != 1)
      throw LogError(path_, at(pos), "chunk info version " + std::to_string(ver) + " is not supported; expected 1");
    Chunk c;
    c.span.pos = h.u64("chunk_pos");
    (void)h.time("start_time");
    (void)h.time("end_time");
    const std::uint32_t n = h.u32("count");
    if (s.data_len != std::uint64_t{n} * 8)
      throw LogError(path_, at(pos), "chunk info declares " + std::to_string(n) + " connections (" +
                                         std::to_string(std::uint64_t{n} * 8) + " bytes) but holds " +
                                         std::to_string(s.data_len) + " bytes");
    data.resize(s.data_len);
    file_.read(s.data_pos, data.data(), s.data_len);
    for (std::uint32_t i = 0; i < n; ++i)
      if (!c.counts.emplace(le32(&data[8 * i]), le32(&data[8 * i + 4])).second)
        throw LogError(path_, at(pos), "chunk info lists connection " + std::to_string(le32(&data[8 * i])) +
                                           " twice");
    if (c.span.pos < first_record_ || c.span.pos >= index_pos)
      throw LogError(path_, at(pos), "chunk info points to offset " + std::to_string(c.span.pos) +
                                         "; expected a chunk between offsets " + std::to_string(first_record_) +
                                         " and " + std::to_string(index_pos));
    return c;
  }

  /// The index section: connection records and one chunk info per chunk, as
  /// many as the bag header declares, the chunks in file order.
  void readIndexSection(std::uint64_t index_pos, std::uint32_t conn_count, std::uint32_t chunk_count) {
    std::vector<std::uint8_t> hb, data;
    for (std::uint64_t pos = index_pos; pos < file_.size();) {
      const RecordSpan s = readRecord(pos, file_.size(), hb);
      const RecordHeader h(path_, at(pos), hb.data(), hb.size());
      const std::uint8_t op = h.op();
      if (op == kOpConnection) {
        data.resize(s.data_len);
        file_.read(s.data_pos, data.data(), s.data_len);
        addConnection(h.u32("conn"), h, data.data(), s.data_len, at(pos));
      } else if (op == kOpChunkInfo) {
        chunks_.push_back(readChunkInfo(pos, s, h, index_pos, data));
      } else {
        throw LogError(path_, at(pos), "unexpected record op " + std::to_string(op) +
                                           " in the index section; expected connection (0x07) or chunk info (0x06)");
      }
      pos = s.end();
    }
    if (connections_.size() != conn_count || chunks_.size() != chunk_count)
      throw LogError(path_, at(index_pos), "the index holds " + std::to_string(connections_.size()) +
                                               " connection(s) and " + std::to_string(chunks_.size()) +
                                               " chunk info(s), but the bag header declares " +
                                               std::to_string(conn_count) + " and " + std::to_string(chunk_count));
    std::sort(chunks_.begin(), chunks_.end(), [](const Chunk& a, const Chunk& b) { return a.span.pos < b.span.pos; });
    for (std::size_t i = 1; i < chunks_.size(); ++i)
      if (chunks_[i].span.pos == chunks_[i - 1].span.pos)
        throw LogError(path_, at(index_pos), "two chunk infos point to the same chunk at offset " +
                                                 std::to_string(chunks_[i].span.pos));
  }

  /// The index data records after chunk `c`: one per connection of its chunk
  /// info, each with one (time, offset) entry per message; the times noted.
  void readIndexData(const Chunk& c, std::uint64_t index_pos, std::vector<std::uint8_t>& hb) {
    std::vector<std::uint8_t> data;
    std::uint64_t pos = c.span.end();
    for (std::size_t k = 0; k < c.counts.size(); ++k) {
      const RecordSpan s = readRecord(pos, index_pos, hb);
      const RecordHeader h(path_, at(pos), hb.data(), hb.size());
      if (h.op() != kOpIndexData)
        throw LogError(path_, at(pos), "expected index data record " + std::to_string(k + 1) + " of " +
                                           std::to_string(c.counts.size()) + " after the chunk at offset " +
                                           std::to_string(c.span.pos) + ", found op " + std::to_string(h.op()));
      const std::uint32_t ver = h.u32("ver");
      if (ver != 1)
        throw LogError(path_, at(pos), "index data version " + std::to_string(ver) + " is not supported; expected 1");
      const std::uint32_t conn = h.u32("conn"), n = h.u32("count");
      const auto expected = c.counts.find(conn);
      if (expected == c.counts.end() || expected->second != n)
        throw LogError(path_, at(pos), "index data lists " + std::to_string(n) + " message(s) of connection " +
                                           std::to_string(conn) + " but the chunk info says " +
                                           std::to_string(expected == c.counts.end() ? 0 : expected->second));
      if (s.data_len != std::uint64_t{n} * 12)
        throw LogError(path_, at(pos), "index data declares " + std::to_string(n) + " entries (" +
                                           std::to_string(std::uint64_t{n} * 12) + " bytes) but holds " +
                                           std::to_string(s.data_len) + " bytes");
      data.resize(s.data_len);
      file_.read(s.data_pos, data.data(), s.data_len);
      for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint32_t sec = le32(&data[12 * i]), nsec = le32(&data[12 * i + 4]);
        if (nsec >= 1000000000u)
          throw LogError(path_, at(pos), "index entry " + std::to_string(i) + " has nsec " + std::to_string(nsec) +
                                             "; expected less than 1000000000");
        noteTime(conn, std::int64_t{sec} * 1000000000 + nsec);
      }
      pos = s.end();
    }
  }

  /// Index section: connection records and one chunk info per chunk, then the
  /// index data records after each chunk for exact per-topic times.
  void readIndex(std::uint64_t index_pos, std::uint32_t conn_count, std::uint32_t chunk_count) {
    readIndexSection(index_pos, conn_count, chunk_count);
    std::vector<std::uint8_t> hb;
    for (auto& c : chunks_) {
      auto counts = std::move(c.counts);
      c = readChunkRecord(c.span.pos, hb);
      c.counts = std::move(counts);
      if (c.span.end() > index_pos)
        throw LogError(path_, at(c.span.pos), "chunk runs past index_pos " + std::to_string(index_pos));
      readIndexData(c, index_pos, hb);
    }
    for (auto& c : chunks_) {
      for (const auto& [conn, n] : c.counts)
        if (!connections_.count(conn))
          throw LogError(path_, at(c.span.pos), "chunk info lists connection " + std::to_string(conn) +
                                                    ", which the index does not declare");
      // read() compares the messages it finds with these counts
      for (auto it = c.counts.begin(); it != c.counts.end();) it = it->second == 0 ? c.counts.erase(it) : std::next(it);
    }
  }

  /// No index: every top-level record from the bag header on; the chunks are
  /// decompressed to find their connections and count their messages.
  void scan() {
    std::vector<std::uint8_t> hb;
    for (std::uint64_t pos = first_record_; pos < file_.size();) {
      const RecordSpan s = readRecord(pos, file_.size(), hb);
      const RecordHeader h(path_, at(pos), hb.data(), hb.size());
      const std::uint8_t op = h.op();
      if (op == kOpChunk) {
        Chunk c = readChunkRecord(pos, hb);
        loadChunk(c);
        walkChunk(c, [&](std::uint8_t rop, const RecordHeader& rh, std::uint64_t inner, const std::uint8_t* data,
                         std::uint32_t len) {
          if (rop == kOpConnection) {
            addConnection(rh.u32("conn"), rh, data, len, inChunk(c.span.pos, inner));
          } else {
            const std::uint32_t conn = rh.u32("conn");
            if (!connections_.count(conn))
              throw LogError(path_, inChunk(c.span.pos, inner),
                             "message of connection " + std::to_string(conn) + " before any connection record declares it");
            ++c.counts[conn];
            noteTime(conn, rh.time("time"));
          }
          return true;
        });
        chunks_.push_back(std::move(c));
      } else if (op == kOpConnection) {
        std::vector<std::uint8_t> data(s.data_len);
        file_.read(s.data_pos, data.data(), s.data_len);
        addConnection(h.u32("conn"), h, data.data(), s.data_len, at(pos));
      } else if (op != kOpIndexData && op != kOpChunkInfo) {
        throw LogError(path_, at(pos), "unexpected record op " + std::to_string(op) +
                                           "; expected a chunk (0x05), index data (0x04), connection (0x07) or "
                                           "chunk info (0x06)");
      }
      pos = s.end();
    }
  }

  void noteTime(std::uint32_t conn, std::int64_t t) {
    auto& [first, last] = conn_span_.try_emplace(conn, t, t).first->second;
    first = std::min(first, t);
    last = std::max(last, t);
  }

  /// One TopicInfo per topic name, merging the connections that share it.
  void buildTopics() {
    std::map<std::string, std::vector<std::uint32_t>> by_topic;
    for (const auto& [id, c] : connections_) by_topic[c.topic].push_back(id);
    std::map<std::uint32_t, std::uint64_t> conn_count;
    for (const auto& ch : chunks_)
      for (const auto& [conn, n] : ch.counts) conn_count[conn] += n;
    for (const auto& [name, ids] : by_topic) {
      TopicInfo t;
      t.name = name;
      t.serialization = Serialization::Ros1;
      const Connection& first = connections_.at(ids.front());
      t.type = first.type;
      t.definition = first.definition;
      bool any = false;
      for (const std::uint32_t id : ids) {
        const Connection& c = connections_.at(id);
        if (c.type != t.type || (!c.md5sum.empty() && !first.md5sum.empty() && c.md5sum != first.md5sum))
          throw LogError(path_, "topic " + name, "its connections disagree on the type: " + t.type + " (md5sum " +
                                                     first.md5sum + ") and " + c.type + " (md5sum " + c.md5sum + ")");
        conn_topic_[id] = topics_.size();
        t.message_count += conn_count[id];
        const auto span = conn_span_.find(id);
        if (span != conn_span_.end()) {
          t.first_record_ns = any ? std::min(t.first_record_ns, span->second.first) : span->second.first;
          t.last_record_ns = any ? std::max(t.last_record_ns, span->second.second) : span->second.second;
          any = true;
        }
      }
      topics_.push_back(std::move(t));
    }
  }

  /// Decompresses `c` into chunk_ (reused), exactly c.size bytes.
  void loadChunk(const Chunk& c) {
    chunk_.resize(c.size);
    if (c.compression == Compression::None) {
      file_.read(c.span.data_pos, chunk_.data(), c.size);
      return;
    }
    packed_.resize(c.span.data_len);
    file_.read(c.span.data_pos, packed_.data(), c.span.data_len);
    const std::string where = at(c.span.pos);
    if (c.compression == Compression::Bz2) {
      unsigned int out_len = c.size;
      const int rc = BZ2_bzBuffToBuffDecompress(reinterpret_cast<char*>(chunk_.data()), &out_len,
                                                reinterpret_cast<char*>(packed_.data()),
                                                static_cast<unsigned int>(packed_.size()), 0, 0);
      if (rc == BZ_OUTBUFF_FULL)
        throw LogError(path_, where, "bz2 chunk decompresses to more than its declared size of " +
                                         std::to_string(c.size) + " bytes");
      if (rc != BZ_OK)
        throw LogError(path_, where, "bz2 chunk does not decompress (libbz2 error " + std::to_string(rc) + ")");
      if (out_len != c.size)
        throw LogError(path_, where, "bz2 chunk decompresses to " + std::to_string(out_len) +
                                         " bytes; its header declares " + std::to_string(c.size));
      return;
    }
    if (!lz4_) {
      LZ4F_dctx* ctx = nullptr;
      if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)))
        throw LogError(path_, where, "cannot create an LZ4 decompression context");
      lz4_.reset(ctx);
    } else {
      LZ4F_resetDecompressionContext(lz4_.get());  // a damaged frame may have left it mid-frame
    }
    std::size_t in_pos = 0, out_pos = 0;
    std::size_t hint = 1;
    while (hint != 0) {
      std::size_t in_n = packed_.size() - in_pos, out_n = chunk_.size() - out_pos;
      if (in_n == 0)
        throw LogError(path_, where, "lz4 chunk ends inside its frame after " + std::to_string(out_pos) +
                                         " of " + std::to_string(c.size) + " bytes");
      hint = LZ4F_decompress(lz4_.get(), chunk_.data() + out_pos, &out_n, packed_.data() + in_pos, &in_n, nullptr);
      if (LZ4F_isError(hint))
        throw LogError(path_, where, std::string("lz4 chunk does not decompress: ") + LZ4F_getErrorName(hint));
      in_pos += in_n, out_pos += out_n;
      if (hint != 0 && in_n == 0 && out_n == 0)
        throw LogError(path_, where, "lz4 chunk decompresses to more than its declared size of " +
                                         std::to_string(c.size) + " bytes");
    }
    if (out_pos != c.size)
      throw LogError(path_, where, "lz4 chunk decompresses to " + std::to_string(out_pos) +
                                       " bytes; its header declares " + std::to_string(c.size));
  }

  /// Calls fn(op, header, inner offset, data, len) for each record of the
  /// loaded chunk until it returns false.
  template <class Fn>
  void walkChunk(const Chunk& c, Fn&& fn) const {
    const std::size_t n = chunk_.size();
    const std::uint8_t* p = chunk_.data();
    for (std::size_t i = 0; i < n;) {
      const std::string where = inChunk(c.span.pos, i);
      if (n - i < 4) throw LogError(path_, where, "chunk data ends inside a record's header length");
      const std::uint32_t hl = le32(p + i);
      if (hl > n - i - 4)
        throw LogError(path_, where, "record header declares " + std::to_string(hl) + " bytes but only " +
                                         std::to_string(n - i - 4) + " remain in the chunk");
      const RecordHeader h(path_, where, p + i + 4, hl);
      const std::size_t dl_pos = i + 4 + hl;
      if (n - dl_pos < 4) throw LogError(path_, where, "chunk data ends inside a record's data length");
      const std::uint32_t dl = le32(p + dl_pos);
      if (dl > n - dl_pos - 4)
        throw LogError(path_, where, "record declares " + std::to_string(dl) + " data bytes but only " +
                                         std::to_string(n - dl_pos - 4) + " remain in the chunk");
      const std::uint8_t op = h.op();
      if (op != kOpMessageData && op != kOpConnection)
        throw LogError(path_, where, "unexpected record op " + std::to_string(op) +
                                         " inside a chunk; expected message data (0x02) or connection (0x07)");
      if (!fn(op, h, i, p + dl_pos + 4, dl)) return;
      i = dl_pos + 4 + dl;
    }
  }

  ReadLimits limits_;
  BagFile file_;
  bool indexed_ = false;
  std::uint64_t first_record_ = 0;
  std::map<std::uint32_t, Connection> connections_;
  std::unordered_map<std::uint32_t, std::size_t> conn_topic_;
  std::map<std::uint32_t, std::pair<std::int64_t, std::int64_t>> conn_span_;
  std::vector<Chunk> chunks_;
  std::vector<std::uint8_t> packed_, chunk_;  // reused from chunk to chunk
  std::unique_ptr<LZ4F_dctx, Lz4Free> lz4_;  // a member, so a constructor that throws frees it
};

}  // namespace

std::unique_ptr<BagReader> openRos1Bag(const std::string& path, const ReadLimits& limits) {
  return std::make_unique<Ros1Bag>(path, limits);
}

}  // namespace fgcal::logs::detail
