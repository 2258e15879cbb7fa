"""`drive-link record` / `replay`: the virtual drive's bus recorded to .asc, .blf and .log at the
same time, each file read back independently with python-can's LogReader, and compared with
what the host's own live view (another socket on the hub) decoded meanwhile; the replay's
decoded TPDOs and reassembled trace upload against the drive's."""

from __future__ import annotations

import binascii
import collections
import contextlib
import csv
import io
import json
import struct
import threading
import time

import can
import numpy as np
import pytest

from drive_link import cli
from drive_link.link._replay import SdoFollower, replay_file
from drive_link.link.drive import Drive
from drive_link.link.record import record_bus

pytestmark = pytest.mark.timeout(180)

FORMATS = ("asc", "blf", "log")
#: TPDO2 of node 1 (contracts §1): measurements.i_p, measurements.speed as two REAL32.
TPDO2 = 0x281


@pytest.fixture(scope="module")
def session(hub_drive, tmp_path_factory):
    """Three recorders running while a Drive spins the motor up and captures a trace."""
    d = tmp_path_factory.mktemp("rec")
    paths = {ext: d / f"bus.{ext}" for ext in FORMATS}
    stop = threading.Event()
    stats: dict = {}
    bus = {"host": "127.0.0.1", "port": hub_drive.port}
    threads = [
        threading.Thread(target=lambda e=e: stats.__setitem__(e, record_bus(bus, paths[e], stop)))
        for e in FORMATS
    ]
    for th in threads:
        th.start()
    time.sleep(0.5)  # the recorders' sockets are open before the first frame of interest
    drive = Drive.connect(host="127.0.0.1", port=hub_drive.port, heartbeat_ms=None)
    try:
        drive.nmt("start")
        device_name = drive.read("manufacturer_device_name")  # > 4 bytes: segmented upload
        live = drive.live
        drive.set_mode("speed")
        drive.set_speed(800)
        drive.enable()
        time.sleep(1.0)
        trace = drive.trace.capture(["i_p", "speed"], divider=10, length=300)
        time.sleep(0.2)
        _t, v_live = live.streams()["measurements.speed"]
        frames_live = live.stats["tpdo"]["TPDO2"]["frames"]
        drive.disable()
    finally:
        drive.close()
    time.sleep(0.3)
    stop.set()
    for th in threads:
        th.join(30)
    return {
        "paths": paths,
        "stats": stats,
        "trace": trace,
        "speed_live": v_live.astype(np.float32),
        "frames_live": frames_live,
        "device_name": device_name,
        "overrun": hub_drive.stats.frames_overrun,
    }


def _speeds(msgs: list[can.Message]) -> np.ndarray:
    return np.array(
        [struct.unpack_from("<f", bytes(m.data), 4)[0] for m in msgs if m.arbitration_id == TPDO2],
        dtype=np.float32,
    )


def _contains_run(haystack: np.ndarray, needle: np.ndarray) -> bool:
    """``needle`` appears in ``haystack`` as a contiguous run (exact values)."""
    if len(needle) == 0:
        return False
    for i in np.flatnonzero(haystack == needle[0]):
        if i + len(needle) <= len(haystack) and np.array_equal(
            haystack[i : i + len(needle)], needle
        ):
            return True
    return False


@pytest.mark.parametrize("ext", FORMATS)
def test_recording_reads_back(session, ext):
    path = session["paths"][ext]
    st = session["stats"][ext]
    # the hub delivered every frame to every client (no receiver fell 4 MiB behind)
    assert session["overrun"] == 0
    msgs = list(can.LogReader(path))  # python-can's reader, independent of the recorder
    assert len(msgs) == st.frames > 0
    per_id = collections.Counter(m.arbitration_id for m in msgs if not m.is_error_frame)
    assert per_id == st.per_id
    # CiA 301/402 traffic of node 1: TPDO1-4, SDO on both servers, NMT, the heartbeat
    for cob in (0x000, 0x181, 0x281, 0x381, 0x481, 0x581, 0x601, 0x681, 0x6B1, 0x701):
        assert per_id[cob] > 0, f"no frame 0x{cob:03X} in {path.name}"
    # every TPDO2 frame the host's live view decoded (its own socket) is in the file, in order
    assert per_id[TPDO2] >= session["frames_live"]
    assert _contains_run(_speeds(msgs), session["speed_live"])
    ts = np.array([m.timestamp for m in msgs])
    assert np.all(np.diff(ts) >= -1e-6) and 1.5 < ts[-1] - ts[0] < 60


