"""Heartbeat consumer 0x1016 (CiA 301 §7.2.8.3.2.3) and the CiA 402 abort connection option
0x6007: when the host's heartbeat stops the drive reacts within the consumer time and sends
EMCY 0x8130 with error register bit 4 (communication)."""

from __future__ import annotations

import threading
import time

import pytest
from conftest import RunQueueProbe
from test_node_support import Bench, emcy_frames

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

HOST = 0x7F
CONSUMER_MS = 60


class HostHeartbeat:
    """The master's heartbeat producer (0x700 + HOST, state OPERATIONAL) every 10 ms."""

    def __init__(self, bench: Bench) -> None:
        self.bench = bench
        self.stop_evt = threading.Event()
        self.last = 0.0
        self.sent: list[float] = []  # when each heartbeat was sent (monotonic s)
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while not self.stop_evt.is_set():
            self.bench.net.send_message(0x700 + HOST, b"\x05")
            self.last = time.monotonic()
            self.sent.append(self.last)
            self.stop_evt.wait(0.01)

    def stop(self) -> float:
        self.stop_evt.set()
        self.thread.join()
        return self.last


@pytest.fixture
def bench():
    b = Bench(speed=1.0)
    b.write("consumer_heartbeat_time.consumer_1", (HOST << 16) | CONSUMER_MS)
    yield b
    b.close()


def test_no_monitoring_before_the_first_heartbeat(bench):
    t0 = time.monotonic()
    time.sleep(3 * CONSUMER_MS / 1000)
    assert emcy_frames(bench.log, since=t0) == []


def test_heartbeat_loss_quick_stop_and_emcy(bench):
    hb = HostHeartbeat(bench)
    bench.enable(-1)
    bench.write("setpoints.i_p_ref", 10.0)
    time.sleep(0.15)
    early = emcy_frames(bench.log)
    if early:  # right only if this (starved) process really left a gap over the consumer time
        gap = max((b - a for a, b in zip(hb.sent, hb.sent[1:], strict=False)), default=0.0)
        hb.stop()
        assert gap > CONSUMER_MS / 1000, (
            f"EMCY {early} while heartbeats came at most {gap * 1e3:.0f} ms apart "
            f"(consumer {CONSUMER_MS} ms)"
        )
        pytest.skip(f"the host's heartbeat thread was starved ({gap * 1e3:.0f} ms gap)")
    probe = RunQueueProbe()  # run-queue wait the kernel imposed on this process meanwhile
    last = hb.stop()
    got = bench.log.wait_for(0x81, 1.0, since=last)
    probe.stop()
    assert got is not None, "no EMCY after heartbeat loss"
    t_emcy = got[0]
    _, code, reg = emcy_frames(bench.log, since=last)[0]
    assert code == 0x8130 and reg & 0x10
    delay = t_emcy - last
    # + 1 ms tick and jitter, + what the kernel kept the process waiting over the interval
    late = 0.04 + probe.wait * delay
    assert CONSUMER_MS / 1000 <= delay <= CONSUMER_MS / 1000 + late, (delay, probe)
    # 0x6007 = 3: quick stop -> (motor at rest) SWITCH ON DISABLED
    assert bench.wait(lambda: bench.read("statusword") & 0x4F == 0x40, 1.0)
    assert bench.read("error_register") & 0x10
    assert bench.read("error_code") == 0x8130
    assert bench.read("statusword") & 0x80  # warning while the heartbeat is missing
    # heartbeat back: communication error cleared with an error-reset EMCY
    t1 = time.monotonic()
    hb2 = HostHeartbeat(bench)
    try:
        assert bench.log.wait_for(0x81, 1.0, since=t1, pred=lambda d: d[:2] == b"\x00\x00")
        assert bench.read("error_register") == 0
    finally:
        hb2.stop()


def test_abort_connection_option_fault(bench):
    bench.write("abort_connection_option_code", 1)
    hb = HostHeartbeat(bench)
    bench.enable(-1)
    last = hb.stop()
    assert bench.wait(lambda: bench.read("statusword") & 0x4F == 0x08, 1.0)  # FAULT
    assert [c for _, c, _ in emcy_frames(bench.log, since=last)] == [0x8130]
    assert bench.read("pre_defined_error_field.standard_error_field_1") & 0xFFFF == 0x8130
    bench.write("controlword", 0x80)
    assert bench.read("statusword") & 0x4F == 0x40
    assert bench.read("error_register") == 0


def test_abort_connection_option_none_keeps_running(bench):
    bench.write("abort_connection_option_code", 0)
    hb = HostHeartbeat(bench)
    bench.enable(-1)
    last = hb.stop()
    assert bench.log.wait_for(0x81, 1.0, since=last) is not None  # EMCY still sent
    time.sleep(0.05)
    assert bench.read("statusword") & 0x6F == 0x27  # still OPERATION ENABLED
