"""The SocketCAN lane runs in the background while the rest of the suite runs.

User-Mode Linux is slow per system call (about 38 µs), so the vcan0 suite inside it takes minutes
of wall time but little of it is waiting on the host: it would double the suite's time if it ran
in turn. :func:`start` boots it once per test run, right after collection (``tests/conftest.py``,
only when ``tests/test_socketcan_lane.py::test_socketcan_lane`` is selected), in a detached
``tests/uml/runner.py`` process that writes its result to a JSON file; the lane test, ordered
last, waits for that file with a bounded time (:func:`wait`).

Once per run: with pytest-xdist every worker collects, so the first worker to create the run's
directory (named after ``PYTEST_XDIST_TESTRUNUID``, the same in every worker of one run) starts
the lane. The runner watches the pytest process that owns the run (xdist's controller, or the
single pytest process) and kills UML when that process is gone, so an interrupted run never
leaves UML behind.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

__all__ = ["RESULT", "run_dir", "start", "wait"]

HERE = Path(__file__).resolve().parent
RUNNER = HERE / "runner.py"
#: File the runner writes when the lane ends: {"rc", "output", "problem", "seconds"}.
RESULT = "result.json"


def _owner_pid() -> int:
    """PID of the pytest process that owns this run (xdist workers are children of it)."""
    return os.getppid() if os.environ.get("PYTEST_XDIST_WORKER") else os.getpid()


def run_dir() -> Path:
    """The lane's directory for this test run (same path in every xdist worker of the run)."""
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID") or f"pid{_owner_pid()}"
    return Path(tempfile.gettempdir()) / f"socketcan-lane-{run}"


def start(argv: Sequence[str], *, timeout: float, env: Mapping[str, str]) -> Path:
    """Start the lane (``argv`` inside UML, at most ``timeout`` s) unless this run already did;
    returns the run's directory. Never raises for a lane that cannot run: the runner writes
    the one-line reason into the result file."""
    d = run_dir()
    try:
        d.mkdir()
    except FileExistsError:
        return d
    cmd = [sys.executable, str(RUNNER), "--timeout", repr(timeout)]
    cmd += ["--result", str(d / RESULT), "--watch-pid", str(_owner_pid())]
    for k, v in env.items():
        cmd += ["-e", f"{k}={v}"]
    cmd += ["--", *argv]
    with open(d / "runner.log", "wb") as log:
        subprocess.Popen(
            cmd,
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
            cwd=HERE.parent.parent,
        )
    (d / "started").write_text(f"{time.time():.3f}\n")
    return d


def wait(d: Path, timeout: float) -> dict | None:
    """The lane's result (dict) once the runner has written it, None after ``timeout`` s."""
    path = d / RESULT
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if path.exists():
            try:
                return json.loads(path.read_text())
            except json.JSONDecodeError:
                pass  # being written (the runner renames it into place; a partial read is rare)
        time.sleep(1.0)
    return None
