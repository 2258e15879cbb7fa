"""One canopen :class:`~canopen.Network` per python-can bus, shared by every drive on it.

python-can allows one reader per bus, so all drives (and scans) on one bus share one Network and
its Notifier thread. :class:`BusMonitor` counts every frame for rates and bus load,
:class:`~drive_link.link._bus_health.BusHealth` error frames and the bus state. Frames are sent
through
:class:`PacedNetwork`, which waits out a full transmit queue instead of failing.

The Notifier calls one function per frame (:func:`dispatcher`: canopen's subscribers, then the
monitor, error frames to the health listener) instead of three listeners; on the project's hub
client data frames skip the Notifier and the ``can.Message`` (:func:`direct_dispatcher`, called
in the bus's receive call on the Notifier's thread, in the order received); the monitor
queues each frame with its arrival time and counts them in batches (issue 11: a dashboard on
the hub receives about 2,200 frames/s).
"""

from __future__ import annotations

import errno
import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import can
import canopen

from firmware_protocol.can_bits import frame_bits, frame_bits_fast

from ._bus_health import BusHealth
from .bus import open_bus

__all__ = [
    "SEND_DEADLINE",
    "BusMonitor",
    "Connection",
    "PacedNetwork",
    "acquire",
    "direct_dispatcher",
    "dispatcher",
    "queue_full",
    "release",
]

log = logging.getLogger(__name__)

#: How long one frame may wait for room in a full transmit queue before the send fails (s).
SEND_DEADLINE = 2.0
#: frames the monitor queues on the bus thread before it counts them there in one go
_MONITOR_BATCH = 128


def queue_full(exc: BaseException) -> bool:
    """Whether a send failed only because the transmit queue is full: SocketCAN's ENOBUFS
    (errno 105; python-can raises ``CanOperationError`` with ``error_code`` 105, issue #2004)
    or python-can's own "Transmit buffer full" after its send timeout."""
    code = getattr(exc, "error_code", None) or getattr(exc, "errno", None)
    text = str(exc)
    return code == errno.ENOBUFS or "No buffer space" in text or "Transmit buffer full" in text


class PacedNetwork(canopen.Network):
    """canopen Network whose sends wait for room in a full transmit queue.

    SocketCAN answers a send into a full queue (``txqueuelen``, 10 by default on real adapters)
    with ENOBUFS at once; a burst (a scan's 127 probes, a block download's 127 segments) then
    fails although the bus only needs a few ms to drain. Each send is retried with growing
    pauses (0.2 ms doubling up to 10 ms) for up to ``send_deadline`` s; only then the last
    error is raised. ``tx_queue_full`` counts the retries.
    """

    send_deadline = SEND_DEADLINE

    def __init__(self, bus: can.BusABC | None = None):
        super().__init__(bus)
        self.tx_queue_full = 0

    def send_message(self, can_id: int, data: bytes, remote: bool = False) -> None:
        if not self.bus:
            raise RuntimeError("Not connected to CAN bus")
        msg = can.Message(
            is_extended_id=can_id > 0x7FF,
            arbitration_id=can_id,
            data=data,
            is_remote_frame=remote,
        )
        deadline: float | None = None
        pause = 0.0002
        while True:
            try:
                with self.send_lock:
                    self.bus.send(msg)
                break
            except (can.CanError, OSError) as exc:
                if not queue_full(exc):
                    raise
                now = time.monotonic()
                if deadline is None:
                    deadline = now + self.send_deadline
                elif now >= deadline:
                    raise
                self.tx_queue_full += 1
                time.sleep(min(pause, max(0.0, deadline - now)))
                pause = min(2 * pause, 0.01)
        self.check()


#: a received frame as the monitor queues it: a Message, or a data frame as
#: (CAN-ID, data, is_extended) from the hub's direct path
_Frame = can.Message | tuple[int, bytes, bool]


