"""The drive's configuration as a CiA 306 DCF file: save, diff, load (all-or-nothing).

A DCF (Device Configuration File, CiA 306 §4.6) is the drive's EDS with a ``ParameterValue=``
for every configured object and a ``[DeviceComissioning]`` section (NodeID, NodeName, Baudrate
in kbit/s, NetNumber, NetworkName, CANopenManager, LSS_SerialNumber); canopen's
``import_od`` and other CANopen tools read it.

The configuration is every object the EDS marks persistent (stored by 0x1010) at index 0x2000
and above: motor and protection data, current and speed controller gains, CiA 402 option
codes, windows, limits and profiles. Communication objects (0x1000-0x1FFF: heartbeat, PDO
mappings, COB-IDs) are the bus integrator's and are neither saved nor loaded: the host sets the
heartbeat consumer itself and PDO mappings change only in PRE-OPERATIONAL.

:func:`load` checks first and writes nothing if any check fails: every value against the
object's limits (one line naming the first that is outside), the cross-object rules of the OD
(e.g. L_c < 2 motor.L, the current-loop and cascade stability rule) on the final set, and the
drive's state (objects marked ConfigOnly need the power stage off). Then only the objects that
differ are written: the controller gains as one staged set through the gain-set objects
(0x20F0/0x20F1) by :func:`drive_link.workflows.gains.apply_gains` (the one gain path), the others
with the ordinary checked writes; if the drive refuses a write part-way, what was written is put
back (rollback) before the error is raised. The dashboard calls :func:`save`, :func:`diff` and
:func:`load` like the CLI does; for a browser download :func:`dcf_text`
(``dcf_text(read_config(drive), drive.node_id)``), for an upload pass the text as an
:class:`io.StringIO` to :func:`diff` / :func:`load`.
"""

from __future__ import annotations

import configparser
import datetime as _dt
import io
import re
import warnings
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from firmware_protocol import EDS_PATH
from firmware_protocol.generate import render_strict_eds
from firmware_protocol.index_ranges import MANUFACTURER

from ..errors import DriveError, InvalidValue, StateError
from ..link import _rules
from ..link._gain_set import ACTIVE_GAIN_FIELD
from ..link._objects import ObjectInfo, ObjectTable, default_table

if TYPE_CHECKING:
    from ..link.drive import Drive

__all__ = [
    "ConfigDiff",
    "DcfContents",
    "Difference",
    "Source",
    "bus_bitrate",
    "config_objects",
    "dcf_text",
    "default_bitrate",
    "diff",
    "load",
    "read_config",
    "read_dcf",
    "save",
    "write_dcf",
]

_SECTION = re.compile(r"^([0-9A-Fa-f]{4})(?:sub([0-9A-Fa-f]{1,2}))?$")


def config_objects(table: ObjectTable | None = None) -> list[ObjectInfo]:
    """The configuration: readable, writable, persistent objects at index ≥ 0x2000."""
    table = table or default_table()
    objs = [
        o
        for o in table
        if o.index >= MANUFACTURER.start
        and o.entry.persistent
        and o.readable
        and o.writable
        and o.fmt
    ]
    return sorted(objs, key=lambda o: (o.index, o.subindex))


def _gain_objects() -> dict[str, str]:
    """OD name of each active gain object → its Gains field."""
    return ACTIVE_GAIN_FIELD


def _text(obj: ObjectInfo, value: Any) -> str:
    """ParameterValue text of ``value`` (CiA 306: integers in hex, REAL32 as decimal): a REAL32
    as the shortest decimal that reads back as the same float32 (``0.0062``, not the float64
    ``0.006200000178068876`` of the float32 the drive answered)."""
    if obj.is_float:
        return str(np.float32(float(value)))
    v = int(value)
    if v < 0:
        return str(v)
    return f"0x{v:0{max(2, obj.bits // 4)}X}"


def _parse(obj: ObjectInfo, text: str, node_id: int) -> float | int:
    s = text.strip().replace("$NODEID", str(node_id))
    try:
        if obj.is_float:
            return float(s)
        if "+" in s[1:]:
            return sum(int(p, 0) for p in s.split("+"))
        return int(s, 0)
    except ValueError:
        raise InvalidValue(
            f"{obj.name} (0x{obj.index:04X}:{obj.subindex:02X}): ParameterValue {text!r} is "
            "not a number"
        ) from None


def default_bitrate() -> int:
    """The bit rate a DCF names when the bus does not say: the highest ``BaudRate_N=1`` of the
    EDS's ``[DeviceInfo]`` (1 Mbit/s for this drive), in bit/s."""
    eds = configparser.RawConfigParser(strict=False, interpolation=None)
    eds.optionxform = str  # type: ignore[assignment,method-assign]
    eds.read(EDS_PATH, encoding="utf-8")
    rates = [
        int(k.split("_", 1)[1])
        for k, v in eds.items("DeviceInfo")
        if k.startswith("BaudRate_") and v.strip() == "1"
    ]
    return max(rates) * 1000


