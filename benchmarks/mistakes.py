#!/usr/bin/env python3
"""Set-up mistakes against the quality verdict: does `fgcal calibrate` flag
each one, does it name the input to fix, and how wrong is a result it did
not flag? And on correct data: how often does each check fire?

    python3 benchmarks/mistakes.py --fgcal build/apps/fgcal [--seeds 20] [--frames 300]
        [--kinds board_scale,joint_sign,...] [--work /tmp/fgcal_mistakes] [--out benchmarks/results]

Per seed it simulates fgcal's default robot (two cameras, 0.5 px, 0.002 rad,
a CAD mount 3 mm / 1 deg off: the demo's set-up), plus one dataset with a
30 ms camera delay and one with a 50 mrad joint zero offset; every other
mistake is an edit of rig.yaml or joints.csv of the correct dataset (the
images are linked, not copied). Each dataset is calibrated with PnP, no
report. A mistake is detected when the verdict is not ok; its field is named
when a finding of severity check or unusable lists one of the mistake's
fields. When not detected, the error left is the largest camera error
against the truth (mm, deg). The correct dataset's findings give each
check's false-alarm rate.

Writes mistakes_<date>_<commit>_seeds<A>-<B>.csv (one row per seed and kind,
each as soon as it is measured) and .md (the table BENCHMARKS.md quotes) into
--out; `--summarize A.csv B.csv ...` prints the table of several runs (seeds
run in several sittings; a seed and kind in a later file replaces the same
seed and kind of an earlier one). Needs PyYAML and numpy.
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
from collections import defaultdict

import numpy as np
import yaml

FINDING = re.compile(r"^  (note|check|unusable) \[(\w+)\](?: fields: (.*))?$")


def run(cmd, **kw):
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


def simulate(fgcal, out, seed, frames, extra=()):
    if os.path.isdir(out):
        return
    frames_arg = [] if "--frames" in extra else ["--frames", str(frames)]
    r = run([fgcal, "simulate", "--out", out, "--seed", str(seed), *frames_arg, *extra])
    if r.returncode != 0:
        sys.exit(f"simulate failed: {r.stderr}")


def variant(base, dest):
    """A copy of the dataset's small files, its image folders linked."""
    if os.path.isdir(dest):
        shutil.rmtree(dest)
    os.makedirs(dest)
    for name in os.listdir(base):
        src = os.path.join(base, name)
        if os.path.isdir(src):
            os.symlink(os.path.abspath(src), os.path.join(dest, name))
        else:
            shutil.copy(src, os.path.join(dest, name))
    return dest


def load_rig(d):
    with open(os.path.join(d, "rig.yaml")) as f:
        return yaml.safe_load(f)


def save_rig(d, rig):
    with open(os.path.join(d, "rig.yaml"), "w") as f:
        yaml.safe_dump(rig, f, sort_keys=False)


def edit_joints(d, change):
    path = os.path.join(d, "joints.csv")
    with open(path) as f:
        rows = list(csv.reader(f))
    header, data = rows[0], [[float(x) if i else int(x) for i, x in enumerate(r)] for r in rows[1:] if r]
    header, data = change(header, data)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        for r in data:
            w.writerow([r[0]] + [repr(x) for x in r[1:]])


def chain_joints(d):
    """The movable joints of the rig's marker chain, as joints.csv names them (the leg's, by prefix)."""
    rig = load_rig(d)
    with open(os.path.join(d, "joints.csv")) as f:
        header = f.readline().strip().split(",")[1:]
    prefix = rig["robot"]["marker_link"].split("_")[0]
    leg = [h for h in header if h.lower().startswith(prefix.lower())]
    return leg or header[:3]


def other_foot(d):
    rig = load_rig(d)
    urdf = os.path.join(d, rig["robot"]["urdf"])
    links = re.findall(r'<link\s+name="([^"]+)"', open(urdf).read())
    foot = rig["robot"]["marker_link"]
    feet = [l for l in links if l != foot and l.split("_")[-1] == foot.split("_")[-1]]
    return feet[0] if feet else None


