"""`drive-link record` at its edges: stopped by SIGTERM/SIGHUP (timeout, kill, systemd) every
format is finished like on Ctrl-C; a format that cannot hold a frame kind says how many it
dropped and why; ``--seconds`` is that long on the bus.

Truth: python-can's own ``LogReader`` reading each file back, and the frames this test itself
put on the bus with python-can (cansend-like)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path

import can
import pytest

from drive_link.link.record import record_bus

pytestmark = pytest.mark.timeout(120)

BIN = Path(sys.executable).parent
FORMATS = (".asc", ".blf", ".log", ".csv", ".trc")


@pytest.fixture(scope="module")
def hub(tmp_path_factory):
    """Hub + one virtual drive (node 1), started OPERATIONAL: its TPDOs (~2,200 frames/s)."""
    from virtual_drive.launch import virtual_bench

    with virtual_bench(nodes=(1,), store_dir=tmp_path_factory.mktemp("store")) as bus:
        with can.Bus(interface="socketcand", host="127.0.0.1", port=bus.port, channel="vcan0") as b:
            b.send(can.Message(arbitration_id=0x000, data=[0x01, 1], is_extended_id=False))
            time.sleep(0.3)
        yield bus


def test_every_format_is_finished_on_sigterm_and_sighup(hub, tmp_path):
    procs = {}
    for ext in FORMATS:
        path = tmp_path / f"bus{ext}"
        cmd = [str(BIN / "drive-link"), "record", str(path), "--host", "127.0.0.1",
               "--port", str(hub.port), "--json"]  # fmt: skip
        procs[ext] = (path, subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE))
    deadline = time.monotonic() + 60
    while not all(p.exists() for p, _ in procs.values()) and time.monotonic() < deadline:
        time.sleep(0.1)
    time.sleep(2.0)  # a few thousand frames each
    for ext, (_path, proc) in procs.items():
        proc.send_signal(signal.SIGHUP if ext == ".log" else signal.SIGTERM)
    for ext, (path, proc) in procs.items():
        out, err = proc.communicate(timeout=60)
        assert proc.returncode == 0, (ext, err.decode())
        res = json.loads(out)
        assert res["interrupted"] is True
        back = list(can.LogReader(path))
        assert res["frames"] == len(back) > 1000, ext  # every frame counted is in the file
        # the tail is there: the last frame read back is from the last moments before the signal
        assert back[-1].timestamp - back[0].timestamp > 1.0, ext


def test_formats_count_what_they_cannot_hold(tmp_path):
    """.trc holds no RTR, error or FD frames and .csv has no FD flag (python-can 4.6's writers):
    they are counted as dropped with the reason; .log and .asc hold them all."""
    ch = f"rec-{uuid.uuid4().hex}"
    sent = [
        can.Message(arbitration_id=0x181, data=b"\x01\x02", is_extended_id=False),
        can.Message(arbitration_id=0x181, is_remote_frame=True, dlc=2, is_extended_id=False),
        can.Message(arbitration_id=0x20000080, is_error_frame=True, dlc=8, data=bytes(8)),
        can.Message(arbitration_id=0x123, is_fd=True, data=bytes(range(12)), is_extended_id=False),
    ]
    stats, stop = {}, threading.Event()
    threads = [
        threading.Thread(
            target=lambda e=e: stats.__setitem__(
                e, record_bus({"interface": "virtual", "channel": ch}, tmp_path / f"x{e}", stop)
            )
        )
        for e in (".trc", ".csv", ".log", ".asc")
    ]
    for th in threads:
        th.start()
    time.sleep(0.5)
    with can.Bus(interface="virtual", channel=ch) as tx:
        for _ in range(3):
            for m in sent:
                tx.send(m)
    time.sleep(0.5)
    stop.set()
    for th in threads:
        th.join(10)
    trc, csv_, log = stats[".trc"], stats[".csv"], stats[".log"]
    assert trc.frames == 3 and len(list(can.LogReader(tmp_path / "x.trc"))) == 3
    assert sorted(trc.dropped.values()) == [3, 3, 3]
    assert {w.split(" holds no ")[1].split()[0] for w in trc.dropped} == {"remote", "error", "CAN"}
    assert csv_.frames == 9 and list(csv_.dropped.values()) == [3]
    assert "FD" in next(iter(csv_.dropped))
    for e in (".log", ".asc"):
        assert stats[e].frames == 12 and stats[e].dropped == {}
        assert len(list(can.LogReader(tmp_path / f"x{e}"))) == 12
    assert log.error_frames == 3


def test_seconds_is_that_long_on_the_bus(hub, tmp_path):
    path = tmp_path / "two.blf"
    t0 = time.monotonic()
    out = subprocess.run(
        [str(BIN / "drive-link"), "record", str(path), "--seconds", "2", "--host", "127.0.0.1",
         "--port", str(hub.port), "--json"],
        capture_output=True, text=True, timeout=60, env={**os.environ},
    )  # fmt: skip
    wall = time.monotonic() - t0
    assert out.returncode == 0, out.stderr
    back = list(can.LogReader(path))
    span = back[-1].timestamp - back[0].timestamp
    assert 1.5 <= span <= 2.5, span
    assert json.loads(out.stdout)["seconds"] == pytest.approx(2.0, abs=0.5)
    assert wall < 2.0 + 28.0  # the command: start-up (seconds at load 20), the 2 s, closing
