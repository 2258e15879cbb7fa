"""COB-ID rules of CiA 301 for the configurable identifiers of the drive.

Objects: EMCY 0x1014, SDO server 0x1201:1/2 (0x1200 is read-only), PDO communication
0x1400/0x1401/0x1800..0x1803 sub 1, and the consumer heartbeat entries 0x1016.

COB-ID layout (CiA 301 §7.5.2.17, .33, .35, .37): bit 31 = 1 "not valid" (object off), bit 30
(EMCY: reserved 0; SDO: dynamic, only static 0 here; TPDO: 1 = no RTR; RPDO: reserved), bit 29
= 1 29-bit identifier (not supported: this is an 11-bit CAN 2.0A device), bits 28..11 = 0 for an
11-bit identifier, bits 10..0 the CAN-ID. The drive refuses with 0x06090030 (invalid value):

- a reserved/unsupported bit set (29-bit frame, bit 30 where it is reserved or "dynamic"),
- a valid COB-ID whose CAN-ID is restricted (CiA 301 §7.3.5, Table 43): 0x000, 0x001-0x07F,
  0x101-0x180, 0x581-0x5FF, 0x601-0x67F, 0x6E0-0x6FF, 0x701-0x77F, 0x780-0x7FF,
- a new CAN-ID while the object is valid (switch it off first: write the old COB-ID with
  bit 31 set, then the new one).

COB-ID SYNC 0x1005 (§7.5.2.5): bit 31 "do not care", bit 30 "gen" (1 = this node produces
SYNC: refused, the drive is a SYNC consumer only), bit 29 frame (29-bit: refused), bits 10..0 the
CAN-ID (restricted IDs refused); a consumer may change the CAN-ID at any time.

Consumer heartbeat entry (§7.5.2.16): bits 31..24 reserved (0), node-ID in 23..16, time in ms
in 15..0. An entry is off when its time is 0; node-ID 0 with a time, or a node-ID above 127, is
refused with 0x06090030; two active entries for the same node with 0x06040043.
"""

from __future__ import annotations

from collections.abc import Sequence

from . import abort_codes
from .entry import ABORT_INVALID_VALUE, LimitError

__all__ = [
    "ABORT_PARAM_INCOMPATIBLE",
    "COB_INVALID",
    "RESTRICTED_CAN_IDS",
    "check_cob_id",
    "check_heartbeat_consumers",
    "check_sync_cob_id",
    "is_restricted",
]

ABORT_PARAM_INCOMPATIBLE = abort_codes.PARAM_INCOMPATIBLE
COB_INVALID = 1 << 31
COB_BIT30 = 1 << 30
COB_FRAME_29BIT = 1 << 29
CAN_ID_MASK = 0x7FF

#: Inclusive ranges of restricted 11-bit CAN-IDs (CiA 301 §7.3.5).
RESTRICTED_CAN_IDS: tuple[tuple[int, int], ...] = (
    (0x000, 0x000),
    (0x001, 0x07F),
    (0x101, 0x180),
    (0x581, 0x5FF),
    (0x601, 0x67F),
    (0x6E0, 0x6FF),
    (0x701, 0x77F),
    (0x780, 0x7FF),
)

#: kind -> may bit 30 be set?
KINDS = {"emcy": False, "sdo": False, "rpdo": True, "tpdo": True}


def is_restricted(can_id: int) -> bool:
    """True for a CAN-ID no configurable object may use (CiA 301 §7.3.5)."""
    return any(lo <= can_id <= hi for lo, hi in RESTRICTED_CAN_IDS)


def check_cob_id(kind: str, new: int, old: int) -> None:
    """Raise :class:`LimitError` (0x06090030) unless ``new`` may replace ``old``.

    ``kind`` is ``"emcy"``, ``"sdo"``, ``"rpdo"`` or ``"tpdo"``.
    """
    if kind not in KINDS:
        raise ValueError(f"unknown COB-ID kind {kind!r}")
    if new & COB_FRAME_29BIT:
        raise LimitError(ABORT_INVALID_VALUE, f"0x{new:08X}: 29-bit identifiers not supported")
    if new & COB_BIT30 and not KINDS[kind]:
        raise LimitError(ABORT_INVALID_VALUE, f"0x{new:08X}: bit 30 is reserved here")
    if new & 0x1FFFF800:
        raise LimitError(ABORT_INVALID_VALUE, f"0x{new:08X}: bits 28..11 must be 0 (11-bit ID)")
    if new & COB_INVALID:
        return  # switching off (or staying off) with any 11-bit ID is allowed
    can_id = new & CAN_ID_MASK
    if is_restricted(can_id):
        raise LimitError(ABORT_INVALID_VALUE, f"CAN-ID 0x{can_id:03X} is restricted")
    if not old & COB_INVALID and (old & CAN_ID_MASK) != can_id:
        raise LimitError(
            ABORT_INVALID_VALUE,
            f"CAN-ID of a valid object cannot change (0x{old & CAN_ID_MASK:03X} -> "
            f"0x{can_id:03X}): set bit 31 first",
        )


def check_sync_cob_id(new: int) -> None:
    """Raise :class:`LimitError` (0x06090030) unless ``new`` is a COB-ID SYNC a SYNC consumer
    takes (see the module doc)."""
    if new & COB_FRAME_29BIT:
        raise LimitError(ABORT_INVALID_VALUE, f"0x{new:08X}: 29-bit identifiers not supported")
    if new & COB_BIT30:
        raise LimitError(ABORT_INVALID_VALUE, f"0x{new:08X}: this node generates no SYNC")
    if new & 0x1FFFF800:
        raise LimitError(ABORT_INVALID_VALUE, f"0x{new:08X}: bits 28..11 must be 0 (11-bit ID)")
    if is_restricted(new & CAN_ID_MASK):
        raise LimitError(ABORT_INVALID_VALUE, f"CAN-ID 0x{new & CAN_ID_MASK:03X} is restricted")


def check_heartbeat_consumers(entries: Sequence[int], own_node_id: int | None = None) -> None:
    """Validate all 0x1016 entries (present values with the written one in place)."""
    seen: set[int] = set()
    for value in entries:
        if value >> 24:
            raise LimitError(ABORT_INVALID_VALUE, f"0x{value:08X}: bits 31..24 are reserved")
        node_id, time_ms = (value >> 16) & 0xFF, value & 0xFFFF
        if node_id > 127:
            raise LimitError(ABORT_INVALID_VALUE, f"node-ID {node_id} is not 1..127")
        if time_ms == 0:
            continue  # entry off
        if node_id == 0:
            raise LimitError(ABORT_INVALID_VALUE, "a consumer time needs a node-ID (1..127)")
        if own_node_id is not None and node_id == own_node_id:
            raise LimitError(ABORT_INVALID_VALUE, f"node {node_id} is this drive itself")
        if node_id in seen:
            raise LimitError(ABORT_PARAM_INCOMPATIBLE, f"node {node_id} is monitored twice")
        seen.add(node_id)
