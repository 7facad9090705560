# The pipeline from Python against the fgcal command: a simulated dataset
# (the demo's set-up, fewer instants) calibrated from Python gives the
# command line's camera poses to 1e-9, evaluate prints the command's table,
# simulate writes the command's files, and every error carries the message
# the command prints, in the class of its exit code.
import os
import shutil

import numpy as np
import pytest

import fgcal
from conftest import cli_error_message, run_cli, runs_without_gil

# The demo's dataset (fgcal demo: a CAD mount off by 3 mm / 1 deg), with fewer
# instants and lighter rendering so that the test takes seconds.
DEMO = dict(frames=40, seed=1, mount_error=(3.0, 1.0), supersampling=2)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo") / "dataset"
    summary = fgcal.simulate(str(out), **DEMO)
    assert summary.instants == 40 and summary.images_written > 40
    return out, summary


def test_simulate_writes_the_commands_files(tmp_path, fgcal_exe, dataset):
    out, summary = dataset
    for f in ("rig.yaml", "joints.csv", "robot.urdf", "ground_truth.yaml"):
        assert (out / f).is_file()
    assert summary.cameras == ["multisense_left", "xtion_rgb"] and len(summary.per_camera) == 2
    assert all(c.T_base_cam.shape == (4, 4) for c in summary.per_camera)
    # The same options through the command line: the same files, byte for byte
    # (the command renders at its default supersampling, which changes images only).
    cli = tmp_path / "cli"
    code, _, err = run_cli(fgcal_exe, "simulate", "--out", cli, "--frames", 40, "--seed", 1, "--mount-error", "3,1")
    assert code == 0, err
    for f in ("rig.yaml", "joints.csv", "robot.urdf", "ground_truth.yaml"):
        assert (cli / f).read_bytes() == (out / f).read_bytes(), f


def test_simulate_option_errors(tmp_path, fgcal_exe):
    with pytest.raises(TypeError, match="unexpected keyword argument 'pixelnoise'"):
        fgcal.simulate(str(tmp_path / "a"), pixelnoise=0.3)
    with pytest.raises(TypeError, match="option 'frames' cannot take str"):
        fgcal.simulate(str(tmp_path / "a"), frames="many")
    code, _, err = run_cli(fgcal_exe, "simulate", "--out", tmp_path / "b", "--cameras", 7)
    assert code == 2
    with pytest.raises(fgcal.InputError) as e:
        fgcal.simulate(str(tmp_path / "b"), cameras=7)
    assert str(e.value) == cli_error_message(err)
    assert e.value.location == "--cameras" and isinstance(e.value, ValueError)
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
    assert all(e.translation_mm < 10 and e.rotation_deg < 1 for e in ev.cameras.values())
    code, _, err = run_cli(fgcal_exe, "evaluate", tmp_path / "missing.yaml", out / "ground_truth.yaml")
    assert code == 2
    with pytest.raises(fgcal.InputError) as e:
        fgcal.evaluate(str(tmp_path / "missing.yaml"), str(out / "ground_truth.yaml"))
    assert str(e.value) == cli_error_message(err)
