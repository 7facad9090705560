#include "fgcal_test/shared_data.hpp"

#include <filesystem>

namespace fgcal::test {

std::optional<std::string> sharedData(const std::string& sub) {
  std::filesystem::path p(FGCAL_SHARED_DATA_DIR);
  if (!sub.empty()) p /= sub;
  std::error_code ec;
  if (!std::filesystem::exists(p, ec)) return std::nullopt;
  return p.string();
}

}  // namespace fgcal::test
