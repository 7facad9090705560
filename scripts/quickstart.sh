#!/usr/bin/env bash
# fgcal quick start: installs what is missing (Debian 12, as root), builds in
# Release, then runs either the demo or every test.
#   bash scripts/quickstart.sh demo    # build, then run the main job on the built-in default
#   bash scripts/quickstart.sh test    # build, then run every test through ctest
set -euo pipefail
mode="${1:-demo}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${FGCAL_BUILD_DIR:-$here/build}"
jobs="$(nproc 2>/dev/null || echo 2)"

case "$mode" in
  demo|test) ;;
  *) echo "usage: $0 demo|test" >&2; exit 2 ;;
esac

# shellcheck source=lib/install_missing.sh
. "$here/scripts/lib/install_missing.sh"
packages=("${FGCAL_PACKAGES[@]}")
if [ "$mode" = test ]; then packages+=(chromium); fi  # renders the calibration report in a test
install_missing "${packages[@]}"

echo "== configuring and building in $build"
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
if [ "$mode" = demo ]; then
  cmake --build "$build" -j "$jobs" --target fgcal  # the demo needs the command only
else
  cmake --build "$build" -j "$jobs"
fi

case "$mode" in
  demo)
    exec "$build/apps/fgcal" demo
    ;;
  test)
    FGCAL_REQUIRE_CHROMIUM=1 ctest --test-dir "$build" --output-on-failure -j "$jobs"
    # Then the whole suite again with AddressSanitizer and UndefinedBehaviorSanitizer
    # in a second build folder; any report (leaks included) fails it.
    asan="${FGCAL_ASAN_BUILD_DIR:-$here/build-asan}"
    export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:print_stacktrace=1:strict_string_checks=1"
    export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:report_error_type=1"
    export LSAN_OPTIONS="suppressions=$here/test/sanitizers/lsan.supp:print_suppressions=0"
    echo "== sanitizers: configuring and building in $asan (address,undefined)"
    t0=$(date +%s)
    cmake -S "$here" -B "$asan" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
          -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
          -DFGCAL_SANITIZE=address,undefined -DFGCAL_BUILD_BENCHMARKS=OFF >/dev/null
    cmake --build "$asan" -j "$jobs"
    t1=$(date +%s)
    ctest --test-dir "$asan" --output-on-failure -j "$jobs"
    echo "== sanitizers: build $((t1 - t0)) s, tests $(($(date +%s) - t1)) s, no report"
    ;;
esac
