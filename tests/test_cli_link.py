"""The `drive-link` command across processes: a `virtual-drive run` child on the loopback hub,
`python -m drive_link.cli` children talking to it. Checks outputs, files, exit codes and the
one-line error rule (no tracebacks)."""

from __future__ import annotations

import contextlib
import csv
import io
import json
import subprocess
import sys

import pytest

from drive_link import cli

pytestmark = pytest.mark.timeout(120)

L = 14.8e-6


def run(hub, *args: str, timeout: float = 60.0) -> subprocess.CompletedProcess:
    """`drive-link ARGS` in a child process (the real command line)."""
    cmd = [sys.executable, "-m", "drive_link.cli", args[0], "--host", "127.0.0.1"]
    cmd += ["--port", str(hub.port), *args[1:]]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)


def run_here(hub, *args: str) -> subprocess.CompletedProcess:
    """`drive-link ARGS` via cli.main in this process (saves an interpreter start); the drive
    is still the `virtual-drive run` child behind the hub."""
    out, err = io.StringIO(), io.StringIO()
    argv = [args[0], "--host", "127.0.0.1", "--port", str(hub.port), *args[1:]]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(argv)
    return subprocess.CompletedProcess(argv, rc, out.getvalue(), err.getvalue())


def one_line_error(p: subprocess.CompletedProcess) -> str:
    assert p.stdout == ""
    assert p.stderr.count("\n") == 1 and "Traceback" not in p.stderr, p.stderr
    return p.stderr


def test_status_scan_and_json(hub_drive):
    p = run(hub_drive, "status", "--json")
    assert p.returncode == 0, p.stderr
    st = json.loads(p.stdout)
    assert st["node_id"] == 1 and st["state"] in ("SWITCH ON DISABLED", "SWITCHED ON")
    assert st["gains"]["L_c"] == pytest.approx(L, rel=1e-6)
    p = run(hub_drive, "scan", "--json")
    assert p.returncode == 0, p.stderr
    assert {"node_id": 1, "device_type": 0x00020192}.items() <= json.loads(p.stdout)[0].items()


def test_enable_setpoint_disable(hub_drive):
    p = run_here(hub_drive, "set-current", "5", "--enable", "--json")
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout) == {"i_p_ref": 5.0, "state": "OPERATION ENABLED"}
    p = run_here(hub_drive, "read", "measurements.i_p", "statusword", "--json")
    vals = json.loads(p.stdout)
    assert (
        vals["measurements.i_p"] == pytest.approx(5.0, abs=0.5)
        and vals["statusword"] & 0x6F == 0x27
    )
    p = run_here(hub_drive, "disable")
    assert p.returncode == 0 and p.stdout.strip() == "SWITCHED ON"