# ---- the mistakes: (fields any one of which names it right, how to make it) ----

def m_board_scale(d):
    rig = load_rig(d)
    rig["target"]["square_size"] *= 1.05
    rig["target"]["marker_size"] *= 1.05
    save_rig(d, rig)


def m_mount_identity(d):
    rig = load_rig(d)
    rig["robot"]["T_link_marker"] = np.eye(4).tolist()
    save_rig(d, rig)


def m_mount_off(d):
    rig = load_rig(d)
    T = np.array(rig["robot"]["T_link_marker"], dtype=float)
    T[0, 3] += 0.03
    rig["robot"]["T_link_marker"] = T.tolist()
    save_rig(d, rig)


def m_wrong_foot(d):
    rig = load_rig(d)
    rig["robot"]["marker_link"] = other_foot(d)
    save_rig(d, rig)


def m_intrinsics_off(d):
    rig = load_rig(d)
    cam = rig["cameras"][1]
    cam["intrinsics"][0] *= 1.04
    cam["intrinsics"][1] *= 1.04
    save_rig(d, rig)


def m_intrinsics_swapped(d):
    rig = load_rig(d)
    a, b = rig["cameras"][0], rig["cameras"][1]
    for k in ("intrinsics", "distortion_model", "distortion_coeffs"):
        a[k], b[k] = b.get(k), a.get(k)
    save_rig(d, rig)


def m_no_distortion(d):
    rig = load_rig(d)
    for cam in rig["cameras"]:
        cam["distortion_model"] = "none"
        cam["distortion_coeffs"] = []
    save_rig(d, rig)


def m_joint_sign(d):
    j = chain_joints(d)[1]

    def change(header, data):
        i = header.index(j)
        for r in data:
            r[i] = -r[i]
        return header, data
    edit_joints(d, change)
    return j


def m_joint_swap(d):
    a, b = chain_joints(d)[1], chain_joints(d)[2]

    def change(header, data):
        h = list(header)
        ia, ib = h.index(a), h.index(b)
        h[ia], h[ib] = h[ib], h[ia]
        return h, data
    edit_joints(d, change)
    return a, b


def m_degrees(d):
    def change(header, data):
        for r in data:
            for i in range(1, len(r)):
                r[i] = math.degrees(r[i])
        return header, data
    edit_joints(d, change)


def m_encoder_sigma_small(d):
    rig = load_rig(d)
    rig["robot"]["encoder_sigma"] = 1e-5
    save_rig(d, rig)


def m_pixel_sigma_small(d):
    rig = load_rig(d)
    for cam in rig["cameras"]:
        cam["pixel_sigma"] = 0.05
    save_rig(d, rig)


def m_rows_cols(d):
    rig = load_rig(d)
    t = rig["target"]
    t["squares_x"], t["squares_y"] = t["squares_y"], t["squares_x"]
    save_rig(d, rig)


def m_principal_point(d):
    """Another resolution's or crop's calibration: the principal point off by (8, 6) px."""
    rig = load_rig(d)
    cam = rig["cameras"][1]
    cam["intrinsics"][2] += 8.0
    cam["intrinsics"][3] += 6.0
    save_rig(d, rig)


def m_leg_length(d):
    """The real leg 5 mm longer than its URDF: the origin of the marker chain's last joint moved 5 mm along itself."""
    joint = chain_joints(d)[-1]
    path = os.path.join(d, load_rig(d)["robot"]["urdf"])
    text = open(path).read()
    m = re.search(r'<joint name="' + re.escape(joint) + r'"[\s\S]*?<origin xyz="([^"]+)"', text)
    xyz = np.array([float(v) for v in m.group(1).split()])
    xyz *= 1.0 + 0.005 / np.linalg.norm(xyz)
    text = text[:m.start(1)] + " ".join(repr(float(v)) for v in xyz) + text[m.end(1):]
    open(path, "w").write(text)


