# The pipeline from Python against the fgcal command: a simulated dataset
# (the demo's set-up, fewer instants) calibrated from Python gives the
# command line's camera poses to 1e-9, evaluate prints the command's table,
# simulate writes the command's files, and every error carries the message
# the command prints, in the class of its exit code.
import os
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

import fgcal
from conftest import cli_error_message, env_path, run_cli, runs_without_gil

# The demo's dataset (fgcal demo: a CAD mount off by 3 mm / 1 deg), with fewer
# instants and lighter rendering so that the test takes seconds (also in the
# sanitized build).
DEMO = dict(frames=24, seed=1, mount_error=(3.0, 1.0), supersampling=1)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo") / "dataset"
    summary = fgcal.simulate(str(out), **DEMO)
    assert summary.instants == 24 and summary.images_written > 24
    return out, summary


def test_simulate_writes_the_commands_files(tmp_path, fgcal_exe, dataset):
    out, summary = dataset
    for f in ("rig.yaml", "joints.csv", "robot.urdf", "ground_truth.yaml"):
        assert (out / f).is_file()
    assert summary.cameras == ["multisense_left", "xtion_rgb"] and len(summary.per_camera) == 2
    assert all(c.T_base_cam.shape == (4, 4) for c in summary.per_camera)
    # The same options through the command line give the same files, byte for
    # byte (a few instants: the command renders at its default supersampling).
    py, cli = tmp_path / "py", tmp_path / "cli"
    fgcal.simulate(str(py), frames=3, seed=4, mount_error=(3.0, 1.0), pixel_noise=0.3, cameras=1,
                   camera_delay_ms={"multisense_left": 2.5}, joint_offsets={"lf_hfe_joint": 0.01},
                   intrinsics_error=(1.0, 2.0), leg_origin_error=(1.0, 0.1))
    code, _, err = run_cli(fgcal_exe, "simulate", "--out", cli, "--frames", 3, "--seed", 4, "--mount-error", "3,1",
                           "--pixel-noise", 0.3, "--cameras", 1, "--camera-delay-ms", "multisense_left=2.5",
                           "--joint-offsets", "lf_hfe_joint=0.01", "--intrinsics-error", "1,2",
                           "--leg-origin-error", "1,0.1")
    assert code == 0, err
    truth = (py / "ground_truth.yaml").read_text()
    assert "time_offset_ms: 2.5" in truth and "lf_hfe_joint: {offset_rad: 0.01}" in truth
    assert "kinematic_origins:" in truth and "kinematic_sigma: [0.001, " in (py / "rig.yaml").read_text()
    for f in ["rig.yaml", "joints.csv", "robot.urdf", "ground_truth.yaml"] + \
             [str(p.relative_to(cli)) for p in sorted(cli.glob("*/*.png"))]:
        assert (cli / f).read_bytes() == (py / f).read_bytes(), f


def test_simulate_leg_and_camera_effects_as_the_command(tmp_path, fgcal_exe):
    # Backlash (one value for the chain, one joint's own), encoder steps, a
    # rolling shutter and an exposure: the command's files, byte for byte.
    py, cli = tmp_path / "py", tmp_path / "cli"
    fgcal.simulate(str(py), frames=2, seed=5, cameras=1, supersampling=1, backlash=0.004,
                   encoder_resolution=0.001, readout_ms={"multisense_left": 20.0}, exposure_ms=4.0)
    code, _, err = run_cli(fgcal_exe, "simulate", "--out", cli, "--frames", 2, "--seed", 5, "--cameras", 1,
                           "--backlash", "0.004", "--encoder-resolution", 0.001,
                           "--readout-ms", "multisense_left=20", "--exposure-ms", 4)
    assert code == 0, err
    # The command's default supersampling differs: compare the files that do not depend on it.
    for f in ["rig.yaml", "joints.csv", "ground_truth.yaml"]:
        assert (cli / f).read_bytes() == (py / f).read_bytes(), f
    truth = (py / "ground_truth.yaml").read_text()
    assert "lf_kfe_joint: {rad: 0.004}" in truth and "encoder_resolution_rad: 0.001" in truth
    assert "readout_ms: 20.0" in truth and "exposure_ms: 4.0" in truth
    assert "readout" not in (py / "rig.yaml").read_text()
    # A joint's own backlash as a dict.
    one = tmp_path / "one"
    fgcal.simulate(str(one), frames=2, cameras=1, render_images=False, backlash={"lf_kfe_joint": 0.01})
    truth = (one / "ground_truth.yaml").read_text()
    assert "lf_kfe_joint: {rad: 0.01}" in truth and "lf_haa_joint: {rad: 0.0}" in truth
    with pytest.raises(fgcal.InputError) as e:
        fgcal.simulate(str(tmp_path / "bad"), readout_ms={"multisense_left": 40.0})
    assert e.value.location == "--readout-ms" and "multisense_left" in str(e.value)
    with pytest.raises(fgcal.InputError) as e:
        fgcal.simulate(str(tmp_path / "bad"), backlash={"knee": 0.01})
    assert e.value.location == "--backlash"


