"""``virtual-drive hub`` as a real process: join line, traffic, clean exit on signals, bad input."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time

import can
import pytest

from virtual_drive.cli import main
from virtual_drive.hub import Hub

pytestmark = pytest.mark.timeout(40)

CMD = [sys.executable, "-m", "virtual_drive.cli"]
JOIN_RE = re.compile(
    r'can\.Bus\(interface="socketcand", host="127\.0\.0\.1", port=(\d+), '
    r'channel="vcan0", tcp_tune=True\)'
)


def _start(*args: str) -> tuple[subprocess.Popen, str]:
    proc = subprocess.Popen(
        [*CMD, "hub", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    line = proc.stdout.readline().strip()
    m = JOIN_RE.fullmatch(line)
    assert m, (line, proc.stderr.read() if proc.poll() is not None else "")
    return proc, line


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_hub_command_serves_and_exits_cleanly_on_signal(sig):
    proc, line = _start("--port", "0", "--bitrate", "500000")
    try:
        # the printed line is literally what a user runs
        a = eval(line, {"can": can})
        b = eval(line, {"can": can})
        time.sleep(Hub.handshake_hold_s + 0.05)
        a.send(
            can.Message(
                arbitration_id=0x601, data=[0x40, 0, 0x10, 0, 0, 0, 0, 0], is_extended_id=False
            )
        )
        m = b.recv(3.0)
        assert m is not None and m.arbitration_id == 0x601 and m.data[0] == 0x40
        a.shutdown()
        b.shutdown()
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    assert "stopped" in err and "1 frames forwarded" in err


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([*CMD, *args], capture_output=True, text=True, timeout=20)


def test_busy_port_is_one_line_error_and_nonzero_exit():
    with Hub(port=0) as hub:
        port = hub.port
        r = _run("hub", "--port", str(port))
    assert r.returncode != 0
    assert r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "already in use" in lines[0] and str(port) in lines[0]


def test_non_loopback_host_exits_nonzero_with_one_line():
    r = _run("hub", "--host", "0.0.0.0")
    assert r.returncode != 0 and r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "127.0.0.1" in lines[0]


@pytest.mark.parametrize(
    "args",
    [
        ["hub", "--host", "192.168.0.2"],
        ["hub", "--drop-rate", "1.5"],
        ["hub", "--delay-ms", "-3"],
        ["hub", "--bitrate", "0"],
        ["hub", "--port", "70000"],
        ["hub", "--port", "abc"],
        ["hub", "--seed", "x"],
        ["hub", "--no-such-option"],
    ],
)
def test_bad_arguments_are_one_line_errors(args, capsys):
    try:
        code = main(args)
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    assert code not in (0, None)
    out, err = capsys.readouterr()
    assert out == ""
    assert len(err.strip().splitlines()) == 1, err
