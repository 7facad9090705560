// SHA-256 (FIPS 180-4), for tests that compare payloads with the digests a
// fixture's own list records (expected_images.csv), without a crypto library.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace fgcal::test {

/// Lower-case hex SHA-256 of `n` bytes at `data`.
std::string sha256Hex(const std::uint8_t* data, std::size_t n);
std::string sha256Hex(const std::string& bytes);
std::string sha256Hex(const std::vector<std::uint8_t>& bytes);

}  // namespace fgcal::test