def test_simulate_option_errors(tmp_path, fgcal_exe):
    with pytest.raises(TypeError, match="unexpected keyword argument 'pixelnoise'"):
        fgcal.simulate(str(tmp_path / "a"), pixelnoise=0.3)
    with pytest.raises(TypeError, match="option 'frames' cannot take str"):
        fgcal.simulate(str(tmp_path / "a"), frames="many")
    code, _, err = run_cli(fgcal_exe, "simulate", "--out", tmp_path / "b", "--camera-count", 7)
    assert code == 2
    with pytest.raises(fgcal.InputError) as e:
        fgcal.simulate(str(tmp_path / "b"), cameras=7)
    assert str(e.value) == cli_error_message(err)
    assert e.value.location == "--camera-count" and isinstance(e.value, ValueError)
    assert not (tmp_path / "b" / "rig.yaml").exists()


def test_evaluate_prints_the_commands_table(tmp_path, fgcal_exe, dataset):
    out, _ = dataset
    cal = tmp_path / "calibration.yaml"
    code, _, err = run_cli(fgcal_exe, "calibrate", out, "-o", cal, "--no-report")
    assert code == 0, err
    code, table, err = run_cli(fgcal_exe, "evaluate", cal, out / "ground_truth.yaml")
    assert code == 0, err
    ev = fgcal.evaluate(str(cal), out / "ground_truth.yaml")  # str or path-like
    assert str(ev) == table
    assert sorted(ev.cameras) == ["multisense_left", "xtion_rgb"] and ev.mount is not None
    assert all(e.translation_mm < 20 and e.rotation_deg < 1 for e in ev.cameras.values())
    code, _, err = run_cli(fgcal_exe, "evaluate", tmp_path / "missing.yaml", out / "ground_truth.yaml")
    assert code == 2
    with pytest.raises(fgcal.InputError) as e:
        fgcal.evaluate(str(tmp_path / "missing.yaml"), str(out / "ground_truth.yaml"))
    assert str(e.value) == cli_error_message(err)


def poses_in_yaml(text):
    """camera name -> T_base_cam read from calibration.yaml's text (numbers as written)."""
    poses, camera, lines = {}, None, text.splitlines()
    for i, line in enumerate(lines):
        if line == "cameras:" or (camera is not None and not line.startswith("  ")):
            camera = "" if line == "cameras:" else None
        elif camera is not None and line.startswith("  ") and not line.startswith("   ") and line.endswith(":"):
            camera = line.strip()[:-1]
        elif camera and line.strip().startswith("T_base_cam:"):
            rows = [l.strip().lstrip("- ").strip("[]") for l in lines[i + 1:i + 5]]
            poses[camera] = np.array([[float(x) for x in r.split(",")] for r in rows])
    return poses


def same_but_date(a, b):
    """Two calibration.yaml texts equal but for the stamp's date_utc, which is each run's own time."""
    date = re.compile(r'^  date_utc: "[^"]*"$', re.M)
    assert len(date.findall(a)) == 1 and len(date.findall(b)) == 1
    return date.sub('  date_utc: ""', a) == date.sub('  date_utc: ""', b)


