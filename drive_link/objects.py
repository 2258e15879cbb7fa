"""The drive's object dictionary as the host sees it: names, types, units and limits.

Read from the EDS in :mod:`firmware_protocol` (the single source of truth). Names follow
docs/contracts.md §1: the bare object name for variables (``"controlword"``) and
``"<object>.<sub>"`` for records and arrays (``"current_controller.L_c"``).
"""

from __future__ import annotations

import configparser
import math
import re
import struct
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

from .errors import InvalidValue, UnknownObject

#: CANopen data type code → (struct format, name).
DATA_TYPES: dict[int, tuple[str, str]] = {
    0x01: ("<?", "BOOLEAN"),
    0x02: ("<b", "INTEGER8"),
    0x03: ("<h", "INTEGER16"),
    0x04: ("<i", "INTEGER32"),
    0x05: ("<B", "UNSIGNED8"),
    0x06: ("<H", "UNSIGNED16"),
    0x07: ("<I", "UNSIGNED32"),
    0x08: ("<f", "REAL32"),
    0x09: ("", "VISIBLE_STRING"),
    0x0A: ("", "OCTET_STRING"),
    0x0F: ("", "DOMAIN"),
    0x11: ("<d", "REAL64"),
    0x15: ("<q", "INTEGER64"),
    0x1B: ("<Q", "UNSIGNED64"),
}

_INT_RANGE: dict[str, tuple[int, int]] = {
    "<?": (0, 1),
    "<b": (-(2**7), 2**7 - 1),
    "<h": (-(2**15), 2**15 - 1),
    "<i": (-(2**31), 2**31 - 1),
    "<q": (-(2**63), 2**63 - 1),
    "<B": (0, 2**8 - 1),
    "<H": (0, 2**16 - 1),
    "<I": (0, 2**32 - 1),
    "<Q": (0, 2**64 - 1),
}

_REAL32_MAX = 3.4028234663852886e38


@dataclass(frozen=True)
class ObjectInfo:
    """One object or sub-object: ``name``, ``index``, ``subindex``, ``data_type`` (CANopen code),
    ``access`` ("ro", "wo", "rw", "const", ...), ``unit``, ``low``/``high`` limits (None = type
    range), ``default`` (text from the EDS), ``description``, ``enum`` (value → label)."""

    name: str
    index: int
    subindex: int
    data_type: int
    access: str
    unit: str = ""
    low: float | None = None
    high: float | None = None
    default: str = ""
    description: str = ""
    enum: tuple[tuple[int, str], ...] = ()
    pdo_mappable: bool = False

    @property
    def fmt(self) -> str:
        """struct format of the value ("" for strings and domains)."""
        return DATA_TYPES.get(self.data_type, ("", ""))[0]

    @property
    def type_name(self) -> str:
        """CANopen data type name."""
        return DATA_TYPES.get(self.data_type, ("", f"0x{self.data_type:04X}"))[1]

    @property
    def bits(self) -> int:
        """Size in bits (0 for variable-length types)."""
        return struct.calcsize(self.fmt) * 8 if self.fmt else 0

    @property
    def readable(self) -> bool:
        """True if SDO upload is allowed."""
        return self.access != "wo"

    @property
    def writable(self) -> bool:
        """True if SDO download is allowed."""
        return self.access in ("rw", "wo", "rww", "rwr")

    @property
    def is_float(self) -> bool:
        """True for REAL32/REAL64."""
        return self.fmt in ("<f", "<d")

    def check(self, value: float | int | str | bytes) -> float | int | str | bytes:
        """Return ``value`` converted to the object's type; :class:`InvalidValue` if it does not
        fit the type or the EDS limits."""
        fmt = self.fmt
        if not fmt:
            if self.data_type == 0x09 and isinstance(value, str):
                return value
            if isinstance(value, bytes | bytearray):
                return bytes(value)
            raise InvalidValue(f"{self.name}: expects {self.type_name}, got {value!r}")
        if isinstance(value, str):
            try:
                value = float(value) if self.is_float else int(value, 0)
            except ValueError:
                raise InvalidValue(f"{self.name}: {value!r} is not a number") from None
        if self.is_float:
            try:
                v = float(value)
            except (TypeError, ValueError):
                raise InvalidValue(f"{self.name}: {value!r} is not a number") from None
            if not math.isfinite(v) or (fmt == "<f" and abs(v) > _REAL32_MAX):
                raise InvalidValue(f"{self.name}: {value!r} is not a finite {self.type_name}")
        else:
            if isinstance(value, float):
                if not value.is_integer():
                    raise InvalidValue(
                        f"{self.name}: {value!r} is not an integer ({self.type_name})"
                    )
                value = int(value)
            if not isinstance(value, int):
                raise InvalidValue(f"{self.name}: {value!r} is not an integer")
            lo, hi = _INT_RANGE[fmt]
            if not lo <= value <= hi:
                raise InvalidValue(
                    f"{self.name}: {value} outside {self.type_name} range [{lo}, {hi}]"
                )
            v = value
        unit = f" {self.unit}" if self.unit and self.unit != "1" else ""
        if self.low is not None and v < self.low:
            raise InvalidValue(f"{self.name}: {v:g}{unit} is below the limit {self.low:g}{unit}")
        if self.high is not None and v > self.high:
            raise InvalidValue(f"{self.name}: {v:g}{unit} is above the limit {self.high:g}{unit}")
        return v

    def encode(self, value: float | int | str | bytes) -> bytes:
        """Bytes on the wire for ``value`` (checked first)."""
        v = self.check(value)
        if not self.fmt:
            return v.encode("ascii") if isinstance(v, str) else bytes(v)
        return struct.pack(self.fmt, v)

    def decode(self, data: bytes) -> float | int | str | bytes:
        """Python value from the bytes on the wire (REAL32 → float, integers → int)."""
        fmt = self.fmt
        if not fmt:
            if self.data_type == 0x09:
                return bytes(data).rstrip(b"\x00").decode("ascii", errors="replace")
            return bytes(data)
        size = struct.calcsize(fmt)
        if len(data) < size:
            # Expedited uploads may be shorter for small types; pad the sign correctly.
            pad = (
                b"\xff"
                if (data and fmt in ("<b", "<h", "<i", "<q") and data[-1] & 0x80)
                else b"\x00"
            )
            data = bytes(data) + pad * (size - len(data))
        v = struct.unpack_from(fmt, data)[0]
        return bool(v) if fmt == "<?" else v


