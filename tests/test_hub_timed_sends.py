"""Frames sent with their bus time (``< sendat >``): the hub's element and the virtual drive
that runs its ticks in batches (issue 11).

Truths: a CAN bus carries each frame when its sender puts it there (an 8-byte classical frame
at 1 Mbit/s takes 111-135 bit times, 47 for a 0-byte one); a TPDO with a 1 ms event timer is on
the bus every 1 ms with the value of that instant (CiA 301 event-driven PDO); a profile-velocity
ramp of 1000 rpm/s moves the speed reference by 1 rpm per ms (CiA 402, 0x6083). The receiver is
python-can's own ``socketcand`` interface, which takes the hub's frame times as they are.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import socket
import statistics
import struct
import threading
import time
from collections.abc import Iterator

import can
import pytest
from conftest import RunQueueProbe, min_rate, recv_frames

from virtual_drive.hub import Hub
from virtual_drive.hub_protocol import (
    CommandSplitter,
    ProtocolError,
    parse_sendat_fields,
    scan_sendats,
)
from virtual_drive.node.drive_node import TIMED_PERIOD, VirtualDrive
from virtual_drive.node.hub_bus import HubBus, format_send, format_sendat

pytestmark = pytest.mark.timeout(120)

#: run-queue wait (s/s) of this process (drive, hub and receiver threads) below which the
#: frames' bus times show the drive's own timing: a hub thread kept waiting more than its
#: back-dating window puts a backlog back to back (hub_protocol.SENDAT_MAX_BACKDATE_S)
CLEAN_WAIT = 0.25


def _skip_if_starved(probe: RunQueueProbe, what: str) -> None:
    if probe.wait >= CLEAN_WAIT:
        pytest.skip(f"{what} not observable: {probe!r}")

_WALL = time.time() - time.monotonic()
TOL_MS = 3e-3  #: µs stamps at both ends (the sender states µs, the hub stamps µs), ms


@pytest.mark.unit
def test_sendat_elements_round_trip_through_both_parsers():
    cases = [
        (0x181, b"", False),
        (0x281, bytes(range(8)), False),
        (0x7FF, b"\xff\x00\x10", False),
        (0x1ABCDEF0, b"\x01\x02", True),
    ]
    at = time.monotonic() - 0.003
    chunk = b"".join(format_sendat(at, i, d, e) for i, d, e in cases)
    frames, used = scan_sendats(chunk)
    assert used == len(chunk)
    assert [(i, d, e) for _, i, d, e in frames] == cases
    for stamp, *_ in frames:
        # (time.time() - time.monotonic() read here and in hub_bus differ by the µs between
        # the two clock reads of each: a preemption there moved it by 2.8 µs once)
        assert stamp == pytest.approx(at + _WALL, abs=100e-6)
    # the generic splitter sees the same elements, and the full parser agrees
    words = CommandSplitter().feed(chunk)
    assert [parse_sendat_fields(w)[1:] for w in words] == cases
    # a plain send is not a sendat: the fast path stops there, the caller goes on
    assert scan_sendats(format_send(0x181, b"\x01") + chunk) == ([], 0)
    for bad in (
        ["sendat", "12.5", "181", "0"],  # usecs must have 6 digits
        ["sendat", "x.000001", "181", "0"],
        ["sendat", "1.000001", "800", "0"],  # standard id above 7FF
        ["sendat", "1.000001", "181", "2", "01"],  # length 2, one byte
    ):
        with pytest.raises(ProtocolError):
            parse_sendat_fields(bad)


def _raw_client(port: int) -> socket.socket:
    s = socket.create_connection(("127.0.0.1", port), timeout=5)
    buf = b""
    for send, want in ((None, b"< hi >"), (b"< open vcan0 >", b"< ok >")):
        if send:
            s.sendall(send)
        while want not in buf:
            buf += s.recv(4096)
        buf = buf[buf.index(want) + len(want) :]
    s.sendall(b"< features >")
    while b">" not in buf:
        buf += s.recv(4096)
    assert buf.split(b">")[0].split() == [b"<", b"features", b"sendat"]
    s.sendall(b"< rawmode >")
    buf = b""
    while b"< ok >" not in buf:
        buf += s.recv(4096)
    return s


def test_hub_puts_sendat_frames_on_the_bus_at_their_time():
    with Hub(port=0, bitrate=1_000_000) as hub:
        rx = can.Bus(
            interface="socketcand", host="127.0.0.1", port=hub.port, channel="vcan0",
            tcp_tune=True,
        )
        tx = _raw_client(hub.port)
        try:
            time.sleep(0.2)
            now = time.monotonic()
            stated = [now - 0.004, now - 0.003, now - 0.002]
            batch = b"".join(
                format_sendat(t, 0x281, struct.pack("<ff", k, 0.0)) for k, t in enumerate(stated)
            )
            # one earlier than its predecessor (kept after it: a sender's order is kept), one
            # in the future (never: on the bus now), one far in the past (a clock not shared)
            batch += format_sendat(now - 0.0035, 0x282, b"\x01")
            batch += format_sendat(now + 5.0, 0x283, b"\x02")
            tx.sendall(batch)
            got = recv_frames(rx, 5)
            arrived = time.time()
            assert [m.arbitration_id for m in got] == [0x281, 0x281, 0x281, 0x282, 0x283]
            for m, t in zip(got[:3], stated, strict=True):
                # on the bus from its stated time: done 111-135 bit times (at 1 Mbit/s) later
                assert 111e-6 <= m.timestamp - (t + _WALL) <= 135e-6 + 2e-6, m
            gaps = [b.timestamp - a.timestamp for a, b in itertools.pairwise(got[:3])]
            assert gaps == [pytest.approx(1e-3, abs=25e-6)] * 2  # (bit stuffing differs)
            assert got[3].timestamp > got[2].timestamp  # order kept
            assert got[3].timestamp <= got[2].timestamp + 200e-6
            assert got[4].timestamp <= arrived  # never in the future
            tx.sendall(format_sendat(time.monotonic() - 10.0, 0x284, b""))
            (old,) = recv_frames(rx, 1)
            assert old.arbitration_id == 0x284
            assert time.time() - old.timestamp <= Hub.max_backdate_s + 0.5
        finally:
            tx.close()
            rx.shutdown()


def test_a_late_batch_takes_the_idle_bus_of_its_time_not_the_bus_after_a_later_frame():
    """A batch stated in the past reaches the hub after a frame another node sent later (a
    drive's tick ends after a host's request went out). On a CAN bus idle at the batch's
    times, its frames were on the bus then: they must not queue behind the later frame, and
    a frame sent after the batch starts on an idle bus (an SDO reply is such a frame)."""
    bitrate = 10_000  # an 8-byte frame is 111-135 bits: 11-14 ms, far above the host's jitter
    with Hub(port=0, bitrate=bitrate) as hub:
        rx = can.Bus(
            interface="socketcand", host="127.0.0.1", port=hub.port, channel="vcan0",
            tcp_tune=True,
        )
        a, b = _raw_client(hub.port), _raw_client(hub.port)
        try:
            time.sleep(0.2)
            a.sendall(format_send(0x100, bytes(8)))  # A1: on the idle bus at once
            first = rx.recv(5.0)
            assert first is not None and first.arbitration_id == 0x100
            frame_s = 135 / bitrate  # the longest an 8-byte frame can take
            t_a1 = first.timestamp - _WALL - frame_s  # (monotonic) A1 was on the bus by then
            # B: four frames stated two frame times apart, all before A1: the bus was idle then
            stated = [t_a1 - (9 - 2 * k) * frame_s for k in range(4)]
            b.sendall(b"".join(format_sendat(t, 0x280 + k, bytes(8)) for k, t in enumerate(stated)))
            t_send_a2 = time.time()
            a.sendall(format_send(0x101, bytes(8)))  # A2: sent after the batch
            got = recv_frames(rx, 5)
            ids = [m.arbitration_id for m in got]
            assert sorted(ids[:4]) == [0x280, 0x281, 0x282, 0x283] and ids[4] == 0x101, ids
            # the batch occupied no bus time after A1: delivered with A1's time (the bus never
            # shows a frame before one it already delivered), not one frame time apart after it
            for m in got[:4]:
                assert m.timestamp == pytest.approx(first.timestamp, abs=1e-6), got
            # A2 found the bus idle: one frame time after it was sent (plus the hub's read),
            # not behind four frames of B (that would be at least 4 x 111 bits = 44 ms)
            assert got[4].timestamp - t_send_a2 < 4 * 111 / bitrate - 5e-3, got[4]
        finally:
            a.close()
            b.close()
            rx.shutdown()


def test_an_sdo_read_answers_with_the_value_of_now_not_of_the_last_tick():
    """The drive on the hub runs its simulation once per tick (10 ms), but an SDO read of a
    measurement answers with the value of the moment it was asked: the deadbeat current loop
    (paper eq. 15) reaches a new reference in 2 samples (40 us), so i_p read right after the
    reference was written is the new reference, not the one of up to a tick ago."""
    from drive_link import Drive

    with Hub(port=0, bitrate=1_000_000) as hub:
        bus = HubBus(channel="vcan0", host="127.0.0.1", port=hub.port)
        drive = VirtualDrive(bus, node_id=1)
        bus.rx_wanted = drive.network.subscribers
        drive.start()
        try:
            assert drive.runner.period == pytest.approx(TIMED_PERIOD) and TIMED_PERIOD >= 0.005
            with Drive.connect(
                node_id=1, heartbeat_ms=None, interface="socketcand", host="127.0.0.1",
                port=hub.port, channel="vcan0",
            ) as d:
                d.write("sim_load.J", 1e4)  # rotor held: i_p follows the reference alone
                d.set_mode("current")
                d.enable()
                seen = []
                for k in range(20):
                    ref = 5.0 if k % 2 else 15.0
                    d.set_current(ref)
                    seen.append((ref, float(d.read("measurements.i_p"))))
                d.disable()
        finally:
            drive.stop()
            bus.shutdown()
    stale = [(ref, i_p) for ref, i_p in seen if abs(i_p - ref) > 0.5]
    assert not stale, seen


def test_a_tick_that_read_the_clock_before_a_read_caught_up_runs_nothing_twice():
    """The pacer reads the clock, then waits for the tick's lock while an SDO read runs the
    simulation up to a later time: its tick then has nothing to run (simulated time never goes
    back, no sample runs twice) and the drive goes on (in run B it stopped: n_samples -1)."""
    with _drive_on_hub() as (drive, _frames):
        time.sleep(0.1)
        runner = drive.runner
        stale = time.monotonic()
        time.sleep(0.005)
        assert runner.catch_up()
        t_sim = drive.sim.time
        runner.tick(stale)  # the pacer's tick with its clock read before the catch-up
        # (the pacer's own tick may come between: simulated time may have moved on, never back)
        assert drive.sim.time >= t_sim
        assert drive.sim.time == pytest.approx(runner._done * 20e-6, abs=1e-9)
        time.sleep(0.05)
        assert runner.error is None and runner.running
        assert drive.sim.time > t_sim


def _scripted_server(
    replies: tuple[bytes | None, ...], linger_s: float = 0.0
) -> tuple[socket.socket, list[bytes], threading.Thread]:
    """A one-client socketcand server on 127.0.0.1 that greets, then answers each element the
    client sends with the next of ``replies`` (None: reads it, answers nothing) and closes
    ``linger_s`` s after the last: (its listening socket, the elements it read, its thread)."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(1)
    seen: list[bytes] = []

    def serve() -> None:
        conn, _ = srv.accept()
        conn.sendall(b"< hi >")
        buf = b""
        for reply in replies:
            while b">" not in buf:
                buf += conn.recv(4096)
            element, _, buf = buf.partition(b">")
            seen.append(element + b">")
            if reply is not None:
                conn.sendall(reply)
        time.sleep(linger_s)
        conn.close()

    th = threading.Thread(target=serve, daemon=True)
    th.start()
    return srv, seen, th


