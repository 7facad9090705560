#!/usr/bin/env python3
"""BENCHMARKS.md's accuracy table from bench_accuracy's per-seed CSV.

    python3 benchmarks/accuracy_table.py benchmarks/results/accuracy_<date>_<commit>.csv

Per case and camera: the mean (sd) over the seeds of the translation error
(mm) and rotation error (deg) of fgcal F2 with PnP factors (the paper's
method), F2 with corner factors, their ratio (corners / pnp, translation and
rotation, on the seeds where both gave a result: a method that refuses a hard
seed must not gain from leaving it out; "(n=K)" when that is fewer than the
case's seeds), F1 with PnP factors, and the best OpenCV hand-eye solver of the row
with its ratio to PnP F2. In the intrinsics case the corner method that
estimates the intrinsics is shown in place of F1. Only the standard library.
"""
import csv
import statistics
import sys
from collections import defaultdict

PNP_F2, PNP_F1 = "fgcal F2", "fgcal F1"
CORNERS_F2, CORNERS_INTR = "fgcal corners F2", "fgcal corners F2, intrinsics estimated"


def mean_sd(v):
    if not v:
        return float("nan"), float("nan")
    return statistics.fmean(v), (statistics.stdev(v) if len(v) > 1 else float("nan"))


def cell(v, digits):
    m, s = mean_sd(v)
    return f"{m:.{digits}f} ({s:.{digits}f})"


def main(paths):
    # case -> method -> camera -> [translation list, rotation list]
    data = defaultdict(lambda: defaultdict(lambda: defaultdict(lambda: ([], []))))
    by_seed = defaultdict(dict)  # (case, method, camera) -> seed -> (translation, rotation)
    seeds = defaultdict(set)
    order = []
    for path in paths:
        with open(path, newline="") as f:
            for row in csv.DictReader(f):
                if row["ok"] != "1":
                    continue
                case = row["case"]
                if case not in order:
                    order.append(case)
                t, r = data[case][row["method"]][row["camera"]]
                t.append(float(row["translation_mm"]))
                r.append(float(row["rotation_deg"]))
                by_seed[case, row["method"], row["camera"]][row["seed"]] = (t[-1], r[-1])
                seeds[case].add(row["seed"])
    print("| case | camera | PnP F2 mm | deg | corners F2 mm | deg | corners / PnP | PnP F1 (or corners, "
          "intrinsics estimated) mm | deg | best OpenCV | mm | OpenCV / PnP F2 |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for case in order:
        methods = data[case]
        third = CORNERS_INTR if case == "intrinsics" and CORNERS_INTR in methods else PNP_F1
        for cam in methods[PNP_F2]:
            pt, pr = methods[PNP_F2][cam]
            ct, cr = methods[CORNERS_F2][cam] if CORNERS_F2 in methods else ([], [])
            ft, fr = methods[third][cam] if third in methods else ([], [])
            opencv = [(statistics.fmean(v[cam][0]), name) for name, v in methods.items()
                      if name.startswith("OpenCV") and v[cam][0]]
            best = min(opencv) if opencv else (float("nan"), "-")
            p_seeds, c_seeds = by_seed[case, PNP_F2, cam], by_seed[case, CORNERS_F2, cam]
            both = sorted(set(p_seeds) & set(c_seeds))
            ratio_t = ratio_r = float("nan")
            if both:
                ratio_t = (statistics.fmean(c_seeds[k][0] for k in both) /
                           statistics.fmean(p_seeds[k][0] for k in both))
                ratio_r = (statistics.fmean(c_seeds[k][1] for k in both) /
                           statistics.fmean(p_seeds[k][1] for k in both))
            paired = f" (n={len(both)})" if both and len(both) < len(seeds[case]) else ""
            name = case + (" (n=%d)" % len(seeds[case]))
            third_label = "" if third == PNP_F1 else "*"
            print(f"| {name} | {cam} | {cell(pt, 3)} | {cell(pr, 4)} | {cell(ct, 3)} | {cell(cr, 4)} | "
                  f"{ratio_t:.2f} / {ratio_r:.2f}{paired} | {cell(ft, 3)}{third_label} | {cell(fr, 4)} | {best[1][7:]} | "
                  f"{best[0]:.2f} | {best[0] / mean_sd(pt)[0]:.1f}x |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: accuracy_table.py ACCURACY.csv [MORE.csv ...]")
    main(sys.argv[1:])