def _num(text: str | None) -> float | None:
    if text is None or text.strip() == "" or "$" in text:
        return None
    t = text.strip()
    try:
        return int(t, 0)
    except ValueError:
        return float(t)


class ObjectTable:
    """All objects of the drive by name and by (index, subindex)."""

    def __init__(self, objects: list[ObjectInfo]):
        self._by_name = {o.name: o for o in objects}
        self._by_index = {(o.index, o.subindex): o for o in objects}

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

    def __iter__(self):
        return iter(self._by_name.values())

    def __len__(self) -> int:
        return len(self._by_name)

    def names(self) -> list[str]:
        """Every object name."""
        return list(self._by_name)

    def by_index(self, index: int, subindex: int = 0) -> ObjectInfo | None:
        """The object at ``index``:``subindex`` or None."""
        return self._by_index.get((index, subindex))


def parse_eds(path: str | Path) -> ObjectTable:
    """Read an EDS (CiA 306) into an :class:`ObjectTable` (incl. the project's Unit/limits keys)."""
    cp = configparser.RawConfigParser(strict=False, interpolation=None)
    cp.optionxform = str  # keep key case
    cp.read(path, encoding="utf-8")
    objects: list[ObjectInfo] = []
    top = re.compile(r"^([0-9A-Fa-f]{4})$")
    sub = re.compile(r"^([0-9A-Fa-f]{4})sub([0-9A-Fa-f]+)$")

    def make(sec: configparser.SectionProxy, name: str, index: int, subindex: int) -> ObjectInfo:
        enum: list[tuple[int, str]] = []
        for part in sec.get("Enum", "").split(","):
            if ":" in part:
                k, lab = part.split(":", 1)
                enum.append((int(k.strip(), 0), lab.strip()))
        return ObjectInfo(
            name=name,
            index=index,
            subindex=subindex,
            data_type=int(sec.get("DataType", "0"), 0),
            access=sec.get("AccessType", "rw").strip().lower(),
            unit=sec.get("Unit", "").strip(),
            low=_num(sec.get("LowLimit")),
            high=_num(sec.get("HighLimit")),
            default=sec.get("DefaultValue", "").strip(),
            description=sec.get("Description", "").strip(),
            enum=tuple(enum),
            pdo_mappable=sec.get("PDOMapping", "0").strip() == "1",
        )

    for section in cp.sections():
        m = top.match(section)
        if not m:
            continue
        index = int(m.group(1), 16)
        sec = cp[section]
        name = sec.get("ParameterName", f"0x{index:04X}").strip()
        otype = int(sec.get("ObjectType", "0x7"), 0)
        if otype in (0x7, 0x2):  # VAR, DOMAIN
            objects.append(make(sec, name, index, 0))
            continue
        for s in cp.sections():
            sm = sub.match(s)
            if sm and int(sm.group(1), 16) == index:
                si = int(sm.group(2), 16)
                sname = cp[s].get("ParameterName", f"sub{si}").strip()
                objects.append(make(cp[s], f"{name}.{sname}", index, si))
    return ObjectTable(objects)


def eds_path() -> Path:
    """Path of the drive's EDS shipped with :mod:`firmware_protocol`."""
    return Path(str(resources.files("firmware_protocol").joinpath("bldc_drive.eds")))


@lru_cache(maxsize=1)
def default_table() -> ObjectTable:
    """The object table of the project's drive (parsed once)."""
    return parse_eds(eds_path())