def test_vdhub_client_uses_sendat_only_where_the_server_takes_it():
    with Hub(port=0) as hub:
        bus = HubBus(channel="vcan0", host="127.0.0.1", port=hub.port)
        try:
            assert bus.timed_sends
        finally:
            bus.shutdown()
    # a server that answers '< features >' with an error (a socketcand daemon does)
    srv, seen, th = _scripted_server((b"< ok >", b"< error unknown command >", b"< ok >"), 0.5)
    try:
        bus = HubBus(channel="vcan0", host="127.0.0.1", port=srv.getsockname()[1])
        try:
            assert not bus.timed_sends
            assert bus.send_many([(0x181, b"\x01")], at=time.monotonic()) == 1  # plain send
        finally:
            bus.shutdown()
        th.join(5)
        assert [e.split()[1] for e in seen] == [b"open", b"features", b"rawmode"]
    finally:
        srv.close()


class _Frames(can.Listener):
    def __init__(self) -> None:
        self.msgs: list[can.Message] = []

    def on_message_received(self, msg: can.Message) -> None:
        self.msgs.append(msg)


@contextlib.contextmanager
def _drive_on_hub() -> Iterator[tuple[VirtualDrive, _Frames]]:
    """A virtual drive (node 1) on an in-process hub at 1 Mbit/s, started, with python-can's
    own socketcand client collecting every frame on the bus."""
    with Hub(port=0, bitrate=1_000_000) as hub:
        bus = HubBus(channel="vcan0", host="127.0.0.1", port=hub.port)
        drive = VirtualDrive(bus, node_id=1)
        bus.rx_wanted = drive.network.subscribers
        rx = can.Bus(
            interface="socketcand", host="127.0.0.1", port=hub.port, channel="vcan0",
            tcp_tune=True,
        )
        frames = _Frames()
        notifier = can.Notifier(rx, [frames])
        drive.start()
        try:
            yield drive, frames
        finally:
            notifier.stop()
            rx.shutdown()
            drive.stop()
            bus.shutdown()


