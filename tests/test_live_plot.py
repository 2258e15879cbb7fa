"""`drive-link live --plot`: the terminal plot follows the virtual drive's speed (text frames
compared with the speed the drive reports by SDO), the quick-stop key stops the motor (CiA 402
statusword), and the curses view runs on a pseudo-terminal and quits on `q`."""

from __future__ import annotations

import contextlib
import fcntl
import io
import itertools
import os
import pty
import re
import select
import struct
import subprocess
import sys
import termios
import time

import pytest

from drive_link import cli
from drive_link.cli.live_plot import handle_key, resolve_signals, run_text
from drive_link.link.drive import Drive

pytestmark = pytest.mark.timeout(240)


@pytest.fixture(scope="module")
def drive(hub_drive):
    d = Drive.connect(host="127.0.0.1", port=hub_drive.port, heartbeat_ms=None)
    d.nmt("start")
    try:
        yield d
    finally:
        with contextlib.suppress(Exception):
            d.disable()
        d.close()


def spin(d: Drive, rpm: float, tol: float = 40.0, timeout: float = 20.0) -> float:
    """Enable in speed mode at ``rpm`` and wait until the drive reports it (SDO), rpm."""
    if d.state != "OPERATION ENABLED":
        if d.state == "QUICK STOP ACTIVE":
            d.disable()
        d.set_mode("speed")
        d.set_speed(rpm)
        d.enable()
    else:
        d.set_speed(rpm)
    deadline = time.monotonic() + timeout
    while True:
        v = float(d.read("measurements.speed"))
        if abs(v - rpm) < tol or time.monotonic() > deadline:
            return v
        time.sleep(0.05)


def _now(frame: str, name: str) -> float:
    m = re.search(rf"^{name} \[[^\]]*\]  now (\S+)", frame, re.M)
    assert m, frame
    return float(m.group(1))


def _panel_rows(frame: str, name: str) -> list[str]:
    lines = frame.splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith(f"{name} ["))
    rows = []
    for line in lines[i + 1 :]:
        if "|" not in line[:11] or line[10] != "|":
            break
        rows.append(line[11:])
    return rows


def test_text_frames_follow_the_speed(drive):
    v1 = spin(drive, 1500)
    assert abs(v1 - 1500) < 40, v1
    live = drive.live
    sig = resolve_signals(live, ["speed", "speed_ref"])
    assert sig == ["measurements.speed", "measurements.speed_ref"]
    seen: dict[int, float] = {}
    calls = [0]

    def step_between_frames(dt: float) -> None:
        calls[0] += 1
        if calls[0] == 2:  # before frame 2: down to 300 rpm
            seen[2] = spin(drive, 300)
        time.sleep(dt)
        seen.setdefault(calls[0], float(drive.read("measurements.speed")))

    out = io.StringIO()
    run_text(live, sig, 2, fps=5, seconds=3.0, width=80, height=24, out=out,
             sleep=step_between_frames)
    frames = out.getvalue().split("--- frame ")[1:]
    assert len(frames) == 2
    # the plotted latest value is the speed the drive reports (SDO read at the same moment)
    assert _now(frames[0], "speed") == pytest.approx(seen[1], abs=40)
    assert _now(frames[1], "speed") == pytest.approx(seen[2], abs=40)
    assert _now(frames[1], "speed_ref") == pytest.approx(300, abs=0.5)
    # frame 2 shows the fall: an early column high, the newest sample ('*' last) low
    rows = _panel_rows(frames[1], "speed")
    n = len(rows)
    marks = [(r, c) for r, row in enumerate(rows) for c, ch in enumerate(row) if ch == "*"]
    last_col = max(c for _, c in marks)
    assert min(r for r, c in marks if c == last_col) >= n // 2
    assert any(r <= 1 for r, c in marks if c < last_col)
    assert "dropped " in frames[1] and "TPDO2" in frames[1]


def test_quick_stop_key(drive):
    assert spin(drive, 1200) > 1000
    assert handle_key("x", drive) == (True, None)  # quit only: the motor keeps turning
    assert drive.state == "OPERATION ENABLED"
    quit_, msg = handle_key(" ", drive)
    assert not quit_ and msg and msg.startswith("quick stop: ")
    # CiA 402 statusword: QUICK STOP ACTIVE (x0x0 0111), or already SWITCH ON DISABLED
    # (x1xx 0000) after the stop with quick_stop_option_code 2 (a disable would give SWITCHED ON)
    sw = int(drive.read("statusword"))
    assert sw & 0x6F == 0x07 or sw & 0x4F == 0x40, hex(sw)
    deadline = time.monotonic() + 10
    while abs(float(drive.read("measurements.speed"))) > 50 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert abs(float(drive.read("measurements.speed"))) <= 50
    drive.disable()


