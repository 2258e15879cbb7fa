"""The command-line contract as a user meets it, through the installed console scripts (issue 23):
every ``--help`` only prints help, one exit-code table for every command and kind of bad value,
options spelled in full, a closed output pipe ends a command quietly, and the README's design
line gives the IP gains.

Oracles: the README's own exit-code table (read from its text), python-control's Ackermann pole
placement for the IP speed gains, argparse's usage line, and Unix's pipe semantics (a reader
that closes the pipe; the pipe shrunk to one page so the writer is still writing then).
"""

from __future__ import annotations

import fcntl
import json
import os
import re
import shlex
import subprocess
import sys
import time
import uuid
from pathlib import Path

import control as ct
import numpy as np
import pytest

pytestmark = pytest.mark.timeout(120)

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
PY = sys.executable
README = (ROOT / "README.md").read_text()
#: no DRIVE_LINK_* or CAN_* defaults from the developer's shell
ENV = {k: v for k, v in os.environ.items() if not k.startswith(("DRIVE_LINK_", "CAN_"))}


def _start(argv: list[str], **kw) -> subprocess.Popen:
    return subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV, **kw
    )


def _run_all(cmds: list[list[str]], timeout: float = 90.0) -> list[tuple[int, str, str, float]]:
    """Run ``cmds`` side by side: (exit status, stdout, stderr, seconds) of each."""
    t0 = time.monotonic()
    procs = [_start(c) for c in cmds]
    out = []
    for p in procs:
        o, e = p.communicate(timeout=timeout)
        out.append((p.returncode, o, e, time.monotonic() - t0))
    return out


# --------------------------------------------------------------------------- --help
HELP = [
    [str(BIN / "drive-link"), "--help"],
    [str(BIN / "drive-link"), "design", "--help"],
    [str(BIN / "virtual-drive"), "--help"],
    [str(BIN / "drive-dashboard"), "--help"],
    [PY, "-m", "virtual_drive.bench", "--help"],
    [PY, "-m", "firmware_protocol.generate", "--help"],
    [PY, "-m", "dashboard.screenshot", "--help"],
    [PY, str(ROOT / "tests/uml/runner.py"), "--help"],
    *([PY, str(p), "--help"] for p in sorted((ROOT / "benchmarks").glob("bench_*.py"))),
]


def test_every_help_only_prints_help_and_exits_0():
    """Each console script, sub-command, ``python -m`` command and benchmark: usage on stdout,
    nothing on stderr, exit 0, quickly (a benchmark that ran instead took seconds and printed
    figures, not a usage line)."""
    results = _run_all(HELP)
    bad = []
    for cmd, (rc, out, err, took) in zip(HELP, results, strict=True):
        name = " ".join(Path(c).name for c in cmd[1 if cmd[0] == PY else 0 :])
        if rc != 0 or not out.startswith("usage:") or err.strip() or took > 60:
            bad.append(f"{name}: exit {rc}, {took:.1f} s, stdout {out[:60]!r}, stderr {err[:80]!r}")
    assert not bad, "\n".join(bad)


# --------------------------------------------------------------------------- exit-code table
def _readme_exit_codes() -> dict[str, int]:
    """The README's table (the **Errors** item of "Using drive-link"): meaning → code."""
    item = README.split("- **Errors**:", 1)[1].split("\n- ", 1)[0].split("\n\n", 1)[0]
    item = re.sub(r"\([^()]*(\([^()]*\)[^()]*)*\)", "", " ".join(item.split()))  # drop asides
    return {m[1].strip(): int(m[0]) for m in re.findall(r"\b(\d{1,3}) ([A-Za-z][A-Za-z /]*)", item)}


CODE = _readme_exit_codes()

#: (argv after ``drive-link``, the README's meaning): no drive needed
OFFLINE = [
    (["set-speed", "5A"], "invalid value"),  # the same value `write` refuses with 7
    (["live", "--seconds", "5A"], "invalid value"),
    (["--node", "x", "status"], "invalid value"),
    (["design", "--a", "abc", "--b", "3e-4"], "invalid value"),
    (["identify", "--csv", "/nonexistent/trace.csv"], "invalid value"),
    (["mode", "sideways"], "usage"),
    (["trace", "--channel", "i_p"], "usage"),  # a typo of --channels, not the bus channel
    (["--nod", "1", "status"], "usage"),  # abbreviations are refused
    (["design", "--Lc", "22.2e-6", "--jso"], "usage"),
]
#: the same, against the virtual drive (``--host/--port`` added)
ONLINE = [
    (["write", "target_velocity", "5A"], "invalid value"),
    (["write", "target_velocity", "1000.5"], "invalid value"),
    (["set-speed", "1e9"], "invalid value"),  # above max_motor_speed
    (["read", "no_such_object"], "invalid value"),
    (["read", "0x6041:7"], "invalid value"),
    (["config", "load", "/nonexistent/bench.dcf"], "invalid value"),
    (["status", "--node", "5", "--sdo-timeout", "0.05"], "no node"),
    (["set-gains", "L_c=40e-6"], "unsafe gains"),
]


def test_the_readme_has_the_table():
    assert {"usage": 2, "no node": 4, "invalid value": 7, "unsafe gains": 8}.items() <= CODE.items()


