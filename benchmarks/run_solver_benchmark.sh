#!/usr/bin/env bash
# The solver benchmark: builds bench_solver (fgcal LM vs Ceres
# SPARSE_NORMAL_CHOLESKY / SPARSE_SCHUR) in build-bench and runs the full grid
# M in {1,2,4,8,16} x N in {1e2..1e5} plus M=2, N=1e6. CSV on stdout and in
# benchmarks/results/solver_<UTC date>.csv, the human summary in .log beside it.
# Extra arguments go to bench_solver (e.g. --sizes medium, --solvers fgcal).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${FGCAL_BENCH_BUILD:-$root/build-bench}
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFGCAL_BUILD_VISION=OFF \
  -DFGCAL_BUILD_KINEMATICS=OFF -DFGCAL_BUILD_APPS=OFF -DFGCAL_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" -j2 --target bench_solver >/dev/null
# Debian's CHOLMOD is built with OpenMP and Ceres shares it: one thread keeps
# both solvers single-threaded (Ceres also gets num_threads=1).
export OMP_NUM_THREADS=1
out="$root/benchmarks/results/solver_$(date -u +%Y-%m-%d)"
mkdir -p "$(dirname "$out")"
{
  echo "# fgcal $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo '?')," \
       "$(git -C "$root" status --porcelain core factors 2>/dev/null | wc -l) file(s) of core/ and factors/ modified;" \
       "$(nproc --all) cores, load $(cut -d' ' -f1-3 /proc/loadavg), $(date -u +%FT%TZ)"
} | tee "$out.log" >&2
# Best of 3, of 15 for sizes under 15,000 factors (N <= 10^3), whose solves
# of a few milliseconds one interrupt or page-fault burst can decide, and of 2
# above 500,000 factors: on a VM with free page reporting the first run after
# a pause pays the host's first touch of its pages (seconds at 3 GB), the run
# right after it does not (BENCHMARKS.md).
"$build/benchmarks/core/bench_solver" --sizes all --repeat 3 --repeat-small 15 --repeat-large 2 --timeout 300 "$@" 2> >(tee -a "$out.log" >&2) | tee "$out.csv"
