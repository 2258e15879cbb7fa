"""Python view of the drive's object dictionary, read from the EDS (the single source of truth).

Structure (objects, sub-objects, data types, access, PDO flags, defaults with ``$NODEID``
resolved) comes from :func:`canopen.import_od`; what canopen 2.4.1 drops or ignores (REAL32
``LowLimit``/``HighLimit``, the custom ``Unit=``/``Enum=`` keys, ``ObjFlags``,
``StorageLocation``, ``MinNonZero``,
``ConfigOnly``) is read from the same file with :mod:`configparser`.

Names follow ``docs/contracts.md`` §1: ``"<object>.<sub>"`` for records and arrays (e.g.
``"current_controller.L_c"``), the bare object name for variables (e.g. ``"controlword"``).

Value checks raise :class:`LimitError` carrying the CiA 301 SDO abort code the drive answers
with, so the drive (before storing) and the host (before sending) reject the same values.
"""

from __future__ import annotations

import configparser
import copy
import difflib
import functools
import os
import re
from collections import Counter
from collections.abc import Iterator, Mapping
from pathlib import Path
from types import MappingProxyType

import canopen
from canopen import objectdictionary as cod

from .constraints import CONSTRAINTS, Constraint
from .entry import (
    ABORT_INVALID_VALUE,
    ABORT_VALUE_TOO_HIGH,
    ABORT_VALUE_TOO_LOW,
    BIT_LENGTH,
    REAL32,
    SIGNED,
    TYPE_NAMES,
    Entry,
    LimitError,
    Number,
    f32,
)

__all__ = [
    "ABORT_INVALID_VALUE",
    "ABORT_VALUE_TOO_HIGH",
    "ABORT_VALUE_TOO_LOW",
    "CONSTRAINTS",
    "EDS_PATH",
    "TYPE_NAMES",
    "Constraint",
    "Entry",
    "LimitError",
    "ObjectDictionaryView",
    "load_od",
]

EDS_PATH: Path = Path(__file__).with_name("bldc_drive.eds")
"""The EDS file shipped with the package."""
_EDS_NAME = os.fspath(EDS_PATH)

_SUB_SECTION = re.compile(r"^([0-9A-Fa-f]{4})[Ss]ub([0-9A-Fa-f]+)$")
_OBJ_SECTION = re.compile(r"^([0-9A-Fa-f]{4})$")


def _parse_number(text: str, data_type: int) -> Number:
    text = text.strip()
    if data_type == REAL32:
        return float(text)
    value = int(text, 0)
    if data_type in SIGNED and text.lower().startswith("0x"):
        bits = BIT_LENGTH[data_type]
        if value >= 1 << (bits - 1):
            value -= 1 << bits
    return value


def _parse_enum(text: str) -> dict[int, str]:
    out: dict[int, str] = {}
    for item in text.split(","):
        value, _, label = item.partition(":")
        out[int(value.strip(), 0)] = label.strip()
    return out


