#!/usr/bin/env bash
# fgcal's solver through its installed package, as a project embedding it
# sees it: installs BUILD_DIR (a built fgcal tree) into BUILD_DIR/consumer-bench/prefix,
# configures benchmarks/consumer against it with find_package(fgcal) and the
# consumer's own CXXFLAGS, builds bench_consumer and runs it on the generator's
# M:N graph (every board seen by default).
#
#   [CXXFLAGS=-march=native] [CALLGRIND=1] benchmarks/run_consumer_benchmark.sh BUILD_DIR [M [N [SEE]]]
# CALLGRIND=1 runs it under valgrind --tool=callgrind, collecting fgcal::optimize
# only, and prints the instruction count (Ir) of the solve: a figure that does
# not depend on the machine's load. GENERATOR_OPTIONS: extra compile options
# of the generator's translation unit (benchmarks/consumer/CMakeLists.txt).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
[ $# -ge 1 ] || { echo "usage: $0 BUILD_DIR [M [N [SEE]]]" >&2; exit 2; }
build=$(cd "$1" && pwd)
work=$build/consumer-bench
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$root/benchmarks/consumer" -B "$work/build" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$work/prefix" "-DCMAKE_CXX_FLAGS=${CXXFLAGS:-}" \
  "-DFGCAL_BENCH_GENERATOR_OPTIONS=${GENERATOR_OPTIONS:-}" >/dev/null
cmake --build "$work/build" >/dev/null
args=("${2:-1}" "${3:-1000}" "${4:-1}")
if [ "${CALLGRIND:-0}" = 1 ]; then
  out=$work/callgrind.out
  OMP_NUM_THREADS=1 valgrind --tool=callgrind "--toggle-collect=fgcal::optimize(*" \
    --callgrind-out-file="$out" "$work/build/bench_consumer" "${args[@]}" 2>/dev/null
  callgrind_annotate "$out" | grep "PROGRAM TOTALS"
else
  OMP_NUM_THREADS=1 "$work/build/bench_consumer" "${args[@]}"
fi
