"""Regenerate the files derived from the EDS: the DSP header and the Markdown OD reference.

Usage::

    python -m firmware_protocol.generate            # rewrite bldc_drive_od.h and OD.md
    python -m firmware_protocol.generate --check    # exit 1 if either drifted from the EDS
    python -m firmware_protocol.generate --strict-eds out.eds   # copy without custom keys

Both outputs are pure functions of the EDS (through :func:`firmware_protocol.od.load_od`) and the
cross-object constraints of :mod:`firmware_protocol.od`; nothing else (no dates) goes in, so a
re-run on an unchanged EDS is byte-identical.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Sequence
from pathlib import Path

from .od import EDS_PATH, Entry, ObjectDictionaryView, load_od

__all__ = [
    "CIA306_OBJECT_KEYS",
    "HEADER_NAME",
    "MARKDOWN_NAME",
    "main",
    "render_header",
    "render_markdown",
    "render_strict_eds",
]

HEADER_NAME = "bldc_drive_od.h"
MARKDOWN_NAME = "OD.md"

_C_TYPES = {
    0x01: "uint16_t",
    0x02: "int16_t",  # INTEGER8: C2000 has no 8-bit type (char is 16 bits)
    0x03: "int16_t",
    0x04: "int32_t",
    0x05: "uint16_t",  # UNSIGNED8: see INTEGER8
    0x06: "uint16_t",
    0x07: "uint32_t",
    0x08: "float",
}
_ACCESS = {"ro": "OD_ACCESS_RO", "wo": "OD_ACCESS_WO", "rw": "OD_ACCESS_RW"}
_ACCESS |= {"rwr": "OD_ACCESS_RW", "rww": "OD_ACCESS_RW", "const": "OD_ACCESS_CONST"}
_SHORT_TYPE = {
    0x01: "BOOL",
    0x02: "I8",
    0x03: "I16",
    0x04: "I32",
    0x05: "U8",
    0x06: "U16",
    0x07: "U32",
    0x08: "REAL32",
    0x09: "VISIBLE_STRING",
    0x0A: "OCTET_STRING",
    0x0F: "DOMAIN",
}
_RANGES = (
    (0x1000, 0x1FFF, "CiA 301 communication objects (0x1000-0x1FFF)"),
    (0x2000, 0x4FFF, "Manufacturer objects, real firmware and virtual drive (0x2000-0x4FFF)"),
    (0x5000, 0x5FFF, "Virtual-drive-only objects (0x5000-0x5FFF, not on the real firmware)"),
    (0x6000, 0x9FFF, "CiA 402 drive profile objects (0x6000-0x9FFF)"),
)
_WIDTH = 56


def _macro(name: str) -> str:
    """C macro stem of an OD name: ``"current_controller.L_c"`` -> ``"OD_CURRENT_CONTROLLER__L_C"``.

    The record/sub separator becomes a double underscore so that e.g. ``motor.rated_current``
    (0x2000:5) and ``motor_rated_current`` (0x6075) stay distinct.
    """
    parts = [re.sub(r"[^0-9A-Za-z]+", "_", p).upper() for p in name.split(".")]
    return "OD_" + "__".join(parts)


def _c_comment(text: str) -> str:
    return text.replace("*/", "* /")


def _c_number(entry: Entry, value: float | int) -> str:
    """A C literal of ``value`` typed for ``entry`` (``f`` floats, ``u``/``UL``/``L`` ints)."""
    dt = entry.data_type
    if dt == 0x08:
        text = repr(float(value))
        if "." not in text and "e" not in text:
            text += ".0"
        return f"{text}f" if float(value) >= 0 else f"({text}f)"
    value = int(value)
    if dt == 0x07:
        return f"0x{value:08X}UL"
    if dt == 0x04:
        return f"({value}L)" if value < 0 else f"{value}L"
    if dt in (0x02, 0x03):
        return f"({value})" if value < 0 else f"{value}"
    return f"{value}u"


def _define(name: str, value: str, comment: str = "") -> str:
    line = f"#define {name:<{_WIDTH}} {value}"
    return f"{line} /* {_c_comment(comment)} */" if comment else line


def _nodeid_offset(entry: Entry) -> int:
    assert entry.default_raw is not None
    text = re.sub(r"\$NODEID", "", entry.default_raw, flags=re.IGNORECASE)
    return int(text.replace("+", "").replace(" ", ""), 0)


def _object_heads(view: ObjectDictionaryView) -> dict[int, str]:
    return {e.index: e.object_name for e in view.entries}


def render_header(view: ObjectDictionaryView) -> str:
    """C99 header for the DSP firmware: indices, types, access, defaults, limits, references.

    No ``uint8_t``/``int8_t`` (8-bit objects use 16-bit C types, as C2000's ``char`` is 16 bits)
    and no ``double``: REAL32 literals carry the ``f`` suffix.
    """
    lines: list[str] = []
    add = lines.append
    add(f"/* {HEADER_NAME} - CANopen object dictionary of the BLDC 5 kW / 48 V drive.")
    add(" *")
    add(" * GENERATED from bldc_drive.eds by `python -m firmware_protocol.generate`: do not edit.")
    add(" * C99, float32 only, 8-bit objects as 16-bit C types (TMS320F28335: char is 16 bits).")
    add(" * Macros: OD_<OBJECT>__<SUB>_<FIELD> for records/arrays, OD_<OBJECT>_<FIELD> otherwise.")
    add(" * Fields: _INDEX, _SUB, _TYPE (CiA 301 code), _CTYPE, _ACCESS, _PDO (1 = mappable),")
    add(" * _DEFAULT, _MIN/_MAX (static limits, inclusive), _REF (index<<16 | sub<<8 | bits).")
    add(" * Units are given in the comments. Cross-object rules are listed at the end. */")
    add("#ifndef BLDC_DRIVE_OD_H")
    add("#define BLDC_DRIVE_OD_H")
    add("")
    add("#include <stdint.h>")
    add("")
    add("/* CiA 301 data type codes */")
    for code, tname in sorted(_SHORT_TYPE.items()):
        add(_define(f"OD_TYPE_{tname}", f"0x{code:04X}u"))
    add("")
    add("/* Access: bit0 readable, bit1 writable, bit2 constant */")
    add(_define("OD_ACCESS_RO", "0x1u"))
    add(_define("OD_ACCESS_WO", "0x2u"))
    add(_define("OD_ACCESS_RW", "0x3u"))
    add(_define("OD_ACCESS_CONST", "0x5u"))
    add("")
    add("/* SDO abort codes of the value checks (CiA 301) */")
    add(_define("OD_ABORT_INVALID_VALUE", "0x06090030UL"))
    add(_define("OD_ABORT_VALUE_TOO_HIGH", "0x06090031UL"))
    add(_define("OD_ABORT_VALUE_TOO_LOW", "0x06090032UL"))
    add(_define("OD_ABORT_READ_ONLY", "0x06010002UL"))
    add(_define("OD_ABORT_STATE", "0x08000022UL"))
    add("")
    add("/* Device */")
    add(_define("OD_DEFAULT_NODE_ID", f"{view.node_id}u"))
    for key in ("NrOfRXPDO", "NrOfTXPDO"):
        if key in view.device_info:
            add(_define(f"OD_NR_OF_{key[4:].upper()}", f"{int(view.device_info[key], 0)}u"))
    add("")

    heads = _object_heads(view)
    seen: dict[str, str] = {}

    def define(name: str, value: str, comment: str = "") -> None:
        if name in seen:
            raise ValueError(f"C macro {name} generated twice ({seen[name]})")
        seen[name] = value
        add(_define(name, value, comment))

    current = None
    for e in view.entries:
        if e.index != current:
            current = e.index
            add("")
            add(f"/* ---- 0x{e.index:04X} {heads[e.index]} ---- */")
            if e.object_name != e.name:
                define(f"{_macro(e.object_name)}_INDEX", f"0x{e.index:04X}u")
        m = _macro(e.name)
        unit = e.unit or ""
        head = f"0x{e.index:04X}:{e.subindex:02X} {e.name} {e.type_name} {e.access}"
        if unit:
            head += f" [{unit}]"
        if e.description:
            head += f" - {e.description}"
        add(f"/* {_c_comment(head)} */")
        define(f"{m}_INDEX", f"0x{e.index:04X}u")
        define(f"{m}_SUB", f"0x{e.subindex:02X}u")
        define(f"{m}_TYPE", f"OD_TYPE_{_SHORT_TYPE[e.data_type]}")
        if e.data_type in _C_TYPES:
            define(f"{m}_CTYPE", _C_TYPES[e.data_type])
        define(f"{m}_ACCESS", _ACCESS[e.access])
        define(f"{m}_PDO", "1u" if e.pdo_mappable else "0u")
        if e.relative:
            off = _nodeid_offset(e)
            define(f"{m}_DEFAULT_NODEID_OFFSET", _c_number(e, off), "default = offset + node-ID")
            define(f"{m}_DEFAULT(node_id)", f"({m}_DEFAULT_NODEID_OFFSET + (uint32_t)(node_id))")
        elif isinstance(e.default, str):
            define(f"{m}_DEFAULT", '"' + e.default.replace('"', '\\"') + '"')
        elif isinstance(e.default, (int, float)):
            define(f"{m}_DEFAULT", _c_number(e, e.default), unit)
        if e.low is not None:
            define(f"{m}_MIN", _c_number(e, e.low), unit)
        if e.high is not None:
            define(f"{m}_MAX", _c_number(e, e.high), unit)
        if e.bit_length:
            define(f"{m}_REF", f"0x{e.od_reference:08X}UL")
        for value, label in sorted((e.enum or {}).items()):
            define(f"{m}_{label.upper()}", _c_number(e, value))

    add("")
    add("/* ---- Cross-object constraints (checked at every write of either side, then the")
    add(" *      abort code is TOO_HIGH for the bounded object, TOO_LOW for the bound) ---- */")
    for c in view.constraints:
        add(f"/* {_c_comment(str(c))}{' - ' + c.reason if c.reason else ''} */")
        define(f"{_macro(c.lhs)}_BOUND_FACTOR", f"{float(c.factor)!r}f")
    add("")
    add("#endif /* BLDC_DRIVE_OD_H */")
    return "\n".join(lines) + "\n"


def _md(text: object) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _md_value(e: Entry, value: float | int | str | bytes | None) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, int) and e.data_type == 0x07 and (value > 0xFFFF or e.relative):
        return f"0x{value:08X}"
    return str(value)


def render_markdown(view: ObjectDictionaryView) -> str:
    """The OD reference page: one table per index range, then enumerations and constraints."""
    out: list[str] = []
    add = out.append
    add("# Object dictionary of the BLDC 5 kW / 48 V drive")
    add("")
    add("Generated from `firmware_protocol/bldc_drive.eds` by")
    add("`python -m firmware_protocol.generate`; do not edit. Names are the Python view names")
    add("(`firmware_protocol.load_od().entry(name)`); C macros in `bldc_drive_od.h` use")
    add("`OD_<OBJECT>__<SUB>_...` (double underscore between record and sub-object).")
    add("Limits are inclusive static limits; `$NODEID` defaults are shown for node-ID 1.")
    add("PDO = may be mapped into a PDO (and recorded by the trace).")
    for low, high, title in _RANGES:
        rows = [e for e in view.entries if low <= e.index <= high]
        if not rows:
            continue
        add("")
        add(f"## {title}")
        add("")
        add("| name | index:sub | type | access | unit | default | limits | PDO | description |")
        add("|---|---|---|---|---|---|---|---|---|")
        for e in rows:
            default = _md_value(e, e.default)
            if e.relative:
                default = f"{e.default_raw} ({default})"
            limits = ""
            if e.low is not None or e.high is not None:
                limits = f"[{_md_value(e, e.low)}, {_md_value(e, e.high)}]"
            cells = [
                f"`{e.name}`",
                f"0x{e.index:04X}:{e.subindex:02X}",
                e.type_name,
                e.access,
                e.unit or "",
                default,
                limits,
                "yes" if e.pdo_mappable else "",
                e.description,
            ]
            add("| " + " | ".join(_md(c) for c in cells) + " |")
    add("")
    add("## Default PDO mapping")
    add("")
    add("| PDO | COB-ID | transmission type | event timer | mapped objects (bits) |")
    add("|---|---|---|---|---|")
    for kind, map_base in (("RPDO", 0x1600), ("TPDO", 0x1A00)):
        for n in range(512):
            mapping = map_base + n
            try:
                count = view.by_index(mapping, 0).default
            except KeyError:
                break
            comm = mapping - 0x200
            cob = view.by_index(comm, 1)
            ttype = view.by_index(comm, 2).default
            timer = view.by_index(comm, 5)
            refs = [view.by_index(mapping, i).default for i in range(1, int(count or 0) + 1)]
            mapped = ", ".join(
                f"`{view.by_reference(int(r)).name}` ({int(r) & 0xFF})" for r in refs
            )
            period = f"{timer.default} {timer.unit}" if timer.default else "-"
            add(f"| {kind}{n + 1} | {cob.default_raw} | 0x{ttype:02X} | {period} | {mapped} |")
    add("")
    add("## Enumerations")
    add("")
    add("| object | values |")
    add("|---|---|")
    for e in view.entries:
        if e.enum:
            values = ", ".join(f"{v} = {label}" for v, label in sorted(e.enum.items()))
            add(f"| `{e.name}` | {_md(values)} |")
    add("")
    add("## Cross-object constraints")
    add("")
    add("Checked by the drive at every write of either side and by the host before sending;")
    add("a violation aborts with 0x06090031 (bounded object too high) or 0x06090032")
    add("(bound too low).")
    add("")
    add("| rule | reason |")
    add("|---|---|")
    for c in view.constraints:
        add(f"| `{_md(str(c))}` | {_md(c.reason)} |")
    return "\n".join(out) + "\n"


#: Keys CiA 306 defines for object and sub-object sections; everything else is project-specific.
CIA306_OBJECT_KEYS = frozenset(
    {
        "SubNumber",
        "ParameterName",
        "ObjectType",
        "DataType",
        "AccessType",
        "LowLimit",
        "HighLimit",
        "DefaultValue",
        "PDOMapping",
        "ObjFlags",
        "CompactSubObj",
        "ParameterValue",
        "UploadFile",
        "DownloadFile",
        "Denotation",
        "ParamRefd",
    }
)
_OBJECT_SECTION = re.compile(r"^\[([0-9A-Fa-f]{4})([Ss]ub[0-9A-Fa-f]+)?\]\s*$")
_SECTION = re.compile(r"^\[.*\]\s*$")


def render_strict_eds(eds_text: str) -> str:
    """The EDS without the project's custom keys (``Unit``, ``Description``, ``Enum``,
    ``StorageLocation``), for strict CiA 306 checkers that reject unknown entries.

    Everything else (sections, order, values, comments) is kept verbatim.
    """
    out = [
        "; Strict CiA 306 copy of bldc_drive.eds generated by python -m firmware_protocol.generate"
        " --strict-eds: units, descriptions and enumerations are in the original file.",
    ]
    in_object = False
    for line in eds_text.splitlines():
        if _SECTION.match(line):
            in_object = bool(_OBJECT_SECTION.match(line))
        elif in_object and "=" in line and not line.lstrip().startswith(";"):
            key = line.split("=", 1)[0].strip()
            if key not in CIA306_OBJECT_KEYS:
                continue
        out.append(line)
    return "\n".join(out) + "\n"


def outputs(view: ObjectDictionaryView) -> dict[str, str]:
    """File name -> generated text."""
    return {HEADER_NAME: render_header(view), MARKDOWN_NAME: render_markdown(view)}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``python -m firmware_protocol.generate``; returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m firmware_protocol.generate",
        description="Regenerate bldc_drive_od.h and OD.md from the EDS.",
    )
    parser.add_argument("--check", action="store_true", help="exit 1 if a file drifted")
    parser.add_argument("--eds", type=Path, default=EDS_PATH, help="EDS file (default: packaged)")
    parser.add_argument(
        "--out-dir", type=Path, default=EDS_PATH.parent, help="directory of the outputs"
    )
    parser.add_argument(
        "--strict-eds",
        type=Path,
        metavar="PATH",
        help="also write a copy of the EDS without the project's custom keys to PATH",
    )
    args = parser.parse_args(argv)
    try:
        view = load_od(args.eds)
        generated = outputs(view)
    except (OSError, ValueError, KeyError) as exc:
        print(f"error: cannot load {args.eds}: {exc}", file=sys.stderr)
        return 2
    if args.strict_eds is not None:
        try:
            strict = render_strict_eds(args.eds.read_text(encoding="utf-8"))
            args.strict_eds.write_text(strict, encoding="utf-8")
        except OSError as exc:
            print(f"error: cannot write {args.strict_eds}: {exc}", file=sys.stderr)
            return 2
        print(f"wrote {args.strict_eds}")
    drift = []
    for name, text in generated.items():
        path = args.out_dir / name
        current = path.read_text(encoding="utf-8") if path.exists() else None
        if current == text:
            continue
        if args.check:
            drift.append(name)
        else:
            path.write_text(text, encoding="utf-8")
            print(f"wrote {path}")
    if drift:
        print(
            f"drift: {', '.join(drift)} differ from {args.eds.name}; "
            "run `python -m firmware_protocol.generate`",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