def _frame_bits(msg: _Frame) -> int:
    """Bits ``msg`` occupied on the wire (exact stuffing; :mod:`firmware_protocol.can_bits`).
    A CAN FD frame counts its classical-frame length (47/67 + 8·n, no stuffing). ``msg`` may
    also be a data frame as (CAN-ID, data, is_extended) (:meth:`BusMonitor.on_frame`)."""
    if isinstance(msg, tuple):
        can_id, data, ext = msg
        if len(data) > 8:
            return (67 if ext else 47) + 8 * len(data)
        return frame_bits_fast(can_id, data, ext)
    data = bytes(msg.data)
    if msg.is_fd or len(data) > 8:
        return (67 if msg.is_extended_id else 47) + 8 * len(data)
    if msg.is_remote_frame:
        return frame_bits(
            msg.arbitration_id, b"", msg.is_extended_id, is_remote=True, dlc=min(msg.dlc, 8)
        )
    return frame_bits_fast(msg.arbitration_id, data, msg.is_extended_id)


class BusMonitor(can.Listener):
    """Counts received frames for rates and bus load (thread-safe).

    Each frame is queued with its arrival time (``time.monotonic()``) and counted in batches:
    every ``_MONITOR_BATCH`` frames on the bus thread, and whenever a figure is read."""

    def __init__(self, window_s: float = 1.0):
        self.window_s = window_s
        self._lock = threading.Lock()
        self._recent: deque[tuple[float, int]] = deque()  # (time, bits)
        #: (arrival, frame) not counted yet; a frame is a Message or (id, data, is_extended)
        self._inbox: deque[tuple[float, _Frame]] = deque()
        self._frames_total = 0
        self._bits_total = 0.0

    def on_message_received(self, msg: can.Message) -> None:
        if msg.is_error_frame:  # a controller report (BusHealth counts it), not a frame on the wire
            return
        inbox = self._inbox
        inbox.append((time.monotonic(), msg))
        if len(inbox) >= _MONITOR_BATCH:
            with self._lock:
                self._count()

    def on_frame(self, can_id: int, data: bytes, is_extended: bool) -> None:
        """Count a data frame received without a :class:`can.Message` (the hub's direct
        path, :class:`Connection`)."""
        inbox = self._inbox
        inbox.append((time.monotonic(), (can_id, data, is_extended)))
        if len(inbox) >= _MONITOR_BATCH:
            with self._lock:
                self._count()

    def _count(self) -> None:
        """Count the queued frames (call with the lock held)."""
        inbox, recent = self._inbox, self._recent
        n = len(inbox)
        if not n:
            return
        bits_sum = 0
        for _ in range(n):  # others may append meanwhile: only the n taken now
            now, msg = inbox.popleft()
            bits = _frame_bits(msg)
            bits_sum += bits
            recent.append((now, bits))
        self._frames_total += n
        self._bits_total += bits_sum
        cutoff = now - self.window_s
        while recent and recent[0][0] < cutoff:
            recent.popleft()

    @property
    def frames_total(self) -> int:
        """Frames received since the start (error frames excluded)."""
        with self._lock:
            self._count()
            return self._frames_total

    @property
    def bits_total(self) -> float:
        """Bits those frames occupied on the wire (exact stuffing)."""
        with self._lock:
            self._count()
            return self._bits_total

    def rates(self) -> tuple[float, float]:
        """(frames/s, bits/s) received over the last ``window_s`` seconds."""
        now = time.monotonic()
        with self._lock:
            self._count()
            cutoff = now - self.window_s
            while self._recent and self._recent[0][0] < cutoff:
                self._recent.popleft()
            n = len(self._recent)
            bits = sum(b for _, b in self._recent)
        return n / self.window_s, bits / self.window_s


def dispatcher(
    network: canopen.Network, monitor: BusMonitor, health: can.Listener
) -> Callable[[can.Message], None]:
    """The Notifier's one callback: what canopen's ``MessageListener``, ``monitor`` and
    ``health`` would do as three listeners, in that order, with one call per frame (``health``
    only gets error frames: it ignores every other frame)."""
    notify = network.notify
    count = monitor.on_message_received
    report = health.on_message_received

    def on_message(msg: can.Message) -> None:
        if msg.is_error_frame:
            report(msg)  # neither canopen nor the monitor takes error frames
            return
        if not msg.is_remote_frame:
            try:
                notify(msg.arbitration_id, msg.data, msg.timestamp)
            except Exception as exc:  # as canopen's MessageListener: a callback's error is logged
                log.error(str(exc))
        count(msg)

    return on_message


