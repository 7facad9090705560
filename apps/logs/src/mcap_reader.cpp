// One MCAP file (https://mcap.dev/spec, major version 0), read without the MCAP
// or ROS libraries: records are opcode (u8), content length (u64 LE), content.
//
// Opening:
// * with a summary (footer -> summary_start != 0): schemas, channels, chunk
//   indexes and statistics come from the summary section (its CRC checked when
//   non-zero); counts and record-time spans per channel from the Message Index
//   records that the chunk indexes point at. When the summary cannot give them
//   (no chunk indexes, no message indexes, messages outside chunks, channels
//   missing from it) the data section is scanned instead.
// * without one (no footer, bad end magic, summary_start 0: a recorder that
//   stopped before closing its file): the data section is scanned from the
//   Header to DataEnd, the Footer or the end of the file, decompressing each
//   chunk. A file that ends exactly between two records reads like a complete
//   one. A file cut inside a record (a chunk half written) is refused with the
//   offset of that record and what it declared: we do not guess which
//   messages were lost.
//
// Reading streams the data section in file order, chunk by chunk, and inside a
// chunk in record order; a chunk holding none of the asked channels (per its
// chunk index) is skipped unread. One chunk at a time is decompressed into a
// buffer reused from chunk to chunk; uncompressed_size is checked against
// ReadLimits::max_chunk_bytes before anything is allocated, decompression must
// produce exactly that size, and a non-zero uncompressed_crc is verified.
//
// Topics: channel topic; type = schema name ("sensor_msgs/msg/Image");
// definition = schema data; Serialization::Cdr. A channel whose
// message_encoding is not "cdr" is listed with the encoding appended to its
// type (mcap_encoding.hpp), so decoding it is refused naming the encoding.
// Channels sharing a topic are merged (they must agree on type).
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include <lz4frame.h>
#include <zstd.h>

#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "mcap_encoding.hpp"
#include "readers.hpp"

namespace fgcal::logs::detail {

namespace {

constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
constexpr std::uint64_t kRecordHeader = 9;    // opcode + length
constexpr std::uint64_t kFooterContent = 20;  // summary_start, summary_offset_start, summary_crc

enum Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

const char* opName(std::uint8_t op) {
  switch (op) {
    case kHeader: return "Header";
    case kFooter: return "Footer";
    case kSchema: return "Schema";
    case kChannel: return "Channel";
    case kMessage: return "Message";
    case kChunk: return "Chunk";
    case kMessageIndex: return "MessageIndex";
    case kChunkIndex: return "ChunkIndex";
    case kAttachment: return "Attachment";
    case kAttachmentIndex: return "AttachmentIndex";
    case kStatistics: return "Statistics";
    case kMetadata: return "Metadata";
    case kMetadataIndex: return "MetadataIndex";
    case kSummaryOffset: return "SummaryOffset";
    case kDataEnd: return "DataEnd";
    default: return "unknown";
  }
}

std::string recordName(std::uint8_t op) {
  char hex[8];
  std::snprintf(hex, sizeof hex, "0x%02x", op);
  return std::string(opName(op)) + " record (opcode " + hex + ")";
}

/// CRC-32 (ISO-HDLC, the zlib one) as MCAP uses it, slicing by 4.
class Crc32 {
 public:
  Crc32() {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t_[0][i] = c;
    }
    for (std::uint32_t i = 0; i < 256; ++i)
      for (int s = 1; s < 4; ++s) t_[s][i] = (t_[s - 1][i] >> 8) ^ t_[0][t_[s - 1][i] & 0xFF];
  }
  std::uint32_t update(std::uint32_t crc, const std::uint8_t* p, std::size_t n) const {
    std::uint32_t c = ~crc;
    while (n >= 4) {
      c ^= static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
           static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
      c = t_[3][c & 0xFF] ^ t_[2][(c >> 8) & 0xFF] ^ t_[1][(c >> 16) & 0xFF] ^ t_[0][c >> 24];
      p += 4;
      n -= 4;
    }
    while (n--) c = t_[0][(c ^ *p++) & 0xFF] ^ (c >> 8);
    return ~c;
  }

 private:
  std::uint32_t t_[4][256];
};

const Crc32& crc32() {
  static const Crc32 c;
  return c;
}

/// Bounded little-endian reader over one record's content; running past the
/// end is a LogError naming the file, `where` and the field.
class Fields {
 public:
  Fields(const std::uint8_t* p, std::uint64_t n, const std::string& file, std::string where, std::string record)
      : p_(p), n_(n), file_(file), where_(std::move(where)), record_(std::move(record)) {}

