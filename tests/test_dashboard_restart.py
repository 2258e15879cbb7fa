"""`drive-dashboard` starts again at once after Ctrl-C on the same ports, also when clients were
connected (issue 23): a port is busy only while something listens on it, not while the closed
connections of the last run wait in TIME_WAIT; and a closed stdout (`| true`) does not stop it.

Oracle: the kernel's own view of the ports (/proc/net/tcp: TIME_WAIT entries on the ports, no
listener) and the installed console script coming up (its ``open http://`` line and an HTTP
answer on both ports).
"""

from __future__ import annotations

import http.client
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from dashboard.browser import free_port

pytestmark = pytest.mark.timeout(180)

BIN = Path(sys.executable).parent
ENV = {k: v for k, v in os.environ.items() if not k.startswith(("DRIVE_LINK_", "CAN_"))}
TIME_WAIT, LISTEN = "06", "0A"  # /proc/net/tcp states


def _start(api: int, gui: int) -> tuple[subprocess.Popen, str]:
    """The console script on these ports; (process, its first stdout line or its error)."""
    p = subprocess.Popen(
        [str(BIN / "drive-dashboard"), "--virtual", "--no-3d", "--port", str(api),
         "--gui-port", str(gui)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV,
    )  # fmt: skip
    line = p.stdout.readline()
    if not line:
        p.wait(30)
        line = p.stderr.read()
    return p, line


def _stop(p: subprocess.Popen) -> None:
    if p.poll() is None:
        p.terminate()
    try:
        p.wait(20)
    except subprocess.TimeoutExpired:
        p.kill()
        p.wait()


def _tcp_states(port: int) -> set[str]:
    """States of the IPv4 sockets whose local port is ``port`` (kernel's /proc/net/tcp)."""
    out = set()
    for row in Path("/proc/net/tcp").read_text().splitlines()[1:]:
        f = row.split()
        if int(f[1].split(":")[1], 16) == port:
            out.add(f[3])
    return out


def _get(port: int, path: str, conn: http.client.HTTPConnection | None = None) -> int:
    conn = conn or http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    conn.request("GET", path, headers={"Connection": "keep-alive"})
    r = conn.getresponse()
    r.read()
    return r.status


def test_the_dashboard_restarts_at_once_on_the_same_ports_after_ctrl_c():
    api, gui = free_port(), free_port()
    p, line = _start(api, gui)
    try:
        assert line.startswith(f"open http://127.0.0.1:{gui}/"), line
        # clients that stay connected (HTTP keep-alive on both ports): the server closes them
        # when it stops, so their server side waits in TIME_WAIT on the very ports
        kept = [http.client.HTTPConnection("127.0.0.1", port, timeout=30) for port in (api, gui)]
        assert _get(api, "/api/state", kept[0]) == 200
        assert _get(gui, "/", kept[1]) == 200
        p.send_signal(signal.SIGINT)  # Ctrl-C
        assert p.wait(30) == 0
    finally:
        _stop(p)
    for c in kept:  # the clients see the server's close and close too (as a browser does)
        c.close()
    states = _tcp_states(api) | _tcp_states(gui)
    assert LISTEN not in states and TIME_WAIT in states, states  # what made the old probe fail
    # again at once, on the same ports; its stdout this time a pipe whose reader is gone
    # (`drive-dashboard --virtual | true`): the URL lines meet a closed pipe, it serves on
    r, w = os.pipe()
    os.close(r)
    p = subprocess.Popen(
        [str(BIN / "drive-dashboard"), "--virtual", "--no-3d", "--port", str(api),
         "--gui-port", str(gui)],
        stdout=w, stderr=subprocess.PIPE, text=True, env=ENV,
    )  # fmt: skip
    os.close(w)
    try:
        deadline = time.monotonic() + 90
        status = None
        while time.monotonic() < deadline and p.poll() is None and status != 200:
            try:
                status = _get(api, "/api/state")
            except OSError:
                time.sleep(0.3)
        assert status == 200 and _get(gui, "/") == 200, (p.poll(), p.poll() and p.stderr.read())
        p.send_signal(signal.SIGINT)
        assert p.wait(30) == 0
        err = p.stderr.read()
        assert "Traceback" not in err and "Broken pipe" not in err, err
    finally:
        _stop(p)


def test_a_port_something_listens_on_is_still_busy():
    """The other half of the rule: a listener makes the port busy (one line, exit 2)."""
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        busy = s.getsockname()[1]
        p = subprocess.run(
            [str(BIN / "drive-dashboard"), "--interface", "virtual", "--channel", "restart-test",
             "--gui-port", str(busy), "--port", str(free_port())],
            capture_output=True, text=True, env=ENV, timeout=60,
        )  # fmt: skip
    assert p.returncode == 2 and "busy" in p.stderr and len(p.stderr.strip().splitlines()) == 1