def direct_dispatcher(
    network: canopen.Network, monitor: BusMonitor
) -> Callable[[int, bytes, float, bool], None]:
    """What :func:`dispatcher` does for a data frame, called by a bus that hands over frames
    without building a :class:`can.Message` (the project's hub client, ``rx_direct``); it
    never raises (it runs inside the bus's receive call)."""
    notify = network.notify
    count = monitor.on_frame

    def on_frame(can_id: int, data: bytes, stamp: float, is_extended: bool) -> None:
        try:
            notify(can_id, bytearray(data), stamp)  # canopen's callbacks get a bytearray
        except Exception as exc:  # as canopen's MessageListener: a callback's error is logged
            log.error(str(exc))
        try:
            count(can_id, data, is_extended)
        except Exception as exc:  # never into the bus's receive call (the Notifier would die)
            log.error("bus monitor: %s", exc)

    return on_frame


class Connection:
    """A bus, its canopen Network (with Notifier) and a frame monitor; reference counted."""

    def __init__(self, bus: can.BusABC, owns_bus: bool, bitrate: int | None):
        self.bus = bus
        self.owns_bus = owns_bus
        self.bitrate = bitrate
        self.monitor = BusMonitor()
        self.health = BusHealth(bus)
        self.network = PacedNetwork(bus)
        # one plain callback (python-can's Notifier calls any callable) for canopen's listener;
        # canopen infers Network.listeners as list[MessageListener] (no annotation of its own)
        self.network.listeners = [dispatcher(self.network, self.monitor, self.health)]  # type: ignore[list-item]
        if owns_bus and hasattr(bus, "rx_direct"):  # the hub client: data frames without
            bus.rx_direct = direct_dispatcher(self.network, self.monitor)  # a Message each
        self.network.NOTIFIER_CYCLE = 0.1
        self.network.connect()
        self.refs = 0
        #: node-IDs with an open Drive on this bus (scan leaves their SDO channels alone)
        self.active_nodes: dict[int, int | None] = {}  # node-ID → device_type

    def close(self) -> None:
        """Stop the notifier; shut the bus down if this connection opened it."""
        net = self.network
        if net.notifier is not None:
            net.notifier.stop(1.0)
            net.notifier = None
        if self.owns_bus:
            try:
                self.bus.shutdown()
            except Exception:
                pass


_registry: dict[int, Connection] = {}
_registry_lock = threading.Lock()


def acquire(
    bus: can.BusABC | None = None, bitrate: int | None = None, **settings: Any
) -> Connection:
    """Shared connection for ``bus`` (or a bus opened from ``settings``); see :func:`release`."""
    with _registry_lock:
        if bus is None:
            bus = open_bus(bitrate=bitrate, **settings)
            conn = Connection(bus, owns_bus=True, bitrate=bitrate)
            _registry[id(bus)] = conn
        else:
            known = _registry.get(id(bus))
            if known is None or known.bus is not bus:
                known = Connection(bus, owns_bus=False, bitrate=bitrate)
                _registry[id(bus)] = known
            conn = known
        conn.refs += 1
        if conn.bitrate is None:
            conn.bitrate = bitrate or _guess_bitrate(bus)
        return conn


def release(conn: Connection) -> None:
    """Drop one reference; the last one stops the notifier (and shuts an owned bus)."""
    with _registry_lock:
        conn.refs -= 1
        if conn.refs > 0:
            return
        if _registry.get(id(conn.bus)) is conn:
            del _registry[id(conn.bus)]
    conn.close()


def _guess_bitrate(bus: can.BusABC) -> int:
    for attr in ("bitrate", "_bitrate"):
        val = getattr(bus, attr, None)
        if isinstance(val, int) and val > 0:
            return val
    return 1_000_000
