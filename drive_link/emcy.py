"""Emergency messages (CiA 301 §7.2.7) and the pre-defined error field 0x1003."""

from __future__ import annotations

import struct
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import canopen

from firmware_protocol import emcy_codes

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

    @property
    def description(self) -> str:
        """Meaning of ``code``."""
        return describe(self.code)

    def __str__(self) -> str:
        return f"EMCY 0x{self.code:04X} ({self.description}), error register 0x{self.register:02X}"


class EmcyListener:
    """Collects the EMCY frames of one node and calls subscribers (on the notifier thread)."""

    def __init__(self, network: canopen.Network, cob_id: int, max_history: int = 256):
        self.cob_id = cob_id
        self._network = network
        self._lock = threading.Lock()
        self.history: list[Emcy] = []
        self.max_history = max_history
        self._callbacks: list[Callable[[Emcy], None]] = []
        network.subscribe(cob_id, self._on_frame)

    def close(self) -> None:
        """Stop listening."""
        try:
            self._network.unsubscribe(self.cob_id, self._on_frame)
        except (KeyError, ValueError):
            pass

    def subscribe(self, callback: Callable[[Emcy], None]) -> None:
        """Call ``callback(emcy)`` for every EMCY received (keep it short: notifier thread)."""
        self._callbacks.append(callback)

    def _on_frame(self, can_id: int, data: bytearray, timestamp: float) -> None:
        if len(data) < 3:
            return
        code, reg = struct.unpack_from("<HB", data)
        e = Emcy(code=code, register=reg, data=bytes(data[3:8]), timestamp=timestamp or time.time())
        with self._lock:
            self.history.append(e)
            del self.history[: -self.max_history]
        for cb in list(self._callbacks):
            try:
                cb(e)
            except Exception:
                pass
