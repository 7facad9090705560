// Helpers shared by the apps tests: scratch folders that clean up after
// themselves, file writing, and a check that a call throws InputError.
#pragma once

#include <atomic>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <catch2/catch.hpp>
#include <unistd.h>

#include "fgcal/apps/errors.hpp"
#include "fgcal_test/files.hpp"

namespace fgcal::apps::test {

namespace fs = std::filesystem;

/// A fresh folder under the system temp folder, removed on destruction.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    std::random_device rd;
    path_ = fs::temp_directory_path() /
            ("fgcal_apps_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + "_" +
             std::to_string(rd()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }
  std::string operator/(const std::string& sub) const { return (path_ / sub).string(); }

 private:
  fs::path path_;
};

inline void writeFile(const std::string& path, const std::string& text) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
  REQUIRE(out.good());
}

using ::fgcal::test::readFile;

/// `text` with the first occurrence of `from` replaced by `to` (which must exist).
inline std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  INFO("looking for: " << from);
  REQUIRE(pos != std::string::npos);
  return text.replace(pos, from.size(), to);
}

/// Runs f, which must throw InputError; returns it for further checks, after
/// checking the exit-code class.
template <class F>
InputError expectInputError(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    CHECK(exitCodeFor(e) == 2);
    return e;
  } catch (const std::exception& e) {
    FAIL("expected InputError, got another exception: " << e.what());
  }
  FAIL("expected InputError, nothing was thrown");
  throw std::logic_error("unreachable");
}

}  // namespace fgcal::apps::test

/// Checks an InputError names `file_part`, `loc_part` and contains each detail part.
#define CHECK_INPUT_ERROR(expr, file_part, loc_part, ...)                               \
  do {                                                                                   \
    const ::fgcal::apps::InputError err_ = ::fgcal::apps::test::expectInputError([&] { (void)(expr); }); \
    INFO("message: " << err_.what());                                                    \
    CHECK_THAT(err_.file(), Catch::Contains(file_part));                                 \
    CHECK_THAT(err_.location(), Catch::Contains(loc_part));                              \
    for (const std::string& part_ : std::initializer_list<std::string>{__VA_ARGS__})     \
      CHECK_THAT(std::string(err_.what()), Catch::Contains(part_));                      \
  } while (0)
