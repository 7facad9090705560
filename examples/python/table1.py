#!/usr/bin/env python3
"""Table I of Reinke et al. from Python: how well each camera is found alone (F1)
and jointly (F2).

Simulates the demo's robot (fgcal's HyQ-like quadruped, a stereo-head camera and
an RGB-D camera, a CAD board mount off by 3 mm / 1 deg) once per seed, calibrates
each dataset with every camera alone (F1) and with both cameras jointly (F2),
and prints the mean absolute error and its standard deviation over the seeds
per axis, per camera, in the layout of the paper's Table I (here in mm and
degrees: the simulated errors are sub-centimetre). With matplotlib it also
plots the errors to a file.

    PYTHONPATH=build/python python3 examples/python/table1.py [--seeds 3] [--frames 150] [--method pnp|corners]
                                                             [--plot FILE.png]
"""
import argparse
import os
import sys
import tempfile

import numpy as np

import fgcal

AXES = ["X", "Y", "Z", "Roll", "Pitch", "Yaw"]
UNITS = ["mm", "mm", "mm", "deg", "deg", "deg"]


def errors_of(evaluation, camera):
    e = evaluation.cameras[camera]
    return [e.x_mm, e.y_mm, e.z_mm, e.roll_deg, e.pitch_deg, e.yaw_deg]


def run(seeds, frames, supersampling, work, threads, method):
    """errors[solve][camera] = one row of |error| per seed, solve F1 or F2."""
    errors = {"F1": {}, "F2": {}}
    for seed in seeds:
        dataset = os.path.join(work, f"seed{seed}")
        summary = fgcal.simulate(dataset, frames=frames, seed=seed, mount_error=(3.0, 1.0),
                                 supersampling=supersampling, overwrite=True)
        truth = os.path.join(dataset, "ground_truth.yaml")
        print(f"seed {seed}: {summary.images_written} images of {', '.join(summary.cameras)}", file=sys.stderr)
        for solve, single in (("F1", True), ("F2", False)):
            result = fgcal.calibrate(dataset, method=method, single_camera=single, threads=threads)
            evaluation = fgcal.evaluate(result, truth)
            for camera in summary.cameras:
                errors[solve].setdefault(camera, []).append(errors_of(evaluation, camera))
            print(f"  {solve}: {result.timings.total:.1f} s", file=sys.stderr)
    return errors


def format_table(errors, seeds, method):
    header = "".join(f"{a + ' (σ) [' + u + ']':>20}" for a, u in zip(AXES, UNITS))
    lines = [f"Mean absolute error (standard deviation) over {len(seeds)} seed(s), as in Table I of Reinke et al. "
             f"(method {method})", ""]
    for camera in errors["F2"]:
        lines += [camera, f"{'':4}{header}"]
        for solve in ("F1", "F2"):
            e = np.abs(np.array(errors[solve][camera]))
            mean, std = e.mean(axis=0), e.std(axis=0)
            digits = [2, 2, 2, 3, 3, 3]
            cells = "".join(f"{m:.{d}f} ({s:.{d}f})".rjust(20) for m, s, d in zip(mean, std, digits))
            lines.append(f"{solve:4}{cells}")
        lines.append("")
    return "\n".join(lines)


def plot(errors, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not found (Debian: python3-matplotlib): no plot", file=sys.stderr)
        return None
    cameras = list(errors["F2"])
    fig, axes = plt.subplots(len(cameras), 2, figsize=(10, 3.2 * len(cameras)), squeeze=False)
    x = np.arange(3)
    for row, camera in enumerate(cameras):
        for col, (first, unit) in enumerate(((0, "mm"), (3, "deg"))):
            ax = axes[row][col]
            for k, solve in enumerate(("F1", "F2")):
                e = np.abs(np.array(errors[solve][camera]))[:, first:first + 3]
                ax.bar(x + (k - 0.5) * 0.38, e.mean(axis=0), 0.38, yerr=e.std(axis=0), capsize=3, label=solve)
            ax.set_xticks(x, AXES[first:first + 3])
            ax.set_ylabel(f"|error| [{unit}]")
            ax.set_title(camera)
            ax.legend()
    fig.suptitle("Mean absolute error over the seeds (bars: standard deviation)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=3, help="simulated datasets (seeds 1..N)")
    parser.add_argument("--frames", type=int, default=150, help="image instants per dataset")
    parser.add_argument("--supersampling", type=int, default=3, help="rendering: samples per pixel side (1..16)")
    parser.add_argument("--method", choices=["pnp", "corners"], default="pnp",
                        help="pnp: a PnP pose factor per image (the paper's); corners: a factor per detected corner")
    parser.add_argument("--threads", type=int, default=0, help="detection threads (0: every core)")
    parser.add_argument("--plot", default="table1_errors.png", help="the plot's file (with matplotlib)")
    parser.add_argument("--keep", help="keep the datasets in this folder (default: a temporary one)")
    args = parser.parse_args()
    seeds = list(range(1, args.seeds + 1))
    try:
        if args.keep:
            os.makedirs(args.keep, exist_ok=True)
            errors = run(seeds, args.frames, args.supersampling, args.keep, args.threads, args.method)
        else:
            with tempfile.TemporaryDirectory(prefix="fgcal-table1-") as work:
                errors = run(seeds, args.frames, args.supersampling, work, args.threads, args.method)
    except fgcal.Error as e:  # InputError or DataError: the message names what to fix
        print(f"table1: {type(e).__name__}: {e}", file=sys.stderr)
        return 2 if isinstance(e, fgcal.InputError) else 1
    print(format_table(errors, seeds, args.method))
    written = plot(errors, args.plot)
    if written:
        print(f"plot: {written}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
