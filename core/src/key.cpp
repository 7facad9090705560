#include "fgcal/core/key.hpp"

namespace fgcal {

std::string keyToString(Key k) {
  const char s = keySymbol(k);
  if (s >= 33 && s <= 126) return std::string(1, s) + std::to_string(keyIndex(k));
  return std::to_string(k);
}

}  // namespace fgcal
