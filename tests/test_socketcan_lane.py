"""The SocketCAN lane: boots User-Mode Linux once (tests/uml/runner.py) and runs, on a real kernel
SocketCAN inside it, tests/uml/vcan_checks.py (the README's vcan0/can0 commands as written, NMT,
CiA 402, error frames, a full transmit queue) and the scenario suite with BENCH_CONDITION=vcan0
(:data:`SCENARIOS`).

Where UML cannot run (package missing, boot or set-up failure, time limit) the test fails with one
line saying so: a lane that cannot run must not pass quietly. ``SOCKETCAN_LANE=off`` in the
environment is the one way to leave it out on purpose (then it is reported as skipped).
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

#: Scenario tests that run inside UML (BENCH_CONDITION=vcan0). The drive's default TPDO streams
#: (2,200 frames/s) exceed what UML moves (about 800 frames/s), see tests/uml/vcan_checks.py.
SCENARIOS: list[str] = []
#: Wall-time limit of the whole lane (boot, checks, power-off), s.
LANE_TIMEOUT = 540.0

pytestmark = pytest.mark.timeout(LANE_TIMEOUT + 60)


def test_socketcan_lane():
    if os.environ.get("SOCKETCAN_LANE", "").lower() == "off":
        pytest.skip("SOCKETCAN_LANE=off")
    argv = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rfE"]
    argv += ["tests/uml/vcan_checks.py", *SCENARIOS]
    t0 = time.monotonic()
    res = uml.run_in_uml(argv, timeout=LANE_TIMEOUT, env={"BENCH_CONDITION": "vcan0"})
    load = Path("/proc/loadavg").read_text().split()[0]
    if res.problem:
        pytest.fail(f"SocketCAN lane did not run: {res.problem}", pytrace=False)
    summary = [ln for ln in res.output.splitlines() if ln.startswith(("FAILED", "ERROR"))]
    last = (res.output.strip().splitlines() or ["no output"])[-1]
    print(f"SocketCAN lane: {last} ({time.monotonic() - t0:.0f} s in UML, load {load})")
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
