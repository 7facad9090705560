// Helpers of test_logs_ros1: scratch folders, file writing, and an
// independent walk over a bag's top-level records so that tests can damage a
// bag at a known place (a chunk header, index_pos). SHA-256 and whole-file
// reading come from test/support.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include "fgcal_test/files.hpp"
#include "fgcal_test/sha256.hpp"

namespace fgcal::logs::test {

namespace fs = std::filesystem;

using ::fgcal::test::readFile;
using ::fgcal::test::sha256Hex;

/// A fresh folder under the system temp folder, removed on destruction.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    std::random_device rd;
    path_ = fs::temp_directory_path() / ("fgcal_logs_ros1_" + std::to_string(::getpid()) + "_" +
                                         std::to_string(counter++) + "_" + std::to_string(rd()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string operator/(const std::string& sub) const { return (path_ / sub).string(); }

 private:
  fs::path path_;
};

inline void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

inline std::uint32_t getU32(const std::string& b, std::size_t at) {
  return std::uint32_t{static_cast<std::uint8_t>(b[at])} | std::uint32_t{static_cast<std::uint8_t>(b[at + 1])} << 8 |
         std::uint32_t{static_cast<std::uint8_t>(b[at + 2])} << 16 |
         std::uint32_t{static_cast<std::uint8_t>(b[at + 3])} << 24;
}

inline void putU32(std::string& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<char>(v >> (8 * i));
}

/// One top-level record of a bag, as the test sees it.
struct Record {
  std::size_t pos = 0, header_pos = 0, data_pos = 0;
  std::uint32_t data_len = 0;
  std::map<std::string, std::string> fields;
  std::map<std::string, std::size_t> field_value_pos;  ///< where each value starts in the file
  int op() const { return static_cast<unsigned char>(fields.at("op")[0]); }
  std::size_t end() const { return data_pos + data_len; }
};

/// The top-level records of a well-formed bag, from the bag header on.
inline std::vector<Record> topLevelRecords(const std::string& b) {
  std::vector<Record> out;
  for (std::size_t pos = 13; pos + 8 <= b.size();) {
    Record r;
    r.pos = pos;
    const std::uint32_t hl = getU32(b, pos);
    r.header_pos = pos + 4;
    for (std::size_t i = r.header_pos; i < r.header_pos + hl;) {
      const std::uint32_t fl = getU32(b, i);
      const std::string f = b.substr(i + 4, fl);
      const auto eq = f.find('=');
      r.fields[f.substr(0, eq)] = f.substr(eq + 1);
      r.field_value_pos[f.substr(0, eq)] = i + 4 + eq + 1;
      i += 4 + fl;
    }
    r.data_len = getU32(b, r.header_pos + hl);
    r.data_pos = r.header_pos + hl + 4;
    pos = r.end();
    out.push_back(r);
  }
  return out;
}

}  // namespace fgcal::logs::test
