"""`drive-link replay` follows the SDO writes in the recording before it judges drops, and a
requested output it cannot make is one line and nothing written.

Truth: the loopback hub loses no frame, so a clean recording has no dropped TPDO; the frames
counted per event-timer stretch are checked against the times the test itself wrote the timer."""

from __future__ import annotations

import contextlib
import io
import itertools
import threading
import time

import can
import pytest

from drive_link import cli
from drive_link.link._replay import replay_file
from drive_link.link.drive import Drive
from drive_link.link.record import record_bus

pytestmark = pytest.mark.timeout(120)


@pytest.fixture(scope="module")
def hub(tmp_path_factory):
    from virtual_drive.launch import virtual_bench

    with virtual_bench(nodes=(1,), store_dir=tmp_path_factory.mktemp("store")) as bus:
        yield bus


def test_replay_judges_drops_with_the_event_timer_in_force(hub, tmp_path):
    path = tmp_path / "timers.blf"
    stop = threading.Event()
    box = {}
    rec = threading.Thread(
        target=lambda: box.setdefault(
            "stats", record_bus({"host": "127.0.0.1", "port": hub.port}, path, stop)
        )
    )
    rec.start()
    time.sleep(0.5)
    with Drive.connect(host="127.0.0.1", port=hub.port, node_id=1, heartbeat_ms=None) as d:
        missed0 = int(d.read("tpdo_missed_events.tpdo2"))
        d.nmt("start")
        time.sleep(1.0)  # TPDO2 at its default 1 ms
        d.write("tpdo2_communication.event_timer", 10)
        time.sleep(1.5)  # 100 Hz
        d.write("tpdo2_communication.event_timer", 1)
        time.sleep(1.0)
        d.nmt("pre-operational")
        # periods the drive itself could not send (starved on a busy host; 0x2070, CiA 301's
        # event timer sends no burst to catch up): missing on the bus, but not lost by it
        starved = int(d.read("tpdo_missed_events.tpdo2")) - missed0
    time.sleep(0.3)
    stop.set()
    rec.join(20)
    rep = replay_file(path, node=1)
    s = rep.summary()
    tp = s["tpdo"]["TPDO2"]
    assert s["tpdo_configurations"] >= 3
    assert tp["expected_hz"] == [1000.0, 100.0]
    # the hub loses nothing: a clean recording (allow a host stall or two at this load)
    assert tp["dropped"] <= 0.03 * tp["frames"] + starved, (tp, starved)
    # the 100 Hz stretch is in the file as such (frames of 0x281 between the two writes)
    frames = [m.timestamp for m in can.LogReader(path) if m.arbitration_id == 0x281]
    gaps = sorted(b - a for a, b in itertools.pairwise(frames))
    assert sum(1 for g in gaps if 0.008 < g < 0.013) > 100  # 10 ms apart: ~150 of them


def test_replay_trace_output_without_a_trace_is_one_line_and_nothing_written(hub, tmp_path):
    path = tmp_path / "quiet.log"
    stop = threading.Event()
    th = threading.Thread(
        target=lambda: record_bus({"host": "127.0.0.1", "port": hub.port}, path, stop, 0.5)
    )
    th.start()
    th.join(20)
    out, err = io.StringIO(), io.StringIO()
    csv_out, trace_out = tmp_path / "live.csv", tmp_path / "trace.csv"
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(["replay", str(path), "--csv", str(csv_out), "--trace-csv", str(trace_out)])
    assert rc == 1 and out.getvalue() == ""
    assert err.getvalue().count("\n") == 1 and "--trace-csv cannot be made" in err.getvalue()
    assert not csv_out.exists() and not trace_out.exists()
    # no TPDO in it (the drive is PRE-OPERATIONAL): --csv cannot be made either
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(["replay", str(path), "--csv", str(csv_out)])
    assert rc == 1 and err.getvalue().count("\n") == 1 and "no TPDO of node 1" in err.getvalue()
    assert not csv_out.exists()
