"""The files other CANopen tools open: the exported EDS (``--strict-eds``) and every DCF the
product writes, opened by two independent checkers from PyPI, CanFestival's objdictgen 3.5 and
eds-utils 0.3, and compared with the EDS as Python's configparser reads it.

Where a checker itself is wrong, the test names its bug and what CiA 306 (v1.3.0) says, and
accepts exactly that complaint and nothing else:

- eds-utils 0.3.1 ``read_eds`` knows the object-section keys ParameterName, Denotation,
  ObjectType, DataType, LowLimit, HighLimit, DefaultValue, AccessType, PDOMapping only; CiA 306
  §4.6.3 also defines ``ObjFlags`` (bit 0 refuse write on download, bit 1 refuse read on scan)
  and, for a DCF (§5), ``ParameterValue`` — the very key a DCF exists for. It reports both as
  "Unknown entry".
- objdictgen 3.5.5 reads EDS only: ``SECTION_KEYNAMES`` lacks ``[DeviceComissioning]``, the
  section CiA 306 §5.1 adds to every DCF (spelt with one 'm'), so it refuses any CiA 306 DCF
  with "Section '[DeviceComissioning]' is unrecognized". Without that one section it opens ours
  and takes each ``ParameterValue`` as the object's value.
- objdictgen 3.5.5 accepts LowLimit/HighLimit only as integers whatever the DataType, though
  CiA 306 gives limits in the object's data type (a REAL32 limit is a real number); the strict
  copy therefore writes whole REAL32 limits as integers and names the fractional ones in a
  comment (checked below against the full EDS).
"""

from __future__ import annotations

import configparser
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from eds_utils.core.file_io.read_eds import read_eds
from objdictgen.node import Node

from drive_link.workflows import config_dcf
from firmware_protocol import EDS_PATH
from firmware_protocol.generate import main as generate_main

pytestmark = [pytest.mark.unit, pytest.mark.timeout(120)]

#: eds-utils 0.3.1's complaint about a CiA 306 key it does not know (see the module docstring)
_EDS_UTILS_UNKNOWN = re.compile(r'^AUTO-FIXED: Unknown entry "(ObjFlags|ParameterValue)" in \[')
_OBJ = re.compile(r"^([0-9A-F]{4})(?:sub([0-9A-F]+))?$", re.I)
_CUSTOM_KEYS = {"Unit", "Description", "Enum", "StorageLocation", "ConfigOnly", "MinNonZero"}


def _ini(path: Path) -> configparser.RawConfigParser:
    cp = configparser.RawConfigParser(strict=True, interpolation=None)
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    cp.read(path, encoding="utf-8")
    return cp


def _strict(tmp_path: Path) -> Path:
    out = tmp_path / "bldc_drive_strict.eds"
    assert generate_main(["--check", "--strict-eds", str(out)]) == 0
    return out


def _objects(cp: configparser.RawConfigParser):
    """(index, subindex, section) of every variable (VAR or sub-object) of an EDS."""
    for sec in cp.sections():
        m = _OBJ.match(sec)
        if not m:
            continue
        index, sub = int(m[1], 16), int(m[2], 16) if m[2] else 0
        if m[2] is None and cp.has_section(f"{sec}sub0"):
            continue  # the record/array header; its sub-objects follow
        yield index, sub, cp[sec]


def _eds_utils_errors(path: Path) -> list[str]:
    _eds, errors = read_eds(str(path))
    return [e for e in errors if not _EDS_UTILS_UNKNOWN.match(e)]


def test_strict_eds_opens_in_objdictgen_and_eds_utils_with_the_eds_values(tmp_path):
    strict = _strict(tmp_path)
    assert strict.read_text().startswith("[FileInfo]\n")  # objdictgen: an EDS starts so
    assert _eds_utils_errors(strict) == []
    node = Node.LoadFile(strict)
    full = _ini(EDS_PATH)
    seen = 0
    for index, sub, sec in _objects(full):
        if sub == 0 and full.has_section(f"{index:04X}sub0"):
            continue  # objdictgen names a record's sub-index 0 itself ("Number of Entries")
        info = node.GetSubentryInfos(index, sub)
        if index < 0x6000:  # CiA 402 objects: objdictgen shows its own DS-402 profile's names
            assert info["name"] == sec["ParameterName"], (index, sub)
        assert info["type"] == int(sec["DataType"], 0), (index, sub)
        default = sec.get("DefaultValue")
        if default is None or "$NODEID" in default or int(sec["DataType"], 0) in (9, 0xA, 0xF):
            continue
        got = node.GetEntry(index, sub if sub or node.GetEntryInfos(index)["struct"] > 1 else 0)
        if int(sec["DataType"], 0) == 8:
            assert np.float32(got) == np.float32(float(default)), (index, sub)
        elif int(sec["DataType"], 0) != 1:
            assert got == int(default, 0) or got == _signed(int(default, 0), sec), (index, sub)
        seen += 1
    assert seen > 200


