#!/usr/bin/env bash
# Regenerates every figure of BENCHMARKS.md: builds the benchmark
# programs in Release and runs them, each writing dated results stamped with
# the machine and the commit into benchmarks/results/, then redraws the solver
# plots in benchmarks/plots/.
#
#   scripts/benchmarks.sh                 # everything (hours on 2 cores)
#   scripts/benchmarks.sh accuracy plots  # selected parts
#
# Parts: solver kinematics vision consistency accuracy end_to_end long_run plots.
# Environment: SEEDS (accuracy, default 30), CONSISTENCY_SEEDS (default 50),
# FGCAL_BENCH_ALL_BUILD (build folder, default build-bench-all; the solver
# grid keeps its own build folder, see benchmarks/run_solver_benchmark.sh),
# NICE (default 10).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${FGCAL_BENCH_ALL_BUILD:-$root/build-bench-all}
seeds=${SEEDS:-30}
consistency_seeds=${CONSISTENCY_SEEDS:-50}
nice_level=${NICE:-10}
parts=("$@")
[ ${#parts[@]} -eq 0 ] && parts=(solver kinematics vision consistency accuracy end_to_end long_run plots)
want() { local p; for p in "${parts[@]}"; do [ "$p" = "$1" ] && return 0; done; return 1; }

results=$root/benchmarks/results
mkdir -p "$results"
date_utc=$(date -u +%Y-%m-%d)
commit=$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)
[ -n "$(git -C "$root" status --porcelain --untracked-files=no 2>/dev/null)" ] && commit="$commit+dirty"
cpu=$(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | cut -d: -f2- | sed 's/^ *//' || true)
mem_gb=$(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo 2>/dev/null || echo '?')
header() {
  echo "# $1"
  echo "# machine: $(uname -n), ${cpu:-unknown CPU}, $(nproc) cores, ${mem_gb} GiB; $(uname -sr)"
  echo "# date: $(date -u +%FT%TZ); commit: $commit; load at start: $(cut -d' ' -f1-3 /proc/loadavg)"
}
failed=()
run() {  # run NAME COMMAND...: output in benchmarks/results/NAME_<date>_<commit>.txt
  # A part that fails its own check (e.g. NEES out of band) is recorded and the
  # others still run; the script exits non-zero at the end.
  local name=$1
  shift
  local out="$results/${name}_${date_utc}_${commit}.txt"
  echo "== $name -> ${out#$root/}" >&2
  { header "$name: $*"; nice -n "$nice_level" "$@"; } 2>&1 | tee "$out" || failed+=("$name")
}

# What the benchmarks need beyond the quick start: Google Benchmark for the
# kinematics part, Ceres for the solver comparison (it repoints BLAS to ATLAS,
# see docs/toolchain.md, gotcha 5).
# shellcheck source=lib/install_missing.sh
. "$root/scripts/lib/install_missing.sh"
install_missing "${FGCAL_PACKAGES[@]}" libbenchmark-dev libceres-dev

targets=()
want kinematics && targets+=(bench_kinematics)
want vision && targets+=(bench_vision)
want consistency && targets+=(bench_consistency)
want accuracy && targets+=(bench_accuracy)
want end_to_end && targets+=(bench_end_to_end)
want long_run && targets+=(bench_long_run)
if [ ${#targets[@]} -gt 0 ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFGCAL_BUILD_APPS=ON \
    -DFGCAL_BUILD_KINEMATICS=ON -DFGCAL_BUILD_VISION=ON -DFGCAL_BUILD_BENCHMARKS=ON -DFGCAL_BUILD_TESTS=OFF >/dev/null
  cmake --build "$build" -j2 --target "${targets[@]}" >/dev/null
fi

if want solver; then
  # Full grid, fgcal against Ceres; writes benchmarks/results/solver_<date>.csv and .log itself.
  nice -n "$nice_level" "$root/benchmarks/run_solver_benchmark.sh" >/dev/null
fi
want kinematics && run kinematics "$build/benchmarks/kinematics/bench_kinematics" --benchmark_min_time=0.5 \
  --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
want vision && run vision "$build/benchmarks/vision/bench_vision" 4
want consistency && run consistency "$build/benchmarks/apps/bench_consistency" --seeds "$consistency_seeds" --frames 150
# bench_accuracy writes accuracy_<date>_<commit>.csv/.md itself; the .txt keeps its log.
want accuracy && run accuracy_log "$build/benchmarks/apps/bench_accuracy" --seeds "$seeds" --threads 2 \
  --out "$results"
want end_to_end && run end_to_end "$build/benchmarks/apps/bench_end_to_end" --frames 1312 \
  --resolutions 640x480,1280x720 --threads 1,2 --memory-frames 2624
want long_run && run long_run "$build/benchmarks/apps/bench_long_run"
want plots && python3 "$root/benchmarks/plot_solver.py" --out "$root/benchmarks/plots"
echo "done: results in ${results#$root/}/, plots in benchmarks/plots/" >&2
if [ ${#failed[@]} -gt 0 ]; then
  echo "parts that failed their own check: ${failed[*]}" >&2
  exit 1
fi
