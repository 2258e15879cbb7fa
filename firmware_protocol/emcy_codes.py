"""EMCY error codes (CiA 301 table 21, CiA 402 §8): the ones the drive sends and their meanings.

The virtual drive (``virtual_drive.node``) and the DSP firmware (macros ``OD_EMCY_*`` in the
generated header) send exactly :data:`EMCY_CODES`; ``OD.md`` lists them. The sample loop's
protection (``virtual_drive/csrc/loop.c``) trips for one of :data:`TRIP_REASONS` (macros
``OD_TRIP_*``), each with its EMCY code. :data:`MEANINGS` and
:func:`describe` are what the host shows (``drive_link``, the dashboard): the exact code when it
is listed, else its class from canopen's own table (:attr:`canopen.emcy.EmcyError.DESCRIPTIONS`).

>>> describe(HEARTBEAT_LOSS)
'life guard / heartbeat error'
>>> describe(0x4999)
'temperature'
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import NamedTuple

from canopen.emcy import EmcyError

__all__ = [
    "DATA_SET_LOST",
    "DC_OVERVOLTAGE",
    "DC_UNDERVOLTAGE",
    "EMCY_CODES",
    "ERROR_RESET",
    "HEARTBEAT_LOSS",
    "MEANINGS",
    "NMT_CONNECTION_LOSS",
    "OVERCURRENT",
    "RPDO_LENGTH",
    "RPDO_VALUE",
    "TRIP_REASONS",
    "TripReason",
    "describe",
]

ERROR_RESET = 0x0000
"""Error reset / no error (sent when the last error is cleared)."""
OVERCURRENT = 0x2310
DC_OVERVOLTAGE = 0x3210
DC_UNDERVOLTAGE = 0x3220
DATA_SET_LOST = 0x6310
NMT_CONNECTION_LOSS = 0x8100
HEARTBEAT_LOSS = 0x8130
RPDO_VALUE = 0x8200
RPDO_LENGTH = 0x8210

#: code -> (macro stem, when the drive sends it)
EMCY_CODES: dict[int, tuple[str, str]] = {
    OVERCURRENT: (
        "OVERCURRENT",
        "overcurrent trip: a phase current above protection.overcurrent_trip (or a non-finite "
        "state); CiA 402 0x2310 - the trip compares |i_a|, |i_b|, |i_c| with a threshold, it "
        "does not detect short circuits or earth leakage (0x2320)",
    ),
    DC_OVERVOLTAGE: ("DC_OVERVOLTAGE", "DC-link voltage above protection.overvoltage_trip"),
    DC_UNDERVOLTAGE: ("DC_UNDERVOLTAGE", "DC-link voltage below protection.undervoltage_trip"),
    DATA_SET_LOST: (
        "DATA_SET_LOST",
        "after boot-up when the parameter store was damaged or unreadable (store_status 2/3): "
        "defaults are in use; error register bit 0",
    ),
    NMT_CONNECTION_LOSS: (
        "NMT_CONNECTION_LOSS",
        "fault code of abort_connection_option_code = 1 after NMT stop / reset while "
        "OPERATION ENABLED (0x603F; no frame in STOPPED)",
    ),
    HEARTBEAT_LOSS: ("HEARTBEAT_LOSS", "a consumer heartbeat (0x1016) timed out; data[3] = node"),
    RPDO_VALUE: (
        "RPDO_VALUE",
        "RPDO dropped as a whole (none of its objects applied): a mapped value was refused; "
        "data[3] = RPDO number, data[4..5] = index (LE), data[6] = sub-index of the refused "
        "object, data[7] = low byte of its SDO abort code (0x30/0x31/0x32/0x22)",
    ),
    RPDO_LENGTH: (
        "RPDO_LENGTH",
        "RPDO shorter than its mapping, not processed; data[3] = RPDO number, data[4] = bytes "
        "received, data[5] = bytes mapped",
    ),
}


class TripReason(NamedTuple):
    """Why the sample loop's protection tripped: macro stem, the EMCY code it sends (``None``:
    the injected code itself) and its text."""

    stem: str
    emcy: int | None
    text: str


#: trip reason number (the C loop's ``fault_reason``, macros ``OD_TRIP_*``) -> its reason
TRIP_REASONS: dict[int, TripReason] = {
    1: TripReason(
        "OVERCURRENT",
        OVERCURRENT,
        "overcurrent: phase current above protection.overcurrent_trip",
    ),
    2: TripReason("NONFINITE", OVERCURRENT, "overcurrent: non-finite (diverged) state"),
    3: TripReason("DC_OVERVOLTAGE", DC_OVERVOLTAGE, "DC-link overvoltage"),
    4: TripReason("DC_UNDERVOLTAGE", DC_UNDERVOLTAGE, "DC-link undervoltage"),
    5: TripReason("INJECTED", None, "injected fault"),
}

MEANINGS: Mapping[int, str] = MappingProxyType(
    {
        ERROR_RESET: "error reset / no error",
        0x1000: "generic error",
        OVERCURRENT: "continuous overcurrent",
        0x2320: "short circuit / instantaneous overcurrent",
        DC_OVERVOLTAGE: "DC-link overvoltage",
        DC_UNDERVOLTAGE: "DC-link undervoltage",
        0x4210: "excess temperature device",
        0x4310: "excess temperature drive",
        0x5000: "device hardware",
        0x6000: "device software",
        0x6300: "data set",
        DATA_SET_LOST: "loss of parameters (stored parameters unusable: defaults in use)",
        NMT_CONNECTION_LOSS: "communication",
        0x8110: "CAN overrun (objects lost)",
        0x8120: "CAN in error passive mode",
        HEARTBEAT_LOSS: "life guard / heartbeat error",
        0x8140: "recovered from bus off",
        RPDO_VALUE: "protocol error (e.g. an RPDO value refused)",
        RPDO_LENGTH: "PDO not processed due to length error",
        0x8220: "PDO length exceeded",
        0xFF00: "device specific",
    }
)
"""EMCY code -> meaning (CiA 301 table 21, CiA 402 §8) for the codes the drive sends and their
CiA neighbours a generic drive may send."""


def describe(code: int) -> str:
    """Meaning of an EMCY error code: the exact code, else the listed code it refines (low
    nibble, then low byte cleared), else its class (canopen's class table), else ``"unknown"``."""
    for mask in (0xFFFF, 0xFFF0, 0xFF00):
        if code & mask in MEANINGS:
            return MEANINGS[code & mask]
    for masked, mask, text in EmcyError.DESCRIPTIONS:
        if code & mask == masked:
            return text.lower()
    return "unknown"
