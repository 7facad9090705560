// fgcal bag-info (see bag_info.hpp).
#include "fgcal/apps/bag_info.hpp"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <map>
#include <system_error>

#include "fgcal/apps/errors.hpp"
#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "fgcal/logs/messages.hpp"

namespace fs = std::filesystem;

namespace fgcal::apps {

namespace {

std::uint64_t sizeOnDisk(const std::string& path) {
  std::error_code ec;
  const fs::path p(path);
  if (!fs::is_directory(p, ec)) {
    const auto n = fs::file_size(p, ec);
    return ec ? 0 : static_cast<std::uint64_t>(n);
  }
  std::uint64_t total = 0;
  for (fs::recursive_directory_iterator it(p, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code ec2;
    if (it->is_regular_file(ec2)) {
      const auto n = it->file_size(ec2);
      if (!ec2) total += static_cast<std::uint64_t>(n);
    }
  }
  return total;
}

// Floor division, so times before the epoch print as the right date.
std::int64_t floorDiv(std::int64_t a, std::int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }

std::string seconds(std::int64_t ns) {
  const std::int64_t s = floorDiv(ns, 1000000000);
  const std::int64_t frac = ns - s * 1000000000;
  char buf[48];
  std::snprintf(buf, sizeof buf, "%" PRId64 ".%09" PRId64, s, frac);
  return buf;
}

std::string humanSize(std::uint64_t bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double v = static_cast<double>(bytes);
  int u = 0;
  while (v >= 1024.0 && u < 4) v /= 1024.0, ++u;
  char buf[64];
  if (u == 0)
    std::snprintf(buf, sizeof buf, "%" PRIu64 " B", bytes);
  else
    std::snprintf(buf, sizeof buf, "%.1f %s (%" PRIu64 " bytes)", v, units[u], bytes);
  return buf;
}

std::string duration(std::int64_t ns) {
  char buf[64];
  const double s = static_cast<double>(ns) * 1e-9;
  if (s < 60.0) {
    std::snprintf(buf, sizeof buf, "%.3f s", s);
  } else {
    const auto total = static_cast<std::int64_t>(s);
    std::snprintf(buf, sizeof buf, "%.3f s (%" PRId64 "h %02" PRId64 "m %02" PRId64 "s)", s, total / 3600,
                  (total / 60) % 60, total % 60);
  }
  return buf;
}

std::string rate(double hz) {
  if (hz <= 0.0) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, hz >= 100.0 ? "%.1f Hz" : "%.2f Hz", hz);
  return buf;
}

}  // namespace

std::string formatUtc(std::int64_t ns) {
  const std::int64_t s = floorDiv(ns, 1000000000);
  const std::int64_t frac = ns - s * 1000000000;
  const std::time_t t = static_cast<std::time_t>(s);
  std::tm tm{};
  if (gmtime_r(&t, &tm) == nullptr) return "(not a representable date)";
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S", &tm);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%s.%09" PRId64 " UTC", date, frac);
  return buf;
}