def test_batched_drive_sends_each_tpdo_on_its_own_ms_with_its_own_value():
    """The drive on the hub wakes every TIMED_PERIOD (not every 1 ms), yet TPDO3's speed reference
    is on the bus every 1 ms and follows a 1000 rpm/s ramp sample by sample (1 rpm per frame,
    not a staircase of five equal values)."""
    with _drive_on_hub() as (drive, frames):
        node = drive.node
        drive.nmt.command(0x01)
        node.set_data(0x6060, 0, struct.pack("<b", 3))  # profile velocity
        node.set_data(0x6083, 0, struct.pack("<I", 1000))  # rpm/s
        for cw in (0x06, 0x07, 0x0F):
            node.set_data(0x6040, 0, struct.pack("<H", cw))
        node.set_data(0x60FF, 0, struct.pack("<i", 3000))  # ramp for 3 s
        time.sleep(0.3)
        it0, t0 = drive.runner.stats.iterations, time.monotonic()
        n0 = len(frames.msgs)
        probe = RunQueueProbe()
        time.sleep(1.0)
        probe.stop()
        wakes = (drive.runner.stats.iterations - it0) / (time.monotonic() - t0)
        window = frames.msgs[n0:]
    assert drive.runner.period == pytest.approx(TIMED_PERIOD) and TIMED_PERIOD >= 0.005
    assert wakes <= 1.2 / TIMED_PERIOD, wakes  # 1 / TIMED_PERIOD wake-ups/s, not 1000
    tpdo3 = [m for m in window if m.arbitration_id == 0x381]
    assert len(tpdo3) >= min_rate(1000, probe.wait), (len(tpdo3), probe)
    stamps = [m.timestamp for m in tpdo3]
    gaps = [b - a for a, b in itertools.pairwise(stamps)]
    assert statistics.median(gaps) == pytest.approx(1e-3, abs=0.05e-3)
    refs = [struct.unpack("<ff", bytes(m.data))[1] for m in tpdo3]
    steps = [b - a for a, b in itertools.pairwise(refs)]
    # 1000 rpm/s: 1 rpm per 1 ms frame; a value sampled once per tick would repeat
    assert sum(abs(s) < 0.25 for s in steps) <= 0.05 * len(steps), steps[:20]
    assert statistics.median(steps) == pytest.approx(1.0, abs=0.1)
    slope = (refs[-1] - refs[0]) / (stamps[-1] - stamps[0])
    assert slope == pytest.approx(1000.0, rel=0.05)
    _skip_if_starved(probe, "1 ms spacing of every frame")
    # one frame per event period: the bus time moves by ~1 ms (a TPDO1/TPDO2 ahead in
    # arbitration shifts it by at most a couple of frame times)
    assert sum(0.7e-3 <= g <= 1.3e-3 for g in gaps) >= 0.95 * len(gaps), sorted(gaps)[:5]


