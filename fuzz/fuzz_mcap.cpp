// Fuzz target: the MCAP reader (openBag on an .mcap file) on arbitrary bytes.
// An accepted file is listed, every topic is read, and each message whose
// type is one of the four sensor_msgs types is decoded (its header stamp too),
// so the chunk walk, the decompressors and the CDR decoders all see the
// bytes. A LogError is an answer; anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "fgcal/logs/messages.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fgcal::logs;
  if (size > 256 * 1024) return 0;
  // The reader takes a path: the input goes to a file of this process.
  static const std::string path =
      (std::filesystem::temp_directory_path() / ("fgcal_fuzz_mcap_" + std::to_string(getpid()) + ".mcap")).string();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  ReadLimits limits;
  limits.max_chunk_bytes = std::size_t{1} << 20;  // keeps hostile uncompressed sizes cheap to refuse or fill
  try {
    const auto bag = openBag(path, limits);
    (void)bag->format();
    std::uint64_t listed = 0;
    for (const auto& t : bag->topics()) listed += t.message_count;
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
        (void)decodeHeaderStamp(m, path);
      } catch (const LogError&) {
      }
      return seen < 100000;
    });
    (void)bag->startNs();
    (void)bag->endNs();
  } catch (const LogError&) {
  } catch (const std::exception& e) {
    fgcal::fuzz::unexpected(e);
  }
  return 0;
}
