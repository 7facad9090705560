#!/usr/bin/env bash
# Ceres SPARSE_SCHUR against fgcal through its installed package, interleaved
# on one machine: per cell and round, bench_solver's Ceres SCHUR (the same
# seeded generator, graph and start) and bench_consumer built against each
# given fgcal build (run_consumer_benchmark.sh installs it and builds the
# consumer with its CXXFLAGS). Every board seen by default (SEE), one thread.
# bench_solver's own fgcal (the in-tree build, its grid's figure) is the side
# "in_tree". Prints per cell the best time of each side and Ceres SCHUR /
# fgcal, and
# writes every run to benchmarks/results/consumer_ceres_<date>.csv.
#
#   benchmarks/compare_consumer_ceres.sh CERES_BUILD LABEL=BUILD_DIR[:CXXFLAGS] ...
# CERES_BUILD: a build whose benchmarks/core/bench_solver has Ceres. E.g.
#   benchmarks/compare_consumer_ceres.sh build default=build-core native=build-native:-march=native
# Environment: CELLS (M:N,..., default 1:1000,1:10000), ROUNDS (default 5),
# REPEAT (solves per side and round, best kept; default 15, 3 from 10^4
# boards), SEE (default 1).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
[ $# -ge 2 ] || { echo "usage: $0 CERES_BUILD LABEL=BUILD_DIR[:CXXFLAGS] ..." >&2; exit 2; }
ceres_bench=$(cd "$1" && pwd)/benchmarks/core/bench_solver
[ -x "$ceres_bench" ] || { echo "$0: $ceres_bench: not built" >&2; exit 2; }
shift
cells=${CELLS:-1:1000,1:10000}
rounds=${ROUNDS:-5}
see=${SEE:-1}
export OMP_NUM_THREADS=1

labels=(in_tree) binaries=()
for spec in "$@"; do
  label=${spec%%=*} rest=${spec#*=}
  dir=${rest%%:*} flags=""
  [ "$rest" != "$dir" ] && flags=${rest#*:}
  CXXFLAGS=$flags "$root/benchmarks/run_consumer_benchmark.sh" "$dir" 1 100 "$see" >/dev/null
  labels+=("$label")
  binaries+=("$(cd "$dir" && pwd)/consumer-bench/build/bench_consumer")
done

out=$root/benchmarks/results/consumer_ceres_$(date -u +%Y-%m-%d).csv
mkdir -p "$(dirname "$out")"
echo "which,round,cell,seconds" >"$out"
echo "# $(nproc --all) cores, load $(cut -d' ' -f1-3 /proc/loadavg); sides: ceres_schur ${labels[*]}" >&2
for cell in ${cells//,/ }; do
  m=${cell%%:*} n=${cell#*:}
  repeat=${REPEAT:-15}
  [ -z "${REPEAT:-}" ] && [ "$n" -ge 10000 ] && repeat=3
  for round in $(seq 1 "$rounds"); do
    line=$("$ceres_bench" --sizes "$cell" --solvers fgcal,schur --see "$see" --repeat "$repeat" 2>/dev/null | tail -n 1)
    IFS=, read -ra f <<<"$line"  # fgcal_s and ceres_schur_s: the 4th and 18th columns of bench_solver's CSV
    echo "ceres_schur,$round,$cell,${f[17]}" >>"$out"
    echo "in_tree,$round,$cell,${f[3]}" >>"$out"
    for i in "${!binaries[@]}"; do
      best=$(for _ in $(seq 1 "$repeat"); do
        "${binaries[$i]}" "$m" "$n" "$see" | sed -n 's/.*, \([0-9.]*\) s, .*/\1/p'
      done | sort -g | head -n 1)
      echo "${labels[$((i + 1))]},$round,$cell,$best" >>"$out"
    done
  done
done
python3 - "$out" "${labels[@]}" <<'EOF'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
labels = sys.argv[2:]
print("| M:N | Ceres SCHUR s (min) | " + " | ".join(f"{l} s (min) | SCHUR / {l} (min) | (median of rounds)" for l in labels) + " |")
print("|---|---|" + "---|---|---|" * len(labels))
for cell in dict.fromkeys(r["cell"] for r in rows):
    t = {w: [float(r["seconds"]) for r in rows if r["cell"] == cell and r["which"] == w and r["seconds"]]
         for w in ["ceres_schur"] + labels}
    c = t["ceres_schur"]
    line = f"| {cell} | {min(c):.4g} |"
    for l in labels:
        ratios = [a / b for a, b in zip(c, t[l])]
        line += f" {min(t[l]):.4g} | {min(c) / min(t[l]):.2f} | {statistics.median(ratios):.2f} |"
    print(line)
print(f"raw: {sys.argv[1]}")
EOF