def test_batched_drive_runs_a_steady_tick_in_one_call_with_each_ms_its_own_value():
    """With its setpoint steady (mode -1, i_p* = 15 A from standstill) the drive runs each
    tick in one simulator call, yet TPDO2's speed on the bus moves every 1 ms as the
    shaft equation says: J dw/dt = K_t i_p - B w - k_gen n - T_load (K_t = K_rpm 60/(2 pi),
    parameters as the object dictionary gives them)."""
    with _drive_on_hub() as (drive, frames):
        node = drive.node
        view = drive.view
        J, B, k_gen, T_load, K_rpm = (
            node.stored(view.entry(name).index, view.entry(name).subindex)
            for name in (
                "sim_load.J", "sim_load.B", "sim_load.k_gen", "sim_load.T_load", "motor.K_rpm"
            )
        )
        drive.nmt.command(0x01)
        node.set_data(0x6060, 0, struct.pack("<b", -1))
        node.set_data(0x2030, 1, struct.pack("<f", 15.0))
        n0 = len(frames.msgs)
        for cw in (0x06, 0x07, 0x0F):
            node.set_data(0x6040, 0, struct.pack("<H", cw))
        time.sleep(0.3)
        chunk0 = drive.runner.stats.max_chunk
        probe = RunQueueProbe()
        time.sleep(0.5)
        probe.stop()
        window = frames.msgs[n0:]
    # whole ticks in one call (pieces ending at each 1 ms due point are <= 50 samples)
    assert chunk0 >= 200, chunk0
    tpdo2 = [m for m in window if m.arbitration_id == 0x281]
    values = [struct.unpack("<ff", bytes(m.data)) for m in tpdo2]
    moving = [(m.timestamp, i_p, n) for m, (i_p, n) in zip(tpdo2, values, strict=True) if n > 1.0]
    assert len(moving) >= min_rate(1000, probe.wait) * 0.3, (len(moving), probe)
    K_t = K_rpm * 60.0 / (2.0 * math.pi)  # N m/A
    rad = 2.0 * math.pi / 60.0
    predicted = 0.0  # rpm: the shaft equation integrated over the received frames
    for (t0, i0, n0_), (t1, _i1, _n1) in itertools.pairwise(moving):
        torque = K_t * i0 - B * n0_ * rad - k_gen * n0_ - T_load
        predicted += torque / J / rad * (t1 - t0)
    gained = moving[-1][2] - moving[0][2]
    assert gained == pytest.approx(predicted, rel=0.05)
    steps = [b[2] - a[2] for a, b in itertools.pairwise(moving)]
    # each 1 ms frame carries the speed of its own instant: no staircase of repeated values
    assert sum(s <= 0.0 for s in steps) <= 0.02 * len(steps), steps[:20]
    assert statistics.median(i for _, i, _ in moving) == pytest.approx(15.0, abs=0.5)


