"""The SocketCAN lane: boots User-Mode Linux (tests/uml/runner.py) and runs, on a real kernel
SocketCAN inside it, tests/uml/vcan_checks.py (the README's vcan0/can0 commands as written, NMT,
CiA 402, error frames, a full transmit queue) and the whole scenario suite of tests/scenarios with
BENCH_CONDITION=vcan0 (the matrix's SocketCAN row).

UML spends about 38 µs per system call: a drive-link call takes 5-15 s there, the lane several
minutes. It therefore runs in the background while the rest of the suite runs (tests/uml/lane.py,
started by tests/conftest.py right after collection); this test is ordered last and waits for it.
``SOCKETCAN_LANE=quick`` runs only :data:`QUICK` inside UML; ``SOCKETCAN_LANE=off`` leaves the
lane out on purpose (reported as skipped).

Where UML cannot run (package missing, boot or set-up failure, time limit) the test fails with one
line saying so: a lane that cannot run must not pass quietly.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent


def _load(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec and spec.loader
    if name not in sys.modules:
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        spec.loader.exec_module(mod)
    return sys.modules[name]


uml = _load("uml_runner", HERE / "uml" / "runner.py")
lane = _load("uml_lane", HERE / "uml" / "lane.py")

#: ``SOCKETCAN_LANE=quick``: the vcan_checks items but the drive-side block upload through
#: vcan1's 10-frame queue, and the scan scenario.
QUICK = "(vcan_checks and not block_upload) or test_scan"
#: Wall-time limit of the lane (boot, all checks, power-off), s.
LANE_TIMEOUT = 900.0
MODE = os.environ.get("SOCKETCAN_LANE", "").strip().lower() or "full"
NODEID = "tests/test_socketcan_lane.py::test_socketcan_lane"

pytestmark = pytest.mark.timeout(LANE_TIMEOUT + 180)


def lane_argv() -> list[str]:
    """The pytest command run inside UML."""
    argv = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rfE"]
    argv += ["--durations=15", "--durations-min=2"]
    argv += ["tests/uml/vcan_checks.py", "tests/scenarios"]
    if MODE == "quick":
        argv += ["-k", QUICK]
    return argv


def start_lane():
    """Start the lane in the background (once per test run); its directory, or None if off."""
    if MODE == "off":
        return None
    return lane.start(lane_argv(), timeout=LANE_TIMEOUT, env={"BENCH_CONDITION": "vcan0"})


def test_socketcan_lane():
    if MODE == "off":
        pytest.skip("SOCKETCAN_LANE=off")
    d = start_lane()  # already running when the whole suite runs (tests/conftest.py)
    res = lane.wait(d, LANE_TIMEOUT + 120)
    if res is not None:
        shutil.rmtree(d, ignore_errors=True)
    load = Path("/proc/loadavg").read_text().split()[0]
    if res is None:
        log = (d / "runner.log").read_text(errors="replace")[-300:] if d else ""
        pytest.fail(f"SocketCAN lane gave no result in time (load {load}): {log}", pytrace=False)
    if res["problem"]:
        pytest.fail(f"SocketCAN lane did not run: {res['problem']}", pytrace=False)
    output = res["output"]
    last = (output.strip().splitlines() or ["no output"])[-1]
    print(f"SocketCAN lane: {last} ({res['seconds']:.0f} s in UML, load {load})")
    print("---- output inside UML (end) ----\n" + output[-8000:])
    assert res["rc"] == 0, lane.failure_message(output)  # one line, then each failure's reason


@pytest.mark.unit
def test_lane_without_uml_says_so_in_one_line(monkeypatch):
    """No UML kernel (package missing): the runner returns one line, runs nothing."""
    monkeypatch.setattr(uml, "KERNELS", ("no-such-linux-uml",))
    res = uml.run_in_uml(["true"], timeout=5)
    assert res.rc is None and res.problem is not None
    assert "\n" not in res.problem and "apt-get install user-mode-linux" in res.problem


@pytest.mark.unit
def test_ci_runs_the_readme_test_command_which_installs_the_lane():
    """.ci/run runs the README's test command as written; the "Set up" section has exactly two
    commands, and the test command installs what the lane and the busy condition need."""
    readme = (HERE.parent / "README.md").read_text()
    setup = readme.split("## Set up", 1)[1].split("\n## ", 1)[0]
    blocks = [b.strip() for b in setup.split("```sh\n")[1:]]
    commands = [b.split("```", 1)[0].strip() for b in blocks]
    assert len(commands) == 2 and all("\n" not in c for c in commands), commands
    ci = (HERE.parent / ".ci" / "run").read_text().strip().splitlines()
    assert ci[-1] == commands[1]
    for pkg in ("chromium", "user-mode-linux", "kmod", "iproute2", "stress-ng"):
        assert f" {pkg}" in commands[1].split("&&")[1], pkg
