"""CANopen meaning of one CAN frame, from the EDS and what the bus said so far.

:class:`FrameDecoder` names a frame by its COB-ID (CiA 301 predefined connection set: NMT,
SYNC, EMCY, TPDO/RPDO 1-4, SDO, heartbeat, LSS) and turns its data into text: NMT commands and
heartbeat states, SDO requests and answers with the object's name and value, PDOs decoded
through the node's current mapping (the EDS default, updated by every SDO write or read of the
PDO's communication and mapping objects seen on the bus), EMCY codes with their meaning.
"""

from __future__ import annotations

import struct
from typing import Any

from firmware_protocol import abort_codes, emcy_codes

from ._live import mapped_fields
from ._objects import ObjectTable, default_table
from ._replay import SdoFollower, _Known

__all__ = ["HEARTBEAT_STATES", "NMT_COMMANDS", "FrameDecoder", "kind_of"]

#: CiA 301 §7.2.8.3.2.1 NMT command specifiers
NMT_COMMANDS = {
    0x01: "start",
    0x02: "stop",
    0x80: "enter pre-operational",
    0x81: "reset node",
    0x82: "reset communication",
}
#: CiA 301 §7.2.8.3.2.2 heartbeat / boot-up states
HEARTBEAT_STATES = {0x00: "boot-up", 0x04: "STOPPED", 0x05: "OPERATIONAL", 0x7F: "PRE-OPERATIONAL"}
#: PDO COB-ID bases of the predefined connection set: TPDO1 0x180, RPDO1 0x200, … RPDO4 0x500
_PDO_BASES = {0x180 + 0x100 * (k - 1) + (0x80 if rx else 0): ("RPDO" if rx else "TPDO", k)
              for k in range(1, 5) for rx in (False, True)}  # fmt: skip


def kind_of(can_id: int) -> tuple[str, int | None]:
    """(kind, node-ID) of a COB-ID in the predefined connection set; node None if none."""
    node = can_id & 0x7F
    if can_id == 0x000:
        return "NMT", None
    if can_id == 0x080:
        return "SYNC", None
    if can_id == 0x100:
        return "TIME", None
    if can_id in (0x7E4, 0x7E5):
        return ("LSS answer" if can_id == 0x7E4 else "LSS request"), None
    base = can_id & 0x780
    if node == 0:
        return "?", None
    if base == 0x080:
        return "EMCY", node
    if base in _PDO_BASES:
        kind, k = _PDO_BASES[base]
        return f"{kind}{k}", node
    if base == 0x580:
        return "SDO answer", node
    if base == 0x600:
        return "SDO request", node
    if base == 0x700:
        return "heartbeat", node
    return "?", None


