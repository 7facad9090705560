#!/usr/bin/env python3
"""How close the extra estimates (time offset, joint offset, intrinsics) come to
what their data can tell: per seed, the camera poses' reported 1-sigma with the
quantity estimated against the same images' calibration without the
perturbation, next to the errors actually made.

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/estimation_bounds.py [--seeds 10] [--frames 300] [--out DIR]

Ratios are of means over the seeds; NEES is the camera pose's, with the
quantity estimated (6 when its covariance is honest). The sigma ratio is the information bound: no estimator that has to find the
quantity from these images can do better on average. When the error ratio is
close to it, the estimator is efficient and a target below it asks for more
informative data (more instants, views), not for a better solver.
Uses the fgcal Python module (the simulator and the calibration).
"""
import argparse
import math
import os
import statistics
import tempfile

import fgcal

CASES = {
    # name: (simulate options of the perturbation, calibrate options, quantity read back)
    "delay": ({"camera_delay_ms": {"xtion_rgb": 15.0}}, {"method": "pnp", "estimate": ["time-offset"]}, "time"),
    "joint-offset": ({"joint_offsets": {"lf_hfe_joint": 0.01}}, {"method": "pnp", "estimate": ["joint-offsets"]},
                     "joint"),
    "intrinsics": ({"intrinsics_error": (1.0, 3.0)}, {"method": "corners", "estimate": ["intrinsics"]}, "intrinsics"),
}
BASELINE = {"delay": "pnp", "joint-offset": "pnp", "intrinsics": "corners"}


def sigmas(cov):
    """Translation (mm) and rotation (deg) 1-sigma: root of the block's trace."""
    t = math.sqrt(sum(cov[i][i] for i in (3, 4, 5))) * 1e3
    r = math.degrees(math.sqrt(sum(cov[i][i] for i in (0, 1, 2))))
    return t, r


def quantity(result, ground_truth, kind):
    """(|error|, sigma) of the estimated quantity: ms, mrad or px (cx)."""
    if kind == "time":
        c = result.cameras["xtion_rgb"]
        return abs(c.time_offset_ms - 15.0), c.time_offset_sigma_ms
    if kind == "joint":
        j = [o for o in result.joint_offsets if o.joint == "lf_hfe_joint"][0]
        return abs(j.offset_rad - 0.01) * 1e3, j.sigma_rad * 1e3
    c = result.cameras["multisense_left"]
    return abs(c.intrinsics[2] - ground_truth["multisense_left"]), c.intrinsics_sigma[2]


def true_cx(path):
    """Each camera's true cx from ground_truth.yaml (the line after its name's intrinsics key)."""
    out, name = {}, None
    for line in open(path):
        s = line.strip()
        if line.startswith("  ") and not line.startswith("    ") and s.endswith(":"):
            name = s[:-1]
        elif s.startswith("intrinsics:") and name:
            out[name] = float(s.split("[")[1].split("]")[0].split(",")[2])
    return out


def run_seed(case, seed, frames, work):
    sim_opts, cal_opts, kind = CASES[case]
    base_dir, pert_dir = os.path.join(work, f"base{seed}"), os.path.join(work, f"{case}{seed}")
    if not os.path.exists(base_dir):
        fgcal.simulate(base_dir, seed=seed, frames=frames)
    fgcal.simulate(pert_dir, seed=seed, frames=frames, overwrite=True, **sim_opts)
    base = fgcal.calibrate(base_dir, method=BASELINE[case], report=False)
    est = fgcal.calibrate(pert_dir, report=False, **cal_opts)
    rows = {}
    for cam in est.cameras:
        s0, s1 = sigmas(base.cameras[cam].covariance), sigmas(est.cameras[cam].covariance)
        e0, e1 = base.evaluation.cameras[cam], est.evaluation.cameras[cam]
        rows[cam] = (s1[0] / s0[0], s1[1] / s0[1], e1.translation_mm, e0.translation_mm, e1.rotation_deg,
                     e0.rotation_deg, e1.nees)
    return rows, quantity(est, true_cx(os.path.join(pert_dir, "ground_truth.yaml")), kind)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--cases", default="delay,joint-offset,intrinsics")
    ap.add_argument("--out", default=None, help="keep the datasets here (default: a temporary folder)")
    a = ap.parse_args()
    work = a.out or tempfile.mkdtemp(prefix="fgcal_bounds_")
    units = {"time": "ms (xtion_rgb's 15 ms)", "joint": "mrad (lf_hfe_joint)", "intrinsics": "px (multisense_left cx)"}
    print(f"{a.seeds} seeds from {a.first_seed}, {a.frames} instants; datasets in {work}\n")
    print("| case | camera | sigma ratio mm | deg | error ratio mm | deg | NEES | estimated quantity: mean abs error "
          "| mean sigma | max abs error |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for case in a.cases.split(","):
        per_cam, q = {}, []
        for seed in range(a.first_seed, a.first_seed + a.seeds):
            rows, qe = run_seed(case, seed, a.frames, work)
            q.append(qe)
            for cam, r in rows.items():
                per_cam.setdefault(cam, []).append(r)
        for i, (cam, rs) in enumerate(per_cam.items()):
            col = list(zip(*rs))
            mean = statistics.fmean
            qtext = (f"{mean(e for e, _ in q):.3f} {units[CASES[case][2]]} | {mean(s for _, s in q):.3f} | "
                     f"{max(e for e, _ in q):.3f}") if i == 0 else " | | "
            print(f"| {case if i == 0 else ''} | {cam} | {mean(col[0]):.2f} | {mean(col[1]):.2f} | "
                  f"{mean(col[2]) / mean(col[3]):.2f} | {mean(col[4]) / mean(col[5]):.2f} | {mean(col[6]):.2f} | {qtext} |", flush=True)


if __name__ == "__main__":
    main()
