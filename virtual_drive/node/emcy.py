"""EMCY producer with the bookkeeping CiA 301 §7.2.7 asks for.

Keeps 0x1001 error register, 0x1003 pre-defined error field (newest first, at most 8 entries,
sub0 = count, writing 0 to sub0 clears it) and CiA 402's 0x603F error code consistent with the
EMCY frames sent on ``cob_id`` (0x80+N): ``[code lo, code hi, error_register, 5 bytes
manufacturer data]``. When the last active error clears, an "error reset" EMCY (code 0x0000)
is sent.
"""

from __future__ import annotations

import logging
import struct
import threading
from collections.abc import Callable

from firmware_protocol.cob_id import CAN_ID_MASK, COB_INVALID
from firmware_protocol.emcy_codes import (  # the codes of OD.md / the C header
    DATA_SET_LOST,
    DC_OVERVOLTAGE,
    DC_UNDERVOLTAGE,
    ERROR_RESET,
    HEARTBEAT_LOSS,
    NMT_CONNECTION_LOSS,
    OVERCURRENT,
    RPDO_LENGTH,
    RPDO_VALUE,
)
from firmware_protocol.od import load_od

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
ERROR_HISTORY_INDEX = _OD.index_of("pre_defined_error_field")
#: the standard error fields, newest first (sub 1, 2, ...)
ERROR_HISTORY_FIELDS: tuple[tuple[int, int], ...] = tuple(
    (ERROR_HISTORY_INDEX, sub) for sub in sorted(_OD.sub_names("pre_defined_error_field"))
)


__all__ = [
    "DATA_SET_LOST",
    "DC_OVERVOLTAGE",
    "DC_UNDERVOLTAGE",
    "ERROR_RESET",
    "HEARTBEAT_LOSS",
    "NMT_CONNECTION_LOSS",
    "OVERCURRENT",
    "RPDO_LENGTH",
    "RPDO_VALUE",
    "EmcyManager",
    "register_bits",
]

logger = logging.getLogger(__name__)

#: 0x1001 bits: 0 generic, 1 current, 2 voltage, 3 temperature, 4 communication.
REG_GENERIC = 0x01
REG_CURRENT = 0x02
REG_VOLTAGE = 0x04
REG_TEMPERATURE = 0x08
REG_COMMUNICATION = 0x10

HISTORY_DEPTH = len(ERROR_HISTORY_FIELDS)
"""Entries 0x1003 holds (its standard error fields in the EDS: 8)."""


def register_bits(code: int) -> int:
    """Error-register bits an EMCY code sets (generic bit 0 is always set with any error)."""
    group = code & 0xF000
    bits = REG_GENERIC
    if group == 0x2000:
        bits |= REG_CURRENT
    elif group == 0x3000:
        bits |= REG_VOLTAGE
    elif group == 0x4000:
        bits |= REG_TEMPERATURE
    elif group == 0x8000:
        bits |= REG_COMMUNICATION
    return bits


class EmcyManager:
    """Active errors, history and EMCY frames.

    :param cob_id: EMCY COB-ID (0x1014, default 0x80+N).
    :param send: ``send(cob_id, data)``.
    :param allowed: False while NMT forbids EMCY (STOPPED); bookkeeping still happens.
    """

    def __init__(
        self, cob_id: int, send: Callable[[int, bytes], None], allowed: Callable[[], bool]
    ) -> None:
        self.cob_id: int | None = cob_id
        self._send = send
        self._allowed = allowed
        self._lock = threading.Lock()
        self.active: dict[int, int] = {}  # code -> register bits
        self.history: list[int] = []  # newest first (0x1003 sub1..)
        self.last_code = 0  # 0x603F

    @property
    def error_register(self) -> int:
        """0x1001 value: OR of the active errors' bits."""
        reg = 0
        for bits in self.active.values():
            reg |= bits
        return reg

    def raise_error(self, code: int, data: bytes = b"") -> bool:
        """Record and send an error; returns False (and sends nothing) if already active."""
        with self._lock:
            if code in self.active:
                return False
            self.active[code] = register_bits(code)
            self.history.insert(0, code)
            del self.history[HISTORY_DEPTH:]
            self.last_code = code
            reg = self.error_register
        logger.warning("EMCY 0x%04X (error register 0x%02X)", code, reg)
        self._emit(code, reg, data)
        return True

    def announce(self, code: int, data: bytes = b"") -> bool:
        """Send the EMCY of an error that is already active again (e.g. after a boot-up, for
        a master that was not listening); no bookkeeping change. False if not active."""
        with self._lock:
            if code not in self.active:
                return False
            reg = self.error_register
        self._emit(code, reg, data)
        return True

    def clear_error(self, code: int) -> None:
        """Clear one active error; sends the error-reset EMCY when none remain."""
        with self._lock:
            if self.active.pop(code, None) is None:
                return
            reg = self.error_register
            if not self.active:
                self.last_code = 0
        if reg == 0:
            self._emit(ERROR_RESET, 0, b"")

    def clear_all(self) -> None:
        """Clear every active error (fault reset); error reset EMCY if any was active."""
        with self._lock:
            had = bool(self.active)
            self.active.clear()
            self.last_code = 0
        if had:
            self._emit(ERROR_RESET, 0, b"")

    def clear_history(self) -> None:
        """0x1003 sub0 := 0."""
        with self._lock:
            self.history.clear()

    def set_cob_id(self, value: int) -> None:
        """0x1014 value: bit 31 set = EMCY not sent (CiA 301 §7.5.2.17), bits 10..0 COB-ID."""
        self.cob_id = None if value & COB_INVALID else value & CAN_ID_MASK

    def _emit(self, code: int, reg: int, data: bytes) -> None:
        if not self._allowed() or self.cob_id is None:
            return
        payload = struct.pack("<HB", code, reg) + bytes(data[:5]).ljust(5, b"\x00")
        self._send(self.cob_id, payload)