class ObjectDictionaryView:
    """Read-only, typed view of the EDS: names, types, units, limits and defaults."""

    def __init__(
        self,
        path: Path,
        node_id: int,
        entries: list[Entry],
        constraints: tuple[Constraint, ...],
        device_info: Mapping[str, str] | None = None,
        file_info: Mapping[str, str] | None = None,
        canopen_od: cod.ObjectDictionary | None = None,
    ) -> None:
        """``canopen_od``: canopen's parse of ``path`` for ``node_id``, handed over (no one else
        may hold it): the template :meth:`canopen_od` copies for that node-ID."""
        self.path = path
        self.node_id = node_id
        #: Raw ``[DeviceInfo]`` keys of the EDS (e.g. ``"NrOfTXPDO"``, ``"BaudRate_1000"``).
        self.device_info: Mapping[str, str] = MappingProxyType(dict(device_info or {}))
        #: Raw ``[FileInfo]`` keys of the EDS.
        self.file_info: Mapping[str, str] = MappingProxyType(dict(file_info or {}))
        self._entries = tuple(sorted(entries, key=lambda e: (e.index, e.subindex)))
        self._by_name = {e.name: e for e in self._entries}
        if len(self._by_name) != len(self._entries):
            names = Counter(e.name for e in self._entries)
            dup = sorted(name for name, n in names.items() if n > 1)
            raise ValueError(f"duplicate object names in the EDS: {', '.join(dup)}")
        self._by_index = {(e.index, e.subindex): e for e in self._entries}
        self._constraints = constraints
        self._od_templates: dict[int, cod.ObjectDictionary] = {}  # canopen_od, by node-ID
        self._defaults: dict[str, Number] = {
            e.name: e.default
            for e in self._entries
            if isinstance(e.default, (int, float)) and not isinstance(e.default, bool)
        }
        for c in constraints:
            for n in c.names:
                self.entry(n)  # every constraint refers to real objects
        if canopen_od is not None:
            self._od_templates[node_id] = self._completed(canopen_od)

    # -- lookup -------------------------------------------------------------------------
    @property
    def entries(self) -> tuple[Entry, ...]:
        """All entries (sub-index 0 of records included), ordered by index and sub-index."""
        return self._entries

    @property
    def constraints(self) -> tuple[Constraint, ...]:
        """Cross-object rules enforced on writes by the drive and the host."""
        return self._constraints

    def __iter__(self) -> Iterator[Entry]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def entry(self, name: str) -> Entry:
        """Entry by python name, e.g. ``"current_controller.L_c"`` or ``"controlword"``.

        Raises ``KeyError`` naming the closest existing names.
        """
        try:
            return self._by_name[name]
        except KeyError:
            close = difflib.get_close_matches(name, self._by_name, n=5, cutoff=0.5)
            if not close:
                close = [n for n in self._by_name if n.startswith(name.split(".")[0])][:5]
            hint = f"; did you mean: {', '.join(close)}?" if close else ""
            raise KeyError(f"no object named {name!r} in the drive OD{hint}") from None

    def address(self, name: str) -> tuple[int, int]:
        """``(index, sub)`` of the object ``name`` (e.g. ``"trace_config.state"``)."""
        e = self.entry(name)
        return e.index, e.subindex

    def index_of(self, object_name: str) -> int:
        """Index of the object (record, array or variable) called ``object_name``."""
        for e in self._entries:
            if e.object_name == object_name:
                return e.index
        raise KeyError(f"no object named {object_name!r} in the drive OD")

    def sub_names(self, object_name: str) -> dict[int, str]:
        """Sub-index -> sub-object name of a record or array (sub 0 left out)."""
        subs = {
            e.subindex: e.sub_name
            for e in self._entries
            if e.object_name == object_name and e.subindex
        }
        if not subs:
            raise KeyError(f"no record named {object_name!r} in the drive OD")
        return subs

    def by_index(self, index: int, sub: int = 0) -> Entry:
        """Entry at ``index``/``sub`` (``KeyError`` if the drive has no such object)."""
        try:
            return self._by_index[(index, sub)]
        except KeyError:
            raise KeyError(f"no object 0x{index:04X}:{sub:02X} in the drive OD") from None

    def od_reference(self, name: str) -> int:
        """``index << 16 | sub << 8 | bitlength`` of ``name`` (PDO mapping / trace channel)."""
        return self.entry(name).od_reference

    def by_reference(self, ref: int) -> Entry:
        """Entry for an OD reference.

        Raises ``KeyError`` if the object is absent, ``ValueError`` if the bit length is wrong.
        """
        entry = self.by_index((ref >> 16) & 0xFFFF, (ref >> 8) & 0xFF)
        if entry.bit_length != ref & 0xFF:
            raise ValueError(
                f"OD reference 0x{ref:08X}: {entry.name} is {entry.bit_length} bits, "
                f"not {ref & 0xFF}"
            )
        return entry

    # -- checks -------------------------------------------------------------------------
    def defaults(self) -> dict[str, Number]:
        """Default value of every numeric entry, by name (a new dict on every call)."""
        return dict(self._defaults)

    def check_constraints(self, values: Mapping[str, Number], changed: str | None = None) -> None:
        """Raise :class:`LimitError` if ``values`` break a cross-object rule.

        Only rules triggered by a name in ``values`` are evaluated (see
        :attr:`Constraint.checked_on`: the staged ``gain_set`` rule is checked when the staged
        values are passed, e.g. at ``gain_set_apply``, not when ``motor.L`` alone is written).
        Names missing from ``values`` take their EDS default. ``changed`` names the object being
        written; the abort code is 0x06090031 when it is pushed above its bound, 0x06090032 when
        a bound it provides is pushed below the other object (e.g. lowering ``motor.L`` under
        ``L_c / 2``). Without ``changed`` the rule's left-hand side is taken as the written one.
        REAL32 values are rounded to float32 first, as the drive stores them.
        """
        for c in self._constraints:
            if not any(n in values for n in c.triggers):
                continue
            merged: dict[str, Number] = {}
            for n in c.names:
                value = values[n] if n in values else self._defaults[n]
                # compare as the drive does: REAL32 values in float32
                merged[n] = f32(float(value)) if self._by_name[n].is_real else value
            if c.holds(merged):
                continue
            lhs_written = changed is None or changed in (c.lhs, c.lhs_times)
            too_high = c.bounds_from_above == lhs_written
            code = ABORT_VALUE_TOO_HIGH if too_high else ABORT_VALUE_TOO_LOW
            shown = ", ".join(f"{n} = {merged[n]:g}" for n in c.names)
            raise LimitError(code, f"{c} violated ({shown})")

    def constraints_for(self, name: str) -> tuple[Constraint, ...]:
        """Rules that read ``name``."""
        return tuple(c for c in self._constraints if name in c.names)

    # -- canopen ------------------------------------------------------------------------
    def canopen_od(self, node_id: int | None = None) -> cod.ObjectDictionary:
        """A fresh :class:`canopen.ObjectDictionary` for a LocalNode or RemoteNode.

        ``$NODEID`` defaults are resolved with ``node_id`` (default: the view's node-ID); REAL32
        limits (which canopen drops) and enumerations are filled in from this view.
        """
        nid = self.node_id if node_id is None else node_id
        template = self._od_templates.get(nid)
        if template is None:  # parse once per node-ID; a deep copy is about 4x cheaper
            template = self._od_templates[nid] = self._build_canopen_od(nid)
        return copy.deepcopy(template)

    def _build_canopen_od(self, nid: int) -> cod.ObjectDictionary:
        return self._completed(canopen.import_od(str(self.path), nid))

    def _completed(self, od: cod.ObjectDictionary) -> cod.ObjectDictionary:
        """``od`` with what canopen drops filled in from this view (REAL32 limits, enums)."""
        for e in self._entries:
            var = od[e.index]
            if e.object_name != e.name:
                assert isinstance(var, (cod.ODRecord, cod.ODArray))
                var = var[e.subindex]
            assert isinstance(var, cod.ODVariable)
            if e.is_real:  # (canopen types the limits as int; a REAL32's are floats)
                var.min, var.max = e.low, e.high  # type: ignore[assignment]
            if e.enum:
                for value, label in e.enum.items():
                    var.add_value_description(value, label)
        return od