def _signed(value: int, sec) -> int:
    bits = {2: 8, 3: 16, 4: 32}.get(int(sec["DataType"], 0))
    return value - (1 << bits) if bits and value >= 1 << (bits - 1) else value


def test_strict_eds_keeps_every_limit_or_names_it(tmp_path):
    strict = _strict(tmp_path)
    text = strict.read_text()
    cp_strict, full = _ini(strict), _ini(EDS_PATH)
    for index, sub, sec in _objects(full):
        name = (
            f"{index:04X}sub{sub:X}"
            if cp_strict.has_section(f"{index:04X}sub{sub:X}")
            else (f"{index:04X}")
        )
        out = cp_strict[name]
        for key in ("LowLimit", "HighLimit"):
            if key not in sec:
                continue
            if int(sec["DataType"], 0) != 8:
                assert out[key] == sec[key]
                continue
            value = float(sec[key])
            if value == int(value):  # objdictgen takes integers only: a whole REAL32 is one
                assert re.fullmatch(r"-?[1-9]\d*|0", out[key]) and int(out[key]) == value
            else:  # fractional: named in the comment before the section, not lost silently
                assert key not in out
                assert re.search(rf"; \[?{name}\]?: REAL32 .*{key} {re.escape(sec[key])}", text)


def test_full_eds_is_cia306_where_the_checkers_look():
    text = EDS_PATH.read_text()
    assert text.startswith("[FileInfo]\n")
    cp = _ini(EDS_PATH)
    for key, value in cp.items("Comments"):  # objdictgen reads a value starting 0x as a number
        assert not value.lower().startswith(("0x", "-0x")), key
    for sec in cp.sections():
        if not _OBJ.match(sec):
            continue
        extra = set(cp[sec]) - set(_strict_keys()) - _CUSTOM_KEYS
        assert extra == set(), sec
        if int(cp[sec].get("ObjectType", "0x7"), 0) == 0x2:  # CiA 306: PDOMapping is a VAR's
            assert "PDOMapping" not in cp[sec], sec


def _strict_keys():
    from firmware_protocol.generate import CIA306_OBJECT_KEYS

    return CIA306_OBJECT_KEYS


def _config_values() -> dict[str, float | int]:
    """A configuration as a drive reports it: REAL32 values are float32s (0.0062 answered by a
    drive is 0.006200000178068876 as a Python float)."""
    out: dict[str, float | int] = {}
    for o in config_dcf.config_objects():
        v = o.entry.default if o.entry.default is not None else 0
        out[o.name] = float(np.float32(v)) if o.is_float else int(v)
    out["current_controller.R_c"] = float(np.float32(0.0062))
    return out


def test_dcf_opens_in_both_checkers_with_the_values_written(tmp_path):
    values = _config_values()
    path = config_dcf.write_dcf(tmp_path / "bench.dcf", values, 5, bitrate=500_000)
    assert _eds_utils_errors(path) == []
    cp = _ini(path)
    assert cp.get("FileInfo", "LastEDS") == "bldc_drive.eds"
    assert cp.get("DeviceComissioning", "Baudrate") == "500"
    # objdictgen: the same file without [DeviceComissioning] (its bug: module docstring)
    with pytest.raises(ValueError, match=r"DeviceComissioning\]' is unrecognized"):
        Node.LoadFile(path)
    text = path.read_text()
    bare = tmp_path / "bench_objdictgen.eds"
    head, _, rest = text.partition("[DeviceComissioning]\n")
    bare.write_text(head + rest.partition("\n\n")[2])
    node = Node.LoadFile(bare)
    from drive_link.link._objects import default_table

    table = default_table()
    for name, value in values.items():
        o = table[name]
        sub = o.subindex if node.GetEntryInfos(o.index)["struct"] > 1 else 0
        got = node.GetEntry(o.index, sub)
        if o.is_float:
            assert np.float32(got) == np.float32(value), name
        else:
            assert got == value or _signed(got, {"DataType": hex(o.entry.data_type)}) == value
    # REAL32 as the float32 it is, in its shortest form
    assert "ParameterValue=0.0062\n" in text
    assert "0.006200000178068876" not in text


def test_dcf_without_a_bitrate_names_the_eds_default_and_warns(tmp_path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        path = config_dcf.write_dcf(tmp_path / "b.dcf", _config_values(), 1)
    assert any("bit rate" in str(w.message) for w in caught)
    baud = _ini(path).get("DeviceComissioning", "Baudrate")
    # the highest rate the EDS's [DeviceInfo] marks supported, read here by configparser
    info = _ini(EDS_PATH)["DeviceInfo"]
    rates = [
        int(k.split("_")[1]) for k, v in info.items() if k.startswith("BaudRate_") and v == "1"
    ]
    assert baud == str(max(rates)) and int(baud) in (10, 20, 50, 125, 250, 500, 800, 1000)
    assert _eds_utils_errors(path) == []
