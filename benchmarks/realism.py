#!/usr/bin/env python3
"""What real legs do to the calibration, with and without its model, by both
methods. --effect origins: a leg whose joint origins differ from its URDF
(`fgcal simulate --leg-origin-error`), calibrated with rig.yaml's
robot.kinematic_sigma set to the error's size and with it removed (the URDF
taken as exact). --effect backlash: gears with play (`fgcal simulate
--backlash`), calibrated with and without `--estimate backlash`. --effect
rolling-shutter: one camera with a rolling shutter and every camera with an
exposure (`--readout-ms`, `--exposure-ms`), calibrated with `--estimate
time-offset,rolling-shutter` and with time-offset alone. --effect all: the
three together, with all three models against time-offset alone and the URDF
taken as exact.

    python3 benchmarks/realism.py --fgcal build/apps/fgcal [--effect origins|backlash|rolling-shutter|all] [--seeds 20]
        [--frames 150] [--error MM,DEG] [--backlash RAD] [--work /tmp/fgcal_realism] [--out benchmarks/results]

Per seed and case it records each camera's error against the truth (mm, deg)
and its NEES, the relative pose of the two cameras (error and NEES with its own
covariance) and the verdict. Writes realism_<date>_<commit>.csv (one row per
seed, case and camera) and .md (mean +- std over seeds, NEES mean and the
share under chi2(6) 0.999 = 22.46) into --out. Needs PyYAML and numpy.
"""
import argparse
import csv
import datetime
import math
import os
import re
import shutil
import subprocess
import sys

import numpy as np
import yaml

CHI2_6_999 = 22.4577


def run(cmd):
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def rotvec(R):
    c = max(-1.0, min(1.0, (np.trace(R) - 1.0) / 2.0))
    a = math.acos(c)
    if a < 1e-12:
        return np.zeros(3)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return a / (2.0 * math.sin(a)) * w


def pose_error(T_est, T_true, cov):
    """[w v] of T_est = T_true Exp(xi) (to first order in v), its mm / deg and NEES."""
    D = np.linalg.inv(T_true) @ T_est
    xi = np.concatenate([rotvec(D[:3, :3]), D[:3, 3]])
    nees = float(xi @ np.linalg.solve(cov, xi)) if cov is not None else float("nan")
    return 1e3 * np.linalg.norm(T_est[:3, 3] - T_true[:3, 3]), math.degrees(np.linalg.norm(xi[:3])), nees


def matrix(x):
    return np.array(x, dtype=float)


def scores(result_yaml, truth_yaml):
    with open(result_yaml) as f:
        res = yaml.safe_load(f)
    with open(truth_yaml) as f:
        truth = yaml.safe_load(f)
    rows = []
    names = list(res["cameras"])
    for name in names:
        cam = res["cameras"][name]
        mm, deg, nees = pose_error(matrix(cam["T_base_cam"]), matrix(truth["cameras"][name]["T_base_cam"]),
                                   matrix(cam["covariance"]))
        rows.append((name, mm, deg, nees))
    if len(names) >= 2:
        a, b = names[0], names[1]
        key = f"T_{a}_{b}"
        rel = res[key]
        T_true = np.linalg.inv(matrix(truth["cameras"][a]["T_base_cam"])) @ matrix(truth["cameras"][b]["T_base_cam"])
        mm, deg, nees = pose_error(matrix(rel[key]), T_true, matrix(rel["covariance"]))
        rows.append((key, mm, deg, nees))
    return res["quality"]["verdict"], rows


def readout_errors(result_yaml, truth_yaml):
    """Each estimated readout (calibration.yaml readout_ms with readout_sigma_ms) against the truth's."""
    with open(result_yaml) as f:
        res = yaml.safe_load(f)
    with open(truth_yaml) as f:
        truth = yaml.safe_load(f)
    out = []
    for name, cam in res["cameras"].items():
        if "readout_sigma_ms" not in cam:
            continue
        t = truth["cameras"][name].get("readout_ms", 0.0)
        out.append(dict(camera=name, estimate=cam["readout_ms"], truth=t, error=cam["readout_ms"] - t,
                        sigma=cam["readout_sigma_ms"]))
    return out


