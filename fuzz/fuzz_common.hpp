// Shared by the fuzz targets (libFuzzer entry points, see fuzz/README.md):
// what counts as a finding. Our documented errors (InputError, the kinematics
// and vision errors) are answers, not findings; any other exception escaping a
// reader is a bug (it would reach the user as an unexplained exit 1), and so
// is a crash, a sanitizer report, a leak or a hang.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <typeinfo>

namespace fgcal::fuzz {

[[noreturn]] inline void unexpected(const std::exception& e) {
  std::fprintf(stderr, "fuzz target: unexpected exception %s: %s\n", typeid(e).name(), e.what());
  std::abort();
}

}  // namespace fgcal::fuzz
