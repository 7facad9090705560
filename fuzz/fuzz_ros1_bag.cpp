// Fuzz target: the ROS 1 bag reader (fgcal::logs) on arbitrary bytes that
// start like a ROS 1 bag. The bytes become a file in memory (memfd, opened by
// its /proc/self/fd path, so openBag takes the same path as for a real file);
// an accepted bag is listed, read to the end, and every message of the four
// sensor_msgs types is decoded, as are all header stamps. LogError is the
// documented answer to a damaged bag; anything else is a finding.
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "fgcal/logs/messages.hpp"
#include "fuzz_common.hpp"

namespace {

/// One memory file reused for every input.
int memoryFile() {
  static const int fd = [] {
    const int f = ::memfd_create("fuzz_ros1_bag", MFD_CLOEXEC);
    if (f < 0) {
      std::perror("memfd_create");
      std::abort();
    }
    return f;
  }();
  return fd;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fgcal::logs;
  // Other formats (MCAP, sqlite3) have readers and fuzz targets of their own.
  if (size < 9 || std::memcmp(data, "#ROSBAG V", 9) != 0 || size > 1024 * 1024) return 0;
  const int fd = memoryFile();
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, data, size, 0) != static_cast<ssize_t>(size)) std::abort();
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  ReadLimits limits;
  limits.max_chunk_bytes = 4 << 20;  // a hostile size field must not allocate 1 GiB per input
  try {
    auto bag = openBag(path, limits);
    (void)bag->format();
    std::uint64_t total = 0;
    for (const auto& t : bag->topics()) total += t.message_count;
    (void)bag->startNs();
    (void)bag->endNs();
    std::uint64_t seen = 0;
    bag->read({}, [&](const RawMessage& m) {
      ++seen;
      try {
        switch (messageKind(m.topic->type)) {
          case MessageKind::JointState: (void)decodeJointState(m, path); break;
          case MessageKind::Image: (void)decodeImage(m, path); break;
          case MessageKind::CompressedImage: (void)decodeCompressedImage(m, path); break;
          case MessageKind::CameraInfo: (void)decodeCameraInfo(m, path); break;
          case MessageKind::Other: break;
        }
      } catch (const LogError&) {
        // a bad message: the next ones are still read
      }
      try {
        (void)decodeHeaderStamp(m, path);
      } catch (const LogError&) {
      }
      return true;
    });
    if (seen != total) {
      std::fprintf(stderr, "read %llu messages but the topics count %llu\n", static_cast<unsigned long long>(seen),
                   static_cast<unsigned long long>(total));
      std::abort();
    }
    if (!bag->topics().empty()) {
      // reading one topic alone gives as many messages as its count
      const TopicInfo& first = bag->topics().front();
      std::uint64_t n = 0;
      bag->read({first.name}, [&](const RawMessage& m) {
        if (m.topic != &first || m.index != n) std::abort();
        ++n;
        return true;
      });
      if (n != first.message_count) std::abort();
    }
  } catch (const LogError&) {
  } catch (const std::exception& e) {
    fgcal::fuzz::unexpected(e);
  }
  return 0;
}