def commit():
    r = run(["git", "-C", os.path.dirname(os.path.abspath(__file__)), "rev-parse", "--short", "HEAD"])
    return r.stdout.strip() or "unknown"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fgcal", required=True)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--effect", choices=("origins", "backlash", "rolling-shutter", "all"), default="origins")
    ap.add_argument("--error", default="1.0,0.15", help="MM,DEG per axis of every joint origin")
    ap.add_argument("--backlash", default="0.004", help="RAD of play in every joint of the chain")
    ap.add_argument("--readout", default="xtion_rgb=25", help="CAM=MS: the rolling-shutter camera and its readout")
    ap.add_argument("--exposure", default="6", help="MS of exposure (motion blur) of every camera")
    ap.add_argument("--work", default="/tmp/fgcal_realism")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "results"))
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    records, readouts = [], []
    if a.effect == "origins":
        effect = ["--leg-origin-error", a.error]
        cases = (("kinematic_sigma", "rig.yaml", []), ("URDF exact", "rig_exact.yaml", []))
        title = f"Leg joint origins off by N(0, {a.error.replace(',', ' mm, ')} deg) per axis"
    elif a.effect == "backlash":
        effect = ["--backlash", a.backlash]
        cases = (("estimate backlash", "rig.yaml", ["--estimate", "backlash"]), ("no model", "rig.yaml", []))
        title = f"Gear backlash of {a.backlash} rad in every joint of the leg"
    elif a.effect == "rolling-shutter":
        effect = ["--readout-ms", a.readout, "--exposure-ms", a.exposure]
        cases = (("estimate rolling-shutter", "rig.yaml", ["--estimate", "time-offset,rolling-shutter"]),
                 ("time offset only", "rig.yaml", ["--estimate", "time-offset"]))
        title = f"Rolling shutter {a.readout.replace('=', ' ')} ms readout, {a.exposure} ms exposure on every camera"
    else:
        effect = ["--leg-origin-error", a.error, "--backlash", a.backlash, "--readout-ms", a.readout,
                  "--exposure-ms", a.exposure]
        cases = (("all three models", "rig.yaml", ["--estimate", "time-offset,backlash,rolling-shutter"]),
                 ("time offset only", "rig_exact.yaml", ["--estimate", "time-offset"]))
        title = (f"All effects: leg origins off by N(0, {a.error.replace(',', ' mm, ')} deg), backlash "
                 f"{a.backlash} rad, rolling shutter {a.readout.replace('=', ' ')} ms, exposure {a.exposure} ms")
    for seed in range(1, a.seeds + 1):
        data = os.path.join(a.work, f"{a.effect}_seed{seed}")
        if not os.path.isdir(data):
            r = run([a.fgcal, "simulate", "--out", data, "--seed", str(seed), "--frames", str(a.frames)] + effect)
            if r.returncode:
                sys.exit(f"simulate failed: {r.stderr}")
        rig = open(os.path.join(data, "rig.yaml")).read()
        with open(os.path.join(data, "rig_exact.yaml"), "w") as f:
            f.write(re.sub(r"  kinematic_sigma: [^\n]*\n", "", rig))
        for model, rig_file, extra in cases:
            for method in ("pnp", "corners"):
                out = os.path.join(a.work, f"{a.effect}_seed{seed}_{method}_{model.replace(' ', '_')}.calibration.yaml")
                r = run([a.fgcal, "calibrate", data, "--rig", os.path.join(data, rig_file), "--method", method,
                         "-o", out, "--no-report"] + extra)
                if r.returncode:
                    print(f"seed {seed} {model} {method}: exit {r.returncode}\n{r.stderr[-800:]}", file=sys.stderr)
                    continue
                verdict, rows = scores(out, os.path.join(data, "ground_truth.yaml"))
                for name, mm, deg, nees in rows:
                    records.append(dict(seed=seed, model=model, method=method, pose=name, mm=mm, deg=deg,
                                        nees=nees, verdict=verdict))
                readouts.extend(dict(seed=seed, model=model, method=method, **r)
                                for r in readout_errors(out, os.path.join(data, "ground_truth.yaml")))
        print(f"seed {seed} done", file=sys.stderr)

    stamp = f"{datetime.date.today().isoformat()}_{commit()}"
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, f"realism_{a.effect}_{stamp}.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(records[0]))
        w.writeheader()
        w.writerows(records)
    lines = [f"{title}; {a.seeds} seeds, {a.frames} frames; mean +- std over seeds.", "",
             "| model | method | pose | error mm | error deg | NEES mean | NEES max | NEES < 22.46 | verdict ok |",
             "|---|---|---|---|---|---|---|---|---|"]
    keys = sorted({(r["model"], r["method"], r["pose"]) for r in records},
                  key=lambda k: ([c[0] for c in cases].index(k[0]), k))
    for model, method, pose in keys:
        rs = [r for r in records if (r["model"], r["method"], r["pose"]) == (model, method, pose)]
        mm = np.array([r["mm"] for r in rs])
        deg = np.array([r["deg"] for r in rs])
        nees = np.array([r["nees"] for r in rs])
        ok = sum(r["verdict"] == "ok" for r in rs)
        lines.append(f"| {model} | {method} | {pose} | {mm.mean():.2f} ± {mm.std():.2f} | "
                     f"{deg.mean():.3f} ± {deg.std():.3f} | {nees.mean():.1f} | {nees.max():.1f} | "
                     f"{(nees < CHI2_6_999).sum()}/{len(rs)} | {ok}/{len(rs)} |")
    if readouts:
        lines += ["", "| model | method | camera | readout error ms | sigma ms | within 2 ms | within 3 sigma |",
                  "|---|---|---|---|---|---|---|"]
        for model, method, cam in sorted({(r["model"], r["method"], r["camera"]) for r in readouts}):
            rs = [r for r in readouts if (r["model"], r["method"], r["camera"]) == (model, method, cam)]
            err = np.array([r["error"] for r in rs])
            sig = np.array([r["sigma"] for r in rs])
            lines.append(f"| {model} | {method} | {cam} (truth {rs[0]['truth']:g}) | {err.mean():+.2f} ± {err.std():.2f} | "
                         f"{sig.mean():.2f} | {(np.abs(err) < 2.0).sum()}/{len(rs)} | "
                         f"{(np.abs(err) < 3.0 * sig).sum()}/{len(rs)} |")
    text = "\n".join(lines) + "\n"
    with open(os.path.join(a.out, f"realism_{a.effect}_{stamp}.md"), "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()
