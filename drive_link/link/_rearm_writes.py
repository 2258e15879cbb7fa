"""The journal side of session supervision (:mod:`drive_link.link.supervision`): which writes a
session replays after a drive restart, what one re-arm did (:class:`RearmReport`), and the CiA
301 §7.2.2 procedure that gives a PDO its parameters back (:func:`write_pdo_group`).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import Any

from firmware_protocol import load_od
from firmware_protocol.index_ranges import COMMUNICATION, RPDO_COMM, RPDO_MAP, TPDO_COMM, TPDO_MAP

from ..errors import DriveError
from ._sdo import SdoChannel

__all__ = [
    "ABORT_CONNECTION_OPTION",
    "NOT_JOURNALLED",
    "RearmReport",
    "journalled",
    "pdo_group",
    "write_entry",
    "write_pdo_group",
]

#: Communication objects never replayed: error history, store/restore commands, read-only
#: identity and error objects.
NOT_JOURNALLED = frozenset(
    {0x1002}  # manufacturer status register (CiA 301; not in this drive's OD)
    | {
        load_od().entry(n).index
        for n in (
            "error_register",
            "pre_defined_error_field.number_of_errors",
            "store_parameters.save_all",
            "restore_default_parameters.restore_all",
        )
    }
)
ABORT_CONNECTION_OPTION = load_od().entry("abort_connection_option_code").index


def journalled(index: int) -> bool:
    """True if a write to ``index`` is part of the session's supervision/communication setup."""
    return (index in COMMUNICATION and index not in NOT_JOURNALLED) or (
        index == ABORT_CONNECTION_OPTION
    )


def pdo_group(index: int) -> tuple[str, int] | None:
    """("rpdo"|"tpdo", k) for the communication/mapping parameter objects of PDO k (0-based),
    else None."""
    for base_comm, base_map, kind in ((RPDO_COMM, RPDO_MAP, "rpdo"), (TPDO_COMM, TPDO_MAP, "tpdo")):
        if base_comm <= index < base_comm + 0x200:
            return kind, index - base_comm
        if base_map <= index < base_map + 0x200:
            return kind, index - base_map
    return None


@dataclass
class RearmReport:
    """What one re-arm did: ``reason``, ``written`` / ``failed`` ("0xIIII:SS" → detail),
    ``at`` (ISO time, UTC), ``seconds`` taken, ``reboot`` (True when the drive had lost the
    session's settings)."""

    reason: str
    reboot: bool = False
    written: list[str] = field(default_factory=list)
    failed: dict[str, str] = field(default_factory=dict)
    at: str | None = None
    seconds: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        return {
            "reason": self.reason,
            "reboot": self.reboot,
            "written": list(self.written),
            "failed": dict(self.failed),
            "at": self.at,
            "seconds": self.seconds,
        }


def write_entry(sdo: SdoChannel, key: tuple[int, int], data: bytes, report: RearmReport) -> None:
    where = f"0x{key[0]:04X}:{key[1]:02X}"
    try:
        SdoChannel.download(sdo, key[0], key[1], data)
        report.written.append(where)
    except DriveError as exc:
        report.failed[where] = str(exc)


def write_pdo_group(
    sdo: SdoChannel,
    group: tuple[str, int],
    keys: list[tuple[int, int]],
    values: dict[tuple[int, int], bytes],
    report: RearmReport,
) -> None:
    """Give PDO ``group`` the ``values`` of ``keys`` by the CiA 301 §7.2.2 procedure:
    invalidate the PDO, clear its mapping, write the entries, the count, the other
    communication parameters and finally the COB-ID (unsupervised transfers)."""
    kind, k = group
    comm = (RPDO_COMM if kind == "rpdo" else TPDO_COMM) + k
    mapping = (RPDO_MAP if kind == "rpdo" else TPDO_MAP) + k
    cob_key = (comm, 1)
    try:
        cob = values.get(cob_key) or SdoChannel.upload(sdo, comm, 1)[:4]
    except DriveError as exc:
        report.failed[f"0x{comm:04X}:01"] = str(exc)
        return
    cob_value = struct.unpack("<I", cob.ljust(4, b"\0"))[0]
    write_entry(sdo, cob_key, struct.pack("<I", cob_value | 0x80000000), report)
    map_keys = [kk for kk in keys if kk[0] == mapping and kk[1] != 0]
    if map_keys or (mapping, 0) in values:
        write_entry(sdo, (mapping, 0), b"\x00", report)
        for kk in sorted(map_keys):
            write_entry(sdo, kk, values[kk], report)
        if (mapping, 0) in values:
            write_entry(sdo, (mapping, 0), values[(mapping, 0)], report)
    for kk in keys:
        if kk[0] == comm and kk[1] != 1:
            write_entry(sdo, kk, values[kk], report)
    write_entry(sdo, cob_key, struct.pack("<I", cob_value), report)
