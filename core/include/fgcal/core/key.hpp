// Keys name variables: a character and an index packed in 64 bits, e.g.
// key('c', 0) for camera 0, key('b', 1234) for board pose 1234.
#pragma once

#include <cstdint>
#include <string>

namespace fgcal {

using Key = std::uint64_t;

constexpr Key key(char symbol, std::uint64_t index) {
  return (static_cast<Key>(static_cast<unsigned char>(symbol)) << 56) | (index & 0x00FFFFFFFFFFFFFFull);
}
constexpr char keySymbol(Key k) { return static_cast<char>(k >> 56); }
constexpr std::uint64_t keyIndex(Key k) { return k & 0x00FFFFFFFFFFFFFFull; }

/// "c0", "b1234"; a key without a printable symbol prints as its number.
std::string keyToString(Key k);

}  // namespace fgcal