KINDS = {
    # kind: (dataset, edit, fields that name it; "JOINT"/"JOINTS" = the edited joints.csv columns)
    "board_scale": ("base", m_board_scale, ["target.square_size", "target.marker_size"]),
    "mount_identity": ("base", m_mount_identity, ["robot.T_link_marker"]),
    "mount_off": ("base", m_mount_off, ["robot.T_link_marker"]),
    "wrong_foot": ("base", m_wrong_foot, ["robot.marker_link"]),
    "intrinsics_off": ("base", m_intrinsics_off, ["cameras[CAM1].intrinsics"]),
    "intrinsics_swapped": ("base", m_intrinsics_swapped, ["cameras[CAM0].intrinsics", "cameras[CAM1].intrinsics"]),
    "no_distortion": ("base", m_no_distortion, ["cameras[CAM0].distortion_coeffs", "cameras[CAM1].distortion_coeffs"]),
    "camera_delay": ("delay", None, ["cameras[CAM1].time_offset_ms"]),
    "joint_sign": ("base", m_joint_sign, ["JOINT"]),
    "joint_swap": ("base", m_joint_swap, ["JOINT"]),
    "degrees": ("base", m_degrees, ["JOINT"]),
    "encoder_sigma_small": ("base", m_encoder_sigma_small, ["robot.encoder_sigma"]),
    "joint_zero_offset": ("offset", None, ["JOINT"]),
    "rows_cols_swapped": ("base", m_rows_cols, ["target.squares_x", "target.squares_y"]),
    "pixel_sigma_small": ("base", m_pixel_sigma_small, ["cameras[CAM0].pixel_sigma", "cameras[CAM1].pixel_sigma"]),
    "principal_point": ("base", m_principal_point, ["cameras[CAM1].intrinsics"]),
    "leg_length": ("base", m_leg_length, ["robot.urdf"]),
}


SHARED_URDF = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "data", "urdf")
# Correct data, for the false-alarm rates: the cases of bench_accuracy that
# are right (its "corrupt" and "intrinsics" cases feed wrong inputs).
CORRECT = {
    "defaults": ["--mount-error", "0,0"],
    "few": ["--frames", "30"],
    "pixel2": ["--pixel-noise", "2"],
    "encoder": ["--encoder-noise", "0.01"],
    "mount": ["--mount-error", "3,1"],
    "anymal": ["--urdf", os.path.join(SHARED_URDF, "anymal_c.urdf"), "--base-link", "base", "--marker-link", "LF_FOOT"],
    "fisheye": ["--distortion", "equidistant"],
}


def findings_of(stderr):
    out = []
    for line in stderr.splitlines():
        m = FINDING.match(line)
        if m:
            out.append((m.group(1), m.group(2), (m.group(3) or "").split()))
    return out


def camera_errors(result_yaml, truth_yaml):
    with open(result_yaml) as f:
        res = yaml.safe_load(f)
    with open(truth_yaml) as f:
        truth = yaml.safe_load(f)
    worst_mm, worst_deg = 0.0, 0.0
    for name, cam in res["cameras"].items():
        if name not in truth["cameras"]:
            continue
        A = np.array(cam["T_base_cam"], dtype=float)
        B = np.array(truth["cameras"][name]["T_base_cam"], dtype=float)
        worst_mm = max(worst_mm, 1e3 * np.linalg.norm(A[:3, 3] - B[:3, 3]))
        c = (np.trace(A[:3, :3].T @ B[:3, :3]) - 1.0) / 2.0
        worst_deg = max(worst_deg, math.degrees(math.acos(max(-1.0, min(1.0, c)))))
    return worst_mm, worst_deg