def _check_codes(cases, extra: list[str]) -> None:
    cmds = [[str(BIN / "drive-link"), *argv, *extra] for argv, _ in cases]
    bad = []
    for (argv, meaning), (rc, _out, err, _) in zip(cases, _run_all(cmds), strict=True):
        lines = err.strip().splitlines()
        if rc != CODE[meaning] or len(lines) != 1 or "Traceback" in err:
            bad.append(f"{shlex.join(argv)}: exit {rc}, README {meaning} = {CODE[meaning]}: {err}")
    assert not bad, "\n".join(bad)


def test_bad_values_exit_with_the_readme_code_offline():
    _check_codes(OFFLINE, [])


def test_bad_values_exit_with_the_readme_code_against_the_drive(hub_drive):
    _check_codes(ONLINE, ["--host", "127.0.0.1", "--port", str(hub_drive.port)])


def test_scan_that_finds_no_node_is_no_node():
    ch = f"nobody-{uuid.uuid4().hex}"  # python-can's in-process virtual bus: no one else on it
    p = subprocess.run(
        [str(BIN / "drive-link"), "scan", "--interface", "virtual", "--channel", ch,
         "--timeout", "0.3"],
        capture_output=True, text=True, env=ENV, timeout=60,
    )  # fmt: skip
    assert p.returncode == CODE["no node"], (p.returncode, p.stdout, p.stderr)
    assert p.stdout == "" and len(p.stderr.strip().splitlines()) == 1
    assert "no node" in p.stderr


# --------------------------------------------------------------------------- closed pipe
def _closed_pipe_status(argv: list[str], read_first_line: bool) -> tuple[int, str, str]:
    """Run ``argv`` with stdout into a one-page pipe; read its first line (or nothing) and close
    the pipe, as ``| head -1`` (or ``| true``) does. Returns (status, first line, stderr)."""
    r, w = os.pipe()
    fcntl.fcntl(r, fcntl.F_SETPIPE_SZ, 4096)  # the writer blocks after one page: still writing
    if not read_first_line:
        os.close(r)
    p = subprocess.Popen(argv, stdout=w, stderr=subprocess.PIPE, text=True, env=ENV)
    os.close(w)
    first = ""
    if read_first_line:
        with os.fdopen(r) as reader:
            first = reader.readline()
    _, err = p.communicate(timeout=60)
    return p.returncode, first, err


def test_a_closed_pipe_ends_drive_link_quietly():
    rc, first, err = _closed_pipe_status([str(BIN / "drive-link"), "objects"], True)
    assert first.split()[:2] == ["INDEX", "NAME"]  # `drive-link objects | head -1`
    assert (rc, err) == (CODE["the reader closed the output pipe"], "")


def test_a_closed_pipe_ends_status_json_quietly(hub_drive):
    argv = [str(BIN / "drive-link"), "status", "--json", "--port", str(hub_drive.port),
            "--host", "127.0.0.1"]  # fmt: skip
    rc, _, err = _closed_pipe_status(argv, False)
    assert (rc, err) == (141, "")


# --------------------------------------------------------------------------- README's design line
def _ip_gains_by_pole_placement(a: float, b: float, xi: float, wn: float, Ts: float):
    """k_p, k_i of the IP loop (Fig. 17) by Ackermann's formula: states w and the unit
    integrator q of e = r - w; u = k_p (k_i (q + e) - w) is state feedback u = -K x with
    K = [k_p (1 + k_i), -k_p k_i]; the poles: s² + 2 ξ ω_n s + ω_n² = 0 mapped by e^{s Ts}."""
    z = np.exp(np.roots([1.0, 2 * xi * wn, wn * wn]) * Ts)
    K = np.asarray(ct.acker(np.array([[a, 0.0], [-1.0, 1.0]]), np.array([[b], [0.0]]), z))
    K1, K2 = K.ravel()
    k_p = K1 + K2
    return k_p, -K2 / k_p


def test_the_readme_design_line_prints_the_ip_gains():
    line = next(
        ln.split("  #", 1)[0].strip()
        for ln in README.splitlines()
        if ln.startswith("drive-link design --a ")
    )
    argv = shlex.split(line)
    p = subprocess.run(
        [str(BIN / argv[0]), *argv[1:]], capture_output=True, text=True, env=ENV, timeout=60
    )
    assert p.returncode == 0, p.stderr
    got = json.loads(p.stdout)
    opt = dict(zip(argv[2::2], argv[3::2], strict=False))
    k_p, k_i = _ip_gains_by_pole_placement(
        float(opt["--a"]), float(opt["--b"]), float(opt["--xi"]), float(opt["--wn"]), 20e-6
    )
    assert got["kp"] == pytest.approx(k_p, rel=1e-6)
    assert got["ki"] == pytest.approx(k_i, rel=1e-6)
    assert 0.21 < k_p < 0.2125 and 2.9e-5 < k_i < 3.1e-5  # the README comment: 0.2112, 3.0e-5


def test_a_closed_pipe_ends_virtual_drive_quietly():
    """`virtual-drive --hub | true`: its ready line meets a closed pipe; it ends at once,
    quietly (once a traceback and exit 1)."""
    argv = [str(BIN / "virtual-drive"), "--hub", "--hub-port", "0", "--log-level", "ERROR"]
    rc, _, err = _closed_pipe_status(argv, False)
    assert (rc, err) == (141, "")
