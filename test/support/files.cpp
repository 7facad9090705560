#include "fgcal_test/files.hpp"

#include <fstream>
#include <iterator>

namespace fgcal::test {

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace fgcal::test