def calibrate(fgcal, d, out_dir):
    os.makedirs(out_dir, exist_ok=True)
    out = os.path.join(out_dir, "calibration.yaml")
    if os.path.exists(out):
        os.remove(out)
    r = run([fgcal, "calibrate", d, "-o", out, "--no-report"])
    return r.returncode, findings_of(r.stderr), out if os.path.exists(out) else None, r.stderr


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fgcal", required=True)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=1)
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--kinds", default=",".join(KINDS))
    ap.add_argument("--correct", default=",".join(CORRECT), help="correct cases for the false-alarm rates")
    ap.add_argument("--work", default="/tmp/fgcal_mistakes")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "results"))
    ap.add_argument("--summarize", nargs="+", metavar="CSV",
                    help="only print the table of earlier runs' CSV files (runs over several sittings)")
    a = ap.parse_args()
    if a.summarize:
        # A (seed, kind) measured again in a later file replaces the earlier
        # row: a re-run after a fix supersedes what it re-measured.
        by_case = {}
        for path in a.summarize:
            with open(path, newline="") as f:
                for r in csv.DictReader(f):
                    r["seed"] = int(r["seed"])
                    r["mm"], r["deg"] = float(r["mm"]), float(r["deg"])
                    by_case[(r["seed"], r["kind"])] = r
        rows = list(by_case.values())
        seeds = sorted({r["seed"] for r in rows})
        a.seeds, a.first_seed = len(seeds), seeds[0]
        print(summarize(rows, a))
        return
    kinds = [k for k in a.kinds.split(",") if k]
    for k in kinds:
        if k not in KINDS:
            sys.exit(f"unknown kind {k}; known: {', '.join(KINDS)}")
    fgcal = os.path.abspath(a.fgcal)
    commit = run(["git", "rev-parse", "--short", "HEAD"], cwd=os.path.dirname(os.path.abspath(__file__))).stdout.strip()
    stem = os.path.join(a.out, f"mistakes_{datetime.date.today()}_{commit}")
    os.makedirs(a.out, exist_ok=True)
    rows = []
    # Each row is written as soon as it is known, so that a long run that is
    # stopped keeps what it measured (--summarize joins several runs' files).
    csv_path = f"{stem}_seeds{a.first_seed}-{a.first_seed + a.seeds - 1}.csv"
    csv_file = open(csv_path, "w", newline="")
    writer = None

    def record(row):
        nonlocal writer
        rows.append(row)
        if writer is None:
            writer = csv.DictWriter(csv_file, fieldnames=list(row))
            writer.writeheader()
        writer.writerow(row)
        csv_file.flush()

    for seed in range(a.first_seed, a.first_seed + a.seeds):
        base = os.path.join(a.work, f"s{seed}", "base")
        simulate(fgcal, base, seed, a.frames)
        rig = load_rig(base)
        cams = [c["name"] for c in rig["cameras"]]
        datasets = {"base": base}
        # the correct dataset: false alarms
        code, found, result, _ = calibrate(fgcal, base, os.path.join(a.work, f"s{seed}", "out_correct"))
        mm, deg = camera_errors(result, os.path.join(base, "ground_truth.yaml")) if result else (float("nan"),) * 2
        record({"seed": seed, "kind": "correct", "exit": code, "verdict": verdict(code, found),
                     "checks": ";".join(f"{s}:{c}" for s, c, _ in found), "named": "", "mm": mm, "deg": deg})
        for case in [c for c in a.correct.split(",") if c]:
            if case not in CORRECT:
                sys.exit(f"unknown correct case {case}; known: {', '.join(CORRECT)}")
            extra = list(CORRECT[case])
            src = os.path.join(a.work, f"s{seed}", "correct_" + case)
            simulate(fgcal, src, seed, a.frames, extra)
            code, found, result, _ = calibrate(fgcal, src, os.path.join(a.work, f"s{seed}", "out_correct_" + case))
            mm, deg = camera_errors(result, os.path.join(src, "ground_truth.yaml")) if result else (float("nan"),) * 2
            record({"seed": seed, "kind": "correct " + case, "exit": code, "verdict": verdict(code, found),
                         "checks": ";".join(f"{s}:{c}" for s, c, _ in found), "named": "", "mm": mm, "deg": deg})
            print(f"seed {seed} correct {case}: exit {code}, {rows[-1]['verdict']}, {rows[-1]['checks']}", flush=True)
        for kind in kinds:
            source, edit, fields = KINDS[kind]
            if source == "delay":
                src = os.path.join(a.work, f"s{seed}", "delay")
                simulate(fgcal, src, seed, a.frames, ["--camera-delay-ms", f"{cams[-1]}=30"])
            elif source == "offset":
                src = os.path.join(a.work, f"s{seed}", "offset")
                joint = chain_joints(base)[1]
                simulate(fgcal, src, seed, a.frames, ["--joint-offsets", f"{joint}=0.05"])
            else:
                src = base
            d = variant(src, os.path.join(a.work, f"s{seed}", kind))
            edited = edit(d) if edit else None
            joints = []
            if kind == "joint_zero_offset":
                joints = [chain_joints(base)[1]]
            elif isinstance(edited, str):
                joints = [edited]
            elif isinstance(edited, tuple):
                joints = list(edited)
            elif kind == "degrees":
                joints = chain_joints(base)
            want = []
            for f in fields:
                if f == "JOINT":
                    want += [f"joints.csv:{j}" for j in joints]
                else:
                    want.append(f.replace("CAM0", cams[0]).replace("CAM1", cams[-1]))
            code, found, result, _ = calibrate(fgcal, d, os.path.join(a.work, f"s{seed}", "out_" + kind))
            named = any(s != "note" and any(x in want for x in fl) for s, _, fl in found)
            mm, deg = camera_errors(result, os.path.join(src, "ground_truth.yaml")) if result else (float("nan"),) * 2
            record({"seed": seed, "kind": kind, "exit": code, "verdict": verdict(code, found),
                         "checks": ";".join(f"{s}:{c}" for s, c, _ in found), "named": int(named), "mm": mm,
                         "deg": deg})
            print(f"seed {seed} {kind}: exit {code}, {rows[-1]['verdict']}, named {named}, "
                  f"{rows[-1]['checks']}", flush=True)
    csv_file.close()
    table = summarize(rows, a)
    with open(csv_path[:-4] + ".md", "w") as f:
        f.write(table)
    print(table)