  std::uint8_t u8(const char* f) { return static_cast<std::uint8_t>(uint(1, f)); }
  std::uint16_t u16(const char* f) { return static_cast<std::uint16_t>(uint(2, f)); }
  std::uint32_t u32(const char* f) { return static_cast<std::uint32_t>(uint(4, f)); }
  std::uint64_t u64(const char* f) { return uint(8, f); }
  std::string str(const char* f) {
    const std::uint32_t len = u32(f);
    need(len, f);
    std::string s(reinterpret_cast<const char*>(p_ + pos_), len);
    pos_ += len;
    return s;
  }
  /// A length-prefixed block (u32 for strings/maps/bytes, u64 for chunk records): returns its start.
  std::uint64_t block(std::uint64_t len, const char* f) {
    need(len, f);
    const std::uint64_t at = pos_;
    pos_ += len;
    return at;
  }
  std::uint64_t pos() const { return pos_; }
  std::uint64_t remaining() const { return n_ - pos_; }
  const std::uint8_t* data() const { return p_; }

  [[noreturn]] void fail(const std::string& what) const { throw LogError(file_, where_, record_ + ": " + what); }

 private:
  void need(std::uint64_t k, const char* f) const {
    if (k > n_ - pos_)
      fail(std::string("field ") + f + " needs " + std::to_string(k) + " bytes but only " + std::to_string(n_ - pos_) +
           " remain in the record");
  }
  std::uint64_t uint(int w, const char* f) {
    need(static_cast<std::uint64_t>(w), f);
    std::uint64_t v = 0;
    for (int i = 0; i < w; ++i) v |= static_cast<std::uint64_t>(p_[pos_ + static_cast<std::uint64_t>(i)]) << (8 * i);
    pos_ += static_cast<std::uint64_t>(w);
    return v;
  }

  const std::uint8_t* p_;
  std::uint64_t n_, pos_ = 0;
  const std::string& file_;
  std::string where_, record_;
};

std::string offsetWhere(std::uint64_t off) { return "offset " + std::to_string(off); }

struct SchemaRec {
  std::string name, encoding, data;
};
struct ChannelRec {
  std::uint16_t schema_id = 0;
  std::string topic, message_encoding;
  // filled by the scan or from the message indexes
  std::uint64_t count = 0;
  std::uint64_t first = std::numeric_limits<std::uint64_t>::max(), last = 0;
};
struct ChunkIndexRec {
  std::uint64_t chunk_start = 0, chunk_length = 0;
  std::vector<std::pair<std::uint16_t, std::uint64_t>> message_index_offsets;
  std::uint64_t message_index_length = 0;
};

class McapReader final : public BagReaderBase {
 public:
  McapReader(std::string path, const ReadLimits& limits) : BagReaderBase(std::move(path)), limits_(limits) {
    in_.open(path_, std::ios::binary);
    if (!in_) throw LogError(path_, "", "cannot open the file for reading");
    in_.seekg(0, std::ios::end);
    const auto end = in_.tellg();
    if (end < 0) throw LogError(path_, "", "cannot determine the file's size");
    size_ = static_cast<std::uint64_t>(end);
    open();
  }

  void read(const std::vector<std::string>& topic_names, const std::function<bool(const RawMessage&)>& fn) override {
    const std::vector<bool> wanted_topic = selectTopics(topic_names);
    std::unordered_map<std::uint16_t, std::size_t> wanted_channel;  // channel id -> topic index
    for (const auto& [id, topic] : channel_topic_)
      if (wanted_topic[topic]) wanted_channel.emplace(id, topic);
    if (wanted_channel.empty()) return;

    std::vector<std::uint64_t> index(topics_.size(), 0);
    bool stop = false;
    const auto skipChunk = [&](std::uint64_t chunk_offset) {
      const auto it = chunk_channels_.find(chunk_offset);
      if (it == chunk_channels_.end()) return false;  // not indexed: read it
      for (std::uint16_t id : it->second)
        if (wanted_channel.count(id)) return false;
      return true;
    };
    walk(skipChunk, [&](const MessageView& m) {
      const auto it = wanted_channel.find(m.channel);
      if (it == wanted_channel.end()) {
        if (!channel_topic_.count(m.channel))
          throw LogError(
              path_, m.where,
              "Message record refers to channel " + std::to_string(m.channel) + ", which no Channel record defines");
        return true;
      }
      RawMessage raw;
      raw.topic = &topics_[it->second];
      raw.index = index[it->second]++;
      raw.record_ns = recordNs(m.log_time, m.where);
      raw.data = m.data;
      raw.size = m.size;
      if (!fn(raw)) stop = true;
      return !stop;
    });
  }

