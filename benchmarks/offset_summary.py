#!/usr/bin/env python3
"""The offset cases of bench_accuracy (delay, joint-offset, base-offset),
seed by seed: how far each estimate is from the truth, how often it misses a
tolerance, whether its sigma is honest, and what estimating it costs the
cameras, with paired bootstrap 95 % intervals (30 seeds are few).

    python3 benchmarks/offset_summary.py RESULTS.csv [--time-tol-ms 0.3] [--joint-tol-mrad 1]

RESULTS.csv is bench_accuracy's per-seed file; its offsets file
(RESULTS_offsets.csv) is read beside it. Per estimated quantity that the
data observe: seeds, mean and largest absolute error, how many seeds miss
the tolerance (time offsets in ms, joint offsets in mrad), the mean reported
sigma, the RMS of error / sigma (1 when the sigma is honest) and its mean
(0 when the estimate is unbiased; a mean away from 0 is a bias that more
data do not average out, in units of the reported sigma). Per case
and camera: the mean error with the quantity estimated over the mean error
of the unperturbed calibration of the same seeds (translation, rotation).
Only the standard library; the bootstrap is seeded, so the output repeats.
"""
import csv
import math
import random
import statistics
import sys
from collections import defaultdict

ESTIMATED, UNPERTURBED = "fgcal F2, estimated", "fgcal F2, unperturbed"
RESAMPLES = 4000


def bootstrap(samples, statistic):
    """95 % percentile interval of statistic(resample) over the seeds."""
    rng = random.Random(12345)
    n = len(samples)
    values = sorted(statistic([samples[rng.randrange(n)] for _ in range(n)]) for _ in range(RESAMPLES))
    return values[int(0.025 * RESAMPLES)], values[int(0.975 * RESAMPLES) - 1]


def rms(v):
    return math.sqrt(sum(x * x for x in v) / len(v))


def quantities(path, time_tol, joint_tol):
    rows = defaultdict(list)  # (case, quantity) -> [(error, sigma)]
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            if r["observed"] != "1":
                continue
            err = float(r["estimate"]) - float(r["truth"])
            rows[(r["case"], r["quantity"])].append((err, float(r["sigma"])))
    print("| case | estimated | seeds | mean abs error | max abs error | beyond tolerance | mean sigma "
          "| RMS error/sigma (95 % interval) | mean error/sigma (95 % interval) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (case, q), v in sorted(rows.items()):
        time = q.startswith("time offset")
        unit, tol = ("ms", time_tol) if time else ("mrad", joint_tol)
        errs = [abs(e) for e, _ in v]
        ratios = [e / s for e, s in v]
        lo, hi = bootstrap(ratios, rms)
        mlo, mhi = bootstrap(ratios, statistics.fmean)
        print(f"| {case} | {q} | {len(v)} | {statistics.fmean(errs):.3f} {unit} | {max(errs):.3f} {unit} "
              f"| {sum(e > tol for e in errs)} of {len(v)} (> {tol:g} {unit}) "
              f"| {statistics.fmean(s for _, s in v):.3f} {unit} | {rms(ratios):.2f} ({lo:.2f}-{hi:.2f}) "
              f"| {statistics.fmean(ratios):+.2f} ({mlo:+.2f} to {mhi:+.2f}) |")


def cameras(path):
    err = defaultdict(dict)  # (case, camera, method) -> seed -> (mm, deg)
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            if r["ok"] == "1":
                err[(r["case"], r["camera"], r["method"])][r["seed"]] = (
                    float(r["translation_mm"]), float(r["rotation_deg"]))
    print()
    print("| case | camera | seeds | estimated / unperturbed mm (95 % interval) | deg (95 % interval) |")
    print("|---|---|---|---|---|")
    for case, camera in sorted({(c, cam) for c, cam, _ in err}):
        est, base = err.get((case, camera, ESTIMATED), {}), err.get((case, camera, UNPERTURBED), {})
        pairs = [(est[s], base[s]) for s in sorted(est) if s in base]
        if not pairs:
            continue
        cells = []
        for axis in (0, 1):
            def ratio(sample):
                return statistics.fmean(e[axis] for e, _ in sample) / statistics.fmean(b[axis] for _, b in sample)
            lo, hi = bootstrap(pairs, ratio)
            cells.append(f"{ratio(pairs):.2f} ({lo:.2f}-{hi:.2f})")
        print(f"| {case} | {camera} | {len(pairs)} | {cells[0]} | {cells[1]} |")


def main(argv):
    args = argv[1:]
    time_tol, joint_tol = 0.3, 1.0
    paths = []
    while args:
        a = args.pop(0)
        if a == "--time-tol-ms" and args:
            time_tol = float(args.pop(0))
        elif a == "--joint-tol-mrad" and args:
            joint_tol = float(args.pop(0))
        elif a.startswith("--"):
            sys.exit(f"offset_summary.py: unknown option {a} (see the docstring)")
        else:
            paths.append(a)
    if len(paths) != 1 or not paths[0].endswith(".csv"):
        sys.exit("usage: offset_summary.py RESULTS.csv [--time-tol-ms 0.3] [--joint-tol-mrad 1]")
    quantities(paths[0][:-4] + "_offsets.csv", time_tol, joint_tol)
    cameras(paths[0])


if __name__ == "__main__":
    main(sys.argv)