def verdict(code, found):
    if any(s == "unusable" for s, _, _ in found) or code == 1:
        return "unusable"
    if any(s == "check" for s, _, _ in found):
        return "check"
    return "ok" if code == 0 else f"exit {code}"


def summarize(rows, a):
    by = defaultdict(list)
    for r in rows:
        by[r["kind"]].append(r)
    out = [f"`python3 benchmarks/mistakes.py --seeds {a.seeds} --frames {a.frames}` "
           f"(seeds {a.first_seed}..{a.first_seed + a.seeds - 1})\n",
           "| mistake | detected | field named | unusable | error left when not detected (largest camera, mm / deg) |",
           "| --- | --- | --- | --- | --- |"]
    for kind, rs in by.items():
        if kind.startswith("correct"):
            continue
        n = len(rs)
        det = [r for r in rs if r["verdict"] != "ok"]
        missed = [r for r in rs if r["verdict"] == "ok"]
        left = (f"{max(r['mm'] for r in missed):.2f} / {max(r['deg'] for r in missed):.3f}" if missed else "-")
        out.append(f"| {kind} | {len(det)}/{n} | {sum(int(r['named']) for r in rs)}/{n} | "
                   f"{sum(r['verdict'] == 'unusable' for r in rs)}/{n} | {left} |")
    correct = [r for r in rows if r["kind"].startswith("correct")]
    out.append("")
    out.append(f"Correct datasets: {sum(r['verdict'] != 'ok' for r in correct)} of {len(correct)} flagged.")
    for kind in sorted(k for k in by if k.startswith("correct")):
        rs = by[kind]
        out.append(f"- {kind}: {sum(r['verdict'] != 'ok' for r in rs)} of {len(rs)} flagged")
    out.append("Checks that fired on correct data:")
    fired = defaultdict(int)
    for r in correct:
        for c in set(x for x in r["checks"].split(";") if x and not x.startswith("note:")):
            fired[c] += 1
    for c, k in sorted(fired.items()):
        out.append(f"- {c}: {k} of {len(correct)}")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    main()
