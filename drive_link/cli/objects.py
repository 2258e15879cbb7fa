"""``drive-link`` commands on the node's objects and parameters: ``read``, ``write``,
``objects``, ``gains``, ``set-gains``, ``store``, ``restore``, ``nmt``, ``faults``."""

from __future__ import annotations

import argparse
from typing import Any

from ..errors import InvalidValue
from ..link import _od_select, units
from ..link._gain_set import GainWriteRefused
from ..link.drive import GAIN_FIELDS, Drive
from ._common import AddCommand, Refused, _emit, _parse_value, _timeout

__all__ = ["add_parsers"]


def _gain_value(name: str, text: str) -> float | int | str:
    """A typed gain (``L_c=20uH``, ``speed_current_limit=50A``) in its object's unit
    (:func:`drive_link.link.units.parse_value`); text that is no number passes through for
    ``type`` (``type=pi``)."""
    from ..link._gain_set import GAIN_OBJECTS as _GAIN_OBJECTS
    from ..link._objects import default_table

    obj = default_table()[_GAIN_OBJECTS[name][1]]
    if name == "type" and _parse_value(text) == text:
        return text
    return units.parse_value(text, obj.unit, integer=not obj.is_float, name=name)


def _with_unit(obj: Any, v: Any) -> str:
    """``v`` with its unit, its enumeration label, or (unsigned without unit: bit fields,
    COB-IDs, codes) its hex form."""
    unit = obj.unit if obj.unit not in ("", "1") else ""
    label = dict(obj.enum).get(v) if obj.enum and isinstance(v, int) else None
    if label is None and not unit and obj.type_name.startswith("UNSIGNED") and isinstance(v, int):
        label = f"0x{v:0{max(2, obj.bits // 4)}X}"
    return f"{v} {unit}".rstrip() + (f" ({label})" if label else "")


def cmd_read(args: argparse.Namespace, d: Drive) -> int:
    objs = [_od_select.select(n, d.table) for n in args.names]
    out = {o.name: d.read(o.name) for o in objs}
    by_name = {o.name: o for o in objs}
    _emit(
        args,
        out,
        lambda: "\n".join(f"{n} = {_with_unit(by_name[n], v)}" for n, v in out.items()),
    )
    return 0


def cmd_write(args: argparse.Namespace, d: Drive) -> int:
    obj = _od_select.select(args.name, d.table)
    value = units.parse_for(obj, args.value)
    try:
        d.write(obj.name, value)
    except GainWriteRefused as gain:  # checked as every write is, then the one gain path
        _apply_one_gain(d, gain)
    back = d.read(obj.name) if obj.readable else value
    _emit(args, {obj.name: back}, f"{obj.name} = {_with_unit(obj, back)}")
    return 0


def _apply_one_gain(d: Drive, gain: GainWriteRefused) -> None:
    """``drive-link write`` of an active gain object: the one gain path
    (:func:`drive_link.apply_gains`, its stability and margin policy) with that one change; a
    refusal names ``set-gains --force`` (exit 7, nothing sent)."""
    from ..workflows.gains import GainsRefused, apply_gains

    try:
        apply_gains(d, {gain.field: gain.value})
    except GainsRefused as exc:
        raise GainsRefused(
            f"{gain.name}: {exc} (gains change through drive_link.apply_gains: "
            f"drive-link set-gains {gain.field}=... [--force])",
            exc.check,
        ) from None


def cmd_objects(args: argparse.Namespace) -> int:
    objs = _od_select.search(args.pattern)
    if not objs:
        raise InvalidValue(f"no object matches {args.pattern!r} (try a part of a name or 0x20)")
    _emit(
        args,
        [_od_select.describe(o) for o in objs],
        lambda: _od_select.table_text(objs),
    )
    return 0


def cmd_gains_get(args: argparse.Namespace, d: Drive) -> int:
    g = d.read_gains().to_dict()
    _emit(args, g, lambda: "\n".join(f"{k:>20} = {v:g}" for k, v in g.items()))
    return 0


