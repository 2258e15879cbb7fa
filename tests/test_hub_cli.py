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


@pytest.mark.unit
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


@pytest.mark.unit
@pytest.mark.parametrize("nodes", ["0-3", "1-200", "3-1", "x", "1,1"])
def test_bad_node_lists_are_one_line_errors(nodes, capsys):
    code = main(["hub", "--port", "0", "--nodes", nodes])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and "node" in err, err


@pytest.mark.timeout(120)
def test_hub_with_two_nodes_is_one_command():
    """`virtual-drive hub --nodes 1-2`: both drives answer SDO on their own node-ID (CiA 301:
    server 0x600 + N, reply 0x580 + N; 0x1000 device type 0x00020192 of this drive), and SIGTERM
    stops the hub and both children."""
    proc = subprocess.Popen(
        [*CMD, "hub", "--port", "0", "--nodes", "1-2"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = proc.stdout.readline().strip()
        assert JOIN_RE.fullmatch(line), (line, proc.stderr.read() if proc.poll() else "")
        ready = [proc.stdout.readline() for _ in range(2)]
        pids = [int(re.search(r"pid (\d+)", r).group(1)) for r in ready]
        assert [re.search(r"node (\d+)", r).group(1) for r in ready] == ["1", "2"]
        bus = eval(line, {"can": can})
        try:
            time.sleep(Hub.handshake_hold_s + 0.05)
            for node in (1, 2):
                bus.send(
                    can.Message(
                        arbitration_id=0x600 + node,
                        data=[0x40, 0x00, 0x10, 0, 0, 0, 0, 0],
                        is_extended_id=False,
                    )
                )
                deadline = time.monotonic() + 10
                reply = None
                while time.monotonic() < deadline:
                    m = bus.recv(1.0)
                    if m is not None and m.arbitration_id == 0x580 + node:
                        reply = m
                        break
                assert reply is not None, f"node {node} did not answer"
                assert bytes(reply.data) == bytes([0x43, 0, 0x10, 0, 0x92, 0x01, 0x02, 0x00])
        finally:
            bus.shutdown()
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    for pid in pids:  # the children are gone too
        assert not _alive(pid), pid


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False
