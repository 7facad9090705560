// Fuzz target: the rosbag2 sqlite3 reader. The bytes are written to a .db3
// file (sqlite reads files, not memory), opened with openBag, its topics
// listed, every message read and, where the topic's type is one of the four
// the calibration decodes, decoded; then the first topic is read alone.
// Findings: a crash, a sanitizer report, an exception other than LogError, a
// message whose topic, index or record time contradicts topics(), or a full
// reading that delivers other counts than topics() states.
//
// Seeds: fuzz/corpus/fuzz_sqlite_bag/ holds only tiny hand-made inputs; the
// real seeds (small rosbag2 files cut from the shared fixtures) are made at
// fuzz-build time by fuzz_sqlite_bag_seeds.cpp into the build's working
// corpus (fuzz/fuzz_sqlite_bag_seeds.cmake).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "fgcal/logs/messages.hpp"
#include "fuzz_common.hpp"

namespace {

namespace fs = std::filesystem;

/// One scratch file per process, removed at exit.
const std::string& scratchFile() {
  static const std::string dir = [] {
    const fs::path d = fs::temp_directory_path() / ("fgcal_fuzz_sqlite_" + std::to_string(::getpid()));
    fs::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(fs::temp_directory_path() / ("fgcal_fuzz_sqlite_" + std::to_string(::getpid())), ec);
    });
    return d.string();
  }();
  static const std::string file = dir + "/bag.db3";
  return file;
}

[[noreturn]] void finding(const std::string& what) {
  std::fprintf(stderr, "fuzz_sqlite_bag: %s\n", what.c_str());
  std::abort();
}

void decode(const fgcal::logs::RawMessage& m, const std::string& file) {
  using namespace fgcal::logs;
  try {
    switch (messageKind(m.topic->type)) {
      case MessageKind::JointState: (void)decodeJointState(m, file); break;
      case MessageKind::Image: (void)decodeImage(m, file); break;
      case MessageKind::CompressedImage: (void)decodeCompressedImage(m, file); break;
      case MessageKind::CameraInfo: (void)decodeCameraInfo(m, file); break;
      case MessageKind::Other: return;
    }
    (void)decodeHeaderStamp(m, file);
  } catch (const LogError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fgcal::logs;
  // SQLite's page walks are slow under the sanitizers: small files only.
  if (size > 64 * 1024) return 0;
  const std::string& path = scratchFile();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out) finding("cannot write the scratch file " + path);
  }
  try {
    ReadLimits limits;
    limits.max_chunk_bytes = 1 << 20;
    const auto bag = openBag(path, limits);
    (void)bag->format();
    (void)bag->startNs();
    (void)bag->endNs();
    const auto& topics = bag->topics();
    for (std::size_t i = 1; i < topics.size(); ++i)
      if (!(topics[i - 1].name < topics[i].name)) finding("topics() not sorted by name, or a name twice");
    std::map<const TopicInfo*, std::uint64_t> seen;
    bag->read({}, [&](const RawMessage& m) {
      if (!m.topic || bag->findTopic(m.topic->name) != m.topic) finding("a message whose topic is not in topics()");
      if (m.index != seen[m.topic]++) finding("indexes of topic " + m.topic->name + " not 0, 1, 2, ...");
      if (m.record_ns < m.topic->first_record_ns || m.record_ns > m.topic->last_record_ns)
        finding("a record time outside the topic's span");
      if (m.size > 0 && !m.data) finding("data null with a size");
      decode(m, path);
      return true;
    });
    for (const auto& t : topics)
      if (seen[&t] != t.message_count) finding("topic " + t.name + ": read count differs from message_count");
    if (!topics.empty()) {
      std::uint64_t n = 0;
      bag->read({topics.front().name}, [&](const RawMessage& m) {
        if (m.topic != &topics.front() || m.index != n++) finding("a one-topic reading differs from the full one");
        return true;
      });
    }
  } catch (const LogError&) {
  } catch (const std::exception& e) {
    fgcal::fuzz::unexpected(e);
  }
  return 0;
}
