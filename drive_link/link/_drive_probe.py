"""What a drive's own objects say about its communication, asked at connect and for the
summary: the EMCY COB-ID (0x1014), the second SDO server (0x1201) and the parameter store's
health (0x2060). Each function takes the SDO read it needs; none changes the drive.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from firmware_protocol import load_od
from firmware_protocol.enums import StoreStatus

from ..errors import DriveError, SdoAbort
from ._objects import ObjectTable
from ._sdo import SdoChannel

__all__ = ["STORE_STATUS", "STORE_STATUS_INDEX", "emcy_cob", "store_status", "trace_server"]

#: 0x2060 store_status (U8, ro) values → name (the EDS enumeration, :class:`StoreStatus`).
STORE_STATUS: dict[int, str] = {int(s): s.name.lower() for s in StoreStatus}
STORE_STATUS_INDEX = load_od().entry("store_status").index

_INVALID = 0x80000000  # CiA 301: bit 31 of a COB-ID entry, "not valid"


def emcy_cob(read: Callable[[str], Any]) -> int | None:
    """The drive's EMCY COB-ID (0x1014, 11 bits), or None if unreadable or not valid."""
    try:
        cob = int(read("cob_id_emcy"))
    except DriveError:
        return None
    return None if cob & _INVALID else cob & 0x7FF


def trace_server(read: Callable[[str], Any]) -> tuple[int, int] | None:
    """(request, response) COB-IDs of the drive's second SDO server (0x1201), or None if it
    has none or they are not valid (uploads then share the first channel)."""
    try:
        rx = int(read("sdo_server_2.cob_id_client_to_server"))
        tx = int(read("sdo_server_2.cob_id_server_to_client"))
    except DriveError:
        return None
    if rx & _INVALID or tx & _INVALID:
        return None
    return rx & 0x7FF, tx & 0x7FF


def store_status(sdo: SdoChannel, table: ObjectTable) -> str:
    """Health of the drive's parameter store, 0x2060: "ok" (stored parameters loaded),
    "defaults" (no store), "damaged" / "unreadable" (stored parameters lost: defaults in use),
    or "unknown" (firmware without 0x2060)."""
    if "store_status" not in table:
        index, sub = STORE_STATUS_INDEX, 0
    else:
        obj = table["store_status"]
        index, sub = obj.index, obj.subindex
    try:
        raw = sdo.upload(index, sub, "store_status")
    except SdoAbort:
        return "unknown"
    if not raw:
        return "unknown"
    return STORE_STATUS.get(raw[0], f"code {raw[0]}")
