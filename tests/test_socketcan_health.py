"""SocketCAN specifics without a SocketCAN kernel: a transmit queue that answers ENOBUFS (errno
105, python-can issue #2004) and the controller's error frames (``linux/can/error.h``), on
python-can buses in this process. The same behaviour on a real kernel SocketCAN is checked in the
SocketCAN lane (tests/test_socketcan_lane.py, inside User-Mode Linux).

Truths: the frames a second bus actually receives; error-frame classes from linux/can/error.h.
"""

from __future__ import annotations

import errno
import threading
import time
import uuid

import can
import pytest

from drive_link import Drive, scan
from drive_link.link._bus_health import (
    BUS_OFF,
    ERROR_ACTIVE,
    ERROR_PASSIVE,
    UNKNOWN,
    BusHealth,
    state_from_error_frame,
)
from drive_link.link._connection import PacedNetwork, queue_full

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]


class QueueBus(can.BusABC):
    """A python-can virtual bus with a transmit queue of ``depth`` frames drained at ``rate``
    frames/s: a send into a full queue raises what python-can's socketcan raises on ENOBUFS."""

    def __init__(self, channel: str, depth: int = 10, rate: float = 8000.0, **kw):
        self._inner = can.Bus(interface="virtual", channel=channel)
        self.depth, self.rate = depth, rate
        self._level = 0.0
        self._t = time.monotonic()
        self.enobufs = 0
        self.sent = 0
        self.channel_info = "queue bus"
        super().__init__(channel=channel, **kw)

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        now = time.monotonic()
        self._level = max(0.0, self._level - (now - self._t) * self.rate)
        self._t = now
        if self._level + 1 > self.depth:
            self.enobufs += 1
            raise can.CanOperationError(
                "Failed to transmit: No buffer space available", errno.ENOBUFS
            )
        self._level += 1
        self.sent += 1
        self._inner.send(msg)

    def _recv_internal(self, timeout):
        return self._inner.recv(timeout), False

    def shutdown(self) -> None:
        self._inner.shutdown()
        super().shutdown()


def test_queue_full_recognises_python_cans_enobufs():
    assert queue_full(can.CanOperationError("Failed to transmit: No buffer space", 105))
    assert queue_full(can.CanOperationError("Transmit buffer full"))
    assert queue_full(OSError(errno.ENOBUFS, "No buffer space available"))
    assert not queue_full(can.CanOperationError("Failed to transmit: Network is down", 100))


def test_paced_network_waits_out_a_full_queue_and_sends_every_frame():
    ch = f"q-{uuid.uuid4().hex}"
    bus = QueueBus(ch, depth=10, rate=2000.0)
    rx = can.Bus(interface="virtual", channel=ch)
    net = PacedNetwork(bus)
    try:
        t0 = time.monotonic()
        for i in range(127):  # a block-transfer-sized burst
            net.send_message(0x600 + (i % 127) + 1, bytes([i]) * 8)
        dt = time.monotonic() - t0
        got = []
        while (m := rx.recv(0.2)) is not None:
            got.append(m.data[0])
        assert got == list(range(127))  # every frame, in order
        assert bus.enobufs > 0 and net.tx_queue_full == bus.enobufs
        assert dt < 10.0  # 127 frames at 2000/s need 0.06 s; bounded even on a busy host
    finally:
        rx.shutdown()
        bus.shutdown()


def test_paced_network_gives_up_after_its_deadline():
    ch = f"q-{uuid.uuid4().hex}"
    bus = QueueBus(ch, depth=0, rate=0.0)  # the queue never drains
    net = PacedNetwork(bus)
    net.send_deadline = 0.3
    try:
        t0 = time.monotonic()
        with pytest.raises(can.CanOperationError, match="No buffer space"):
            net.send_message(0x601, bytes(8))
        assert 0.3 <= time.monotonic() - t0 < 5.0
    finally:
        bus.shutdown()


def test_other_send_errors_are_not_retried():
    class Down(QueueBus):
        def send(self, msg, timeout=None):
            self.sent += 1
            raise can.CanOperationError("Failed to transmit: Network is down", errno.ENETDOWN)

    bus = Down(f"q-{uuid.uuid4().hex}")
    try:
        with pytest.raises(can.CanOperationError, match="Network is down"):
            PacedNetwork(bus).send_message(0x601, bytes(8))
        assert bus.sent == 1
    finally:
        bus.shutdown()