def write_dcf(
    path: str | Path,
    values: dict[str, float | int],
    node_id: int,
    *,
    node_name: str = "",
    bitrate: int | None = None,
    table: ObjectTable | None = None,
) -> Path:
    """Write ``values`` (object name → value in its OD unit) as a DCF based on the shipped EDS.

    ``bitrate`` in bit/s (written in kbit/s; None: :func:`default_bitrate` with a warning)."""
    path = Path(path)
    text = dcf_text(
        values, node_id, file_name=path.name, node_name=node_name, bitrate=bitrate, table=table
    )
    path.write_text(text, encoding="utf-8")
    return path


def dcf_text(
    values: dict[str, float | int],
    node_id: int,
    *,
    file_name: str = "drive.dcf",
    node_name: str = "",
    bitrate: int | None = None,
    table: ObjectTable | None = None,
) -> str:
    """The DCF of :func:`write_dcf` as text (for a browser download).

    It is the strict CiA 306 copy of the EDS (:func:`firmware_protocol.generate.render_strict_eds`,
    which objdictgen and eds-utils open) with ``[FileInfo] LastEDS``, a ``ParameterValue=`` per
    configured object and ``[DeviceComissioning]``. ``bitrate`` in bit/s; None writes
    :func:`default_bitrate` and warns (:class:`UserWarning`) that the bus did not say."""
    table = table or default_table()
    if bitrate is None:
        bitrate = default_bitrate()
        warnings.warn(
            f"the bus bit rate is unknown: the DCF names the EDS default {bitrate // 1000} kbit/s"
            " (pass --bitrate)",
            UserWarning,
            stacklevel=2,
        )
    eds = configparser.RawConfigParser(strict=False, interpolation=None)
    eds.optionxform = str  # type: ignore[assignment,method-assign]
    eds.read_string(render_strict_eds(EDS_PATH.read_text(encoding="utf-8")))
    now = _dt.datetime.now()
    fi = "FileInfo"
    eds.set(fi, "FileName", file_name)
    eds.set(fi, "LastEDS", EDS_PATH.name)
    eds.set(fi, "Description", f"configuration of node {node_id} saved by drive-link")
    eds.set(fi, "ModificationTime", now.strftime("%I:%M%p"))
    eds.set(fi, "ModificationDate", now.strftime("%m-%d-%Y"))
    eds.set(fi, "ModifiedBy", "drive-link config save")
    dc = "DeviceComissioning"
    if not eds.has_section(dc):
        eds.add_section(dc)
    for k, v in (
        ("NodeID", f"0x{node_id:02X}"),
        ("NodeName", node_name or f"node{node_id}"),
        ("Baudrate", str(int(bitrate) // 1000)),
        ("NetNumber", "1"),
        ("NetworkName", "drive-link"),
        ("CANopenManager", "0"),
        ("LSS_SerialNumber", "0"),
    ):
        eds.set(dc, k, v)
    for name, value in values.items():
        obj = table[name]
        sec = _section(obj, eds)
        eds.set(sec, "ParameterValue", _text(obj, value))
    buf = io.StringIO()
    eds.write(buf, space_around_delimiters=False)
    return buf.getvalue()


def _section(obj: ObjectInfo, eds: configparser.RawConfigParser) -> str:
    for sec in (f"{obj.index:04X}sub{obj.subindex:X}", f"{obj.index:04X}"):
        for cand in (sec, sec.lower()):
            if eds.has_section(cand):
                if "sub" not in cand and eds.has_section(f"{cand}sub0"):
                    continue
                return cand
    raise InvalidValue(f"{obj.name}: no section 0x{obj.index:04X}:{obj.subindex:02X} in the EDS")


@dataclass
class DcfContents:
    """What :func:`read_dcf` found: ``values`` (configuration object name → value),
    ``ignored`` (names with a ParameterValue outside the configuration), ``node_id``."""

    values: dict[str, float | int]
    ignored: list[str]
    node_id: int | None


Source = str | Path | io.StringIO
"""A DCF file path, or its text in an :class:`io.StringIO` (an upload in the dashboard)."""


def read_dcf(path: Source, node_id: int = 1, table: ObjectTable | None = None) -> DcfContents:
    """The ParameterValues of a DCF (a path, or an :class:`io.StringIO` of its text);
    :class:`InvalidValue` (one line) for an unreadable file, an object the drive does not
    have, or a value that is not a number."""
    table = table or default_table()
    eds = configparser.RawConfigParser(strict=False, interpolation=None)
    eds.optionxform = str  # type: ignore[assignment,method-assign]
    try:
        if isinstance(path, io.StringIO):
            eds.read_string(path.getvalue(), source="<upload>")
            path = Path("<upload>")
        else:
            path = Path(path)
            with path.open(encoding="utf-8") as f:
                eds.read_file(f)
    except (OSError, UnicodeDecodeError, configparser.Error) as exc:
        raise InvalidValue(f"cannot read {path}: {exc}") from None
    dcf_node = None
    if eds.has_option("DeviceComissioning", "NodeID"):
        try:
            dcf_node = int(eds.get("DeviceComissioning", "NodeID"), 0)
        except ValueError:
            raise InvalidValue(f"{path}: [DeviceComissioning] NodeID is not a number") from None
    config = {o.name for o in config_objects(table)}
    values: dict[str, float | int] = {}
    ignored: list[str] = []
    for sec in eds.sections():
        m = _SECTION.match(sec)
        if m is None or not eds.has_option(sec, "ParameterValue"):
            continue
        index, sub = int(m[1], 16), int(m[2] or "0", 16)
        obj = table.by_index(index, sub)
        if obj is None:
            raise InvalidValue(
                f"{path}: [{sec}] 0x{index:04X}:{sub:02X} is not an object of this drive"
            )
        if obj.name not in config:
            ignored.append(obj.name)
            continue
        values[obj.name] = _parse(obj, eds.get(sec, "ParameterValue"), node_id)
    if not values:
        raise InvalidValue(f"{path}: no configuration values (ParameterValue) in the file")
    return DcfContents(values, ignored, dcf_node)


def read_config(drive: Drive) -> dict[str, float | int]:
    """The drive's configuration as it reports it now (object name → value)."""
    return {o.name: drive.read_number(o.name) for o in config_objects(drive.table)}


def save(
    drive: Drive, path: str | Path, *, bitrate: int | None = None, node_name: str = ""
) -> dict[str, Any]:
    """Read the configuration from ``drive`` and write it to ``path`` as a DCF; returns
    ``{"file", "objects", "node_id", "bitrate"}``.

    ``bitrate`` (bit/s) names the bus's bit rate in ``[DeviceComissioning] Baudrate``; without
    it, the bit rate the bus reports (python-can buses that know it), else the EDS default with
    a :class:`UserWarning` (:func:`default_bitrate`)."""
    values = read_config(drive)
    if bitrate is None:
        bitrate = bus_bitrate(drive.bus)
    out = write_dcf(
        path, values, drive.node_id, node_name=node_name, bitrate=bitrate, table=drive.table
    )
    return {
        "file": str(out),
        "objects": len(values),
        "node_id": drive.node_id,
        "bitrate": bitrate if bitrate is not None else default_bitrate(),
    }


def bus_bitrate(bus: Any) -> int | None:
    """The bit rate (bit/s) a python-can bus reports about itself, or None if it does not."""
    for attr in ("bitrate", "_bitrate"):
        val = getattr(bus, attr, None)
        if isinstance(val, int) and not isinstance(val, bool) and val > 0:
            return val
    return None


@dataclass(frozen=True)
class Difference:
    """One object whose value differs: ``name``, ``index`` (0xIIII:SS), ``unit``, ``drive``
    (value on the drive) and ``file`` (value in the DCF, as the drive would store it)."""

    name: str
    index: str
    unit: str
    drive: float | int
    file: float | int

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {
            "name": self.name,
            "index": self.index,
            "unit": self.unit,
            "drive": self.drive,
            "file": self.file,
        }


@dataclass
class ConfigDiff:
    """:func:`diff`'s result: ``changes`` (objects that differ), ``same`` (count),
    ``ignored`` (names in the file outside the configuration), ``node_id`` of the file."""

    changes: list[Difference]
    same: int
    ignored: list[str] = field(default_factory=list)
    node_id: int | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {
            "changes": [c.as_dict() for c in self.changes],
            "same": self.same,
            "ignored": self.ignored,
            "node_id": self.node_id,
        }


def _checked(table: ObjectTable, values: dict[str, float | int]) -> dict[str, float | int]:
    """Every value as the drive would store it; the first out of limits raises
    :class:`InvalidValue` naming it."""
    out: dict[str, float | int] = {}
    for name, v in values.items():
        obj = table[name]
        try:
            out[name] = obj.check(v)  # type: ignore[assignment]
        except InvalidValue as exc:
            raise InvalidValue(f"nothing written: {exc}") from None
    return out


def diff(drive: Drive, path: Source) -> ConfigDiff:
    """Compare the DCF at ``path`` with the drive (values as the drive would store them)."""
    dcf = read_dcf(path, drive.node_id, drive.table)
    wanted = _checked(drive.table, dcf.values)
    changes: list[Difference] = []
    same = 0
    for name, want in wanted.items():
        have = drive.read(name)
        if have == want:
            same += 1
            continue
        obj = drive.table[name]
        idx = f"0x{obj.index:04X}:{obj.subindex:02X}"
        changes.append(Difference(name, idx, obj.unit, have, want))  # type: ignore[arg-type]
    return ConfigDiff(changes, same, dcf.ignored, dcf.node_id)


def load(
    drive: Drive, path: Source, *, dry_run: bool = False, force: bool = False
) -> dict[str, Any]:
    """Apply the DCF at ``path`` to ``drive`` all-or-nothing (see the module doc); with
    ``dry_run`` check everything and write nothing. A gain set with poor margins (a warning of
    :func:`drive_link.workflows.gains.check_gains`) is refused unless ``force``; an unstable one
    always. Returns ``{"changes", "written", "dry_run", "ignored", "node_id"}``."""
    d = diff(drive, path)
    changes = {c.name: c.file for c in d.changes}
    _check_rules(drive, changes)
    _check_gain_set(drive, changes, force)
    needs_off = [n for n in changes if drive.table[n].entry.config_only]
    if needs_off and drive.state == "OPERATION ENABLED":
        raise StateError(
            f"nothing written: {needs_off[0]} (and {len(needs_off) - 1} more) is written only "
            "with the power stage off: run `drive-link disable` first"
            if len(needs_off) > 1
            else f"nothing written: {needs_off[0]} is written only with the power stage off: "
            "run `drive-link disable` first"
        )
    result = {
        "changes": [c.as_dict() for c in d.changes],
        "written": 0,
        "dry_run": dry_run,
        "ignored": d.ignored,
        "node_id": d.node_id,
    }
    if dry_run or not changes:
        return result
    _apply(drive, changes, {c.name: c.drive for c in d.changes}, force)
    result["written"] = len(changes)
    return result


def _check_rules(drive: Drive, changes: dict[str, float | int]) -> None:
    """The OD's cross-object rules on the final set (the drive's values for the rest)."""
    if not changes:
        return
    try:
        _rules.check_rules(drive.read, changes)
        _rules.check_loops(drive.read, changes)
    except InvalidValue as exc:
        raise InvalidValue(f"nothing written: {exc}") from None


def _check_gain_set(drive: Drive, changes: dict[str, float | int], force: bool) -> None:
    """The gain policy of :func:`drive_link.workflows.gains.check_gains` on the final gain set and
    motor (nothing written when it refuses)."""
    names = _gain_objects()
    gain_changes = {names[n]: v for n, v in changes.items() if n in names}
    if not gain_changes:
        return
    from firmware_protocol.current_stability import MOTOR_KEYS

    from . import gains as _gains

    merged = {**drive.read_gains().to_dict(), **gain_changes}
    motor = {
        k: float(changes[f"motor.{k}"] if f"motor.{k}" in changes else drive.read(f"motor.{k}"))
        for k in MOTOR_KEYS
    }
    check = _gains.check_gains(
        merged,
        motor["R"],
        motor["L"],
        rated_current=motor.get("rated_current"),
        V_dc_nominal=motor.get("V_dc_nominal"),
    )
    if not check.allowed(force):
        hint = "" if check.refusals else " (--force loads it anyway)"
        raise InvalidValue(f"nothing written: gain set refused: {'; '.join(check.problems)}{hint}")


def _apply(
    drive: Drive,
    changes: dict[str, float | int],
    before: dict[str, float | int],
    force: bool = False,
) -> None:
    """Write ``changes``: plain objects first, then the gains as one set; roll back on error."""
    gains = _gain_objects()
    gain_changes = {gains[n]: v for n, v in changes.items() if n in gains}
    plain = [n for n in changes if n not in gains]
    done: list[str] = []
    try:
        for n in plain:
            drive.write(n, changes[n])
            done.append(n)
        if gain_changes:
            _apply_gains(drive, gain_changes, force)
    except (DriveError, KeyboardInterrupt):
        _rollback(drive, done, before)
        raise


def _apply_gains(drive: Drive, gain_changes: dict[str, float | int], force: bool) -> None:
    """The gain-set path :func:`drive_link.workflows.gains.apply_gains`: one check, stage the set in
    0x20F0, apply with 0x20F1, read back (the drive checks the set as a whole)."""
    from . import gains as _gains

    _gains.apply_gains(drive, gain_changes, force=force)


def _rollback(drive: Drive, done: Iterable[str], before: dict[str, float | int]) -> None:
    for n in reversed(list(done)):
        try:
            drive.write(n, before[n])
        except DriveError:
            pass