def test_formats_hold_the_same_frames(session):
    seqs = {
        e: [(m.arbitration_id, bytes(m.data)) for m in can.LogReader(session["paths"][e])]
        for e in FORMATS
    }
    # the recorders started and stopped a few frames apart: compare the common middle part
    ref = seqs["log"][50:-50]
    for e in ("asc", "blf"):
        s = seqs[e]
        starts = [i for i, x in enumerate(s) if x == ref[0]]  # heartbeats repeat: try each
        assert any(s[i : i + len(ref)] == ref for i in starts), e


@pytest.mark.parametrize("ext", ["blf", "log"])
def test_replay_matches_the_drive(session, ext):
    rep = replay_file(session["paths"][ext], node=1)
    _t, speed = rep.live.streams()["measurements.speed"]
    assert _contains_run(speed.astype(np.float32), session["speed_live"])
    summary = rep.summary()
    assert summary["tpdo"]["TPDO2"]["frames"] == session["stats"][ext].per_id[TPDO2]
    assert summary["signals"]["measurements.speed"]["max"] == pytest.approx(
        float(session["speed_live"].max()), rel=0.2
    )
    # the trace upload (SDO block upload of 0x2102 on the second server) reassembled
    up = [u for u in rep.uploads if (u.index, u.subindex) == (0x2102, 0)]
    assert len(up) == 1 and up[0].complete and up[0].crc_ok is True
    seg = [u for u in rep.uploads if u.kind == "segmented" and (u.index, u.subindex) == (0x1008, 0)]
    assert [u.data.decode() for u in seg] == [session["device_name"]]
    tr = session["trace"]
    assert len(rep.traces) == 1
    got = rep.traces[0]
    assert got.divider == tr.divider == 10 and got.trigger_index == tr.trigger_index
    for name, v in tr.signals.items():
        assert np.array_equal(got.signals[name], v), name