def cmd_gains_set(args: argparse.Namespace, d: Drive) -> int:
    from ..workflows.gains import GainsRefused, apply_gains

    changes: dict[str, float | int | str] = {}
    for item in args.assignments:
        if "=" not in item:
            raise InvalidValue(f"expected NAME=VALUE, got {item!r}")
        k, v = item.split("=", 1)
        if k not in GAIN_FIELDS:
            raise InvalidValue(f"unknown gain {k!r}; known: {', '.join(GAIN_FIELDS)}")
        val = _gain_value(k, v)  # units: L_c=20uH
        if isinstance(val, str) and k != "type":  # type=pi as well as type=1
            raise InvalidValue(f"{k}: {v!r} is not a number")
        changes[k] = val
    model = (args.model_a, args.model_b) if args.model_a is not None else None
    try:
        res = apply_gains(d, changes, force=args.force, speed_model=model)
    except GainsRefused as exc:
        hint = "" if exc.unstable else " (use --force to apply anyway)"
        raise Refused(str(exc).replace(" (force to apply anyway)", "") + hint) from None
    back = res.gains
    out = {"gains": back, "margins": res.check.figures, "warnings": list(res.check.warnings)}
    _emit(
        args,
        out,
        lambda: (
            "\n".join(f"{k:>20} = {v:g}" for k, v in back.items())
            + "".join(f"\nwarning: {p}" for p in res.check.warnings)
        ),
    )
    return 0


def cmd_store(args: argparse.Namespace, d: Drive) -> int:
    d.store()
    _emit(args, {"stored": True}, "parameters stored")
    return 0


def cmd_restore(args: argparse.Namespace, d: Drive) -> int:
    d.restore_defaults(reset=args.reset)
    msg = "defaults restored" + (" and node reset" if args.reset else " (apply after reset node)")
    _emit(args, {"restored": True, "reset": args.reset}, msg)
    return 0


def cmd_nmt(args: argparse.Namespace, d: Drive) -> int:
    cmd = args.command.replace("-", " ") if args.command.startswith("reset") else args.command
    if cmd.startswith("reset"):
        d.reset(communication_only=cmd == "reset communication", timeout=_timeout(args, 3.0) + 2)
    else:
        d.nmt(cmd)
    _emit(args, {"sent": cmd}, f"NMT {cmd} sent to node {d.node_id}")
    return 0


def cmd_faults(args: argparse.Namespace, d: Drive) -> int:
    hist = d.error_history()
    reg = int(d.read("error_register"))
    out = {
        "error_register": reg,
        "error_code": int(d.read("error_code")),
        "history": [{"code": e.code, "description": e.description} for e in hist],
    }
    if args.clear:
        d.clear_error_history()
    _emit(
        args,
        out,
        lambda: (
            f"error register 0x{reg:02X}\n"
            + ("\n".join(f"  0x{e.code:04X} {e.description}" for e in hist) or "  (no errors)")
        ),
    )
    return 0


def add_parsers(add: AddCommand) -> None:
    """The object, gain, parameter, NMT and fault commands."""
    p = add(
        "read", cmd_read, "read objects by name or index (current_controller.L_c, 0x6041, 0x2010:2)"
    )
    p.add_argument("names", nargs="+", metavar="OBJECT", help="name or INDEX[:SUB] (hex sub)")
    p = add(
        "write",
        cmd_write,
        "write one object by name or index; the value may carry a unit (20uH, 50A, 1000rpm)",
    )
    p.add_argument("name", metavar="OBJECT", help="name or INDEX[:SUB] (hex sub)")
    p.add_argument("value", help="value in the object's unit, or with a unit; enum labels too")
    p = add(
        "objects",
        cmd_objects,
        "list the objects: name, index:sub, type, unit, limits, access (no bus needed)",
        False,
    )
    p.add_argument(
        "pattern",
        nargs="?",
        default=None,
        metavar="PATTERN",
        help="part of a name or description, a shell pattern (*L_c*), or an index (0x2010)",
    )
    p = add("gains", cmd_gains_get, "show the active gains")
    p = add("set-gains", cmd_gains_set, "apply gains atomically, e.g. set-gains L_c=13e-6 k_p=0.5")
    p.add_argument("assignments", nargs="+", metavar="NAME=VALUE")
    p.add_argument(
        "--force",
        action="store_true",
        help="apply despite poor margins (an unstable set is never applied)",
    )
    p.add_argument(
        "--model-a", type=float, default=None, help="speed model a for the speed-loop check"
    )
    p.add_argument("--model-b", type=float, default=None, help="speed model b (rpm/A per sample)")
    add("store", cmd_store, "store parameters in non-volatile memory (0x1010)")
    p = add("restore", cmd_restore, "restore default parameters (0x1011)")
    p.add_argument("--reset", action="store_true", help="reset the node so they apply now")
    p = add("nmt", cmd_nmt, "send an NMT command")
    p.add_argument(
        "command", choices=["start", "stop", "pre-operational", "reset-node", "reset-communication"]
    )
    p = add("faults", cmd_faults, "error register and fault history (0x1003)")
    p.add_argument("--clear", action="store_true", help="clear the history afterwards")
