"""One canopen :class:`~canopen.Network` per python-can bus, shared by every drive on it.

python-can allows one reader per bus, so all drives (and scans) on one bus share one Network and
its Notifier thread. :class:`BusMonitor` counts every frame for rates and bus load.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from typing import Any

import can
import canopen

from .bus import open_bus


def frame_bits(dlc: int, extended: bool = False) -> float:
    """Approximate bits on the wire of one data frame (incl. typical bit stuffing, 3-bit IFS).

    Standard frame: 47 + 8·dlc bits without stuffing; stuffing adds about 1 bit in 5 of the
    stuffed part (34 + 8·dlc bits) in the worst case, ~half that for random data.
    """
    base = (67 if extended else 47) + 8 * dlc
    stuffed = (54 if extended else 34) + 8 * dlc
    return base + 0.1 * stuffed


class BusMonitor(can.Listener):
    """Counts received frames per CAN-ID for rates and bus load (thread-safe)."""

    def __init__(self, window_s: float = 1.0):
        self.window_s = window_s
        self._lock = threading.Lock()
        self._recent: deque[tuple[float, float]] = deque()  # (time, bits)
        self.frames_total = 0
        self.bits_total = 0.0

    def on_message_received(self, msg: can.Message) -> None:
        bits = frame_bits(msg.dlc, msg.is_extended_id)
        now = time.monotonic()
        with self._lock:
            self.frames_total += 1
            self.bits_total += bits
            self._recent.append((now, bits))
            cutoff = now - self.window_s
            while self._recent and self._recent[0][0] < cutoff:
                self._recent.popleft()

    def rates(self) -> tuple[float, float]:
        """(frames/s, bits/s) received over the last ``window_s`` seconds."""
        now = time.monotonic()
        with self._lock:
            cutoff = now - self.window_s
            while self._recent and self._recent[0][0] < cutoff:
                self._recent.popleft()
            n = len(self._recent)
            bits = sum(b for _, b in self._recent)
        return n / self.window_s, bits / self.window_s


class Connection:
    """A bus, its canopen Network (with Notifier) and a frame monitor; reference counted."""

    def __init__(self, bus: can.BusABC, owns_bus: bool, bitrate: int | None):
        self.bus = bus
        self.owns_bus = owns_bus
        self.bitrate = bitrate
        self.monitor = BusMonitor()
        self.network = canopen.Network(bus)
        self.network.listeners.append(self.monitor)
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
            conn = _registry.get(id(bus))
            if conn is None or conn.bus is not bus:
                conn = Connection(bus, owns_bus=False, bitrate=bitrate)
                _registry[id(bus)] = conn
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
