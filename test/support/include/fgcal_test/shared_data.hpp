// Where the shared real test data lives (../shared/data, a CMake cache
// variable FGCAL_SHARED_DATA_DIR). Tests that need it call
// FGCAL_REQUIRE_SHARED_DATA(sub), which skips the test case with a clear
// message when the folder is absent.
#pragma once

#include <optional>
#include <string>

#include <catch2/catch.hpp>

namespace fgcal::test {

/// The shared data folder joined with `sub`, or nullopt when it does not exist.
std::optional<std::string> sharedData(const std::string& sub = "");

}  // namespace fgcal::test

#define FGCAL_REQUIRE_SHARED_DATA(var, sub)                                                     \
  const auto var##_opt_ = ::fgcal::test::sharedData(sub);                                       \
  if (!var##_opt_) {                                                                            \
    WARN("SKIPPED: shared data folder '" << FGCAL_SHARED_DATA_DIR << "/" << (sub)               \
                                         << "' is absent (set -DFGCAL_SHARED_DATA_DIR=...)");   \
    return;                                                                                     \
  }                                                                                             \
  const std::string var = *var##_opt_