# (the command's options, calibrate()'s, the method and solve in the result)
RUNS = {
    "F2": ([], {}, "pnp", "F2"),
    "F1": (["--single-camera"], dict(single_camera=True), "pnp", "F1"),
    # the corner method with offsets, the estimate as a list
    "corners+offsets": (["--method", "corners", "--estimate", "time-offset,joint-offsets"],
                        dict(method="corners", estimate=["time-offset", "joint-offsets"]), "corners", "F2"),
    # no method: the intrinsics select the corner method, as on the command line
    "intrinsics": (["--estimate", "intrinsics"], dict(estimate="intrinsics"), "corners", "F2"),
    "rolling shutter": (["--method", "corners", "--estimate", "time-offset,rolling-shutter"],
                        dict(method="corners", estimate="time-offset,rolling-shutter"), "corners", "F2"),
}


@pytest.mark.parametrize("run", list(RUNS))
def test_calibrate_gives_the_commands_poses(tmp_path, fgcal_exe, dataset, run):
    out, summary = dataset
    cli_args, kwargs, method, solve = RUNS[run]
    cli = tmp_path / "cli.yaml"
    code, _, err = run_cli(fgcal_exe, "calibrate", out, "-o", cli, "--no-report", *cli_args)
    assert code == 0, err
    result = fgcal.calibrate(out, **kwargs)
    assert (result.method, result.solve) == (method, solve)
    assert list(result.cameras) == summary.cameras
    cli_text = cli.read_text()
    expected = poses_in_yaml(cli_text)
    assert sorted(expected) == sorted(summary.cameras)
    for name, cam in result.cameras.items():
        assert cam.T_base_cam.shape == (4, 4) and cam.covariance.shape == (6, 6)
        np.testing.assert_allclose(cam.T_base_cam, expected[name], rtol=0, atol=1e-9)
    # the whole file: every pose, covariance, sigma, count and figure, to the last digit
    assert same_but_date(result.yaml(), cli_text)
    estimate = kwargs.get("estimate", [])
    estimated = estimate.split(",") if isinstance(estimate, str) else estimate
    assert result.estimated == estimated
    for cam in result.cameras.values():
        assert (cam.time_offset_ms is not None) == ("time-offset" in estimated)
        assert (cam.readout_ms is not None) == ("rolling-shutter" in estimated)
        assert (cam.intrinsics is not None) == ("intrinsics" in estimated)
        if cam.intrinsics is not None:
            assert cam.intrinsics.shape == (4,) and np.all(cam.intrinsics_sigma > 0)
    assert (len(result.joint_offsets) > 0) == ("joint-offsets" in estimated)
    if run != "F2":
        return
    # written by Python: the command's file
    written = tmp_path / "py.yaml"
    again = fgcal.calibrate(str(out), output=written, report=False)
    assert same_but_date(written.read_text(), cli_text)
    assert again.yaml_path == str(written) and not again.report_path
    assert (tmp_path / "py.urdf.xml").read_text() == (tmp_path / "cli.urdf.xml").read_text()


def test_calibration_result_holds_residuals_and_timings(dataset):
    out, summary = dataset
    result = fgcal.calibrate(str(out), cameras=summary.cameras)
    used = [im for im in result.images if im.used]
    assert len(used) == sum(c.images_used for c in result.cameras.values())
    for im in result.images:
        assert im.camera in result.cameras and (out / im.camera / f"{im.stamp_ns}.png").is_file()
        if im.used:
            # the residual of its fiducial factor is the one the solver's chi-square was computed from
            W = np.linalg.inv(1.1 * im.covariance)  # the default pnp_covariance_scale
            assert im.residual @ W @ im.residual == pytest.approx(im.chi2, rel=1e-6)
    for cam in result.cameras.values():
        assert cam.corner_residuals_px.shape[1] == 2 and len(cam.corner_residuals_px) >= 6 * cam.images_used
        rms = np.sqrt(np.mean(np.sum(cam.corner_residuals_px ** 2, axis=1)))
        assert rms == pytest.approx(cam.rms_reprojection_px, rel=1e-9)
    assert result.instants == summary.instants and result.mount.estimated and result.mount.covariance.shape == (6, 6)
    assert result.timings.total > 0 and result.timings.detection > 0 and result.timings.report == 0
    label, final = result.solves[-1]
    assert label.startswith("final") and final.converged and final.cost_history[-1] == final.final_cost
    assert result.evaluation is not None and sorted(result.evaluation.cameras) == sorted(summary.cameras)
    assert "Calibration (pnp, F2" in result.summary