 private:
  struct MessageView {
    std::uint16_t channel;
    std::uint64_t log_time;
    const std::uint8_t* data;
    std::size_t size;
    const std::string& where;
  };

  // ---- file access -------------------------------------------------------

  void readAt(std::uint64_t off, std::uint8_t* dst, std::uint64_t n) {
    if (off > size_ || n > size_ - off)
      throw LogError(
          path_, offsetWhere(off),
          "expected " + std::to_string(n) + " bytes, but the file ends at " + std::to_string(size_) + " (cut short?)");
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(off));
    in_.read(reinterpret_cast<char*>(dst), static_cast<std::streamsize>(n));
    if (static_cast<std::uint64_t>(in_.gcount()) != n)
      throw LogError(path_, offsetWhere(off),
                     "read error: got " + std::to_string(in_.gcount()) + " of " + std::to_string(n) + " bytes");
  }

  struct RecordHead {
    std::uint8_t op = 0;
    std::uint64_t len = 0;
  };

  /// The record header at `off`; its content must lie inside [off, limit).
  RecordHead head(std::uint64_t off, std::uint64_t limit) {
    std::uint8_t b[kRecordHeader];
    if (off > limit)
      throw LogError(path_, offsetWhere(off),
                     "expected a record here, but the offset lies past the end (" + std::to_string(limit) + ")");
    if (limit - off < kRecordHeader)
      throw LogError(path_, offsetWhere(off),
                     "expected a record header (9 bytes), but only " + std::to_string(limit - off) + " bytes remain" +
                         (limit == size_ ? " in the file (cut short?)" : " before the summary"));
    readAt(off, b, kRecordHeader);
    RecordHead h;
    h.op = b[0];
    for (int i = 0; i < 8; ++i) h.len |= static_cast<std::uint64_t>(b[1 + i]) << (8 * i);
    if (h.len > limit - off - kRecordHeader)
      throw LogError(path_, offsetWhere(off),
                     recordName(h.op) + " declares " + std::to_string(h.len) + " bytes but only " +
                         std::to_string(limit - off - kRecordHeader) +
                         (limit == size_ ? " remain in the file (the file was cut short?)"
                                         : " remain before the summary section"));
    return h;
  }

  /// Reads a whole small record's content into `record_buf_`.
  Fields content(std::uint64_t off, const RecordHead& h) {
    if (h.len > limits_.max_chunk_bytes)
      throw LogError(path_, offsetWhere(off),
                     recordName(h.op) + " of " + std::to_string(h.len) + " bytes is larger than the limit of " +
                         std::to_string(limits_.max_chunk_bytes) + " bytes");
    record_buf_.resize(static_cast<std::size_t>(h.len));
    readAt(off + kRecordHeader, record_buf_.data(), h.len);
    return Fields(record_buf_.data(), h.len, path_, offsetWhere(off), recordName(h.op));
  }