class FrameDecoder:
    """Decodes frames; :meth:`observe` must see every SDO frame (to follow PDO mappings)."""

    def __init__(self, table: ObjectTable | None = None):
        self.table = table or default_table()
        self._sdo: dict[int, SdoFollower] = {}  # node → the follower of its first SDO server
        self._pdo_cache: dict[int, dict[int, tuple[str, list]]] = {}  # node → cob → fields

    def observe(self, can_id: int, data: bytes, t: float) -> None:
        """Feed a frame (cheap for anything but SDO)."""
        base, node = can_id & 0x780, can_id & 0x7F
        if base in (0x580, 0x600) and node:
            f = self._sdo.get(node)
            if f is None:
                f = self._sdo[node] = SdoFollower(0x600 + node, 0x580 + node)
            before = len(f.writes) + len(f.reads)
            f.feed(can_id, data, t)
            if len(f.writes) + len(f.reads) != before:
                self._pdo_cache.pop(node, None)  # a value seen: the mapping may have changed

    # -- text -----------------------------------------------------------------------------
    def text(self, can_id: int, data: bytes) -> str:
        """The frame's meaning in one line."""
        kind, node = kind_of(can_id)
        try:
            if kind == "NMT":
                return self._nmt(data)
            if kind == "heartbeat":
                return (
                    HEARTBEAT_STATES.get(data[0] & 0x7F, f"state 0x{data[0]:02X}") if data else ""
                )
            if kind == "EMCY":
                return self._emcy(data)
            if kind.startswith(("TPDO", "RPDO")) and node is not None:
                return self._pdo(can_id, node, data)
            if kind == "SDO request":
                return self._sdo_request(data)
            if kind == "SDO answer":
                return self._sdo_answer(data)
            if kind == "SYNC":
                return f"SYNC counter {data[0]}" if data else "SYNC"
        except (IndexError, struct.error):
            return f"{kind} ({len(data)} bytes: too short)"
        return ""

    def _nmt(self, d: bytes) -> str:
        what = NMT_COMMANDS.get(d[0], f"command 0x{d[0]:02X}")
        return f"{what} {'all nodes' if d[1] == 0 else f'node {d[1]}'}"

    def _emcy(self, d: bytes) -> str:
        code = d[0] | d[1] << 8
        if code == emcy_codes.ERROR_RESET:
            return f"0x0000 error reset, register 0x{d[2]:02X}"
        return f"0x{code:04X} {emcy_codes.describe(code)}, register 0x{d[2]:02X}"

    def _object(self, index: int, sub: int) -> tuple[str, Any]:
        obj = self.table.by_index(index, sub)
        return (f"0x{index:04X}:{sub:02X} " + (obj.name if obj else "(not in the EDS)")), obj

    def _value(self, obj: Any, raw: bytes) -> str:
        if obj is None or not obj.fmt:
            return raw.hex(" ")
        v = obj.decode(raw[: struct.calcsize(obj.fmt)])
        return _fmt(obj.name, v, obj.unit).split("=", 1)[1]

    def _sdo_request(self, d: bytes) -> str:
        ccs, index, sub = d[0] >> 5, d[1] | d[2] << 8, d[3]
        if d[0] == 0x80:
            return f"abort {self._object(index, sub)[0]}: {self._abort(d)}"
        if ccs == 2:
            return f"read {self._object(index, sub)[0]}"
        if ccs == 1:
            name, obj = self._object(index, sub)
            if d[0] & 0x02:  # expedited
                n = 4 - ((d[0] >> 2) & 0x03) if d[0] & 0x01 else 4
                return f"write {name} = {self._value(obj, d[4 : 4 + n])}"
            return f"write {name} (segmented)"
        if ccs == 5:
            return f"block read {self._object(index, sub)[0]}" if d[0] & 0x03 == 0 else "block read"
        if ccs == 6:
            return "block write"
        return "segment"

    def _sdo_answer(self, d: bytes) -> str:
        scs, index, sub = d[0] >> 5, d[1] | d[2] << 8, d[3]
        if d[0] == 0x80:
            return f"abort {self._object(index, sub)[0]}: {self._abort(d)}"
        if scs == 2:
            name, obj = self._object(index, sub)
            if d[0] & 0x02:
                n = 4 - ((d[0] >> 2) & 0x03) if d[0] & 0x01 else 4
                return f"{name} = {self._value(obj, d[4 : 4 + n])}"
            return f"{name}: segmented upload"
        if scs == 3:
            return f"{self._object(index, sub)[0]} written"
        if scs == 6:
            return "block upload"
        return "segment"

    def _abort(self, d: bytes) -> str:
        code = struct.unpack_from("<I", d, 4)[0]
        return f"0x{code:08X} {abort_codes.meaning(code)}"

    def _pdo(self, can_id: int, node: int, d: bytes) -> str:
        fields = self._fields(node).get(can_id)
        if fields is None:
            return f"{len(d)} bytes (no mapping known)"
        name, flds = fields
        parts = []
        for f in flds:
            if not f.fmt or (f.offset + f.bits) // 8 > len(d):
                continue
            v = struct.unpack_from(f.fmt, d, f.offset // 8)[0]
            parts.append(_fmt(f.name, v, f.unit))
        return f"{name}: " + ", ".join(parts) if parts else name

    def _fields(self, node: int) -> dict[int, tuple[str, list]]:
        """COB-ID → (PDO name, mapped fields) of node ``node`` as known now (cached)."""
        cached = self._pdo_cache.get(node)
        if cached is not None:
            return cached
        f = self._sdo.get(node)
        known = _Known(self.table, node, [f] if f is not None else [])
        out: dict[int, tuple[str, list]] = {}
        for kind in ("tpdo", "rpdo"):
            for k in range(1, 5):
                try:
                    cob = known.int(f"{kind}{k}_communication.cob_id")
                    n = known.int(f"{kind}{k}_mapping.number_of_mapped_objects")
                    refs = [known.int(f"{kind}{k}_mapping.mapped_object_{i}") for i in
                            range(1, n + 1)]  # fmt: skip
                except KeyError:
                    continue
                if cob & 0x80000000:
                    continue
                mapped = ((r >> 16, (r >> 8) & 0xFF, r & 0xFF) for r in refs)
                out[cob & 0x7FF] = (f"{kind.upper()}{k}", mapped_fields(mapped, self.table))
        self._pdo_cache[node] = out
        return out


def _fmt(name: str, v: Any, unit: str) -> str:
    if isinstance(v, float):
        text = f"{v:.6g}"
    elif isinstance(v, int) and name.endswith(("word", "cob_id")):
        text = f"0x{v:04X}"
    elif isinstance(v, int) and "mapped_object_" in name:  # index, sub-index, bits
        text = f"0x{v:08X}"
    else:
        text = str(v)
    return f"{name}={text}" + (f" {unit}" if unit else "")
