"""EMCY error codes the drive sends (CiA 301 Table 21, CiA 402 §8) and what triggers them.

The virtual drive (``virtual_drive.node``) and the DSP firmware (macros ``OD_EMCY_*`` in the
generated header) send exactly these; ``OD.md`` lists them.
"""

from __future__ import annotations

__all__ = [
    "DATA_SET_LOST",
    "DC_OVERVOLTAGE",
    "DC_UNDERVOLTAGE",
    "EMCY_CODES",
    "HEARTBEAT_LOSS",
    "NMT_CONNECTION_LOSS",
    "OVERCURRENT",
    "RPDO_LENGTH",
    "RPDO_VALUE",
]

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
