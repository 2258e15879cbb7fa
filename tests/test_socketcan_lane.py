"""The SocketCAN lane: boots User-Mode Linux once (tests/uml/runner.py) and runs, on a real kernel
SocketCAN inside it, tests/uml/vcan_checks.py (the README's vcan0/can0 commands as written, NMT,
CiA 402, error frames, a full transmit queue) and scenarios of tests/scenarios with
BENCH_CONDITION=vcan0.

Which scenarios: UML spends about 38 µs per system call; a drive-link call takes 5-15 s there on a
busy host and the whole scenario suite 9-10 min (measured at load 15), so by default the lane runs
:data:`SELECTION` (about 3 min at load 15, 6 min at load 30). ``SOCKETCAN_LANE=full`` runs the
whole suite on vcan0 (time limit :data:`FULL_TIMEOUT`); ``SOCKETCAN_LANE=off`` leaves the lane
out on purpose (reported as skipped).

Where UML cannot run (package missing, boot or set-up failure, time limit) the test fails with one
line saying so: a lane that cannot run must not pass quietly.
"""

from __future__ import annotations

import importlib.util
import os
import sys
import time
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("uml_runner", HERE / "uml" / "runner.py")
assert _spec and _spec.loader
uml = sys.modules.setdefault("uml_runner", importlib.util.module_from_spec(_spec))
_spec.loader.exec_module(uml)

#: What runs inside UML by default (pytest -k expression on vcan_checks + tests/scenarios): every
#: vcan_checks item but the drive-side block upload through vcan1's 10-frame queue (a second
#: drive start, about 1 min on a busy host; the host side of a full queue is checked), and the
#: scan scenario. NMT + 402 and a speed setpoint are in vcan_checks; 64 KiB uploads in
#: benchmarks/bench_socketcan_uml.py; everything with SOCKETCAN_LANE=full.
SELECTION = "(vcan_checks and not block_upload) or test_scan"
#: Wall-time limits of the lane (boot, checks, power-off), s.
LANE_TIMEOUT = 720.0
FULL_TIMEOUT = 1500.0
MODE = os.environ.get("SOCKETCAN_LANE", "").strip().lower()

pytestmark = pytest.mark.timeout((FULL_TIMEOUT if MODE == "full" else LANE_TIMEOUT) + 60)


def test_socketcan_lane():
    if MODE == "off":
        pytest.skip("SOCKETCAN_LANE=off")
    argv = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rfE"]
    argv += ["--durations=12", "--durations-min=2"]
    argv += ["tests/uml/vcan_checks.py", "tests/scenarios"]
    if MODE != "full":
        argv += ["-k", SELECTION]
    t0 = time.monotonic()
    limit = FULL_TIMEOUT if MODE == "full" else LANE_TIMEOUT
    res = uml.run_in_uml(argv, timeout=limit, env={"BENCH_CONDITION": "vcan0"})
    load = Path("/proc/loadavg").read_text().split()[0]
    if res.problem:
        pytest.fail(f"SocketCAN lane did not run: {res.problem}", pytrace=False)
    summary = [ln for ln in res.output.splitlines() if ln.startswith(("FAILED", "ERROR"))]
    last = (res.output.strip().splitlines() or ["no output"])[-1]
    print(f"SocketCAN lane: {last} ({time.monotonic() - t0:.0f} s in UML, load {load})")
    print("---- output inside UML (end) ----\n" + res.output[-8000:])
    assert res.rc == 0, "SocketCAN lane (inside UML): " + "; ".join(summary or [last])


def test_lane_without_uml_says_so_in_one_line(monkeypatch):
    """No UML kernel (package missing): the runner returns one line, runs nothing."""
    monkeypatch.setattr(uml, "KERNELS", ("no-such-linux-uml",))
    res = uml.run_in_uml(["true"], timeout=5)
    assert res.rc is None and res.problem is not None
    assert "\n" not in res.problem and "apt-get install user-mode-linux" in res.problem


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
