// Helpers of test_logs_ros1: a SHA-256 (FIPS 180-4) to compare image payloads
// with expected_images.csv without adding a crypto dependency, scratch
// folders, file bytes, and an independent walk over a bag's top-level records
// so that tests can damage a bag at a known place (a chunk header, index_pos).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

namespace fgcal::logs::test {

namespace fs = std::filesystem;

/// Lower-case hex SHA-256 of `n` bytes.
inline std::string sha256Hex(const std::uint8_t* data, std::size_t n) {
  static constexpr std::uint32_t k[64] = {
      0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
      0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
      0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
      0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
      0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
      0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
      0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
      0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};
  std::array<std::uint32_t, 8> h = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                    0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
  auto rotr = [](std::uint32_t x, int r) { return (x >> r) | (x << (32 - r)); };
  auto block = [&](const std::uint8_t* p) {
    std::uint32_t w[64];
    for (int i = 0; i < 16; ++i)
      w[i] = std::uint32_t{p[4 * i]} << 24 | std::uint32_t{p[4 * i + 1]} << 16 | std::uint32_t{p[4 * i + 2]} << 8 |
             p[4 * i + 3];
    for (int i = 16; i < 64; ++i) {
      const std::uint32_t s0 = rotr(w[i - 15], 7) ^ rotr(w[i - 15], 18) ^ (w[i - 15] >> 3);
      const std::uint32_t s1 = rotr(w[i - 2], 17) ^ rotr(w[i - 2], 19) ^ (w[i - 2] >> 10);
      w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    std::uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], hh = h[7];
    for (int i = 0; i < 64; ++i) {
      const std::uint32_t t1 = hh + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + k[i] + w[i];
      const std::uint32_t t2 = (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
      hh = g, g = f, f = e, e = d + t1, d = c, c = b, b = a, a = t1 + t2;
    }
    h[0] += a, h[1] += b, h[2] += c, h[3] += d, h[4] += e, h[5] += f, h[6] += g, h[7] += hh;
  };
  std::size_t i = 0;
  for (; n - i >= 64; i += 64) block(data + i);
  std::uint8_t tail[128] = {};
  const std::size_t rest = n - i;
  for (std::size_t j = 0; j < rest; ++j) tail[j] = data[i + j];
  tail[rest] = 0x80;
  const std::size_t len = rest < 56 ? 64 : 128;
  const std::uint64_t bits = static_cast<std::uint64_t>(n) * 8;
  for (int j = 0; j < 8; ++j) tail[len - 1 - j] = static_cast<std::uint8_t>(bits >> (8 * j));
  block(tail);
  if (len == 128) block(tail + 64);
  std::string hex;
  char buf[9];
  for (const std::uint32_t v : h) {
    std::snprintf(buf, sizeof buf, "%08x", v);
    hex += buf;
  }
  return hex;
}

inline std::string sha256Hex(const std::string& s) {
  return sha256Hex(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
}

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

inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

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
