"""`drive-link` leaves the drive as it found it and refuses before it changes anything.

A `virtual-drive run` child behind the loopback hub; the commands run through cli.main (and one
real `python -m drive_link.cli` child for Ctrl-C). The truth is the drive's own objects read
back over SDO: statusword (CiA 402 state), modes_of_operation_display, target_velocity,
setpoints.i_p_ref."""

from __future__ import annotations

import contextlib
import io
import json
import signal
import subprocess
import sys
import time

import pytest

from drive_link import cli

pytestmark = pytest.mark.timeout(180)


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


def dl(hub, *args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    argv = [args[0], "--host", "127.0.0.1", "--port", str(hub.port), *args[1:]]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(argv)
    return rc, out.getvalue(), err.getvalue()


def where(hub) -> dict:
    """State, mode and setpoints as the drive reports them."""
    rc, out, err = dl(hub, "status", "--json")
    assert rc == 0, err
    st = json.loads(out)
    rc, out, err = dl(hub, "read", "target_velocity", "setpoints.i_p_ref", "--json")
    assert rc == 0, err
    return {"state": st["state"], "mode": st["mode"], **json.loads(out)}


def one_line(err: str) -> str:
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def put(hub, state: str, mode: str, rpm: int, amps: float) -> dict:
    """Bring the drive to a known state (through the CLI, disabling first)."""
    assert dl(hub, "nmt", "start")[0] == 0
    assert dl(hub, "disable")[0] == 0
    assert dl(hub, "mode", mode)[0] == 0
    assert dl(hub, "write", "target_velocity", str(rpm))[0] == 0
    assert dl(hub, "write", "setpoints.i_p_ref", str(amps))[0] == 0
    if state != "SWITCH ON DISABLED":
        assert dl(hub, "enable")[0] == 0
    if state == "SWITCHED ON":
        assert dl(hub, "disable")[0] == 0
    w = where(hub)
    assert w["state"] == state and w["mode"] == mode
    return w


def test_setpoint_refused_before_anything_changes(hub):
    before = put(hub, "SWITCHED ON", "current", 0, 0.0)
    # not enabled: refused in one line naming --enable; neither mode nor setpoint changed
    rc, out, err = dl(hub, "set-speed", "1000")
    assert rc == 1 and "--enable" in one_line(err)
    assert where(hub) == before
    # out of limits: refused, mode not switched
    rc, out, err = dl(hub, "set-speed", "1e5", "--enable")
    assert rc == 7 and "above the limit" in one_line(err)
    assert where(hub) == before
    # zero is the stopped state: written without enabling
    rc, out, err = dl(hub, "set-speed", "0 rpm", "--json")
    assert rc == 0 and json.loads(out) == {"target_velocity": 0, "state": "SWITCHED ON"}
    # a negative value with a unit is a value, not an option
    rc, out, err = dl(hub, "set-current", "-2.5A", "--enable", "--json")
    assert rc == 0, err
    assert json.loads(out) == {"i_p_ref": -2.5, "state": "OPERATION ENABLED"}


def test_mode_change_while_enabled_is_explained_or_done(hub):
    put(hub, "OPERATION ENABLED", "speed", 300, 0.0)
    rc, out, err = dl(hub, "mode", "current")
    assert rc == 1 and "disable" in one_line(err) and "--re-enable" in err
    rc, out, err = dl(hub, "set-current", "2A")
    assert rc == 1 and "--switch-mode" in one_line(err)
    # any write the drive refuses in its state (abort 0x08000022) names the fix
    rc, out, err = dl(hub, "write", "motor.L", "15uH")
    assert rc == 6 and "0x08000022" in one_line(err) and "`drive-link disable` first" in err
    w = where(hub)
    assert (w["mode"], w["state"], w["setpoints.i_p_ref"]) == ("speed", "OPERATION ENABLED", 0.0)
    rc, out, err = dl(hub, "set-current", "2A", "--switch-mode", "--json")
    assert rc == 0, err
    assert json.loads(out) == {"i_p_ref": 2.0, "state": "OPERATION ENABLED"}
    assert where(hub)["mode"] == "current"
    rc, out, err = dl(hub, "mode", "speed", "--re-enable", "--json")
    assert rc == 0 and json.loads(out) == {"mode": "speed", "state": "OPERATION ENABLED"}
    dl(hub, "disable")


def test_step_and_identify_restore_state_mode_setpoint(hub):
    before = put(hub, "OPERATION ENABLED", "current", 0, 3.0)
    rc, out, err = dl(hub, "step", "speed", "--delta", "200", "--length", "300", "--json")
    assert rc == 0, err
    assert where(hub) == before
    before = put(hub, "SWITCHED ON", "speed", 0, 0.0)
    rc, out, err = dl(hub, "step", "current", "--from", "10A", "--to", "15A", "--json")
    assert rc == 0, err
    assert json.loads(out)["to"] == 15.0
    assert where(hub) == before
    rc, out, err = dl(
        hub, "identify-drive", "--to", "8A", "--divider", "20", "--length", "400", "--json"
    )
    assert rc == 0, err
    assert where(hub) == before
    # an error inside the step also restores: --no-enable fails after the step has selected
    # current mode and written i_from (drive_link.workflows.steps.current_step)
    rc, out, err = dl(hub, "step", "current", "--from", "12", "--no-enable")
    assert rc == 1 and "enable it first" in one_line(err)
    assert where(hub) == before


def test_ctrl_c_during_a_step_restores(hub):
    before = put(hub, "SWITCHED ON", "speed", 0, 0.0)
    # SIGINT raises KeyboardInterrupt in the child even where the test runner's process ignores
    # SIGINT (an ignored signal is inherited, and Python then installs no handler)
    main = (
        "import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
        "from drive_link.cli import main; sys.exit(main())"
    )
    cmd = [sys.executable, "-c", main, "step", "speed", "--length", "3000"]
    cmd += ["--divider", "200", "--host", "127.0.0.1", "--port", str(hub.port)]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while where(hub)["state"] != "OPERATION ENABLED":  # the step is running
            assert p.poll() is None and time.monotonic() < deadline, p.communicate()
            time.sleep(0.1)
        p.send_signal(signal.SIGINT)
        _out, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 130 and "interrupted" in one_line(err), err
    assert where(hub) == before
    rc, out, err = dl(hub, "read", "trace_config.state", "--json")
    assert rc == 0, err
    assert json.loads(out)["trace_config.state"] not in (1, 2)  # not left armed / recording
