"""A dead drive fails a call fast (issue 29, item 2).

Truth: CiA 301 §7.2.8.3.2: a heartbeat consumer that receives no heartbeat within its time
counts the producer as gone. With drive_link watching the drive's heartbeat (0x1017 = 100 ms by
default), a node whose heartbeat stayed away for the host's consumer time (3 periods, at least
1 s) is gone: a call to it fails within one producer period plus one SDO response timeout
(0.3 s), saying so, instead of resending for seconds (5.7 s); a call made as the node died
fails when that consumer time is over. The last heartbeat's time is taken by a sniffer on the bus
(its own python-can ``virtual`` bus), not from drive_link.
"""

from __future__ import annotations

import time
import uuid

import can
import pytest

from drive_link import Drive
from drive_link.errors import NodeGone

pytestmark = pytest.mark.timeout(60)

SLACK_S = 0.15  #: scheduling slack on a loaded 2-core host (s)


@pytest.fixture
def parts():
    from virtual_drive.node import VirtualDrive

    ch = f"dead-{uuid.uuid4().hex}"
    b_drive = can.Bus(interface="virtual", channel=ch)
    b_host = can.Bus(interface="virtual", channel=ch)
    b_sniff = can.Bus(interface="virtual", channel=ch)
    vd = VirtualDrive(b_drive, node_id=4).start()
    d = Drive.connect(bus=b_host, node_id=4, heartbeat_ms=100)
    yield d, vd, b_sniff
    d.close()
    vd.stop()
    for b in (b_drive, b_host, b_sniff):
        b.shutdown()


def last_heartbeat(sniff: can.BusABC) -> float:
    """Monotonic time of the last 0x704 frame the sniffer received (drained now)."""
    last = None
    while (msg := sniff.recv(0)) is not None:
        if msg.arbitration_id == 0x704:
            last = msg.timestamp
    assert last is not None, "no heartbeat on the bus"
    return last - time.time() + time.monotonic()  # (virtual bus stamps with time.time())


def test_a_dead_drive_fails_calls_fast_saying_the_node_is_gone(parts):
    d, vd, sniff = parts
    producer_s = int(d.read("producer_heartbeat_time")) / 1000.0
    assert producer_s == pytest.approx(0.1)
    timeout_s = d.sdo.client.RESPONSE_TIMEOUT
    consumer_s = d.supervisor.consumer_s()  # the host's consumer time: 3 periods, >= 1 s
    time.sleep(0.25)
    vd.stop()  # frozen: no heartbeat, no SDO answer
    t_last = last_heartbeat(sniff)
    # a call at the moment of death fails once the consumer time is over (was ~5.7 s)
    t0 = time.monotonic()
    with pytest.raises(NodeGone, match=r"node 4 is gone: no heartbeat for \d+ ms"):
        d.read("statusword")
    t_fail = time.monotonic()
    assert t_fail <= t_last + consumer_s + timeout_s + SLACK_S, (
        f"failed {t_fail - t_last:.3f} s after the last heartbeat (call {t_fail - t0:.3f} s)"
    )
    # the node is gone: a call fails within one heartbeat period plus one SDO timeout, after
    # one request (a node back on the bus would answer it), without resends
    while sniff.recv(0) is not None:
        pass
    t1 = time.monotonic()
    with pytest.raises(NodeGone):
        d.write("target_velocity", 10)
    assert time.monotonic() - t1 <= producer_s + timeout_s + SLACK_S
    requests = [m for m in iter(lambda: sniff.recv(0), None) if m.arbitration_id == 0x604]
    assert len(requests) == 1



class _StallingClock:
    """``time`` for :mod:`drive_link.link._sdo_segmented` whose monotonic clock jumps ahead by
    ``stall_s`` at its ``at``-th reading: the host did not run the caller for that long there
    (a busy host can preempt it between any two statements)."""

    def __init__(self, at: int, stall_s: float) -> None:
        self.at, self.stall_s, self.readings, self.offset = at, stall_s, 0, 0.0

    def monotonic(self) -> float:
        self.readings += 1
        if self.readings == self.at:
            self.offset = self.stall_s
        return time.monotonic() + self.offset

    def __getattr__(self, name: str):
        return getattr(time, name)


def test_a_stall_anywhere_in_a_call_to_a_gone_node_sends_one_request(parts, monkeypatch):
    """The SocketCAN lane at host load 7.8 (ci33) saw a call to a stopped drive send its request
    twice, one SDO timeout apart. The property: whatever point of the call the host stalls at,
    a node that is gone gets one request, and the call fails with NodeGone, not a resend."""
    from drive_link.link import _sdo_segmented

    d, vd, sniff = parts
    time.sleep(0.25)
    vd.stop()
    with pytest.raises(NodeGone):
        d.read("statusword")  # gone now
    stall_s = 0.05
    for at in range(1, 16):
        while sniff.recv(0) is not None:
            pass
        clock = _StallingClock(at, stall_s)
        monkeypatch.setattr(_sdo_segmented, "time", clock)
        with pytest.raises(NodeGone):
            d.write("target_velocity", 10)
        monkeypatch.setattr(_sdo_segmented, "time", time)
        time.sleep(0.05)
        requests = [m for m in iter(lambda: sniff.recv(0), None) if m.arbitration_id == 0x604]
        assert len(requests) == 1, f"stall of {stall_s} s at clock reading {at}: " \
            f"{len(requests)} requests"  # fmt: skip


@pytest.mark.parametrize(("value", "expected"), [(None, 2.0), ("5", 5.0), ("1.5", 1.5)])
def test_the_host_consumer_floor_comes_from_the_environment(value, expected, monkeypatch):
    """``DRIVE_LINK_CONSUMER_MIN_S`` sets the shortest time drive_link waits for a silent node
    (the SocketCAN lane sets 5 for User-Mode Linux); unset, 2 s (CiA 301 leaves it to the
    consumer; docs/contracts.md documents both)."""
    from drive_link.link.supervision import CONSUMER_MIN_ENV, consumer_min_s

    monkeypatch.delenv(CONSUMER_MIN_ENV, raising=False)
    if value is not None:
        monkeypatch.setenv(CONSUMER_MIN_ENV, value)
    assert consumer_min_s() == expected


@pytest.mark.parametrize("value", ["x", "0.5", "nan", "-3"])
def test_a_bad_host_consumer_floor_is_one_line_from_drive_link(value, hub_drive):
    """Through the installed command against a virtual drive: one line naming the variable and
    the value, a non-zero exit, no traceback."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    exe = Path(sys.executable).with_name("drive-link")
    env = {**os.environ, "DRIVE_LINK_CONSUMER_MIN_S": value}
    out = subprocess.run(
        [str(exe), "--host", "127.0.0.1", "--port", str(hub_drive.port), "status"],
        env=env, capture_output=True, text=True, timeout=120,
    )
    want = f"DRIVE_LINK_CONSUMER_MIN_S must be a number of seconds >= 1, got '{value}'"
    assert out.returncode != 0 and want in out.stderr, out
    assert "Traceback" not in out.stderr and len(out.stderr.strip().splitlines()) == 1, out.stderr