def test_bad_input_one_line_and_exit_codes(hub_drive, tmp_path):
    p = run_here(hub_drive, "write", "current_controller.L_c", "1e-3")
    assert p.returncode == 7 and "deadbeat loop stable for L_c < 2 L" in one_line_error(p)
    p = run_here(hub_drive, "write", "setpoints.i_p_ref", "abc")
    assert p.returncode == 7 and "not a number" in one_line_error(p)
    p = run_here(hub_drive, "read", "current_controller.Lc")
    assert p.returncode == 7 and "no object named" in one_line_error(p)
    p = run_here(hub_drive, "status", "--node", "5", "--sdo-timeout", "0.05")
    assert p.returncode == 4 and "no answer from node 5" in one_line_error(p)
    p = subprocess.run(
        [sys.executable, "-m", "drive_link.cli", "status", "--host", "127.0.0.1", "--port", "1"],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert p.returncode == 3 and "no hub at 127.0.0.1:1" in one_line_error(p)
    # a value outside the EDS enumeration is refused before sending, naming the abort code
    # the drive would answer with (CiA 301 0x06090030)
    p = run_here(hub_drive, "write", "modes_of_operation", "1")
    assert p.returncode == 7 and "SDO abort 0x06090030" in one_line_error(p)
    # the drive refuses (SDO abort with its meaning) what the client cannot check: CiA 301
    # §7.5.2.7 allows only 0 to be written to 0x1003:0
    p = run_here(hub_drive, "write", "pre_defined_error_field.number_of_errors", "1")
    assert p.returncode == 6 and "0x06090030 (invalid value for parameter)" in one_line_error(p)


def test_gains_margin_check_and_force(hub_drive):
    p = run_here(hub_drive, "set-gains", f"L_c={1.6 * L}")
    assert p.returncode == 8
    assert "L_c = 1.6 L > 1.5 L" in one_line_error(p)
    assert json.loads(run_here(hub_drive, "gains", "--json").stdout)["L_c"] == pytest.approx(
        L, rel=1e-6
    )
    p = run_here(hub_drive, "set-gains", f"L_c={1.6 * L}", "--force", "--json")
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    assert out["gains"]["L_c"] == pytest.approx(1.6 * L, rel=1e-6) and out["warnings"]
    p = run_here(hub_drive, "set-gains", f"L_c={L}", "k_p=0.5", "--json")
    assert p.returncode == 0 and json.loads(p.stdout)["gains"]["k_p"] == pytest.approx(0.5)


def test_trace_and_step_files(hub_drive, tmp_path):
    p = run_here(
        hub_drive,
        "trace",
        "--channels",
        "i_p,speed",
        "--length",
        "1000",
        "--divider",
        "5",
        "--csv",
        str(tmp_path / "t.csv"),
        "--png",
        str(tmp_path / "t.png"),
        "--json",
    )
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    assert out["samples"] == 1000 and out["dt"] == pytest.approx(100e-6)
    rows = list(csv.reader((tmp_path / "t.csv").open()))
    assert (
        rows[0] == ["t [s]", "measurements.i_p [A]", "measurements.speed [rpm]"]
        and len(rows) == 1001
    )
    assert (tmp_path / "t.png").read_bytes()[:4] == b"\x89PNG"
    p = run_here(
        hub_drive,
        "step",
        "current",
        "--from",
        "10",
        "--to",
        "15",
        "--csv",
        str(tmp_path / "s.csv"),
        "--png",
        str(tmp_path / "s.png"),
        "--json",
    )
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    assert out["kind"] == "current" and out["to"] == 15.0
    assert out["metrics"]["rise_time"] < 1e-4  # deadbeat: two 20 µs samples
    assert "measurements.i_p_predicted [A]" in next(csv.reader((tmp_path / "s.csv").open()))
    run_here(hub_drive, "disable")


def test_progress_bar_on_stderr(hub_drive):
    p = run(hub_drive, "trace", "--channels", "i_p", "--length", "2000", "--progress")
    assert p.returncode == 0, p.stderr
    assert "upload [" in p.stderr and "100.0 %" in p.stderr


def test_usage_errors_are_one_line():
    for argv in (["bogus"], ["trace", "--trigger", "sometimes"]):
        p = subprocess.run(
            [sys.executable, "-m", "drive_link.cli", *argv],
            capture_output=True,
            text=True,
            timeout=30,
        )
        assert p.returncode == 2
        assert "error:" in one_line_error(p)


# --------------------------------------------------------------------------- bus options order
#: minimal positional arguments per sub-command (parse-only test of every command)
_POSITIONALS = {
    "mode": ["speed"],
    "set-speed": ["100"],
    "set-current": ["1"],
    "read": ["statusword"],
    "write": ["target_velocity", "0"],
    "set-gains": ["k_p=0.5"],
    "nmt": ["start"],
    "step": ["current"],
    "identify": ["--csv", "x.csv"],
    "config": ["save", "x.dcf"],
    "record": ["x.asc"],
    "replay": ["x.asc"],
}
_BUS = ["--interface", "socketcan", "--channel", "vcan7", "--bitrate", "500000", "--node", "9"]
_BUS += ["--sdo-timeout", "0.7", "--timeout", "2.5", "--json"]
_WANT = {
    "interface": "socketcan",
    "channel": "vcan7",
    "bitrate": 500000,
    "node": 9,
    "sdo_timeout": 0.7,
    "timeout": 2.5,
    "json": True,
}


def _parsed(argv: list[str]) -> dict:
    ap = cli.build_parser()
    args = ap.parse_args(argv)
    cli._merge_bus(args)
    return {k: getattr(args, k, None) for k in _WANT}


@pytest.mark.unit
def test_every_command_takes_bus_options_before_and_after():
    sub = next(a for a in cli.build_parser()._actions if a.dest == "cmd")
    assert len(sub.choices) >= 20
    for name in sub.choices:
        pos = _POSITIONALS.get(name, [])
        before = _parsed([*_BUS, name, *pos])
        if name in ("design", "identify"):  # offline commands: only --json is theirs
            assert before["json"] is True, name
            continue
        assert before == _WANT, name
        if name == "trace":  # its --channels extends --channel: the bus channel goes before it
            after = [o for o in _BUS if o not in ("--channel", "vcan7")]
            assert _parsed(["--channel", "vcan7", name, *pos, *after]) == _WANT, name
            with pytest.raises(SystemExit):
                _parsed([name, *pos, *_BUS])
            continue
        assert _parsed([name, *pos, *_BUS]) == _WANT, name
        defaults = _parsed([name, *pos])
        assert defaults["node"] == 1 and defaults["json"] is False and defaults["timeout"] is None


@pytest.mark.unit
def test_option_after_the_command_wins_and_host_port_both_sides():
    got = _parsed(["--node", "3", "status", "--node", "5"])
    assert got["node"] == 5
    ap = cli.build_parser()
    args = ap.parse_args(["--host", "127.0.0.1", "nmt", "start", "--port", "29999"])
    cli._merge_bus(args)
    assert (args.host, args.port, args.command) == ("127.0.0.1", 29999, "start")


def test_bus_options_before_the_command_reach_the_drive(hub_drive):
    """The README's order (`drive-link --host H --port P status`) talks to the same drive."""
    cmd = [sys.executable, "-m", "drive_link.cli", "--host", "127.0.0.1"]
    cmd += ["--port", str(hub_drive.port), "--json", "status"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout)["node_id"] == 1
    out, err = io.StringIO(), io.StringIO()
    argv = ["--port", str(hub_drive.port), "read", "device_type", "--host", "127.0.0.1", "--json"]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(argv)
    assert rc == 0, err.getvalue()
    assert json.loads(out.getvalue()) == {"device_type": 0x00020192}
    # a bad option before the command is still a one-line usage error
    p = subprocess.run(
        [sys.executable, "-m", "drive_link.cli", "--node", "x", "status"],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert p.returncode == 7 and "invalid int value" in one_line_error(p)  # a value: 7
