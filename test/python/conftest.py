# Shared by the Python module's tests (run by ctest through /usr/bin/python3 -m
# pytest; test/python/CMakeLists.txt sets PYTHONPATH to the build tree's
# python/ folder and the paths below).
import os
import subprocess
import sys
import threading

import pytest


def env_path(name):
    """A path ctest passes in the environment; the test is skipped without it."""
    value = os.environ.get(name)
    if not value:
        pytest.skip(f"{name} is not set (the tests are run by ctest, which sets it)")
    return value


@pytest.fixture(scope="session")
def fgcal_exe():
    return env_path("FGCAL_EXE")


def run_cli(exe, *args, cwd=None):
    """Runs the fgcal command; returns (exit code, stdout, stderr)."""
    p = subprocess.run([exe, *map(str, args)], capture_output=True, text=True, cwd=cwd)
    return p.returncode, p.stdout, p.stderr


def cli_error_message(stderr):
    """The message of the command line's error line, 'fgcal: error: MESSAGE'."""
    lines = [l for l in stderr.splitlines() if l.startswith("fgcal: error: ")]
    assert lines, f"no 'fgcal: error:' line in:\n{stderr}"
    return lines[-1][len("fgcal: error: "):]


def runs_without_gil(call, *args, attempts=3, **kwargs):
    """True when another Python thread ran while `call` was running.

    With a switch interval far longer than the call, a thread holding the
    GIL keeps it until it releases it itself: the main thread, woken as the
    worker enters the call, gets to run before the call returns only if the
    call released the GIL. A call that holds the GIL never lets it; one that
    releases it could still finish before a busy machine schedules the main
    thread, hence a few attempts.
    """
    return any(_ran_during(call, args, kwargs) for _ in range(attempts))


def _ran_during(call, args, kwargs):
    started, state = threading.Event(), {"returned": False}

    def worker():
        started.set()
        state["result"] = call(*args, **kwargs)
        state["returned"] = True

    old = sys.getswitchinterval()
    sys.setswitchinterval(1000.0)
    try:
        t = threading.Thread(target=worker)
        t.start()
        started.wait()
        ran_during_call = not state["returned"]
        t.join()
    finally:
        sys.setswitchinterval(old)
    assert "result" in state, "the call raised"
    return ran_during_call
