#!/usr/bin/env bash
# Before/after timing of the solver for a change to core/: builds bench_solver
# at two commits (git worktrees under build-compare/) and runs them
# interleaved, cell by cell (before, after, before, after, ...), fgcal only.
# On a VM whose speed drifts by 10-30 % over minutes, two full grids run one
# after the other differ by more than the change does; alternating runs of the
# same cell see the same machine. Prints, per cell, the best (min) time of
# each side and their ratio, and writes every run to
# benchmarks/results/solver_compare_<date>_<before>_<after>.csv.
#
#   benchmarks/compare_solver.sh BEFORE_COMMIT [AFTER_COMMIT (default: the work tree)]
# Environment: ROUNDS (alternations per cell, default 4), CELLS (M:N,...,
# default the grid's 20 cells up to N = 10^5), EXTRA (more bench_solver
# options, e.g. "--see 1" for every camera seeing every board), EXTRA_AFTER
# (options for the after side only: with the same commit on both sides,
# "--fgcal-solver streamed" compares two linear solvers of one commit).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
[ $# -ge 1 ] || { echo "usage: $0 BEFORE_COMMIT [AFTER_COMMIT]" >&2; exit 2; }
rounds=${ROUNDS:-4}
cells=${CELLS:-1:100,2:100,4:100,8:100,16:100,1:1000,2:1000,4:1000,8:1000,16:1000,1:10000,2:10000,4:10000,8:10000,16:10000,1:100000,2:100000,4:100000,8:100000,16:100000}
extra=${EXTRA:-}
extra_after=${EXTRA_AFTER:-}
work=$root/build-compare

build_at() {  # build_at COMMIT|"" DIR: bench_solver of COMMIT (the work tree when empty) built in DIR
  local commit=$1 dir=$2 src=$root
  if [ -n "$commit" ]; then
    src=$work/src-$commit
    [ -d "$src" ] || git -C "$root" worktree add --detach -f "$src" "$commit" >/dev/null
  fi
  cmake -S "$src" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFGCAL_BUILD_VISION=OFF \
    -DFGCAL_BUILD_KINEMATICS=OFF -DFGCAL_BUILD_APPS=OFF -DFGCAL_BUILD_TESTS=OFF >/dev/null
  cmake --build "$dir" -j2 --target bench_solver >/dev/null
}
before=$(git -C "$root" rev-parse --short "$1")
after=${2:+$(git -C "$root" rev-parse --short "$2")}
build_at "$before" "$work/build-$before"
build_at "$after" "$work/build-${after:-worktree}"
bin_before=$work/build-$before/benchmarks/core/bench_solver
bin_after=$work/build-${after:-worktree}/benchmarks/core/bench_solver

export OMP_NUM_THREADS=1  # CHOLMOD single-threaded, as in the grid
tag=${extra_after:+_$(echo "$extra_after" | tr -c 'A-Za-z0-9.\n-' '_' | sed 's/^[-_]*//; s/_*$//')}
out=$root/benchmarks/results/solver_compare_$(date -u +%Y-%m-%d)_${before}_${after:-worktree}${tag}.csv
mkdir -p "$(dirname "$out")"
echo "which,round,cell,fgcal_s,linearize_s,solve_s,other_s,max_rss_kb" >"$out"
echo "# before $before, after ${after:-work tree} $extra_after; $(nproc --all) cores, load $(cut -d' ' -f1-3 /proc/loadavg); $extra" >&2
rss_file=$(mktemp)
trap 'rm -f "$rss_file"' EXIT
for cell in ${cells//,/ }; do
  n=${cell#*:}
  repeat=3  # best of 3 inside each run; 15 for cells of a few milliseconds, 2 above 10^6 boards
  [ "$n" -le 1000 ] && repeat=15
  [ "$n" -ge 1000000 ] && repeat=2
  for round in $(seq 1 "$rounds"); do
    for side in before after; do
      bin=$bin_before side_extra=""
      [ $side = after ] && bin=$bin_after side_extra=$extra_after
      # The run's peak RSS (the problem and its solves) from /usr/bin/time.
      # shellcheck disable=SC2086
      line=$(/usr/bin/time -f %M -o "$rss_file" "$bin" --sizes "$cell" --repeat "$repeat" --solvers fgcal $extra \
        $side_extra 2>/dev/null | tail -n 1)
      IFS=, read -ra f <<<"$line"  # the CSV columns of bench_solver: fgcal_s 4th, linearize 7th, solve 9th, other 10th
      echo "$side,$round,$cell,${f[3]},${f[6]},${f[8]},${f[9]},$(tail -n 1 "$rss_file")" >>"$out"
    done
  done
done
python3 - "$out" <<'EOF'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print("| M:N | before s (min) | after s (min) | after/before (min) | after/before (median) | peak RSS MB before / after |")
print("|---|---|---|---|---|---|")
for cell in dict.fromkeys(r["cell"] for r in rows):
    t = {s: [float(r["fgcal_s"]) for r in rows if r["cell"] == cell and r["which"] == s and r["fgcal_s"]]
         for s in ("before", "after")}
    if t["before"] and t["after"]:
        m = {s: max(int(r["max_rss_kb"]) for r in rows if r["cell"] == cell and r["which"] == s) / 1024
             for s in ("before", "after")}
        print(f"| {cell} | {min(t['before']):.4g} | {min(t['after']):.4g} | {min(t['after']) / min(t['before']):.3f} "
              f"| {statistics.median(t['after']) / statistics.median(t['before']):.3f} | {m['before']:.0f} / {m['after']:.0f} |")
EOF
echo "runs: ${out#"$root"/}" >&2