BagSummary summarizeBag(const std::string& path, bool read_stamps) {
  BagSummary out;
  out.path = path;
  try {
    const std::unique_ptr<logs::BagReader> bag = logs::openBag(path);
    out.format = bag->format();
    out.start_ns = bag->startNs();
    out.end_ns = bag->endNs();
    std::map<std::string, std::size_t> index;
    std::vector<std::string> known;
    for (const logs::TopicInfo& t : bag->topics()) {
      BagTopicSummary s;
      s.name = t.name;
      s.type = t.type;
      s.serialization = t.serialization == logs::Serialization::Ros1 ? "ros1" : "cdr";
      s.message_count = t.message_count;
      s.first_record_ns = t.first_record_ns;
      s.last_record_ns = t.last_record_ns;
      if (t.message_count >= 2 && t.last_record_ns > t.first_record_ns)
        s.rate_hz = static_cast<double>(t.message_count - 1) /
                    (static_cast<double>(t.last_record_ns - t.first_record_ns) * 1e-9);
      s.known_type = logs::messageKind(t.type) != logs::MessageKind::Other;
      if (s.known_type && t.message_count > 0) known.push_back(t.name);
      out.message_count += t.message_count;
      index[t.name] = out.topics.size();
      out.topics.push_back(std::move(s));
    }
    if (read_stamps && !known.empty()) {
      std::vector<std::int64_t> last(out.topics.size(), 0);
      bag->read(known, [&](const logs::RawMessage& m) {
        const std::size_t i = index.at(m.topic->name);
        BagTopicSummary& s = out.topics[i];
        const std::int64_t stamp = logs::decodeHeaderStamp(m, path);
        if (!s.stamps_read) {
          s.stamps_read = true;
          s.min_stamp_ns = s.max_stamp_ns = stamp;
        } else {
          if (stamp < last[i]) ++s.stamps_out_of_order;
          s.min_stamp_ns = std::min(s.min_stamp_ns, stamp);
          s.max_stamp_ns = std::max(s.max_stamp_ns, stamp);
        }
        last[i] = stamp;
        return true;
      });
    }
  } catch (const logs::LogError& e) {
    throw InputError(e.file(), e.where(), e.detail());
  }
  out.size_bytes = sizeOnDisk(path);
  return out;
}

std::string formatBagInfo(const BagSummary& b) {
  std::string s;
  const auto line = [&](const char* key, const std::string& value) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%-10s", key);
    s += buf + value + "\n";
  };
  line("path:", b.path);
  line("format:", b.format);
  if (b.message_count > 0) {
    line("duration:", duration(b.end_ns - b.start_ns));
    line("start:", seconds(b.start_ns) + " s (" + formatUtc(b.start_ns) + ")");
    line("end:", seconds(b.end_ns) + " s (" + formatUtc(b.end_ns) + ")");
  } else {
    line("duration:", "- (no messages)");
  }
  line("size:", humanSize(b.size_bytes));
  line("messages:", std::to_string(b.message_count));
  line("topics:", std::to_string(b.topics.size()) + (b.topics.empty() ? "" : "  (times are record times)"));
  if (b.topics.empty()) return s;

  const bool any_stamps =
      std::any_of(b.topics.begin(), b.topics.end(), [](const BagTopicSummary& t) { return t.stamps_read; });
  std::vector<std::vector<std::string>> rows;
  rows.push_back({"topic", "type", "count", "rate", "serialization"});
  if (any_stamps) rows[0].push_back("header stamps (s)");
  for (const BagTopicSummary& t : b.topics) {
    std::vector<std::string> r{t.name, t.type, std::to_string(t.message_count), rate(t.rate_hz), t.serialization};
    if (any_stamps) {
      if (t.stamps_read) {
        std::string span = seconds(t.min_stamp_ns) + " .. " + seconds(t.max_stamp_ns);
        if (t.stamps_out_of_order > 0)
          span += ", " + std::to_string(t.stamps_out_of_order) + " stored after a later stamp";
        r.push_back(span);
      } else {
        r.push_back(t.known_type ? "-" : "- (type not read)");
      }
    }
    rows.push_back(std::move(r));
  }
  std::vector<std::size_t> width(rows[0].size(), 0);
  for (const auto& r : rows)
    for (std::size_t c = 0; c < r.size(); ++c) width[c] = std::max(width[c], r[c].size());
  for (const auto& r : rows) {
    std::string l = " ";
    for (std::size_t c = 0; c < r.size(); ++c) {
      const bool right = c == 2 || c == 3;  // count and rate
      const std::string pad(width[c] - r[c].size(), ' ');
      l += " " + (right ? pad + r[c] : r[c] + (c + 1 < r.size() ? pad : ""));
      if (c + 1 < r.size()) l += " ";
    }
    s += l + "\n";
  }
  return s;
}

}  // namespace fgcal::apps
