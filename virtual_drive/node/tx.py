"""Batched transmission: the frames due at one instant (the TPDOs of a pacing tick) in one write.

:func:`make_send_many` gives the TPDO engine a ``send_many(frames)`` for a drive: on a bus with
``send_many`` (:class:`virtual_drive.node.hub_bus.HubBus`: one ``sendall`` for all frames) it is
used under the drive's send lock with the drive's error bookkeeping (``tx_errors``,
``last_tx_ok``); on any other python-can bus the frames go one by one through the drive's own
``_send`` (ENOBUFS retries and all). ``at`` (monotonic s) is when the frames were due: a bus
with ``timed_sends`` (the loopback hub) puts them on the emulated bus from that time.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any

import can

__all__ = ["make_send_many"]

logger = logging.getLogger(__name__)


def make_send_many(drive: Any) -> Callable[..., None]:
    """``send_many(frames, at=None)`` for ``drive`` (a VirtualDrive: ``bus``, ``_send``,
    ``_send_lock``, ``tx_errors``, ``last_tx_ok``); never raises."""

    bus = drive.bus
    if getattr(bus, "timed_sends", False):
        hold = bus.send_many  # (the pacing thread's frames, held until its flush: no lock)
    else:
        hold = None

    def send_many(frames: list[tuple[int, bytes]], at: float | None = None) -> None:
        if at is not None and hold is not None:
            hold(frames, at)
            return
        bus_send_many = getattr(bus, "send_many", None)
        if bus_send_many is None:
            for cob_id, data in frames:
                drive._send(cob_id, data)
            return
        try:
            with drive._send_lock:
                if at is None:
                    bus_send_many(frames)
                else:  # (the bus sends them now if it cannot say when they were due)
                    bus_send_many(frames, at)
            drive.last_tx_ok = time.monotonic()
        except (can.CanError, OSError) as exc:
            drive.tx_errors += len(frames)
            if drive.tx_errors < 10 or drive.tx_errors % 1000 < len(frames):
                logger.warning("send of %d frames failed: %s", len(frames), exc)

    return send_many