def test_calibrate_releases_the_gil(dataset):
    out, _ = dataset
    assert runs_without_gil(fgcal.calibrate, str(out), cameras=["xtion_rgb"])


def test_calibrate_a_bag_gives_the_commands_result(tmp_path, fgcal_exe):
    # The shared ANYmal bag (MCAP: cam0 raw mono8, cam1 JPEG), with its
    # rig.yaml given the cameras' topics and the URDF's absolute path.
    fixture = os.path.join(env_path("FGCAL_SHARED_DATA_DIR"), "bags", "anymal_small")
    if not os.path.isdir(fixture):
        pytest.skip(f"{fixture} is missing (the shared data)")
    urdf = os.path.realpath(os.path.join(fixture, "..", "..", "urdf", "anymal_c.urdf"))
    lines = []
    for line in open(os.path.join(fixture, "rig.yaml")).read().splitlines():
        lines.append(f"  urdf: {urdf}" if line.startswith("  urdf:") else line)
        topic = {"  - name: cam0": "/cam0/image_raw", "  - name: cam1": "/cam1/image_raw/compressed"}.get(line)
        if topic:
            lines.append(f"    topic: {topic}")
    rig = tmp_path / "rig.yaml"
    rig.write_text("\n".join(lines) + "\n")
    bag = os.path.join(fixture, "anymal_small.mcap")
    cli = tmp_path / "cli.yaml"
    code, _, err = run_cli(fgcal_exe, "calibrate", bag, "--rig", rig, "-o", cli, "--no-report")
    assert code == 0, err
    result = fgcal.calibrate(bag, rig=rig)
    assert list(result.cameras) == ["cam0", "cam1"] and same_but_date(result.yaml(), cli.read_text())
    assert all(im.used for im in result.images) and len(result.images) > 0
    # without rig=, the command's message
    code, _, err = run_cli(fgcal_exe, "calibrate", bag, "-o", cli, "--no-report")
    assert code == 2
    with pytest.raises(fgcal.InputError) as e:
        fgcal.calibrate(bag)
    assert str(e.value) == cli_error_message(err) and "--rig" in str(e.value)


def damaged(dataset, tmp_path, edit):
    """A copy of the dataset with `edit(folder)` applied."""
    out, _ = dataset
    copy = tmp_path / "damaged"
    shutil.copytree(out, copy)
    edit(copy)
    return copy


def test_calibrate_errors_are_the_commands(tmp_path, fgcal_exe, dataset):
    def rig_edit(old, new):
        def edit(folder):
            rig = folder / "rig.yaml"
            text = rig.read_text()
            assert old in text
            rig.write_text(text.replace(old, new, 1))
        return edit

    def keep_images(n):
        def edit(folder):
            for camera in folder.iterdir():
                if camera.is_dir():
                    for png in sorted(camera.glob("*.png"))[n:]:
                        png.unlink()
        return edit

    cases = [  # (dataset, the command's options, calibrate()'s, exit code, exception)
        (tmp_path / "no_such_dataset", [], {}, 2, fgcal.InputError),
        (damaged(dataset, tmp_path / "a", rig_edit("pixel_sigma: 0.5", "pixel_sigma: -1")), [], {}, 2,
         fgcal.InputError),
        (dataset[0], ["--cameras", "no_such_camera"], dict(cameras="no_such_camera"), 2, fgcal.InputError),
        (dataset[0], ["--method", "bundle"], dict(method="bundle"), 2, fgcal.InputError),
        (dataset[0], ["--estimate", "time-offset,focal"], dict(estimate=["time-offset", "focal"]), 2,
         fgcal.InputError),
        (dataset[0], ["--method", "pnp", "--estimate", "intrinsics"], dict(method="pnp", estimate=["intrinsics"]), 2,
         fgcal.InputError),
        (damaged(dataset, tmp_path / "b", keep_images(2)), [], {}, 1, fgcal.DataError),
    ]
    for folder, args, kwargs, code, error in cases:
        rc, _, err = run_cli(fgcal_exe, "calibrate", folder, "-o", tmp_path / "x.yaml", "--no-report", *args)
        assert rc == code, err
        with pytest.raises(error) as e:
            fgcal.calibrate(str(folder), **kwargs)
        assert str(e.value) == cli_error_message(err)
        assert isinstance(e.value, fgcal.Error)
        assert isinstance(e.value, ValueError if code == 2 else RuntimeError)
        if error is fgcal.InputError:
            assert e.value.file or e.value.location
    with pytest.raises(TypeError, match="option 'estimate' cannot take int"):
        fgcal.calibrate(str(dataset[0]), estimate=3)
    with pytest.raises(TypeError, match="unexpected keyword argument 'single'"):
        fgcal.calibrate(str(dataset[0]), single=True)
    assert not (tmp_path / "x.yaml").exists()


