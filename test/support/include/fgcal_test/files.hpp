// Reading a whole file in a test, in one place.
#pragma once

#include <filesystem>
#include <string>

namespace fgcal::test {

/// Every byte of the file at `path`, unchanged (binary mode, no newline
/// translation); "" when it cannot be opened, so that a test may check that an
/// output was not written.
std::string readFile(const std::filesystem::path& path);

}  // namespace fgcal::test
