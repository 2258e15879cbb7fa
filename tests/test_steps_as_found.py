"""Step tests leave the drive as found without braking, and start from a settled start
(issue 24 deliverable 2, issue 26 item 3), through the `drive-link` console script against a
virtual drive. The truth is the drive's own objects read back over SDO."""

from __future__ import annotations

import contextlib
import io
import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from drive_link import cli

pytestmark = pytest.mark.timeout(180)

DRIVE_LINK = str(Path(sys.executable).parent / "drive-link")


@pytest.fixture(scope="module")
def hub(tmp_path_factory):
    from virtual_drive.hub import Hub
    from virtual_drive.node import spawn_virtual_drive

    store = tmp_path_factory.mktemp("store") / "params.json"
    with Hub(port=0) as h:
        proc = spawn_virtual_drive(port=h.port, node_id=1, store=store)
        try:
            yield h
        finally:
            proc.stop()


def dl(hub, *args: str) -> subprocess.CompletedProcess:
    cmd = [DRIVE_LINK, args[0], "--host", "127.0.0.1", "--port", str(hub.port), *args[1:]]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120)


def dl_in(hub, *args: str) -> tuple[int, str]:
    """cli.main in this process (setup and read-back: no interpreter start per call)."""
    out, err = io.StringIO(), io.StringIO()
    argv = [args[0], "--host", "127.0.0.1", "--port", str(hub.port), *args[1:]]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(argv)
    return rc, out.getvalue() + err.getvalue()


def read(hub, *names: str) -> dict:
    rc, out = dl_in(hub, "read", *names, "--json")
    assert rc == 0, out
    return json.loads(out)


def at_1000rpm(hub) -> dict:
    assert dl_in(hub, "nmt", "start")[0] == 0
    rc, out = dl_in(hub, "set-speed", "1000rpm", "--enable")
    assert rc == 0, out
    deadline = time.monotonic() + 30
    while abs(read(hub, "measurements.speed")["measurements.speed"] - 1000) > 20:
        assert time.monotonic() < deadline
        time.sleep(0.2)
    return here(hub)


def here(hub) -> dict:
    _rc, out = dl_in(hub, "status", "--json")
    st = json.loads(out)
    return {"state": st["state"], "mode": st["mode"],
            **read(hub, "target_velocity", "setpoints.i_p_ref", "disable_operation_option_code")}


def test_current_step_from_speed_mode_leaves_speed_mode_at_1000rpm(hub):
    before = at_1000rpm(hub)
    assert before["state"] == "OPERATION ENABLED" and before["mode"] == "speed"
    p = dl(hub, "step", "current", "--from", "15A", "--to", "20A")
    assert p.returncode == 0, p.stderr
    # the step said what it changes before it started, and what it puts back
    assert "current mode" in p.stdout.splitlines()[0] and "1000 rpm" in p.stdout.splitlines()[0]
    assert here(hub) == before


def test_mode_switch_coasts_instead_of_braking_at_the_current_limit(hub):
    """The switch out of speed mode at 1000 rpm (what a step test or identification does)
    turns the power stage off coasting: right after it the motor still turns (plant time
    constant 0.93 s); the drive's own disable ramp (0x605C = 1, kept as found) brakes at the
    current limit to standstill before SWITCHED ON is reached."""
    from drive_link import Drive
    from drive_link.workflows.restore import leave_as_found
    from drive_link.workflows.steps import ensure_mode

    before = at_1000rpm(hub)
    with Drive.connect(node_id=1, host="127.0.0.1", port=hub.port) as d:
        with leave_as_found(d):
            ensure_mode(d, "current")
            w = float(d.read("measurements.speed"))
            assert d.mode == "current" and d.state == "OPERATION ENABLED"
        assert w > 300, w
    assert here(hub) == before


def test_speed_step_starts_settled_and_refuses_an_unsettled_start(hub):
    before = at_1000rpm(hub)
    p = dl(hub, "step", "speed", "--start", "500", "--delta", "500", "--json")
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    assert out["start"] == pytest.approx(500, abs=5) and out["from"] == pytest.approx(500, abs=5)
    assert here(hub) == before
    # too short a timeout to settle from 1000 to 500 rpm: exit 5, one line, no metrics
    p = dl(hub, "step", "speed", "--start", "500", "--delta", "500", "--settle-timeout", "0.3s")
    assert p.returncode == 5 and p.stderr.count("\n") == 1, p.stderr
    assert "not settled" in p.stderr and "no metrics" in p.stderr
    assert "rise time" not in p.stdout
    assert here(hub) == before
