#!/usr/bin/env bash
# Fuzzes fgcal's input readers with libFuzzer:
#   bash scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]
# Installs clang and libclang-rt-14-dev when missing (Debian 12, as root),
# builds every target of fuzz/ with -fsanitize=fuzzer,address,undefined in
# build-fuzz/, then runs each for SECONDS_PER_TARGET (default 60) seconds,
# niced, starting from the committed seed corpus fuzz/corpus/<target>/ and a
# working corpus in build-fuzz/corpus/<target>/ that grows between runs.
# A crash, sanitizer report, leak or timeout stops that target; its input is
# written to build-fuzz/findings/<target>/. Fix the bug, then copy the input to
# fuzz/regressions/<target>/ so the regression test (ctest
# fuzz_regression:<target>, normal build) keeps it fixed.
# Exit status: 0 when no target found anything, 1 otherwise.
set -euo pipefail
seconds="${1:-60}"
shift || true
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${FGCAL_FUZZ_BUILD_DIR:-$here/build-fuzz}"
jobs="$(nproc 2>/dev/null || echo 2)"

# shellcheck source=lib/install_missing.sh
. "$here/scripts/lib/install_missing.sh"
install_missing "${FGCAL_PACKAGES[@]}" clang libclang-rt-14-dev

echo "== configuring and building the fuzz targets in $build"
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" \
      -DCMAKE_CXX_COMPILER=clang++ \
      -DFGCAL_BUILD_FUZZERS=ON -DFGCAL_BUILD_TESTS=OFF -DFGCAL_BUILD_BENCHMARKS=OFF -DFGCAL_BUILD_APPS=OFF >/dev/null
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=()
  for f in "$here"/fuzz/fuzz_*.cpp; do targets+=("$(basename "$f" .cpp)"); done
fi
nice -n 10 cmake --build "$build" -j "$jobs" --target "${targets[@]}"

export ASAN_OPTIONS="${ASAN_OPTIONS:-halt_on_error=1:detect_leaks=1:allocator_may_return_null=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}"
status=0
for t in "${targets[@]}"; do
  work="$build/corpus/$t"
  findings="$build/findings/$t"
  mkdir -p "$work" "$findings"
  dict=()
  [ -f "$here/fuzz/$t.dict" ] && dict=(-dict="$here/fuzz/$t.dict")
  echo "== $t: ${seconds} s"
  if ! nice -n 10 "$build/fuzz/$t" "$work" "$here/fuzz/corpus/$t" "${dict[@]}" \
        -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
        -artifact_prefix="$findings/" -print_final_stats=1 2>"$build/$t.log"; then
    echo "!! $t found a problem; input(s) in $findings, log in $build/$t.log" >&2
    tail -n 40 "$build/$t.log" >&2
    status=1
  else
    grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb" "$build/$t.log" | tr '\n' ' '
    echo
  fi
done
exit $status
