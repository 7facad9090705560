#!/usr/bin/env bash
# Calibrating from a ROS bag against calibrating from the same data as a
# dataset folder of PNGs: peak memory (max RSS) and wall time of
# `fgcal calibrate`, at two sizes (default 2,000 and 20,000 images).
#
#   benchmarks/run_bag_benchmark.sh [--sizes 2000,20000] [--resolution 640x480]
#       [--images mixed|raw|png] [--compression none|lz4|bz2] [--threads N]
#       [--repeat R] [--work DIR] [--build DIR] [--keep] [--reuse]
#
# For each size N it
#   1. simulates a dataset folder of N images (2 cameras: cam0 at 30 Hz, cam1 at
#      15 Hz, so N / 1.5 instants; every image rendered, at --resolution, one
#      sample per pixel) with build/benchmarks/apps/make_bench_dataset;
#   2. writes it as a ROS 1 bag with ROS's own Python writer (Debian's
#      python3-rosbag + python3-sensor-msgs; make_bag_from_dataset.py):
#      --images mixed (default) stores cam0 as sensor_msgs/Image mono8 and cam1
#      as CompressedImage holding the very PNG bytes of the folder; raw / png
#      store every camera one way;
#   3. runs `fgcal calibrate DATASET` and `fgcal calibrate BAG --rig RIG.yaml`
#      (--no-report) under /usr/bin/time -v, R times each, alternating;
#   4. prints a table (wall time, CPU time, peak RSS), the ratios the issue asks
#      about (peak at the large size / peak at the small size, per input; bag
#      wall time / folder wall time) and how far the bag's calibration is from
#      the folder's (they read the same images and joints, so they should agree).
#
# --keep leaves the folders and bags in --work; --reuse then skips steps 1-2
# for the sizes whose folder and bag are already there.
#
# Disk: about 150 KB per 640x480 image in the folder plus 300 KB (Image) or
# 150 KB (CompressedImage) in the bag; the 20,000-image pair takes ~6-9 GB
# under --work (default /tmp), deleted after each size unless --keep.
# Time on a 2-core machine: roughly 3 min simulation + 4 min conversion + 2 x
# 6 min calibration for 20,000 images at 640x480.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$ROOT/build
WORK=""
SIZES=2000,20000
RES=640x480
IMAGES=mixed
COMPRESSION=none
THREADS=0
REPEAT=1
KEEP=0
REUSE=0
while [ $# -gt 0 ]; do
  case "$1" in
    --sizes) SIZES=$2; shift 2 ;;
    --resolution) RES=$2; shift 2 ;;
    --images) IMAGES=$2; shift 2 ;;
    --compression) COMPRESSION=$2; shift 2 ;;
    --threads) THREADS=$2; shift 2 ;;
    --repeat) REPEAT=$2; shift 2 ;;
    --work) WORK=$2; shift 2 ;;
    --build) BUILD=$2; shift 2 ;;
    --keep) KEEP=1; shift ;;
    --reuse) REUSE=1; shift ;;
    -h|--help) awk 'NR > 1 && /^#/ {sub(/^# ?/, ""); print; next} NR > 1 {exit}' "$0"; exit 0 ;;
    *) echo "run_bag_benchmark.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
