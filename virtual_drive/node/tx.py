"""The drive's transmitter: every frame it sends goes through one :class:`Transmitter`.

:class:`Transmitter` owns the bus's send side: the send lock (one writer at a time: SDO
answers, EMCY, heartbeat and the pacing thread's TPDOs), the count of failed sends
(``tx_errors``) and the time of the last frame the bus accepted (``last_tx_ok``).

- :meth:`Transmitter.send` puts one frame on the bus (a full SocketCAN queue, ENOBUFS, is retried
  for up to 10 ms);
- :meth:`Transmitter.send_many` is the TPDO engine's batched send: the frames due at one
  instant (the TPDOs of a pacing tick) in one write on a bus with ``send_many``
  (:class:`virtual_drive.node.hub_bus.HubBus`: one ``sendall`` for all frames), one by one
  through :meth:`send` on any other python-can bus. ``at`` (monotonic s) is when the frames were
  due: a bus with ``timed_sends`` (the loopback hub) puts them on the emulated bus from that
  time, and holds them until :meth:`Transmitter.flush` (one write per tick).
"""

from __future__ import annotations

import errno
import logging
import threading
import time
from collections.abc import Callable

import can

__all__ = ["Transmitter"]

logger = logging.getLogger(__name__)


class Transmitter:
    """The send side of a drive's bus; never raises (errors are counted in ``tx_errors``).

    :param bus: any python-can bus (``timed_sends``/``send_many``/``flush`` used if it has them).
    """

    def __init__(self, bus: can.BusABC) -> None:
        self.bus = bus
        #: one writer at a time on the bus
        self.send_lock = threading.Lock()
        self.tx_errors = 0  #: frames the bus refused
        self.last_tx_ok = time.monotonic()  #: time of the last frame the bus accepted
        #: the bus takes frames with their bus time (the loopback hub)
        self.timed_sends = bool(getattr(bus, "timed_sends", False))
        # (the pacing thread's frames, held until its flush: no lock); a bus with timed_sends
        # (HubBus, HubPort) has send_many(frames, at) and flush(), which BusABC does not declare
        self._hold: Callable[[list[tuple[int, bytes]], float], object] | None = (
            getattr(bus, "send_many", None) if self.timed_sends else None
        )
        self._bus_flush: Callable[[], object] | None = (
            getattr(bus, "flush", None) if self.timed_sends else None
        )

    def _count_error(self, n: int, what: str, exc: Exception) -> None:
        self.tx_errors += n
        if self.tx_errors < 10 or self.tx_errors % 1000 < n:
            logger.warning("%s failed: %s", what, exc)

    def send(self, cob_id: int, data: bytes) -> None:
        """Put one frame on the bus.

        A full transmit queue (SocketCAN's ENOBUFS with the default ``txqueuelen 10``, e.g. in
        a 127-frame block-upload burst) is retried for up to 10 ms before the frame is dropped.
        """
        msg = can.Message(arbitration_id=cob_id, data=data, is_extended_id=False)
        for attempt in range(21):
            try:
                with self.send_lock:
                    self.bus.send(msg)
                self.last_tx_ok = time.monotonic()
                return
            except (can.CanError, OSError) as exc:
                full = getattr(exc, "errno", None) == errno.ENOBUFS or "No buffer space" in str(exc)
                if full and attempt < 20:
                    time.sleep(0.0005)
                    continue
                self._count_error(1, f"send 0x{cob_id:03X}", exc)
                return

    def send_many(self, frames: list[tuple[int, bytes]], at: float | None = None) -> None:
        """The frames due at one instant ``at`` (monotonic s; None: now) in one bus write."""
        if at is not None and self._hold is not None:
            self._hold(frames, at)
            return
        bus_send_many = getattr(self.bus, "send_many", None)
        if bus_send_many is None:
            for cob_id, data in frames:
                self.send(cob_id, data)
            return
        try:
            with self.send_lock:
                if at is None:
                    bus_send_many(frames)
                else:  # (the bus sends them now if it cannot say when they were due)
                    bus_send_many(frames, at)
            self.last_tx_ok = time.monotonic()
        except (can.CanError, OSError) as exc:
            self._count_error(len(frames), f"send of {len(frames)} frames", exc)

    def send_at(self, cob_id: int, data: bytes, at: float) -> None:
        """One frame due at ``at`` (monotonic s), held as :meth:`send_many` holds frames."""
        self.send_many([(cob_id, data)], at)

    def flush(self) -> None:
        """End of a timed tick: the bus writes the frames it held (one write per tick)."""
        try:
            if self._bus_flush is None:  # (not a timed bus: nothing is held)
                return
            with self.send_lock:
                self._bus_flush()
            self.last_tx_ok = time.monotonic()
        except (can.CanError, OSError) as exc:
            self._count_error(1, "send of the tick's frames", exc)