  std::int64_t recordNs(std::uint64_t t, const std::string& where) const {
    if (t > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
      throw LogError(path_, where, "log_time " + std::to_string(t) + " does not fit signed 64-bit nanoseconds");
    return static_cast<std::int64_t>(t);
  }

  // ---- opening -----------------------------------------------------------

  void open() {
    std::array<std::uint8_t, 8> magic{};
    if (size_ < magic.size()) throw LogError(path_, "offset 0", "expected the MCAP magic, but the file is shorter");
    readAt(0, magic.data(), magic.size());
    if (magic != kMagic)
      throw LogError(path_, "offset 0", "expected the MCAP magic \\x89MCAP0\\r\\n at the start of the file");
    const RecordHead h = head(8, size_);
    if (h.op != kHeader)
      throw LogError(path_, offsetWhere(8), "expected a Header record first, found " + recordName(h.op));
    {
      Fields f = content(8, h);
      profile_ = f.str("profile");
      library_ = f.str("library");
    }
    data_start_ = 8 + kRecordHeader + h.len;

    const bool summary = readFooterAndSummary();
    if (!summary || !countsFromIndexes()) scan();
    buildTopics();
    format_ = "MCAP";
    if (!profile_.empty()) format_ += ", profile " + profile_;
    std::string comp;
    for (const auto& c : compressions_) comp += (comp.empty() ? "" : "+") + (c.empty() ? std::string("none") : c);
    if (!comp.empty()) format_ += ", chunk compression " + comp;
    format_ += summary ? ", indexed" : ", no summary (scanned)";
  }

  /// The footer's summary start and CRC; nullopt when the file has no footer.
  struct FooterInfo {
    std::uint64_t offset = 0;  ///< of the footer record
    std::uint64_t summary_start = 0;
    std::uint32_t summary_crc = 0;
  };
  std::optional<FooterInfo> readFooter() {
    const std::uint64_t tail = kRecordHeader + kFooterContent + kMagic.size();
    if (size_ < data_start_ + tail) return std::nullopt;
    std::array<std::uint8_t, kRecordHeader + kFooterContent + 8> b{};
    readAt(size_ - tail, b.data(), b.size());
    if (!std::equal(kMagic.begin(), kMagic.end(), b.end() - 8)) return std::nullopt;
    if (b[0] != kFooter) return std::nullopt;
    std::uint64_t len = 0;
    for (int i = 0; i < 8; ++i) len |= static_cast<std::uint64_t>(b[1 + static_cast<std::size_t>(i)]) << (8 * i);
    FooterInfo footer;
    footer.offset = size_ - tail;
    if (len != kFooterContent)
      throw LogError(path_, offsetWhere(footer.offset),
                     "Footer record declares " + std::to_string(len) + " bytes; expected 20");
    Fields f(b.data() + kRecordHeader, kFooterContent, path_, offsetWhere(footer.offset), "Footer record");
    footer.summary_start = f.u64("summary_start");
    (void)f.u64("summary_offset_start");
    footer.summary_crc = f.u32("summary_crc");
    return footer;
  }

  /// The summary section's CRC (when the footer gives one) against its bytes.
  void checkSummaryCrc(const FooterInfo& footer) {
    if (footer.summary_crc == 0) return;
    std::vector<std::uint8_t> buf;
    std::uint32_t crc = 0;
    const std::uint64_t upto = footer.offset + kRecordHeader + 16;  // through summary_offset_start
    for (std::uint64_t o = footer.summary_start; o < upto;) {
      const std::uint64_t n = std::min<std::uint64_t>(upto - o, 1 << 20);
      buf.resize(static_cast<std::size_t>(n));
      readAt(o, buf.data(), n);
      crc = crc32().update(crc, buf.data(), buf.size());
      o += n;
    }
    if (crc != footer.summary_crc)
      throw LogError(path_, offsetWhere(footer.summary_start),
                     "summary section CRC mismatch: the footer says " + std::to_string(footer.summary_crc) +
                         ", the bytes give " + std::to_string(crc) + " (damaged file)");
  }

  /// A ChunkIndex record of the summary: the chunk's place and the offsets
  /// of its message indexes, checked to lie in the data section.
  void addChunkIndex(Fields& f, std::uint64_t off) {
    ChunkIndexRec ci;
    (void)f.u64("message_start_time");
    (void)f.u64("message_end_time");
    ci.chunk_start = f.u64("chunk_start_offset");
    ci.chunk_length = f.u64("chunk_length");
    const std::uint32_t map_len = f.u32("message_index_offsets");
    const std::uint64_t map_at = f.block(map_len, "message_index_offsets");
    Fields m(f.data() + map_at, map_len, path_, offsetWhere(off), "ChunkIndex message_index_offsets");
    while (m.remaining() > 0) {
      const std::uint16_t ch = m.u16("channel_id");
      ci.message_index_offsets.emplace_back(ch, m.u64("offset"));
    }
    ci.message_index_length = f.u64("message_index_length");
    compressions_.insert(f.str("compression"));
    if (ci.chunk_start < data_start_ || ci.chunk_start > data_end_ || ci.chunk_length > data_end_ - ci.chunk_start)
      f.fail("chunk at offset " + std::to_string(ci.chunk_start) + " (" + std::to_string(ci.chunk_length) +
             " bytes) lies outside the data section");
    auto& ids = chunk_channels_[ci.chunk_start];
    for (const auto& [ch, o] : ci.message_index_offsets) ids.push_back(ch);
    chunk_indexes_.push_back(std::move(ci));
  }

  /// The summary section's records: schemas, channels, chunk indexes, statistics.
  void readSummary(std::uint64_t summary_start, std::uint64_t footer_off) {
    for (std::uint64_t off = summary_start; off < footer_off;) {
      const RecordHead r = head(off, footer_off);
      if (r.op == kSchema || r.op == kChannel || r.op == kChunkIndex || r.op == kStatistics) {
        Fields f = content(off, r);
        if (r.op == kSchema) {
          addSchema(f);
        } else if (r.op == kChannel) {
          addChannel(f);
        } else if (r.op == kChunkIndex) {
          addChunkIndex(f, off);
        } else {
          stats_message_count_ = f.u64("message_count");
          (void)f.u16("schema_count");
          stats_channel_count_ = f.u32("channel_count");
          have_stats_ = true;
        }
      }  // else: indexes of attachments/metadata, summary offsets, unknown opcodes
      off += kRecordHeader + r.len;
    }
  }

  /// True when the file has a footer and a summary section, which are then parsed.
  bool readFooterAndSummary() {
    data_end_ = size_;
    const std::optional<FooterInfo> footer = readFooter();
    if (!footer) return false;
    data_end_ = footer->summary_start == 0 ? footer->offset : footer->summary_start;
    if (footer->summary_start == 0) return false;
    if (footer->summary_start < data_start_ || footer->summary_start > footer->offset)
      throw LogError(path_, offsetWhere(footer->offset),
                     "Footer summary_start " + std::to_string(footer->summary_start) +
                         " lies outside the file's records [" + std::to_string(data_start_) + ", " +
                         std::to_string(footer->offset) + "]");
    checkSummaryCrc(*footer);
    readSummary(footer->summary_start, footer->offset);
    return true;
  }

  void addSchema(Fields& f) {
    const std::uint16_t id = f.u16("id");
    SchemaRec s;
    s.name = f.str("name");
    s.encoding = f.str("encoding");
    const std::uint32_t n = f.u32("data");
    const std::uint64_t at = f.block(n, "data");
    s.data.assign(reinterpret_cast<const char*>(f.data() + at), n);
    if (id == 0) f.fail("schema id 0 is reserved (it means 'no schema')");
    schemas_.emplace(id, std::move(s));  // a repeated id keeps the first
  }

  void addChannel(Fields& f) {
    const std::uint16_t id = f.u16("id");
    ChannelRec c;
    c.schema_id = f.u16("schema_id");
    c.topic = f.str("topic");
    c.message_encoding = f.str("message_encoding");
    channels_.emplace(id, std::move(c));
  }

  /// Counts and spans from the message indexes the chunk indexes point at.
  /// False when the summary cannot give them, so the caller scans.
  bool countsFromIndexes() {
    if (channels_.empty() && (!have_stats_ || stats_message_count_ > 0)) return false;
    if (have_stats_ && stats_channel_count_ != channels_.size()) return false;
    if (chunk_indexes_.empty()) return have_stats_ && stats_message_count_ == 0;
    std::uint64_t total = 0;
    for (const auto& ci : chunk_indexes_) {
      if (ci.message_index_offsets.empty()) return false;  // written without message indexes
      for (const auto& [ch, o] : ci.message_index_offsets) {
        const auto it = channels_.find(ch);
        if (it == channels_.end()) return false;
        const RecordHead r = head(o, data_end_);
        if (r.op != kMessageIndex)
          throw LogError(path_, offsetWhere(o),
                         "the chunk index of the chunk at offset " + std::to_string(ci.chunk_start) +
                             " points here for channel " + std::to_string(ch) + ", but found " + recordName(r.op));
        Fields f = content(o, r);
        if (f.u16("channel_id") != ch) f.fail("expected the message index of channel " + std::to_string(ch));
        const std::uint32_t n = f.u32("records");
        if (n % 16 != 0 || n > f.remaining()) f.fail("records array of " + std::to_string(n) + " bytes");
        ChannelRec& c = it->second;
        for (std::uint32_t k = 0; k < n / 16; ++k) {
          const std::uint64_t t = f.u64("log_time");
          (void)f.u64("offset");
          ++c.count;
          ++total;
          c.first = std::min(c.first, t);
          c.last = std::max(c.last, t);
        }
      }
    }
    if (have_stats_ && total != stats_message_count_) {
      // Messages outside chunks, or a chunk without its index: only a scan finds them.
      for (auto& [id, c] : channels_) c.count = 0, c.first = std::numeric_limits<std::uint64_t>::max(), c.last = 0;
      return false;
    }
    return true;
  }

  /// A linear pass over the data section that counts messages per channel
  /// and collects every schema and channel, inside chunks too.
  void scan() {
    chunk_channels_.clear();  // every chunk is read when the counts come from a scan
    for (auto& [id, c] : channels_) c.count = 0, c.first = std::numeric_limits<std::uint64_t>::max(), c.last = 0;
    walk([](std::uint64_t) { return false; },
         [&](const MessageView& m) {
           const auto it = channels_.find(m.channel);
           if (it == channels_.end())
             throw LogError(path_, m.where,
                            "Message record refers to channel " + std::to_string(m.channel) +
                                ", which no earlier Channel record defines");
           ChannelRec& c = it->second;
           ++c.count;
           c.first = std::min(c.first, m.log_time);
           c.last = std::max(c.last, m.log_time);
           return true;
         },
         /*collect=*/true);
  }

  void buildTopics() {
    std::map<std::string, TopicInfo> by_name;
    std::map<std::string, std::uint16_t> first_channel;
    for (const auto& [id, c] : channels_) {
      TopicInfo t;
      t.name = c.topic;
      if (c.schema_id != 0) {
        const auto s = schemas_.find(c.schema_id);
        if (s == schemas_.end())
          throw LogError(path_, "topic " + c.topic,
                         "channel " + std::to_string(id) + " refers to schema " + std::to_string(c.schema_id) +
                             ", which no Schema record defines");
        t.type = s->second.name;
        t.definition = s->second.data;
      }
      if (c.message_encoding != "cdr") t.type = typeWithForeignEncoding(t.type, c.message_encoding);
      t.serialization = Serialization::Cdr;
      t.message_count = c.count;
      if (c.count > 0) {
        t.first_record_ns = recordNs(c.first, "topic " + c.topic);
        t.last_record_ns = recordNs(c.last, "topic " + c.topic);
      }
      const auto [it, fresh] = by_name.emplace(t.name, t);
      if (fresh) {
        first_channel[t.name] = id;
        continue;
      }
      TopicInfo& m = it->second;
      if (m.type != t.type)
        throw LogError(path_, "topic " + t.name,
                       "channels " + std::to_string(first_channel[t.name]) + " and " + std::to_string(id) +
                           " share the topic with different types: " + m.type + " and " + t.type);
      if (t.message_count > 0) {
        m.first_record_ns = m.message_count > 0 ? std::min(m.first_record_ns, t.first_record_ns) : t.first_record_ns;
        m.last_record_ns = m.message_count > 0 ? std::max(m.last_record_ns, t.last_record_ns) : t.last_record_ns;
        m.message_count += t.message_count;
      }
    }
    for (auto& [name, t] : by_name) topics_.push_back(std::move(t));
    for (const auto& [id, c] : channels_) {
      const std::string& name = c.topic;  // a structured binding cannot be captured in C++17
      const auto it = std::find_if(topics_.begin(), topics_.end(), [&](const TopicInfo& t) { return t.name == name; });
      channel_topic_.emplace(id, static_cast<std::size_t>(it - topics_.begin()));
    }
  }

  // ---- the data section walk ---------------------------------------------

  /// Visits every Message of the data section in file order. `skip(offset)`
  /// says a chunk need not be read; `on(msg)` returns false to stop. With
  /// `collect`, Schema and Channel records are gathered (the scan).
  template <class Skip, class On>
  void walk(const Skip& skip, const On& on, bool collect = false) {
    for (std::uint64_t off = data_start_; off < data_end_;) {
      const RecordHead r = head(off, data_end_);
      const std::uint64_t next = off + kRecordHeader + r.len;
      if (r.op == kDataEnd || r.op == kFooter) return;
      if (r.op == kChunk) {
        if (!skip(off) && !chunk(off, r, on, collect)) return;
      } else if (r.op == kMessage) {
        Fields f = content(off, r);
        const std::string where = offsetWhere(off);
        MessageView m{f.u16("channel_id"), 0, nullptr, 0, where};
        (void)f.u32("sequence");
        m.log_time = f.u64("log_time");
        (void)f.u64("publish_time");
        m.data = f.data() + f.pos();
        m.size = static_cast<std::size_t>(f.remaining());
        if (!on(m)) return;
      } else if (collect && (r.op == kSchema || r.op == kChannel)) {
        Fields f = content(off, r);
        r.op == kSchema ? addSchema(f) : addChannel(f);
      }
      off = next;
    }
  }

  /// A chunk record's fields before its records.
  struct ChunkHead {
    std::uint64_t usize = 0;  ///< uncompressed size of the records
    std::uint32_t ucrc = 0;   ///< their CRC; 0: none
    std::string compression;
    std::uint64_t rlen = 0;        ///< stored size of the records
    std::uint64_t records_at = 0;  ///< file offset of the stored records
  };

  /// The chunk record's fixed fields and compression name, read alone so that
  /// a skipped or oversized chunk is never loaded; checked against the record
  /// and the limits.
  ChunkHead chunkHead(std::uint64_t off, const RecordHead& r, const std::string& where, bool collect) {
    const std::uint64_t fixed = 8 + 8 + 8 + 4 + 4;
    std::array<std::uint8_t, fixed> b{};
    if (r.len < fixed)
      throw LogError(path_, offsetWhere(off),
                     "Chunk record of " + std::to_string(r.len) + " bytes is shorter than its fixed fields (32 bytes)");
    readAt(off + kRecordHeader, b.data(), fixed);
    Fields f(b.data(), fixed, path_, offsetWhere(off), "Chunk record");
    (void)f.u64("message_start_time");
    (void)f.u64("message_end_time");
    ChunkHead h;
    h.usize = f.u64("uncompressed_size");
    h.ucrc = f.u32("uncompressed_crc");
    const std::uint32_t clen = f.u32("compression");
    if (clen > 64 || fixed + clen + 8 > r.len)
      throw LogError(path_, offsetWhere(off),
                     "Chunk record: compression name of " + std::to_string(clen) + " bytes does not fit the record");
    std::array<std::uint8_t, 64 + 8> b2{};
    readAt(off + kRecordHeader + fixed, b2.data(), clen + 8);
    h.compression.assign(reinterpret_cast<const char*>(b2.data()), clen);
    Fields f2(b2.data() + clen, 8, path_, offsetWhere(off), "Chunk record");
    h.rlen = f2.u64("records");
    h.records_at = off + kRecordHeader + fixed + clen + 8;
    if (h.rlen > r.len - (fixed + clen + 8))
      throw LogError(path_, offsetWhere(off),
                     "Chunk record: records field declares " + std::to_string(h.rlen) +
                         " bytes but the record holds only " + std::to_string(r.len - (fixed + clen + 8)));
    if (h.compression != "" && h.compression != "zstd" && h.compression != "lz4")
      throw LogError(path_, where, "unknown chunk compression '" + h.compression + "'; expected \"\", zstd or lz4");
    if (collect) compressions_.insert(h.compression);
    if (h.usize > limits_.max_chunk_bytes || h.rlen > limits_.max_chunk_bytes)
      throw LogError(path_, where,
                     "chunk of " + std::to_string(h.usize) + " bytes uncompressed (" + std::to_string(h.rlen) +
                         " stored) is larger than the limit of " + std::to_string(limits_.max_chunk_bytes) + " bytes");
    return h;
  }

  /// The chunk's records into chunk_buf_, decompressed and CRC-checked.
  void loadChunkRecords(const ChunkHead& h, const std::string& where) {
    if (h.compression.empty()) {
      if (h.rlen != h.usize)
        throw LogError(path_, where,
                       "uncompressed chunk stores " + std::to_string(h.rlen) +
                           " bytes but declares uncompressed_size " + std::to_string(h.usize));
      chunk_buf_.resize(static_cast<std::size_t>(h.usize));
      readAt(h.records_at, chunk_buf_.data(), h.rlen);
    } else {
      packed_buf_.resize(static_cast<std::size_t>(h.rlen));
      readAt(h.records_at, packed_buf_.data(), h.rlen);
      chunk_buf_.resize(static_cast<std::size_t>(h.usize));
      h.compression == "zstd" ? unzstd(where, h.usize) : unlz4(where, h.usize);
    }
    if (h.ucrc != 0) {
      const std::uint32_t crc = crc32().update(0, chunk_buf_.data(), chunk_buf_.size());
      if (crc != h.ucrc)
        throw LogError(path_, where,
                       "chunk CRC mismatch: uncompressed_crc is " + std::to_string(h.ucrc) +
                           " but the records give " + std::to_string(crc) + " (damaged chunk)");
    }
  }

  /// Decompresses the chunk at `off` and visits its messages; false when `on` stopped.
  template <class On>
  bool chunk(std::uint64_t off, const RecordHead& r, const On& on, bool collect) {
    const std::string where = "chunk at offset " + std::to_string(off);
    const ChunkHead h = chunkHead(off, r, where, collect);
    loadChunkRecords(h, where);
    const std::uint64_t usize = h.usize;
    const std::uint8_t* p = chunk_buf_.data();
    for (std::uint64_t pos = 0; pos < usize;) {
      const std::string rwhere = where + ", byte " + std::to_string(pos) + " of its records";
      if (usize - pos < kRecordHeader)
        throw LogError(path_, rwhere,
                       "expected a record header (9 bytes), but only " + std::to_string(usize - pos) +
                           " bytes remain in the chunk");
      const std::uint8_t op = p[pos];
      std::uint64_t len = 0;
      for (int i = 0; i < 8; ++i)
        len |= static_cast<std::uint64_t>(p[pos + 1 + static_cast<std::uint64_t>(i)]) << (8 * i);
      if (len > usize - pos - kRecordHeader)
        throw LogError(path_, rwhere,
                       recordName(op) + " declares " + std::to_string(len) + " bytes but only " +
                           std::to_string(usize - pos - kRecordHeader) + " remain in the chunk");
      Fields rf(p + pos + kRecordHeader, len, path_, rwhere, recordName(op));
      if (op == kMessage) {
        MessageView m{rf.u16("channel_id"), 0, nullptr, 0, rwhere};
        (void)rf.u32("sequence");
        m.log_time = rf.u64("log_time");
        (void)rf.u64("publish_time");
        m.data = rf.data() + rf.pos();
        m.size = static_cast<std::size_t>(rf.remaining());
        if (!on(m)) return false;
      } else if (collect && op == kSchema) {
        addSchema(rf);
      } else if (collect && op == kChannel) {
        addChannel(rf);
      }
      pos += kRecordHeader + len;
    }
    return true;
  }

  void unzstd(const std::string& where, std::uint64_t usize) {
    if (!zstd_) zstd_.reset(ZSTD_createDCtx());
    if (!zstd_) throw LogError(path_, where, "cannot create a zstd decompression context");
    const std::size_t got =
        ZSTD_decompressDCtx(zstd_.get(), chunk_buf_.data(), chunk_buf_.size(), packed_buf_.data(), packed_buf_.size());
    if (ZSTD_isError(got))
      throw LogError(path_, where,
                     std::string("zstd decompression failed (") + ZSTD_getErrorName(got) + "); expected " +
                         std::to_string(usize) + " bytes");
    if (got != usize)
      throw LogError(path_, where,
                     "zstd chunk decompressed to " + std::to_string(got) + " bytes; its uncompressed_size is " +
                         std::to_string(usize));
  }

  void unlz4(const std::string& where, std::uint64_t usize) {
    if (!lz4_) {
      LZ4F_dctx* ctx = nullptr;
      if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)))
        throw LogError(path_, where, "cannot create an lz4 decompression context");
      lz4_.reset(ctx);
    }
    LZ4F_resetDecompressionContext(lz4_.get());
    std::size_t in_pos = 0, out_pos = 0;
    std::size_t ret = 1;
    while (in_pos < packed_buf_.size()) {
      std::size_t in_n = packed_buf_.size() - in_pos, out_n = chunk_buf_.size() - out_pos;
      ret =
          LZ4F_decompress(lz4_.get(), chunk_buf_.data() + out_pos, &out_n, packed_buf_.data() + in_pos, &in_n, nullptr);
      if (LZ4F_isError(ret))
        throw LogError(path_, where, std::string("lz4 decompression failed (") + LZ4F_getErrorName(ret) + ")");
      in_pos += in_n;
      out_pos += out_n;
      if (in_n == 0 && out_n == 0) {
        if (out_pos == chunk_buf_.size())
          throw LogError(path_, where,
                         "lz4 chunk decompresses to more than its uncompressed_size " + std::to_string(usize));
        break;
      }
    }
    if (ret != 0 && out_pos == usize)
      throw LogError(path_, where,
                     "lz4 chunk decompresses to more than its uncompressed_size " + std::to_string(usize));
    if (ret != 0) throw LogError(path_, where, "lz4 frame ends early: the chunk's compressed records are incomplete");
    if (out_pos != usize)
      throw LogError(path_, where,
                     "lz4 chunk decompressed to " + std::to_string(out_pos) + " bytes; its uncompressed_size is " +
                         std::to_string(usize));
  }

  struct ZstdFree {
    void operator()(ZSTD_DCtx* c) const { ZSTD_freeDCtx(c); }
  };
  struct Lz4Free {
    void operator()(LZ4F_dctx* c) const { LZ4F_freeDecompressionContext(c); }
  };

  ReadLimits limits_;
  std::ifstream in_;
  std::uint64_t size_ = 0, data_start_ = 0, data_end_ = 0;
  std::string profile_, library_;
  std::map<std::uint16_t, SchemaRec> schemas_;
  std::map<std::uint16_t, ChannelRec> channels_;
  std::vector<ChunkIndexRec> chunk_indexes_;
  std::unordered_map<std::uint64_t, std::vector<std::uint16_t>> chunk_channels_;  // chunk offset -> channels
  std::set<std::string> compressions_;
  bool have_stats_ = false;
  std::uint64_t stats_message_count_ = 0;
  std::uint32_t stats_channel_count_ = 0;
  std::unordered_map<std::uint16_t, std::size_t> channel_topic_;
  std::vector<std::uint8_t> record_buf_, packed_buf_, chunk_buf_;
  std::unique_ptr<ZSTD_DCtx, ZstdFree> zstd_;
  std::unique_ptr<LZ4F_dctx, Lz4Free> lz4_;
};

}  // namespace

std::unique_ptr<BagReader> openMcapFile(const std::string& path, const ReadLimits& limits) {
  return std::make_unique<McapReader>(path, limits);
}

}  // namespace fgcal::logs::detail
