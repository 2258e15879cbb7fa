"""The drive's object dictionary as the host sees it: a thin adapter over :mod:`firmware_protocol`.

Every fact (names, indices, types, access, units, limits, defaults, enumerations, PDO flags)
comes from :func:`firmware_protocol.load_od`, the one reading of the EDS; limit checks are
:meth:`firmware_protocol.Entry.check`, the same code the drive runs before storing a write.
What is host-specific lives here: parsing CLI text into numbers, struct encode/decode of
and mapping :class:`firmware_protocol.LimitError` to :class:`InvalidValue`. Values on the wire are
encoded and decoded by canopen's own :class:`~canopen.objectdictionary.ODVariable` of the same
EDS (``encode_raw`` / ``decode_raw``): one model of an object, the one a :class:`canopen.RemoteNode`
uses too (:attr:`ObjectTable.od`).
Names follow docs/contracts.md §1: the bare object name for variables (``"controlword"``) and
``"<object>.<sub>"`` for records and arrays (``"current_controller.L_c"``).
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import lru_cache

import canopen
from canopen.objectdictionary import ODVariable

from firmware_protocol import Entry, LimitError, load_od
from firmware_protocol.entry import ABORT_VALUE_TOO_HIGH, ABORT_VALUE_TOO_LOW

from ..errors import ABORT_MEANINGS, InvalidValue, UnknownObject

__all__ = ["STRUCT_FORMATS", "ObjectInfo", "ObjectTable", "default_table"]

#: CANopen data type code → struct format of the value on the wire (little-endian, CiA 301),
#: as canopen encodes it (``ODVariable.STRUCT_TYPES``; BOOLEAN … REAL32, the drive's types).
STRUCT_FORMATS: dict[int, str] = {
    dt: "<" + s.format.lstrip("<")
    for dt, s in ODVariable.STRUCT_TYPES.items()
    if 0x01 <= dt <= 0x08
}

_SIGNED_TYPES = (0x02, 0x03, 0x04)


@dataclass(frozen=True)
class ObjectInfo:
    """One object or sub-object, as a host-side view of its :class:`firmware_protocol.Entry`.

    Attributes mirror the entry: ``name``, ``index``, ``subindex``, ``data_type`` (CANopen
    code), ``access`` ("ro", "wo", "rw", "const", ...), ``unit`` ("" if none), ``low``/``high``
    limits in the object's unit (None = type range), ``default`` (text from the EDS),
    ``description``, ``enum`` (value → label pairs) and ``pdo_mappable``. ``var`` is canopen's
    :class:`~canopen.objectdictionary.ODVariable` of the same object: it encodes and decodes.
    """

    entry: Entry
    var: ODVariable = field(compare=False, repr=False)

    @property
    def name(self) -> str:
        """OD name, e.g. ``"current_controller.L_c"``."""
        return self.entry.name

    @property
    def index(self) -> int:
        """16-bit object index."""
        return self.entry.index

    @property
    def subindex(self) -> int:
        """8-bit sub-index (0 for variables)."""
        return self.entry.subindex

    @property
    def data_type(self) -> int:
        """CANopen data type code (CiA 301 table 44)."""
        return self.entry.data_type

    @property
    def access(self) -> str:
        """Access type as in the EDS ("ro", "wo", "rw", "const", ...)."""
        return self.entry.access

    @property
    def unit(self) -> str:
        """Unit of the value ("" when the EDS names none)."""
        return self.entry.unit or ""

    @property
    def low(self) -> float | int | None:
        """Inclusive low limit in ``unit`` (None = the type's range)."""
        return self.entry.low

    @property
    def high(self) -> float | int | None:
        """Inclusive high limit in ``unit`` (None = the type's range)."""
        return self.entry.high

    @property
    def default(self) -> str:
        """Default value as written in the EDS ("" if none; ``$NODEID`` left unresolved)."""
        return self.entry.default_raw or ""

    @property
    def description(self) -> str:
        """Description from the EDS."""
        return self.entry.description

    @property
    def enum(self) -> tuple[tuple[int, str], ...]:
        """Allowed values and their labels (empty if the object is not enumerated)."""
        return tuple(sorted(self.entry.enum.items())) if self.entry.enum else ()

    @property
    def pdo_mappable(self) -> bool:
        """True if the object may be mapped into a PDO."""
        return self.entry.pdo_mappable

    @property
    def fmt(self) -> str:
        """struct format of the value ("" for strings and domains)."""
        return STRUCT_FORMATS.get(self.data_type, "")

    @property
    def type_name(self) -> str:
        """CANopen data type name, e.g. ``"REAL32"``."""
        return self.entry.type_name

    @property
    def bits(self) -> int:
        """Size in bits on the wire (0 for variable-length types)."""
        return struct.calcsize(self.fmt) * 8 if self.fmt else 0

    @property
    def readable(self) -> bool:
        """True if SDO upload is allowed."""
        return self.entry.readable

    @property
    def writable(self) -> bool:
        """True if SDO download is allowed."""
        return self.entry.writable

    @property
    def is_float(self) -> bool:
        """True for REAL32."""
        return self.entry.is_real

    def check(self, value: float | int | str | bytes) -> float | int | str | bytes:
        """Return ``value`` as the object's type (REAL32 rounded to float32, as the drive stores
        it); :class:`InvalidValue` if :meth:`firmware_protocol.Entry.check` refuses it.

        Text is accepted for numeric objects (``"0x10"``, ``"1.5e-6"``), as typed on a CLI.
        """
        if self.fmt and isinstance(value, str):
            try:
                value = float(value) if self.is_float else int(value, 0)
            except ValueError:
                raise InvalidValue(f"{self.name}: {value!r} is not a number") from None
        if isinstance(value, bool):
            value = int(value)
        try:
            return self.entry.check(value)
        except LimitError as exc:
            raise InvalidValue(self._refusal(exc)) from None

    def _refusal(self, exc: LimitError) -> str:
        """One-line message for a value :meth:`Entry.check` refused."""
        code = exc.abort_code
        if code in (ABORT_VALUE_TOO_HIGH, ABORT_VALUE_TOO_LOW):
            bound = self.high if code == ABORT_VALUE_TOO_HIGH else self.low
            side = "above" if code == ABORT_VALUE_TOO_HIGH else "below"
            what = (
                f"{side} the limit" if bound is not None else f"outside the {self.type_name} range"
            )
            what += "; "
        else:
            what = ""
        meaning = ABORT_MEANINGS.get(code, "unknown abort code")
        return f"{exc.message} ({what}the drive answers SDO abort 0x{code:08X}: {meaning})"

    def encode(self, value: float | int | str | bytes) -> bytes:
        """Bytes on the wire for ``value`` (checked first; canopen's ``encode_raw``)."""
        v = self.check(value)
        if not self.fmt and isinstance(v, bytes | bytearray):
            return bytes(v)
        return bytes(self.var.encode_raw(v))

    def decode(self, data: bytes) -> float | int | str | bytes:
        """Python value from the bytes on the wire (REAL32 → float, integers → int; canopen's
        ``decode_raw`` after fitting the length: an expedited upload may carry fewer bytes
        than the type (sign-extended here) or the 4 bytes of an unspecified size)."""
        if not self.fmt:
            return _plain(self.var.decode_raw(bytes(data)))
        size = struct.calcsize(self.fmt)
        data = bytes(data[:size])
        if len(data) < size:
            negative = bool(data) and self.data_type in _SIGNED_TYPES and data[-1] & 0x80
            data += (b"\xff" if negative else b"\x00") * (size - len(data))
        return _plain(self.var.decode_raw(data))


def _plain(value: float | int | str | bytes | bytearray) -> float | int | str | bytes:
    """canopen's decoded value with a bytearray (DOMAIN) as bytes."""
    return bytes(value) if isinstance(value, bytearray) else value


def _variable(od: canopen.ObjectDictionary, e: Entry) -> ODVariable:
    """canopen's variable of entry ``e`` (the object itself or its sub-index)."""
    obj = od[e.index]
    if e.object_name == e.name:
        var = obj
    elif isinstance(obj, ODVariable):
        raise TypeError(f"{e.name}: 0x{e.index:04X} has no sub-indices")
    else:
        var = obj[e.subindex]
    if not isinstance(var, ODVariable):
        raise TypeError(f"{e.name}: 0x{e.index:04X}:{e.subindex:02X} is no variable")
    return var


class ObjectTable:
    """All objects of the drive by name and by (index, subindex)."""

    def __init__(self, objects: list[ObjectInfo], od: canopen.ObjectDictionary | None = None):
        self._by_name = {o.name: o for o in objects}
        self._by_index = {(o.index, o.subindex): o for o in objects}
        #: canopen's dictionary the objects' ``var`` belong to (for a :class:`canopen.RemoteNode`)
        self.od = od

    @classmethod
    def from_od(cls, node_id: int = 1) -> ObjectTable:
        """Table of every entry of :func:`firmware_protocol.load_od` (the shipped EDS)."""
        view = load_od(node_id=node_id)
        od = view.canopen_od()
        objects = [ObjectInfo(e, _variable(od, e)) for e in view.entries]
        return cls(objects, od)

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def __getitem__(self, name: str) -> ObjectInfo:
        try:
            return self._by_name[name]
        except KeyError:
            close = [n for n in self._by_name if name.split(".")[-1] == n.split(".")[-1]]
            hint = f" (did you mean {', '.join(sorted(close)[:4])}?)" if close else ""
            raise UnknownObject(
                f"no object named {name!r} in the drive's dictionary{hint}"
            ) from None

    def __iter__(self) -> Iterator[ObjectInfo]:
        return iter(self._by_name.values())

    def __len__(self) -> int:
        return len(self._by_name)

    def names(self) -> list[str]:
        """Every object name."""
        return list(self._by_name)

    def by_index(self, index: int, subindex: int = 0) -> ObjectInfo | None:
        """The object at ``index``:``subindex`` or None."""
        return self._by_index.get((index, subindex))


@lru_cache(maxsize=1)
def default_table() -> ObjectTable:
    """The object table of the project's drive (built once from :func:`load_od`)."""
    return ObjectTable.from_od()