def test_batched_drive_keeps_an_inhibit_time_on_the_bus():
    """CiA 301 §7.5.2.37: TPDO2 with a 1 ms event timer and a 2 ms inhibit time (sub 3 =
    20 x 100 us) is on the bus every 2 ms, never closer, when the drive plans a whole
    tick's TPDOs at once; TPDO3 at 3 ms and TPDO1/TPDO4 at 10 ms keep their own periods."""
    with _drive_on_hub() as (drive, frames):
        node = drive.node
        node.set_data(0x1801, 1, struct.pack("<I", 0x80000281))
        node.set_data(0x1801, 3, struct.pack("<H", 20))
        node.set_data(0x1801, 1, struct.pack("<I", 0x281))
        node.set_data(0x1802, 5, struct.pack("<H", 3))  # TPDO3 every 3 ms
        drive.nmt.command(0x01)
        time.sleep(0.2)
        n0 = len(frames.msgs)
        probe = RunQueueProbe()
        time.sleep(0.6)
        probe.stop()
        window = frames.msgs[n0:]
    stamps = [m.timestamp for m in window if m.arbitration_id == 0x281]
    gaps = [b - a for a, b in itertools.pairwise(stamps)]
    assert len(stamps) >= min_rate(500, probe.wait) * 0.6, (len(stamps), probe)
    _skip_if_starved(probe, "the spacing of every frame")
    assert statistics.median(gaps) == pytest.approx(2.0e-3, abs=0.05e-3)
    # the bus time of each frame is its due time plus its arbitration (a frame ahead of it
    # may delay it by up to one frame time, 135 us, which the next gap gives back)
    assert min(gaps) >= 2.0e-3 - 0.14e-3, min(gaps)
    # the other TPDOs keep their own event timers meanwhile (3 ms; TPDO1 and TPDO4: 10 ms):
    # every gap is the period give or take the arbitration behind a frame due at the same
    # time (TPDO3 and TPDO2 meet every 6 ms: up to one frame time, 135 us, either way)
    for cob_id, period in ((0x381, 3e-3), (0x181, 10e-3), (0x481, 10e-3)):
        t = [m.timestamp for m in window if m.arbitration_id == cob_id]
        assert len(t) >= 0.5 / period, (hex(cob_id), len(t))
        gaps = [b - a for a, b in itertools.pairwise(t)]
        near = [g for g in gaps if abs(g - period) <= 0.3e-3]
        assert len(near) >= 0.95 * len(gaps), (hex(cob_id), sorted(gaps))
        assert statistics.fmean(near) == pytest.approx(period, abs=0.03e-3), hex(cob_id)