def run_here(hub, *args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    argv = [args[0], "--host", "127.0.0.1", "--port", str(hub.port), *args[1:]]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(argv)
    return rc, out.getvalue(), err.getvalue()


def test_cli_frames_and_bad_signal(hub_drive, drive):
    rc, out, err = run_here(
        hub_drive, "live", "--plot", "i_p", "speed", "--frames", "1", "--fps", "20",
        "--width", "70", "--height", "16",
    )
    assert rc == 0, err
    assert "--- frame 1/1" in out and "i_p [A]  now" in out and "speed [rpm]  now" in out
    rc, out, err = run_here(hub_drive, "live", "--plot", "torque", "--frames", "1")
    assert rc == 7 and out == "" and err.count("\n") == 1 and "streamed: " in err
    rc, out, err = run_here(hub_drive, "live", "--plot", "speed", "--fps", "0", "--frames", "1")
    assert rc == 7 and err.count("\n") == 1


def test_curses_view_quits_with_a_quick_stop(hub_drive, drive):
    assert spin(drive, 1000) > 900
    master, slave = pty.openpty()
    fcntl.ioctl(master, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 100, 0, 0))
    cmd = [sys.executable, "-m", "drive_link.cli", "live", "--plot", "speed", "i_p",
           "--host", "127.0.0.1", "--port", str(hub_drive.port)]
    proc = subprocess.Popen(cmd, stdin=slave, stdout=slave, stderr=slave,
                            env={**os.environ, "TERM": "xterm"})
    os.close(slave)
    buf = b""
    try:
        deadline = time.monotonic() + 90  # interpreter start on a busy host
        while b"quick stop and quit" not in buf and time.monotonic() < deadline:
            r, _, _ = select.select([master], [], [], 0.5)
            if r:
                with contextlib.suppress(OSError):
                    buf += os.read(master, 65536)
        assert b"quick stop and quit" in buf and b"speed [rpm]" in buf, buf[-2000:]
        os.write(master, b"q")
        deadline = time.monotonic() + 30
        while proc.poll() is None and time.monotonic() < deadline:
            r, _, _ = select.select([master], [], [], 0.2)
            if r:
                with contextlib.suppress(OSError):
                    buf += os.read(master, 65536)
        assert proc.poll() == 0, buf[-2000:]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(master)
    assert b"quick stop: " in buf  # printed after the view closed
    # CiA 402 quick stop: QUICK STOP ACTIVE (x0x0 0111), then, with quick_stop_option_code 2
    # (the default), SWITCH ON DISABLED (x1xx 0000) once stopped; the motor slows down
    sw = int(drive.read("statusword"))
    assert sw & 0x6F == 0x07 or sw & 0x4F == 0x40, hex(sw)
    assert float(drive.read("measurements.speed")) < 900


@pytest.mark.unit
def test_render_of_a_known_ramp_with_lost_frames():
    """A 1 kHz TPDO carrying a 0 → 1000 rpm ramp over 1 s, 10 frames left out: the panel's
    newest sample is top right, the oldest bottom left, every column at or above the one before,
    the labels are the ramp's ends, and the 10 lost frames are shown."""
    import canopen
    import numpy as np

    from drive_link.cli.live_plot import render
    from drive_link.link._live import LiveStreams, MappedField, TpdoConfig

    cfg = TpdoConfig(2, 0x281, 0xFF, 1, [MappedField("measurements.speed", 0x2040, 5, 0, 32,
                                                     "<f", "rpm")])
    net = canopen.Network()
    live = LiveStreams(net, [cfg], seconds=5)
    lost = set(range(500, 510))
    for k in range(1001):
        if k not in lost:
            net.notify(0x281, bytearray(struct.pack("<f", k)), 1.0 + k / 1000)
    lines = render(live, ["measurements.speed"], seconds=1.0, width=61, height=12)
    assert lines[0] == "speed [rpm]  now 1000  min 0  max 1000"
    rows = [line[11:] for line in lines[1:] if line[10:11] == "|"]
    assert lines[1].startswith("      1000|") and lines[len(rows)].startswith("         0|")
    star = {c: r for r, row in enumerate(rows) for c, ch in enumerate(row) if ch == "*"}
    cols = sorted(star)
    assert star[cols[-1]] == 0 and star[cols[0]] == len(rows) - 1
    assert all(star[a] >= star[b] for a, b in itertools.pairwise(cols))
    assert len(cols) == 50 and np.ptp(cols) == 49  # every column of the 50-wide plot has data
    assert lines[-1].startswith("dropped 10 of 1001")