def _entry_from(
    var: cod.ODVariable,
    name: str,
    object_name: str,
    section: Mapping[str, str],
) -> Entry:
    dt = var.data_type
    if dt is None:
        raise ValueError(f"{name}: no DataType")
    low = _parse_number(section["LowLimit"], dt) if "LowLimit" in section else None
    high = _parse_number(section["HighLimit"], dt) if "HighLimit" in section else None
    enum = MappingProxyType(_parse_enum(section["Enum"])) if "Enum" in section else None
    min_nonzero = _parse_number(section["MinNonZero"], dt) if "MinNonZero" in section else None
    default: Number | str | bytes | None = var.default
    if dt == REAL32 and default is not None:
        default = float(default)
    return Entry(
        name=name,
        index=var.index,
        subindex=var.subindex,
        data_type=dt,
        access=var.access_type,
        unit=section.get("Unit"),
        low=low,
        high=high,
        default=default,
        default_raw=section.get("DefaultValue"),
        pdo_mappable=bool(var.pdo_mappable),
        description=section.get("Description", ""),
        enum=enum,
        persistent=section.get("StorageLocation", "").upper() == "PERSIST",
        obj_flags=int(section.get("ObjFlags", "0"), 0),
        object_name=object_name,
        sub_name=var.name if object_name != name else "",
        min_nonzero=min_nonzero,
        config_only=section.get("ConfigOnly", "0").strip() == "1",
    )


