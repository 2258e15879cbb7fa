"""`drive-link shell` against a `virtual-drive run` child on the loopback hub: lines from a pipe
(the one-shot commands on one session, one-line errors, exit codes), and on a pseudo-terminal
(readline TAB completion of object names, the history file)."""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import pty
import select
import subprocess
import sys
import time

import pytest

from drive_link import cli
from drive_link.cli.shell import Shell
from drive_link.link.drive import Drive

pytestmark = pytest.mark.timeout(200)

#: CiA 301 0x1016 entry the session sets: host node-ID 0x7F in bits 23..16, 1000 ms in 15..0.
CONSUMER_ENTRY = (0x7F << 16) | 1000


def _cmd(hub, *extra: str) -> list[str]:
    return [sys.executable, "-m", "drive_link.cli", "shell", "--host", "127.0.0.1",
            "--port", str(hub.port), *extra]


def run_here(hub, *args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    argv = [args[0], "--host", "127.0.0.1", "--port", str(hub.port), *args[1:]]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(argv)
    return rc, out.getvalue(), err.getvalue()


def run_shell(hub, text: str, monkeypatch, *extra: str) -> tuple[int, str, str]:
    """`drive-link shell` via cli.main in this process with ``text`` as its (non-tty) stdin;
    the drive is the `virtual-drive run` child behind the hub."""
    monkeypatch.setattr(sys, "stdin", io.StringIO(text))
    return run_here(hub, "shell", *extra)


def test_lines_from_a_pipe(hub_drive, monkeypatch):
    lines = [
        "# a comment, then a blank line",
        "",
        "read consumer_heartbeat_time.consumer_1 --json",
        "bogus",
        "read no_such_object",
        "read statusword --node 5",
        "shell",
        "set-current 2 --enable --json",
        "read measurements.i_p --json",
        "disable --json",
        "exit 3",
        "read statusword --json",  # after exit: never runs
    ]
    rc, stdout, stderr = run_shell(hub_drive, "\n".join(lines) + "\n", monkeypatch)
    assert rc == 3, stderr
    assert "Traceback" not in stderr
    errors = stderr.splitlines()
    assert len(errors) == 4 and all(e.startswith("drive-link: error: ") for e in errors), errors
    assert "unknown command 'bogus'" in errors[0]
    assert "no_such_object" in errors[1]
    assert "node 1" in errors[2] and "another shell" in errors[2]
    assert "already in a shell" in errors[3]
    out = [json.loads(line) for line in stdout.splitlines()]
    # the session's supervision: the drive watches this shell's heartbeat (set at connect,
    # still there lines later: one Drive for the whole session)
    assert out[0] == {"consumer_heartbeat_time.consumer_1": CONSUMER_ENTRY}
    assert out[1]["state"] == "OPERATION ENABLED"
    assert out[2]["measurements.i_p"] == pytest.approx(2.0, abs=0.5)
    assert out[3]["state"] == "SWITCHED ON"
    assert len(out) == 4  # the line after `exit` did not run
    # closing the session took the supervision away again
    rc, stdout, _ = run_here(hub_drive, "read", "consumer_heartbeat_time.consumer_1", "--json")
    assert rc == 0 and json.loads(stdout) == {"consumer_heartbeat_time.consumer_1": 0}


def test_last_failing_line_gives_the_exit_code(hub_drive, monkeypatch):
    rc, stdout, stderr = run_shell(
        hub_drive, "write current_controller.L_c 1e-3\n", monkeypatch, "--no-heartbeat"
    )
    # the same refusal and exit code as the one-shot command (7: invalid value), then EOF
    assert rc == 7 and stderr.count("\n") == 1 and "Traceback" not in stderr
    assert stdout == ""
    rc, stdout, stderr = run_shell(hub_drive, "read bogus --json\n", monkeypatch, "--no-heartbeat")
    assert rc == 7 and stderr == ""  # an unknown object: invalid value, as the one-shot command
    assert json.loads(stdout)["exit_code"] == 7 and "bogus" in json.loads(stdout)["error"]


@pytest.fixture(scope="module")
def shell(hub_drive):
    ap = cli.build_parser()
    args = ap.parse_args(["shell", "--host", "127.0.0.1", "--port", str(hub_drive.port)])
    cli._merge_bus(args)
    d = Drive.connect(host="127.0.0.1", port=hub_drive.port, heartbeat_ms=None)
    try:
        yield Shell(d, args)
    finally:
        d.close()


def test_completion_candidates(shell):
    assert {"read", "record", "replay", "restore"} <= set(shell.candidates("re"))
    assert "shell" not in shell.candidates("sh")
    assert shell.candidates("read current_controller.L_") == ["current_controller.L_c"]
    # every object of the table is offered, and only objects
    assert set(shell.candidates("read ")) == set(shell.drive.table.names())
    assert shell.candidates("read statusword current_controller.R_") == ["current_controller.R_c"]
    assert shell.candidates("write current_controller.L_c ") == []  # the value
    assert shell.candidates("mode ") == ["current", "speed", "torque"]
    assert shell.candidates("nmt re") == ["reset-communication", "reset-node"]
    assert "--json" in shell.candidates("status --j")
    assert shell.candidates("help sta") == ["status"]
    assert shell.candidates("bogus ") == []


def _read_until(fd: int, needle: bytes, timeout: float) -> bytes:
    buf = b""
    deadline = time.monotonic() + timeout
    while needle not in buf:
        left = deadline - time.monotonic()
        if left <= 0:
            raise AssertionError(f"{needle!r} not seen in {buf[-2000:]!r}")
        r, _, _ = select.select([fd], [], [], min(left, 0.5))
        if r:
            try:
                chunk = os.read(fd, 4096)
            except OSError:
                break
            if not chunk:
                break
            buf += chunk
    return buf


def test_terminal_completion_and_history(hub_drive, tmp_path):
    """On a pty: TAB completes an object name (readline), Ctrl-D ends, the history is kept."""
    history = tmp_path / "history"
    master, slave = pty.openpty()
    env = {**os.environ, "HOME": str(tmp_path), "TERM": "dumb", "DRIVE_LINK_HISTORY": str(history)}
    proc = subprocess.Popen(
        _cmd(hub_drive, "--no-heartbeat"), stdin=slave, stdout=slave, stderr=slave, env=env
    )
    os.close(slave)
    try:
        _read_until(master, b"drive-link[1]> ", 90)  # interpreter start on a busy host
        os.write(master, b"read current_controller.L_\t--json\r")
        out = _read_until(master, b"drive-link[1]> ", 30).decode()
        answer = next(line for line in out.splitlines() if line.startswith("{"))
        assert json.loads(answer)["current_controller.L_c"] == pytest.approx(14.8e-6, rel=1e-6)
        os.write(master, b"\x04")  # Ctrl-D
        assert proc.wait(timeout=30) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(master)
    assert "read current_controller.L_c --json" in history.read_text().splitlines()


def test_help_lists_every_command(shell, capsys):
    assert shell.run_line("help") == 0
    text = capsys.readouterr().out
    for name in ("read", "write", "record", "replay", "live", "exit"):
        assert f"\n  {name} " in text
    assert shell.run_line("help nosuch") == 2
    assert shell.run_line("read --help") == 0  # argparse's help, the shell goes on
    assert "positional arguments" in capsys.readouterr().out


def test_namespace_inherits_the_shell_options(shell):
    args = shell._parse(["status"])
    assert isinstance(args, argparse.Namespace)
    assert (args.host, args.port, args.node) == ("127.0.0.1", shell.args.port, 1)