def test_table1_example(tmp_path):
    # examples/python/table1.py on one small dataset: the table's rows and, with
    # matplotlib, the plot.
    script = os.path.join(env_path("FGCAL_SOURCE_DIR"), "examples", "python", "table1.py")
    plot = tmp_path / "table1.png"
    p = subprocess.run([sys.executable, script, "--seeds", "1", "--frames", "16", "--supersampling", "1",
                        "--plot", str(plot)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    rows = {}
    camera = None
    for line in p.stdout.splitlines():
        if line in ("multisense_left", "xtion_rgb"):
            camera = line
        elif camera and line[:2] in ("F1", "F2"):
            cells = re.findall(r"(\d+\.\d+) \((\d+\.\d+)\)", line)
            assert len(cells) == 6, line
            rows[(camera, line[:2])] = [float(m) for m, _ in cells]
    assert sorted(rows) == [(c, m) for c in ("multisense_left", "xtion_rgb") for m in ("F1", "F2")]
    for (camera, method), errors in rows.items():  # 16 instants: errors of about a centimetre and a degree
        assert max(errors[:3]) < 50 and max(errors[3:]) < 5, (camera, method, errors)  # mm, deg
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        assert "no plot" in p.stderr and not plot.exists()
    else:
        assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f"plot: {plot}" in p.stdout


def test_calibration_result_carries_its_quality_verdict(dataset):
    out, summary = dataset
    result = fgcal.calibrate(str(out))
    q = result.quality
    assert q.verdict in ("ok", "check", "unusable")
    # the demo's 24 instants are fewer than advised: a note, which leaves the verdict alone
    few = [f for f in q.findings if f.check == "few_instants"]
    assert len(few) == 1 and few[0].severity == "note" and "24 instant" in few[0].message
    for f in q.findings:
        assert f.severity in ("note", "check", "unusable")
        assert isinstance(f.fields, list) and isinstance(f.estimate, dict) and isinstance(f.command, str)
    text = result.yaml()
    assert text.index("quality:") < text.index("cameras:")
    assert f"  verdict: {q.verdict}\n" in text
    assert result.summary.lstrip().startswith("verdict: " + q.verdict.upper())


def test_calibration_result_carries_the_urdfs_share_and_relative_poses(tmp_path):
    # A leg whose joint origins are off by 1 mm / 0.15 deg per axis, and
    # rig.yaml's robot.kinematic_sigma of that size.
    out = tmp_path / "leg"
    fgcal.simulate(str(out), frames=24, seed=2, supersampling=1, leg_origin_error=(1.0, 0.15))
    result = fgcal.calibrate(str(out))
    origins = result.kinematic_origins
    assert [o.joint for o in origins] == ["lf_haa_joint", "lf_hfe_joint", "lf_kfe_joint"]
    assert not any(origins[0].observed)  # the origin nearest the base moves every board rigidly
    assert all(o.correction.shape == (6,) and o.sigma.shape == (6,) for o in origins)
    for cam in result.cameras.values():
        share = cam.sigma_from_urdf_mm_deg
        assert share is not None and share.shape == (6,)
        assert np.linalg.norm(share[:3]) > 0.5  # mm: most of a camera's sigma is the leg's
    (rel,) = result.relative_poses
    assert (rel.a, rel.b) == tuple(result.cameras)
    assert rel.covariance.shape == (6, 6) and rel.T_a_b.shape == (4, 4)
    cams = list(result.cameras.values())
    assert np.linalg.norm(rel.sigma_mm_deg[:3]) < 0.5 * np.linalg.norm(cams[1].sigma_mm_deg[:3])