def load_od(path: str | Path | None = None, node_id: int = 1) -> ObjectDictionaryView:
    """Load the OD view from an EDS file (default: :data:`EDS_PATH`).

    ``node_id`` (1..127) resolves ``$NODEID`` in defaults such as COB-IDs. Views are cached
    per file version and node-ID (they are immutable: frozen entries and constraints, read-only
    mappings, ``defaults()`` a new dict per call), so a repeated call costs one ``stat`` of the
    file (a few us; a path is resolved once per spelling and file): a changed, replaced or
    re-pointed file (other inode, mtime or size) is read again. Raises
    ``FileNotFoundError`` for a missing file and ``ValueError`` for a file that is not a valid
    drive EDS (syntax, duplicate names, a constraint naming a missing object).
    """
    if not 1 <= node_id <= 127:
        raise ValueError(f"node_id must be 1..127, got {node_id}")
    name = _EDS_NAME if path is None else os.fspath(path)
    st = os.stat(name)  # (follows symlinks: the version of the file that would be read)
    cwd = "" if os.path.isabs(name) else os.getcwd()
    eds_path = _resolved(name, cwd, st.st_dev, st.st_ino)
    try:
        return _load_cached(eds_path, node_id, st.st_ino, st.st_mtime_ns, st.st_size)
    except (configparser.Error, KeyError, ValueError, TypeError) as exc:
        raise ValueError(f"{eds_path} is not a valid drive EDS: {exc}") from exc


@functools.lru_cache(maxsize=64)
def _resolved(name: str, cwd: str, dev: int, ino: int) -> Path:
    """The absolute, symlink-free path of ``name`` (relative to ``cwd`` if not absolute),
    resolved once per path as given and file it names (a re-pointed link names another)."""
    return Path(cwd, name).resolve()


@functools.lru_cache(maxsize=16)
def _load_cached(
    eds_path: Path, node_id: int, ino: int, mtime_ns: int, size: int
) -> ObjectDictionaryView:
    """Parse once per (file version, node-ID); the view is immutable so sharing it is safe."""
    od = canopen.import_od(str(eds_path), node_id)
    raw = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    raw.optionxform = str  # type: ignore[assignment,method-assign]
    with open(eds_path, encoding="utf-8") as fp:
        raw.read_file(fp)
    sections: dict[tuple[int, int | None], Mapping[str, str]] = {}
    for sec in raw.sections():
        if m := _SUB_SECTION.match(sec):
            sections[(int(m.group(1), 16), int(m.group(2), 16))] = raw[sec]
        elif m := _OBJ_SECTION.match(sec):
            sections[(int(m.group(1), 16), None)] = raw[sec]

    entries: list[Entry] = []
    for obj in od.values():
        if obj.index < 0x1000:
            continue  # DummyUsage pseudo-objects
        if isinstance(obj, cod.ODVariable):
            entries.append(_entry_from(obj, obj.name, obj.name, sections[(obj.index, None)]))
            continue
        for var in obj.values():
            entries.append(
                _entry_from(
                    var,
                    f"{obj.name}.{var.name}",
                    obj.name,
                    sections[(obj.index, var.subindex)],
                )
            )
    return ObjectDictionaryView(
        eds_path,
        node_id,
        entries,
        CONSTRAINTS,
        device_info=dict(raw["DeviceInfo"]) if raw.has_section("DeviceInfo") else None,
        file_info=dict(raw["FileInfo"]) if raw.has_section("FileInfo") else None,
        # the parse above is also the view's canopen template for its own node-ID (a second
        # import_od of the same file was about 45 ms of every drive-link and virtual-drive start)
        canopen_od=od,
    )