def run_here(hub, *args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    argv = [args[0], "--host", "127.0.0.1", "--port", str(hub.port), *args[1:]]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(argv)
    return rc, out.getvalue(), err.getvalue()


def test_record_and_replay_commands(hub_drive, session, tmp_path):
    path = tmp_path / "short.asc"
    rc, out, err = run_here(hub_drive, "record", str(path), "--seconds", "0.5", "--json")
    assert rc == 0, err
    res = json.loads(out)
    # the drive's heartbeat (0x701, every 100 ms by default) is on the bus all the time
    assert res["frames"] == len(list(can.LogReader(path))) and res["frames_per_id"]["0x701"] >= 2
    csv_out, trace_out = tmp_path / "live.csv", tmp_path / "trace.csv"
    rc, out, err = run_here(
        hub_drive, "replay", str(session["paths"]["log"]), "--csv", str(csv_out),
        "--trace-csv", str(trace_out), "--plot", "speed", "--width", "60", "--height", "12",
    )
    assert rc == 0, err
    assert "TPDO2 0x281" in out and "speed [rpm]  now" in out
    with open(csv_out) as fh:
        rows = list(csv.reader(fh))
    assert rows[0][0] == "t [s]" and "measurements.speed [rpm]" in rows[0]
    col = rows[0].index("measurements.speed [rpm]")
    speeds = np.array([float(r[col]) for r in rows[1:]], dtype=np.float32)
    assert _contains_run(speeds, session["speed_live"])
    with open(trace_out) as fh:
        rows = list(csv.reader(fh))
    col = rows[0].index("measurements.speed [rpm]")
    trace_speed = np.array([float(r[col]) for r in rows[1:]], dtype=np.float32)
    assert np.array_equal(trace_speed, session["trace"].signals["measurements.speed"])
    png = tmp_path / "trace.png"
    rc, out, err = run_here(hub_drive, "replay", str(session["paths"]["blf"]), "--trace-png",
                            str(png), "--json")
    assert rc == 0, err
    assert json.loads(out)["trace_png"] == [str(png)]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bad_input_one_line_nothing_written(hub_drive, tmp_path):
    for name, needle in (("x.xyz", "unknown log format"), ("x", "unknown log format")):
        rc, out, err = run_here(hub_drive, "record", str(tmp_path / name), "--seconds", "0.1")
        assert rc == 7 and out == "" and err.count("\n") == 1 and needle in err, err
        assert not (tmp_path / name).exists()
    try:
        import asammdf  # noqa: F401
    except ImportError:
        rc, out, err = run_here(hub_drive, "record", str(tmp_path / "x.mf4"), "--seconds", "0.1")
        assert rc == 7 and "asammdf" in err and err.count("\n") == 1
        assert not (tmp_path / "x.mf4").exists()
    rc, out, err = run_here(hub_drive, "record", str(tmp_path / "z.asc"), "--seconds", "inf")
    assert rc == 7 and err.count("\n") == 1 and not (tmp_path / "z.asc").exists()  # value
    # no hub there: bus error (3), no file
    rc = cli.main(["record", str(tmp_path / "y.asc"), "--host", "127.0.0.1", "--port", "1"])
    assert rc == 3 and not (tmp_path / "y.asc").exists()
    rc, out, err = run_here(hub_drive, "replay", str(tmp_path / "missing.asc"))
    assert rc == 7 and "no such file" in err and err.count("\n") == 1
    junk = tmp_path / "junk.asc"
    junk.write_text("this is not\na vector log\n")
    rc, out, err = run_here(hub_drive, "replay", str(junk))
    assert rc == 7 and err.count("\n") == 1 and "Traceback" not in err


def _segments(data: bytes) -> list[bytes]:
    return [data[i : i + 7] for i in range(0, len(data), 7)]


@pytest.mark.unit
def test_block_upload_reassembly_with_losses():
    """CiA 301 block upload built frame by frame: a segment the client lost (it acknowledges
    the last one in sequence, leftovers of the old sub-block follow, the server sends the rest
    as a new sub-block from 1), a resent acknowledgement (drive_link's number in byte 3)."""
    data = bytes(range(256)) * 2  # 512 bytes: 74 segments, the last with 1 byte used
    segs = _segments(data)
    rx, tx = 0x681, 0x6B1
    f = SdoFollower(rx, tx)
    t = [0.0]

    def c(*b: int) -> None:
        f.feed(rx, bytes(b).ljust(8, b"\0"), t[0])

    def s(payload: bytes) -> None:
        f.feed(tx, payload.ljust(8, b"\0"), t[0])

    c(0xA4, 0x02, 0x21, 0x00, 40)  # initiate 0x2102:00, CRC supported, blksize 40
    s(bytes([0xC6, 0x02, 0x21, 0x00]) + struct.pack("<I", len(data)))
    c(0xA3)  # start
    pos = 0
    for seq in range(1, 41):  # sub-block 1: the client lost segment 13 (the recording has it)
        s(bytes([seq]) + segs[pos + seq - 1])
        if seq == 14:  # the gap seen: ackseq 12 at once; 15..40 are leftovers
            c(0xA2, 12, 40, 1)
    pos += 12  # the server goes on from segment 13, numbered from 1
    for seq in range(1, 41):
        if seq == 20:
            c(0xA2, 12, 40, 1)  # the same acknowledgement again (late answer): ignored
        s(bytes([seq]) + segs[pos + seq - 1])
    c(0xA2, 40, 40, 2)
    pos += 40
    left = len(segs) - pos
    for seq in range(1, left + 1):
        s(bytes([seq | (0x80 if seq == left else 0)]) + segs[pos + seq - 1])
    c(0xA2, left, 40, 3)
    unused = 7 * len(segs) - len(data)
    crc = binascii.crc_hqx(data, 0)
    s(bytes([0xC1 | unused << 2, crc & 0xFF, crc >> 8]))
    c(0xA1)
    assert len(f.uploads) == 1
    u = f.uploads[0]
    assert u.data == data and u.size == len(data) and u.crc_ok is True and u.complete


def test_record_until_ctrl_c(hub_drive, tmp_path):
    """Without --seconds the recording runs until Ctrl-C (SIGINT in the main thread), then
    the file is closed properly and the summary printed (exit 0).

    Ctrl-C is SIGINT with Python's own handler, as in a user's terminal: a test run started in
    the background of a non-interactive shell (``cmd &``) inherits SIGINT ignored, and
    ``_thread.interrupt_main`` then does nothing (the recording ran into the 180 s timeout)."""
    import _thread
    import signal

    path = tmp_path / "ctrl_c.log"
    gone = threading.Event()

    def ctrl_c_once_recording() -> None:
        deadline = time.monotonic() + 60
        while not path.exists() and not gone.is_set() and time.monotonic() < deadline:
            time.sleep(0.05)
        if not gone.wait(1.5):
            _thread.interrupt_main()

    th = threading.Thread(target=ctrl_c_once_recording, daemon=True)
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    th.start()
    try:
        rc, out, err = run_here(hub_drive, "record", str(path), "--json")
    finally:
        gone.set()
        th.join(5)
        signal.signal(signal.SIGINT, old)
    assert rc == 0, err
    res = json.loads(out)
    assert res["interrupted"] is True and 1.0 < res["seconds"] < 60
    msgs = list(can.LogReader(path))
    assert len(msgs) == res["frames"] and res["frames_per_id"]["0x701"] >= 5  # 100 ms heartbeat