def test_a_frame_sent_now_is_stated_with_its_time_on_a_sendat_hub():
    """ci30/ci34/ci36 at load 8-9: TPDO2 (inhibit 1.5 ms) 0.25-0.9 ms apart on the hub. A frame
    the drive sends now (heartbeat, SDO answer, EMCY) went as a plain send, which takes the
    time the hub reads it: later, on a busy hub, than the TPDO batch stated before it, whose
    frames then had to follow it and were squeezed. On a hub that takes sendat, every frame
    carries the time it was sent."""
    srv, seen, th = _scripted_server((b"< ok >", b"< features sendat >", b"< ok >", None))
    try:
        bus = HubBus(channel="vcan0", host="127.0.0.1", port=srv.getsockname()[1])
        try:
            assert bus.timed_sends
            t0 = time.time()
            assert bus.send_many([(0x701, b"\x05")]) == 1  # no time given: sent now
            t1 = time.time()
            th.join(5)
        finally:
            bus.shutdown()
        words = seen[-1].split()
        assert words[1] == b"sendat", seen[-1]
        assert t0 - 1e-3 <= float(words[2]) <= t1 + 1e-3, (seen[-1], t0, t1)
    finally:
        srv.close()


class _StallingClock:
    """``time`` whose clocks both jump ahead by ``stall_s`` at the ``at``-th reading (of either):
    the thread was preempted there."""

    def __init__(self, at: int, stall_s: float) -> None:
        self.at, self.stall_s, self.readings, self.offset = at, stall_s, 0, 0.0

    def _read(self, clock) -> float:
        self.readings += 1
        if self.readings == self.at:
            self.offset = self.stall_s
        return clock() + self.offset

    def monotonic(self) -> float:
        return self._read(time.monotonic)

    def time(self) -> float:
        return self._read(time.time)


@pytest.mark.parametrize("at", range(1, 7))
def test_the_wall_clock_offset_ignores_a_stall_between_its_readings(at, monkeypatch):
    """Read as ``time.time() - time.monotonic()``, a thread preempted between the two got an
    offset off by the preemption for its process's life (the hub's and each drive's): a drive's
    sendat times then looked up to 5 ms in the future and its frames were squeezed together."""
    from virtual_drive import hub_protocol

    truth = time.time() - time.monotonic()  # (idle here: a few µs)
    monkeypatch.setattr(hub_protocol, "time", _StallingClock(at, 0.005))
    assert hub_protocol.wall_offset() == pytest.approx(truth, abs=1e-4)


def test_sendat_frames_that_reach_the_hub_late_are_counted():
    """A ``sendat`` frame stated more than the spacing hold (5 ms) before it reached the hub is
    counted (``HubStats.frames_late``): the evidence that the host stalled its sender or the
    hub, after which a sender's spacing may show shortened on the emulated bus. Frames stated
    within the hold, and plain sends, are not."""
    from virtual_drive.hub_bus import SPACING_HOLD_S, Bus, Client, HubCounters
    from virtual_drive.hub_faults import FaultInjection

    a, b = socket.socketpair()
    try:
        counters = HubCounters()
        bus = Bus("vcan0", 1_000_000, FaultInjection(), counters, 0.0, 0.0)  # monotonic stamps
        client = Client(a, ("127.0.0.1", 0))
        now = 1000.0
        ages = (0.020, SPACING_HOLD_S + 1e-4, SPACING_HOLD_S - 1e-4, 0.001)
        bus.enqueue_timed(
            client, [(now - age, 0x281, bytes([k]), False) for k, age in enumerate(ages)], now, 0.05
        )
        assert counters.late == 2 and counters.received == 4
        bus.enqueue_timed(client, [(now + 0.002 - 0.001, 0x282, b"", False)], now + 0.002, 0.05)
        bus.enqueue(client, [(0x283, b"\x01", False)], now + 0.003)
        assert counters.late == 2 and counters.received == 6
    finally:
        a.close()
        b.close()
