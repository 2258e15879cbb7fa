"""Emergency messages (CiA 301 §7.2.7) and the pre-defined error field 0x1003.

Reception is canopen's :class:`~canopen.emcy.EmcyConsumer` (``RemoteNode.emcy``) with the small
hardening of :class:`EmcyListener`; this module adds the meanings of the codes and the
:class:`Emcy` value the library hands out.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from canopen.emcy import EmcyConsumer, EmcyError

from firmware_protocol import emcy_codes

__all__ = ["EMCY_CODES", "Emcy", "EmcyListener", "describe"]

EMCY_CODES: Mapping[int, str] = emcy_codes.MEANINGS
"""EMCY error code -> meaning (CiA 301 table 21, CiA 402): :mod:`firmware_protocol.emcy_codes`."""
describe = emcy_codes.describe


@dataclass(frozen=True)
class Emcy:
    """One emergency: ``code`` (U16), ``register`` (0x1001 value), ``data`` (5 manufacturer
    bytes), ``timestamp`` (s, host clock; None for entries read from 0x1003), ``description``."""

    code: int
    register: int = 0
    data: bytes = b""
    timestamp: float | None = None

    @classmethod
    def from_error(cls, err: EmcyError) -> Emcy:
        """The :class:`Emcy` of a canopen :class:`~canopen.emcy.EmcyError`."""
        return cls(code=err.code, register=err.register, data=bytes(err.data),
                   timestamp=err.timestamp)  # fmt: skip

    @property
    def description(self) -> str:
        """Meaning of ``code``."""
        return describe(self.code)

    def __str__(self) -> str:
        return f"EMCY 0x{self.code:04X} ({self.description}), error register 0x{self.register:02X}"


class EmcyListener(EmcyConsumer):
    """canopen's :class:`~canopen.emcy.EmcyConsumer` of one node (``RemoteNode.emcy``), made
    safe for a long session on a real bus.

    What it adds to canopen's consumer: a frame shorter than 8 bytes (3 is enough for code and
    register) is accepted instead of raising ``struct.error`` on the bus thread, the log keeps
    the last ``max_history`` entries instead of growing for ever, a raising subscriber does not
    keep the others from being called, and subscribers get :class:`Emcy` values.
    ``log``/``active``/``wait()`` are canopen's.
    """

    def __init__(self, max_history: int = 256):
        super().__init__()
        self.max_history = max_history

    def on_emcy(self, can_id: int, data: bytes | bytearray, timestamp: float) -> None:
        """Bus-thread handler (subscribed to the node's EMCY COB-ID)."""
        if len(data) < 3:
            return  # not an EMCY (CiA 301 §7.2.7.3.1: 8 bytes; code and register are needed)
        super().on_emcy(can_id, bytes(data[:8]).ljust(8, b"\x00"), timestamp or time.time())
        with self.emcy_received:
            del self.log[: -self.max_history]
            del self.active[: -self.max_history]

    @property
    def history(self) -> list[Emcy]:
        """EMCYs received, oldest first (at most ``max_history``)."""
        with self.emcy_received:
            return [Emcy.from_error(e) for e in self.log]

    def subscribe(self, callback: Callable[[Emcy], None]) -> None:
        """Call ``callback(emcy)`` for every EMCY received (keep it short: bus thread)."""

        def safe(err: EmcyError) -> None:
            try:
                callback(Emcy.from_error(err))
            except Exception:
                pass  # a subscriber's bug must not stop the other subscribers

        self.add_callback(safe)