@pytest.fixture
def drive_on_queue_bus(tmp_path):
    """The virtual drive on a python-can virtual bus; the host's bus has a 10-frame queue."""
    from virtual_drive.node import VirtualDrive

    ch = f"q-{uuid.uuid4().hex}"
    b_drive = can.Bus(interface="virtual", channel=ch)
    b_host = QueueBus(ch, depth=10, rate=3000.0)
    vd = VirtualDrive(b_drive, node_id=5, store_path=tmp_path / "p.json").start()
    yield b_host, ch
    vd.stop()
    b_drive.shutdown()
    b_host.shutdown()


def test_scan_burst_of_127_probes_through_a_10_frame_queue(drive_on_queue_bus):
    bus, ch = drive_on_queue_bus
    probe = can.Bus(interface="virtual", channel=ch)
    seen: set[int] = set()
    stop = threading.Event()

    def listen():
        while not stop.is_set():
            m = probe.recv(0.05)
            is_probe = m is not None and m.data[:4] == b"\x40\x00\x10\x00"
            if is_probe and 0x601 <= m.arbitration_id <= 0x67F:
                seen.add(m.arbitration_id - 0x600)

    t = threading.Thread(target=listen, daemon=True)
    t.start()
    try:
        nodes = scan(bus, timeout=0.5)
    finally:
        time.sleep(0.2)
        stop.set()
        t.join(2)
        probe.shutdown()
    assert bus.enobufs > 0  # the queue did overflow
    assert seen == set(range(1, 128))  # yet every probe went out
    assert [(n.node_id, n.device_type) for n in nodes] == [(5, 0x00020192)]
    assert nodes[0].nmt_state == "PRE-OPERATIONAL"


# --------------------------------------------------------------------------- error frames
def _err(cls: int, d1: int = 0) -> can.Message:
    return can.Message(
        arbitration_id=cls, is_error_frame=True, data=bytes([0, d1, 0, 0, 0, 0, 0, 0])
    )


def test_error_frame_classes():
    assert state_from_error_frame(_err(0x040)) == BUS_OFF
    assert state_from_error_frame(_err(0x100)) == ERROR_ACTIVE
    assert state_from_error_frame(_err(0x004, 0x20)) == ERROR_PASSIVE  # TX passive
    assert state_from_error_frame(_err(0x004, 0x10)) == ERROR_PASSIVE  # RX passive
    assert state_from_error_frame(_err(0x004, 0x08)) == ERROR_ACTIVE  # TX warning
    assert state_from_error_frame(_err(0x004, 0x40)) == ERROR_ACTIVE  # back to error active
    assert state_from_error_frame(_err(0x080)) is None  # bus error: no state change


def test_status_reports_error_frames_and_bus_off(tmp_path):
    from virtual_drive.node import VirtualDrive

    ch = f"e-{uuid.uuid4().hex}"
    b_drive = can.Bus(interface="virtual", channel=ch)
    b_host = can.Bus(interface="virtual", channel=ch)
    b_ctrl = can.Bus(interface="virtual", channel=ch)  # plays the CAN controller's reports
    vd = VirtualDrive(b_drive, node_id=6, store_path=tmp_path / "p.json").start()
    d = Drive.connect(bus=b_host, node_id=6, heartbeat_ms=None)
    try:
        st = d.status()
        assert st["bus_state"] == UNKNOWN and st["bus_error_frames"] == 0  # virtual: no controller

        def wait_state(want: str, frames: int) -> dict:
            deadline = time.monotonic() + 10
            while True:
                h = d.bus_health()
                if h == {"bus_state": want, "bus_error_frames": frames}:
                    return h
                assert time.monotonic() < deadline, h
                time.sleep(0.02)

        b_ctrl.send(_err(0x004, 0x20))
        wait_state(ERROR_PASSIVE, 1)
        b_ctrl.send(_err(0x080))
        b_ctrl.send(_err(0x040))
        wait_state(BUS_OFF, 3)
        st = d.status()
        assert st["bus_state"] == BUS_OFF and st["bus_error_frames"] == 3
        b_ctrl.send(_err(0x100))
        wait_state(ERROR_ACTIVE, 4)
        # error frames are reports, not traffic: the bus-load monitor does not count them
        assert d._conn.monitor.frames_total > 0
    finally:
        d.close()
        vd.stop()
        for b in (b_drive, b_host, b_ctrl):
            b.shutdown()


def test_bus_state_from_a_backend_that_implements_it():
    class Passive(can.BusABC):
        def __init__(self):
            super().__init__(channel="x")

        def send(self, msg, timeout=None):
            pass

        def _recv_internal(self, timeout):
            return None, False

        @property
        def state(self):
            return can.BusState.PASSIVE

    assert BusHealth(Passive()).state == ERROR_PASSIVE
