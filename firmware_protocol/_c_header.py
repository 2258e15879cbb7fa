"""Render the C99 header of the OD for the DSP firmware (``bldc_drive_od.h``).

Conventions: no ``uint8_t``/``int8_t`` (TMS320F28335's ``char`` is 16 bits, so 8-bit objects use
``uint16_t``/``int16_t``), no ``double`` (REAL32 literals carry the ``f`` suffix), 32-bit integer
literals carry ``UL``/``L`` (``int`` is 16 bits on C2000).
"""

from __future__ import annotations

import re

from . import abort_codes, current_stability, stability
from .cob_id import RESTRICTED_CAN_IDS
from .emcy_codes import EMCY_CODES, TRIP_REASONS
from .entry import Entry
from .od import ObjectDictionaryView

__all__ = ["HEADER_NAME", "macro_name", "render_header"]

HEADER_NAME = "bldc_drive_od.h"

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
_WIDTH = 56


def macro_name(name: str) -> str:
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
    for macro, code in (
        ("INVALID_VALUE", abort_codes.INVALID_VALUE),
        ("VALUE_TOO_HIGH", abort_codes.VALUE_TOO_HIGH),
        ("VALUE_TOO_LOW", abort_codes.VALUE_TOO_LOW),
        ("READ_ONLY", abort_codes.WRITE_READ_ONLY),
        ("STATE", abort_codes.DEVICE_STATE),
    ):
        add(_define(f"OD_ABORT_{macro}", f"0x{code:08X}UL"))
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
                define(f"{macro_name(e.object_name)}_INDEX", f"0x{e.index:04X}u")
        m = macro_name(e.name)
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
        if e.min_nonzero is not None:
            define(f"{m}_MIN_NONZERO", _c_number(e, e.min_nonzero), f"{unit}: 0 or >= this")
        if e.config_only:
            define(f"{m}_CONFIG_ONLY", "1u", "write only with the power stage off, else 0x08000022")
        if e.bit_length:
            define(f"{m}_REF", f"0x{e.od_reference:08X}UL")
        for value, label in sorted((e.enum or {}).items()):
            define(f"{m}_{label.upper()}", _c_number(e, value))

    add("")
    add("/* ---- Cross-object constraints (checked at every write of either side, then the")
    add(" *      abort code is TOO_HIGH for the bounded object, TOO_LOW for the bound) ---- */")
    for c in view.constraints:
        add(f"/* {_c_comment(str(c))}{' - ' + c.reason if c.reason else ''} */")
        define(f"{macro_name(c.lhs)}_BOUND_FACTOR", f"{float(c.factor)!r}f")
    add("")
    add("/* ---- IP speed loop stability rule (see OD.md): accept (k_p, k_i) only if")
    add(" *      k_p > 0, k_i > 0, k_p k_i b > 0, 2 (1 + a) - k_p b (2 + k_i) > 0")
    add(" *      and |a - k_p b| < 1, slowest pole |p| <= exp(-Ts / OD_SPEED_LOOP_TAU_MAX) ---- */")
    define("OD_SPEED_MODEL_A", f"{stability.A_IDENTIFIED!r}f", "identified pole a, eq. (26)")
    define("OD_SPEED_MODEL_B", f"{stability.B_IDENTIFIED!r}f", "rpm/(A sample), eq. (26)")
    define("OD_LOOP_TS", f"{stability.TS!r}f", "s")
    define("OD_SPEED_LOOP_TAU_MAX", f"{stability.TAU_MAX!r}f", "s")
    define("OD_SPEED_LOOP_ZETA_MIN", f"{stability.ZETA_MIN!r}f", "least damping of a pair")
    add("")
    add("/* ---- Current loop admissibility (see OD.md): closed-loop poles inside rho, a law")
    add(" *      without integral action only with the back-EMF feed-forward, predictive")
    add(" *      compensation error <= share of rated current, cascade poles stable ---- */")
    define("OD_CURRENT_LOOP_TAU_MAX", f"{current_stability.TAU_MAX_CURRENT!r}f", "s")
    define("OD_CURRENT_COMP_MAX_SHARE", f"{current_stability.COMP_MAX_SHARE!r}f", "1")
    define(
        "OD_CURRENT_NO_INTEGRAL_MIN_L_RATIO",
        f"{current_stability.NO_INTEGRAL_MIN_RATIO!r}f",
        "L_c/L, predictive or R_c = 0",
    )
    add("")
    add("/* ---- Restricted 11-bit CAN-IDs (CiA 301 7.3.5): no valid configurable COB-ID may use")
    add(" *      them; 29-bit COB-IDs (bit 29) and a new CAN-ID while valid are refused ---- */")
    define("OD_COB_RESTRICTED_COUNT", f"{len(RESTRICTED_CAN_IDS)}u")
    for k, (lo, hi) in enumerate(RESTRICTED_CAN_IDS, start=1):
        define(f"OD_COB_RESTRICTED_{k}_LO", f"0x{lo:03X}u")
        define(f"OD_COB_RESTRICTED_{k}_HI", f"0x{hi:03X}u")
    add("")
    add("/* ---- EMCY error codes the drive sends (see OD.md) ---- */")
    for code, (stem, _when) in sorted(EMCY_CODES.items()):
        define(f"OD_EMCY_{stem}", f"0x{code:04X}u")
    add("")
    add("/* ---- Trip reasons of the sample loop's protection (fault_reason) and the EMCY code")
    add(" *      each trip sends (an injected fault sends the injected code) ---- */")
    for number, reason in sorted(TRIP_REASONS.items()):
        define(f"OD_TRIP_{reason.stem}", f"{number}u", reason.text)
        if reason.emcy is not None:
            define(f"OD_TRIP_{reason.stem}_EMCY", f"OD_EMCY_{EMCY_CODES[reason.emcy][0]}")
    add("")
    add("#endif /* BLDC_DRIVE_OD_H */")
    return "\n".join(lines) + "\n"
