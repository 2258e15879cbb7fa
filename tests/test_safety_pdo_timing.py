"""TPDO timing (CiA 301 §7.2.2.5, §7.5.2.35/37): inhibit time on exact time, inhibit writes,
missed event periods counted where a master can read them.

Truths: CiA 301 — the inhibit time (sub 3, 100 µs units) is the minimum time between two
transmissions of a PDO and shall not be changed while the PDO exists (COB-ID bit 31 = 0); an
event-driven TPDO with event timer 1 ms and inhibit 2 ms is sent every 2 ms. Timings come from
the virtual bus's own send time stamps (``msg.timestamp``, set when the drive sends) and are
compared with what an independent run-queue probe says the kernel gave the process.
"""

from __future__ import annotations

import itertools
import statistics
import threading
import time

import can
import pytest
from canopen.sdo import SdoAbortedError
from conftest import RunQueueProbe, min_rate
from test_node_support import Bench

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

#: run-queue wait (s/s) below which a window shows the drive's own timing
CLEAN_WAIT = 0.25


class Stamps(can.Listener):
    """Send time stamps (s) of the frames on one COB-ID."""

    def __init__(self, cob_id: int) -> None:
        self.cob_id = cob_id
        self.t: list[float] = []
        self._lock = threading.Lock()

    def on_message_received(self, msg: can.Message) -> None:
        if msg.arbitration_id == self.cob_id:
            with self._lock:
                self.t.append(msg.timestamp)

    def between(self, t0: float, t1: float) -> list[float]:
        with self._lock:
            return [t for t in self.t if t0 <= t <= t1]


@pytest.fixture
def bench():
    b = Bench(speed=1.0)
    # only TPDO2 runs: fewer frames for this single-process test
    for k in (1, 3, 4):
        b.write(f"tpdo{k}_communication.cob_id", 0x80000001 + 0x80 + 0x100 * k)
    yield b
    b.close()


def test_inhibit_time_changes_only_while_the_pdo_is_invalid(bench):
    name = "tpdo2_communication.inhibit_time"
    with pytest.raises(SdoAbortedError) as exc:
        bench.write(name, 20)  # TPDO2 valid
    assert exc.value.code == 0x06090030
    assert bench.read(name) == 0
    bench.write("tpdo2_communication.cob_id", 0x80000281)
    bench.write(name, 20)
    bench.write("tpdo2_communication.cob_id", 0x281)
    bench.nmt(0x01)
    assert bench.wait(lambda: bench.drive.nmt.state == 0x05)
    with pytest.raises(SdoAbortedError) as exc:
        bench.write(name, 10)  # valid and OPERATIONAL
    assert exc.value.code == 0x06090030
    assert bench.read(name) == 20
    bench.write(name, 20)  # the same value is no change


def test_two_ms_inhibit_gives_500_hz_not_the_next_tick(bench):
    bench.write("tpdo2_communication.cob_id", 0x80000281)
    bench.write("tpdo2_communication.inhibit_time", 20)  # 2.0 ms
    bench.write("tpdo2_communication.cob_id", 0x281)
    stamps = Stamps(0x281)
    bench.net.notifier.add_listener(stamps)
    bench.nmt(0x01)
    time.sleep(0.2)
    # a window in which the kernel let this process run: the 2 ms spacing is a property of the
    # drive's scheduling and cannot be seen while the process waits for a CPU
    best: tuple[RunQueueProbe, list[float], float] | None = None
    for _ in range(5):
        probe = RunQueueProbe()
        t0 = time.time()
        time.sleep(1.0)
        t1 = time.time()
        probe.stop()
        if best is None or probe.wait < best[0].wait:
            best = (probe, stamps.between(t0, t1), t1 - t0)
        if probe.wait < CLEAN_WAIT:
            break
    probe, t, span = best
    rate = len(t) / span
    gaps = [b - a for a, b in itertools.pairwise(t)]
    # never more often than every 2 ms: the inhibit time counts from the end of a send, so
    # even the bus's own send stamps are at least 2 ms apart
    assert rate <= 500 * 1.01 + 1, rate
    assert min(gaps) >= 2.0e-3 - 1e-6, min(gaps)
    assert rate >= min_rate(500, probe.wait, margin=0.75), (rate, probe)
    if probe.wait >= CLEAN_WAIT:
        pytest.skip(f"2 ms spacing not observable: {probe!r} in the best of 5 windows")
    # and not snapped to the 1 ms pacing tick (that gave 331-336 Hz, i.e. 3 ms gaps); the
    # thread's wake-up lateness (GIL hand-over included) adds to each 2 ms gap
    assert statistics.median(gaps) < 2.7e-3, (statistics.median(gaps), probe)


def test_stalled_periods_are_counted_not_burst(bench):
    """The drive's transmit path is held for 50 ms (its send lock, as a stalled process or a
    full transmit queue would): one late frame, no burst, and the 1 ms periods that passed
    without a frame appear in 0x2070."""
    stamps = Stamps(0x281)
    bench.net.notifier.add_listener(stamps)
    bench.nmt(0x01)
    time.sleep(0.2)
    before = bench.read("tpdo_missed_events.tpdo2")
    with bench.drive.tx.send_lock:
        t_stall = time.time()
        time.sleep(0.05)
        t_release = time.time()
    time.sleep(0.1)
    missed = bench.read("tpdo_missed_events.tpdo2") - before
    t_read = time.time()
    # at least the held 50 ms; more only if the machine stalled the process as well
    assert 40 <= missed <= (t_read - t_stall) * 1000 + 2, missed
    assert len(stamps.between(t_release, t_read)) >= 3  # frames flow again after the stall
    # no catch-up burst of the ~50 missed frames: the frame held in the send path, the late
    # one, then the 1 ms grid again (a few frames in the first 5 ms, not dozens)
    first = stamps.between(t_release, t_release + 0.005)
    assert len(first) <= 8, [round((t - t_release) * 1e3, 2) for t in first]
