#!/usr/bin/env python3
"""Log-log plots of the solver benchmark: wall time against the
number of board poses N, one panel per number of cameras M, fgcal against
Ceres SPARSE_NORMAL_CHOLESKY and SPARSE_SCHUR. Python 3 standard library only.

    benchmarks/plot_solver.py [CSV] [--out benchmarks/plots]

CSV defaults to the newest benchmarks/results/solver_*.csv (modification time,
then name). Writes <out>/solver_time_vs_N.svg (all panels) and
<out>/solver_time_vs_N_M<m>.svg (one per M), and prints what it wrote.
"""
import csv
import glob
import math
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SERIES = [  # column, label, colour, dash
    ("fgcal_s", "fgcal", "#d62728", ""),
    ("ceres_snc_s", "Ceres SNC", "#1f77b4", "6,3"),
    ("ceres_schur_s", "Ceres SCHUR", "#2ca02c", "2,3"),
]


def newest_csv():
    files = glob.glob(os.path.join(ROOT, "benchmarks", "results", "solver_*.csv"))
    if not files:
        sys.exit("no benchmarks/results/solver_*.csv: run benchmarks/run_solver_benchmark.sh first")
    return max(files, key=lambda f: (os.path.getmtime(f), f))


def num(s):
    try:
        v = float(s)
        return v if math.isfinite(v) and v > 0 else None
    except (TypeError, ValueError):
        return None


def load(path):
    data = {}  # M -> series column -> [(N, seconds)]
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            m, n = num(row.get("cameras")), num(row.get("frames"))
            if m is None or n is None:
                continue
            for col, _, _, _ in SERIES:
                t = num(row.get(col))
                if t is not None:
                    data.setdefault(int(m), {}).setdefault(col, []).append((n, t))
    for series in data.values():
        for pts in series.values():
            pts.sort()
    return data


def decades(lo, hi):
    return list(range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1))


def fmt_pow(e):
    return {0: "1", 1: "10"}.get(e, "10^%d" % e) if e >= 0 else "10^%d" % e


def panel(m, series, x0, y0, w, h, xr, yr):
    """SVG elements of one panel at (x0, y0) of size w x h; xr, yr: decade ranges."""
    out = []
    lx = lambda n: x0 + (math.log10(n) - xr[0]) / (xr[-1] - xr[0]) * w
    ly = lambda t: y0 + h - (math.log10(t) - yr[0]) / (yr[-1] - yr[0]) * h
    out.append('<rect x="%.1f" y="%.1f" width="%.1f" height="%.1f" fill="none" stroke="#333"/>' % (x0, y0, w, h))
    for e in xr:
        x = lx(10.0 ** e)
        out.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="#ddd"/>' % (x, y0, x, y0 + h))
        out.append('<text x="%.1f" y="%.1f" font-size="11" text-anchor="middle">%s</text>' % (x, y0 + h + 14, fmt_pow(e)))
    for e in yr:
        y = ly(10.0 ** e)
        out.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="#ddd"/>' % (x0, y, x0 + w, y))
        out.append('<text x="%.1f" y="%.1f" font-size="11" text-anchor="end">%s</text>' % (x0 - 4, y + 4, fmt_pow(e)))
    out.append('<text x="%.1f" y="%.1f" font-size="13" text-anchor="middle" font-weight="bold">M = %d camera%s</text>'
               % (x0 + w / 2, y0 - 6, m, "" if m == 1 else "s"))
    out.append('<text x="%.1f" y="%.1f" font-size="11" text-anchor="middle">N (board poses)</text>' % (x0 + w / 2, y0 + h + 30))
    for col, label, colour, dash in SERIES:
        pts = series.get(col, [])
        if not pts:
            continue
        d = " ".join("%s%.1f,%.1f" % ("M" if i == 0 else "L", lx(n), ly(t)) for i, (n, t) in enumerate(pts))
        out.append('<path d="%s" fill="none" stroke="%s" stroke-width="2"%s/>'
                   % (d, colour, ' stroke-dasharray="%s"' % dash if dash else ""))
        for n, t in pts:
            out.append('<circle cx="%.1f" cy="%.1f" r="3" fill="%s"><title>%s M=%d N=%d: %.4g s</title></circle>'
                       % (lx(n), ly(t), colour, label, m, n, t))
    return out


def svg(panels, data, title, xr, yr):
    pw, ph, ml, mt, gap = 260, 220, 60, 60, 40
    cols = min(len(panels), 3)
    rows = (len(panels) + cols - 1) // cols
    width, height = max(ml + cols * (pw + gap), 620), mt + rows * (ph + 60) + 30
    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" font-family="sans-serif">' % (width, height),
           '<rect width="100%" height="100%" fill="white"/>',
           '<text x="%d" y="20" font-size="14">%s</text>' % (ml, title)]
    # legend
    x = ml
    for _, label, colour, dash in SERIES:
        out.append('<line x1="%d" y1="36" x2="%d" y2="36" stroke="%s" stroke-width="2"%s/>'
                   % (x, x + 30, colour, ' stroke-dasharray="%s"' % dash if dash else ""))
        out.append('<text x="%d" y="40" font-size="12">%s</text>' % (x + 35, label))
        x += 130
    out.append('<text x="%d" y="40" font-size="12">wall time, s (log-log)</text>' % x)
    for i, m in enumerate(panels):
        r, c = divmod(i, cols)
        out += panel(m, data[m], ml + c * (pw + gap), mt + 10 + r * (ph + 60), pw, ph, xr, yr)
    out.append("</svg>")
    return "\n".join(out) + "\n"


def main(argv):
    out_dir = os.path.join(ROOT, "benchmarks", "plots")
    args = list(argv)
    if "--out" in args:
        i = args.index("--out")
        out_dir = args[i + 1]
        del args[i:i + 2]
    path = args[0] if args else newest_csv()
    data = load(path)
    if not data:
        sys.exit("%s: no rows with cameras, frames and times" % path)
    ns = [n for s in data.values() for pts in s.values() for n, _ in pts]
    ts = [t for s in data.values() for pts in s.values() for _, t in pts]
    xr, yr = decades(min(ns), max(ns)), decades(min(ts), max(ts))
    os.makedirs(out_dir, exist_ok=True)
    source = os.path.relpath(path, ROOT)
    written = []
    name = os.path.join(out_dir, "solver_time_vs_N.svg")
    with open(name, "w") as f:
        f.write(svg(sorted(data), data, "Solver time against N per M (source: %s)" % source, xr, yr))
    written.append(name)
    for m in sorted(data):
        name = os.path.join(out_dir, "solver_time_vs_N_M%d.svg" % m)
        with open(name, "w") as f:
            f.write(svg([m], data, "M = %d (source: %s)" % (m, source), xr, yr))
        written.append(name)
    for w in written:
        print(os.path.relpath(w, ROOT))
    print("from", source)


if __name__ == "__main__":
    main(sys.argv[1:])