W=${RES%x*}; H=${RES#*x}
[ -z "$WORK" ] && WORK=$(mktemp -d /tmp/fgcal_bag_bench.XXXXXX)
mkdir -p "$WORK"
PY=/usr/bin/python3   # Debian's python: the pyenv python3 does not see the ROS packages

# ---- install step: ROS 1's Python bag writer, only for this benchmark ----------
if ! $PY -c 'import rosbag, genpy, yaml, sensor_msgs.msg, PIL' 2>/dev/null; then
  echo "installing python3-rosbag python3-sensor-msgs python3-yaml python3-pil (Debian) ..." >&2
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get install -y --no-install-recommends python3-rosbag python3-roslz4 python3-sensor-msgs python3-yaml python3-pil >&2
fi
[ -x /usr/bin/time ] || { echo "needs GNU time (/usr/bin/time; Debian package 'time')" >&2; exit 2; }

# ---- build ----------------------------------------------------------------------
if [ ! -f "$BUILD/CMakeCache.txt" ]; then
  cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release >&2
fi
nice cmake --build "$BUILD" -j2 --target fgcal make_bench_dataset >&2
FGCAL=$BUILD/apps/fgcal
MAKE_DS=$BUILD/benchmarks/apps/make_bench_dataset

# run LABEL N OUT -- command...: one timed calibration, appended to $WORK/runs.tsv.
# Besides /usr/bin/time's peak, VmRSS of the calibrate process is sampled
# every 0.2 s: its largest value while images are still being read and
# detected (before the progress line "detected N/N images") is the memory of
# the reading side alone; what comes after is the factor graph and the solve.
run() {
  local label=$1 n=$2 out=$3; shift 4
  local log=$WORK/time_${label}_${n}.log err=$WORK/stderr_${label}_${n}.log
  /usr/bin/time -v -o "$log" "$@" >"$WORK/stdout_${label}_${n}.log" 2>"$err" &
  local tpid=$! cpid="" detect_kb=0 kb
  while kill -0 "$tpid" 2>/dev/null; do
    [ -z "$cpid" ] && cpid=$(pgrep -P "$tpid" | head -1 || true)
    if [ -n "$cpid" ] && ! grep -q 'detected \([0-9]*\)/\1 images' "$err" 2>/dev/null; then
      kb=$(awk '/^VmRSS:/ {print $2}' "/proc/$cpid/status" 2>/dev/null || true)
      [ -n "$kb" ] && [ "$kb" -gt "$detect_kb" ] && detect_kb=$kb
    fi
    sleep 0.2
  done
  if ! wait "$tpid"; then
    echo "calibrate ($label, $n images) failed:" >&2
    tail -5 "$err" >&2
    return 1
  fi
  local wall rss user sys
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {n = split($2, p, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + p[i]; print s}' "$log")
  rss=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$log")
  user=$(awk -F': ' '/User time/ {print $2}' "$log")
  sys=$(awk -F': ' '/System time/ {print $2}' "$log")
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$label" "$n" "$wall" "$(awk -v u="$user" -v s="$sys" 'BEGIN {print u + s}')" \
    "$rss" "$out" "$detect_kb" >>"$WORK/runs.tsv"
  printf '  %-6s %6s images: %7.1f s wall, peak RSS %6.0f MB (%6.0f MB while reading and detecting)\n' "$label" "$n" \
    "$wall" "$(awk -v r="$rss" 'BEGIN {print r / 1024}')" "$(awk -v r="$detect_kb" 'BEGIN {print r / 1024}')" >&2
}

FAILED=0
: >"$WORK/runs.tsv"
: >"$WORK/sizes.tsv"
echo "work folder: $WORK" >&2
for N in ${SIZES//,/ }; do
  FRAMES=$(( (N * 2 + 2) / 3 ))   # cam0 instants: N / 1.5, rounded up
  DS=$WORK/ds_$N BAG=$WORK/bag_$N.bag
  echo "== $N images ($FRAMES instants, $RES)" >&2
  t0=$(date +%s)
  if [ "$REUSE" = 1 ] && [ -f "$DS/rig.yaml" ] && [ -f "$BAG" ] && [ -f "$WORK/bag_$N.rig.yaml" ]; then
    echo "  reusing $DS and $BAG" >&2
    t1=$t0 t2=$t0
  else
    "$MAKE_DS" --out "$DS" --frames "$FRAMES" --width "$W" --height "$H" --overwrite >&2
    t1=$(date +%s)
    $PY "$ROOT/benchmarks/apps/make_bag_from_dataset.py" "$DS" "$BAG" --images "$IMAGES" --compression "$COMPRESSION" >&2
    t2=$(date +%s)
  fi
  # "$DS/": a folder given as a symbolic link is followed
  images=$(find "$DS/" -mindepth 2 -name '*.png' | wc -l)
  printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$N" "$images" "$(du -sb "$DS/" | cut -f1)" "$(stat -c %s "$BAG")" \
    "$((t1 - t0))" "$((t2 - t1))" >>"$WORK/sizes.tsv"
  echo "  simulated in $((t1 - t0)) s, bag written in $((t2 - t1)) s" >&2
  for r in $(seq 1 "$REPEAT"); do
    run folder "$N" "$WORK/cal_folder_$N.yaml" -- "$FGCAL" calibrate "$DS" -o "$WORK/cal_folder_$N.yaml" \
      --no-report --threads "$THREADS" || FAILED=1
    run bag "$N" "$WORK/cal_bag_$N.yaml" -- "$FGCAL" calibrate "$BAG" --rig "$WORK/bag_$N.rig.yaml" \
      -o "$WORK/cal_bag_$N.yaml" --no-report --threads "$THREADS" || FAILED=1
  done
  if [ "$KEEP" = 0 ]; then rm -rf "$DS" "$BAG"; fi
done

# ---- table ----------------------------------------------------------------------
$PY - "$WORK" "$IMAGES" "$COMPRESSION" "$RES" <<'EOF'
import sys, os, yaml
work, images, compression, res = sys.argv[1:5]
runs = [l.rstrip("\n").split("\t") for l in open(os.path.join(work, "runs.tsv")) if l.strip()]
sizes = {l.split("\t")[0]: l.rstrip("\n").split("\t") for l in open(os.path.join(work, "sizes.tsv")) if l.strip()}
best = {}  # (label, n) -> (min wall, cpu at that run, max peak rss, max rss while detecting)
for label, n, wall, cpu, rss, out, det in runs:
    w, c, r, d = float(wall), float(cpu), int(rss), int(det)
    b = best.get((label, n))
    best[(label, n)] = (min(b[0], w) if b else w, c if not b or w < b[0] else b[1],
                        max(b[2], r) if b else r, max(b[3], d) if b else d)
ns = sorted({n for _, n in best}, key=int)
print("Bag: ROS 1 bag written by python3-rosbag (compression %s; images: %s), %s, `fgcal calibrate --no-report`."
      % (compression, images, res))
print()
print("| input | images | on disk MB | wall s (min of runs) | CPU s | peak RSS MB | RSS MB while reading + detecting |")
print("|---|---|---|---|---|---|---|")
for n in ns:
    s = sizes[n]
    for label in ("folder", "bag"):
        if (label, n) not in best:
            continue
        w, c, r, d = best[(label, n)]
        disk = int(s[2]) if label == "folder" else int(s[3])
        print("| %s | %s | %.0f | %.1f | %.1f | %.0f | %.0f |" % (label, s[1], disk / 1e6, w, c, r / 1024, d / 1024))
print()
if len(ns) >= 2:
    lo, hi = ns[0], ns[-1]
    for label in ("bag", "folder"):
        if (label, lo) in best and (label, hi) in best:
            print("peak RSS %s: %s images / %s images = %.2f; while reading + detecting: %.2f" % (
                label, hi, lo, best[(label, hi)][2] / best[(label, lo)][2], best[(label, hi)][3] / best[(label, lo)][3]))
for n in ns:
    if ("bag", n) in best and ("folder", n) in best:
        print("wall time bag / folder at %s images = %.2f" % (n, best[("bag", n)][0] / best[("folder", n)][0]))

def poses(path):
    with open(path) as f:
        d = yaml.safe_load(f)
    return {k: v["T_base_cam"] for k, v in d["cameras"].items()}
for n in ns:
    a, b = os.path.join(work, "cal_folder_%s.yaml" % n), os.path.join(work, "cal_bag_%s.yaml" % n)
    if os.path.exists(a) and os.path.exists(b):
        pa, pb = poses(a), poses(b)
        diff = max(abs(x - y) for c in pa for ra, rb in zip(pa[c], pb.get(c, pa[c])) for x, y in zip(ra, rb))
        print("largest |T_base_cam(bag) - T_base_cam(folder)| entry at %s images: %.3g" % (n, diff))
EOF
echo "raw logs: $WORK" >&2
exit $FAILED
