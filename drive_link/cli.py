"""The drive-link command: talk to a drive (DSP or virtual) from a shell.

Every command takes the bus options (--interface/--channel/--bitrate, or --host/--port for the
loopback hub; unset = python-can config/env), --node and --json. Values take units (20uH, 50A,
1000rpm, "-1e30"), converted to the object's unit in the object dictionary; a bare number is in
that unit. Every failure is one line on stderr (with --json: {"error": ..., "exit_code": N} on
stdout) and a non-zero exit code:

1 drive refused / failed check, 2 usage, 3 bus error, 4 node not found (``scan``: none), 5 timeout,
6 SDO abort, 7 invalid value (an option's too), 8 unsafe gains refused (use --force), 130
interrupted, 141 the reader closed the output pipe (quietly, as other Unix tools).
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import re
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn

from firmware_protocol import abort_codes
from firmware_protocol.index_ranges import PDO_PARAMETERS

from . import _connection, _od_select, units
from ._jsonable import jsonable as _jsonable
from .cia402 import FAULT, FAULT_REACTION_ACTIVE, OPERATION_ENABLED
from .cli_connect import (
    add_hidden_aliases,
    bus_options,
    bus_settings_from_args,
    connect_from_args,
)
from .closed_pipe import run_quietly
from .drive import GAIN_FIELDS, Drive
from .errors import (
    BusError,
    DriveError,
    DriveTimeout,
    InvalidValue,
    NodeNotFound,
    SdoAbort,
    StateError,
    UnknownObject,
)

__all__ = [
    "EXIT_CODES",
    "EXIT_UNSAFE",
    "Failed",
    "Refused",
    "build_parser",
    "main",
    "quantity",
]

EXIT_CODES: list[tuple[type[BaseException], int]] = [
    (BusError, 3),
    (NodeNotFound, 4),
    (DriveTimeout, 5),
    (SdoAbort, 6),
    (InvalidValue, 7),
    (UnknownObject, 7),  # an object name or index the dictionary does not have
    (DriveError, 1),
]
EXIT_INVALID = 7
EXIT_UNSAFE = 8


class Refused(DriveError):  # noqa: N818
    """A command refused to act (e.g. unsafe gains without --force)."""


class Failed(DriveError):  # noqa: N818
    """A command ran but its result is a failure (e.g. a failed check)."""


# --------------------------------------------------------------------------- output helpers
def _emit(args: argparse.Namespace, data: Any, text: str | Callable[[], str]) -> None:
    if args.json:
        print(json.dumps(_jsonable(data)))
    else:
        print(text() if callable(text) else text)


def _progress_bar(args: argparse.Namespace) -> Callable[[int, int | None], None] | None:
    """A tqdm bar on stderr for an upload (a terminal, or ``--progress``); None with --json."""
    if args.json or (not sys.stderr.isatty() and not getattr(args, "progress", False)):
        return None
    from tqdm import tqdm

    bars: list[tqdm] = []

    def update(done: int, total: int | None) -> None:
        if not bars:  # made at the first report, when the size is known (or not)
            shape = "[{bar:30}] {percentage:5.1f} % " if total else ""
            bar_format = "{desc} " + shape + "{n_fmt}B"
            bars.append(
                tqdm(
                    desc="upload",
                    total=total or None,
                    unit="B",
                    unit_scale=True,
                    unit_divisor=1024,
                    file=sys.stderr,
                    ascii=" #",
                    mininterval=0.1,
                    bar_format=bar_format,
                )
            )
        bar = bars[0]
        bar.update(done - bar.n)
        if total and done >= total:
            bar.close()

    return update


def _parse_value(text: str) -> float | int | str:
    try:
        return int(text, 0)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def _gain_value(name: str, text: str) -> float | int | str:
    """A typed gain (``L_c=20uH``, ``speed_current_limit=50A``) in its object's unit
    (:func:`drive_link.units.parse_value`); text that is no number passes through for
    ``type`` (``type=pi``)."""
    from ._gain_set import GAIN_OBJECTS as _GAIN_OBJECTS
    from ._objects import default_table

    obj = default_table()[_GAIN_OBJECTS[name][1]]
    if name == "type" and _parse_value(text) == text:
        return text
    return units.parse_value(text, obj.unit, integer=not obj.is_float, name=name)


# --------------------------------------------------------------------------- commands
def cmd_scan(args: argparse.Namespace) -> int:
    from ._scan import scan

    conn = _connection.acquire(**bus_settings_from_args(args))  # --fd, --bus-kwargs ... too
    listen = _timeout(args, 1.0)
    try:
        nodes = scan(conn.bus, timeout=listen)
    finally:
        _connection.release(conn)
    if not nodes:  # exit 4 "no node", as for a command whose node does not answer
        raise NodeNotFound(
            f"no node answered on the bus (SDO probe of 1..127, heartbeats for {listen:g} s)"
        )
    data = [
        {
            "node_id": n.node_id,
            "device_type": n.device_type,
            "nmt_state": n.nmt_state,
            "abort_code": n.abort_code,
        }
        for n in nodes
    ]

    def text() -> str:
        lines = []
        for n in nodes:
            dt = (
                f"device_type 0x{n.device_type:08X} ({n.profile})"
                if n.device_type is not None
                else "no SDO answer"
            )
            lines.append(f"node {n.node_id:3d}: {dt}, {n.nmt_state or 'no heartbeat seen'}")
        return "\n".join(lines)

    _emit(args, data, text)
    return 0


#: What a store_status value means for the user (0x2060).
_STORE_STATUS_TEXT = {
    "ok": "stored parameters loaded",
    "defaults": "no stored parameters: defaults in use",
    "damaged": "STORED PARAMETERS DAMAGED: defaults in use (EMCY 0x6310), store again",
    "unreadable": "STORED PARAMETERS UNREADABLE: defaults in use (EMCY 0x6310), store again",
    "unknown": "not reported by this firmware (no 0x2060)",
}


def _status_text(st: dict) -> str:
    lines = []
    for k, v in st.items():
        if k == "store_status":
            v = f"{v} ({_STORE_STATUS_TEXT.get(str(v), 'unexpected value')})"
        elif k == "supervision_rearmed_at" and v is None:
            v = "never (no restart seen)"
        elif k == "error_code" and isinstance(v, int):
            from ._emcy import describe

            v = f"0x{v:04X} ({describe(v)})" if v else "0x0000"
        elif k in ("statusword", "error_register") and isinstance(v, int):
            v = f"0x{v:04X}" if k == "statusword" else f"0x{v:02X}"
        lines.append(f"{k:>22}: {v}")
    return "\n".join(lines)


def cmd_status(args: argparse.Namespace, d: Drive) -> int:
    st = d.status()
    st["gains"] = d.read_gains().to_dict()
    _emit(args, st, lambda: _status_text(st))
    return 0


def _state_cmd(fn_name: str) -> Callable[[argparse.Namespace, Drive], int]:
    def run(args: argparse.Namespace, d: Drive) -> int:
        state = getattr(d, fn_name)(timeout=_timeout(args, 3.0))
        _emit(args, {"state": state}, state)
        return 0

    return run


def _usable_state(d: Drive) -> str:
    """The CiA 402 state; :class:`StateError` with the fix when the drive is in FAULT."""
    state = d.state
    if state in (FAULT, FAULT_REACTION_ACTIVE):
        raise StateError(f"the drive is in {state}: run `drive-link faults`, then `fault-reset`")
    return state


def _switch_mode(args: argparse.Namespace, d: Drive, mode: str, allowed: bool, flag: str) -> bool:
    """Select ``mode``. The drive changes modes only with the power stage off (0x6060 answers
    0x08000022 in OPERATION ENABLED): if it is enabled in another mode, disable, switch and
    return True (the caller enables again) when ``allowed``; otherwise a one-line refusal
    naming the fix. Nothing is changed before that check."""
    state = _usable_state(d)
    now = d.mode
    if now == mode:
        return False
    if state == OPERATION_ENABLED:
        if not allowed:
            raise StateError(
                f"the drive is OPERATION ENABLED in {now} mode and changes mode only with the "
                f"power stage off: run `drive-link disable` first, or add {flag} "
                "(disable, switch, enable again)"
            )
        d.disable(timeout=_timeout(args, 3.0))
        d.set_mode(mode)
        return True
    d.set_mode(mode)
    return False


def cmd_mode(args: argparse.Namespace, d: Drive) -> int:
    if _switch_mode(args, d, args.mode, args.re_enable, "--re-enable"):
        d.enable(timeout=_timeout(args, 3.0))
    _emit(args, {"mode": d.mode, "state": d.state}, f"mode {d.mode} ({d.state})")
    return 0


def _set_setpoint(
    args: argparse.Namespace, d: Drive, mode: str, name: str, value: float | int, key: str
) -> int:
    """Write the setpoint ``name`` in ``mode``: the value is checked against the object's
    limits and the drive's state first (nothing is changed when refused); a drive that is not
    enabled is refused unless ``--enable`` (a zero setpoint is written: it is the stopped
    state); prints the read-back as ``key`` with the state."""
    obj = d.table[name]
    value = obj.check(value)
    state = _usable_state(d)
    if state != OPERATION_ENABLED and not args.enable and value != 0:
        raise StateError(
            f"nothing written: the drive is {state} and a setpoint moves nothing until it is "
            "enabled; add --enable (or run `drive-link enable` first)"
        )
    again = _switch_mode(args, d, mode, args.switch_mode, "--switch-mode")
    d.write(name, value)
    if args.enable or again:
        d.enable(timeout=_timeout(args, 3.0))
    out = {key: d.read(name), "state": d.state}
    unit = obj.unit
    _emit(args, out, f"{key} {out[key]:g} {unit} ({out['state']})")
    return 0


def cmd_set_speed(args: argparse.Namespace, d: Drive) -> int:
    return _set_setpoint(args, d, "speed", "target_velocity", args.rpm, "target_velocity")


def cmd_set_current(args: argparse.Namespace, d: Drive) -> int:
    return _set_setpoint(args, d, "current", "setpoints.i_p_ref", args.amps, "i_p_ref")


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
    d.write(obj.name, value)
    back = d.read(obj.name) if obj.readable else value
    _emit(args, {obj.name: back}, f"{obj.name} = {_with_unit(obj, back)}")
    return 0


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
    from .gains import GainsRefused, apply_gains

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


def cmd_live(args: argparse.Namespace, d: Drive) -> int:
    import time

    live = d.live
    time.sleep(args.seconds)
    st = live.stats
    latest = live.latest()
    out = {"stats": st, "latest": latest}
    _emit(
        args,
        out,
        lambda: "\n".join(
            [
                f"{k}: {v['rate_hz']:.0f} Hz (expected {v['expected_hz']}), "
                f"frames {v['frames']}, dropped {v['dropped']}"
                for k, v in st["tpdo"].items()
            ]
            + [f"bus load {100 * (st.get('bus_load') or 0):.1f} %"]
            + [f"{k} = {v:.4g}" for k, v in latest.items()]
        ),
    )
    return 0


def _save_outputs(args: argparse.Namespace, obj: Any, out: dict) -> None:
    if getattr(args, "csv", None):
        out["csv"] = str(obj.to_csv(args.csv))
    if getattr(args, "png", None):
        out["png"] = str(obj.to_png(args.png))


def cmd_trace(args: argparse.Namespace, d: Drive) -> int:
    from .trace import Trigger

    level = args.level
    if isinstance(level, str):
        src = args.source if args.source in d.table else f"measurements.{args.source}"
        unit = d.table[src].unit if src in d.table else ""
        level = units.parse_value(level, unit, name=f"--level ({src})")
    trig = Trigger(args.trigger, args.source, level, args.edge)
    tr = d.trace.capture(
        channels=[c.strip() for c in args.channels.split(",") if c.strip()],
        divider=args.divider,
        length=args.length,
        pre_trigger=args.pre_trigger,
        trigger=trig,
        timeout=args.wait,
        progress=_progress_bar(args),
    )
    out: dict[str, Any] = {
        "samples": len(tr.t),
        "dt": tr.dt,
        "trigger_index": tr.trigger_index,
        "signals": {
            k: {"unit": tr.units[k], "min": float(v.min()), "max": float(v.max())}
            for k, v in tr.signals.items()
        },
    }
    _save_outputs(args, tr, out)
    _emit(
        args,
        out,
        lambda: "\n".join(
            [f"{len(tr.t)} samples every {tr.dt * 1e6:g} µs, trigger at {tr.trigger_index}"]
            + [
                f"{k} [{s['unit']}]: {s['min']:.4g} .. {s['max']:.4g}"
                for k, s in out["signals"].items()
            ]
            + [f"saved {out[k]}" for k in ("csv", "png") if k in out]
        ),
    )
    return 0


def _settle_args(args: argparse.Namespace) -> Any:
    """The --settle-window/--settle-timeout/--settle-tol options as a :class:`steps.Settle`
    (None: the experiment's defaults)."""
    from .steps import Settle

    given = {
        k: v
        for k, v in (
            ("window_s", args.settle_window),
            ("timeout_s", args.settle_timeout),
            ("tol", args.settle_tol),
        )
        if v is not None
    }
    return Settle(**given) if given else None


def _say(args: argparse.Namespace) -> Callable[[str], None]:
    """An experiment's 'what I change' line, printed first on stdout (stderr keeps the
    one-line error); with --json it is the result's "changes"."""
    return lambda text: None if args.json else print(text, flush=True)


def cmd_step(args: argparse.Namespace, d: Drive) -> int:
    from . import steps

    if args.kind == "current":
        for v in (args.i_from, args.i_to):
            d.table["setpoints.i_p_ref"].check(v)
    elif args.start is not None:
        for v in (args.start, args.start + args.delta):
            d.table["target_velocity"].check(units.parse_value(v, "rpm", integer=True))
    settle = _settle_args(args)
    _usable_state(d)
    res = _run_step(args, d, steps, settle)  # leaves the drive as found (drive_link.steps)
    out = res.summary()
    _save_outputs(args, res, out)
    m = res.metrics
    unit = out["unit"]

    def text() -> str:
        lines = [
            f"{res.kind} step {res.y_from:g} → {res.y_to:g} {unit} "
            f"(settled start {res.start:.4g} {unit})",
            f"  rise time         {m.rise_time * 1e3:.4g} ms",
            f"  overshoot         {m.overshoot_pct:.3g} %",
            f"  settling time     {m.settling_time * 1e3:.4g} ms",
            f"  steady-state err  {m.steady_state_error:.4g} {unit}",
        ]
        lines += [f"saved {out[k]}" for k in ("csv", "png") if k in out]
        return "\n".join(lines)

    _emit(args, out, text)
    return 0


def _run_step(args: argparse.Namespace, d: Drive, steps: Any, settle: Any) -> Any:
    """The step test itself (drive_link.steps: settled start, drive left as found)."""
    hooks = steps.Hooks(say=_say(args))
    if args.kind == "current":
        return steps.current_step(
            d,
            args.i_from,
            args.i_to,
            divider=args.divider,
            length=args.length,
            pre_trigger=args.pre_trigger,
            enable=not args.no_enable,
            hooks=hooks,
            settle=settle,
            brake=args.brake,
        )
    model = (args.model_a, args.model_b) if args.model_a is not None else None
    return steps.speed_step(
        d,
        args.delta,
        start_rpm=args.start,
        divider=args.divider,
        length=args.length,
        pre_trigger=args.pre_trigger,
        enable=not args.no_enable,
        model=model,
        hooks=hooks,
        settle=settle,
        brake=args.brake,
    )


def cmd_identify(args: argparse.Namespace, d: Drive) -> int:
    from . import design
    from .steps import Hooks, identify_speed_model

    for v in (args.i_from, args.i_to):
        d.table["setpoints.i_p_ref"].check(v)
    settle = _settle_args(args)
    _usable_state(d)
    ident = identify_speed_model(  # the dashboard's identification too; leaves as found
        d,
        args.i_from,
        args.i_to,
        divider=args.divider,
        length=args.length,
        pre_trigger=args.pre_trigger,
        settle_s=args.settle,
        hooks=Hooks(say=_say(args)),
        settle=settle,
        brake=args.brake,
    )
    tr, fit = ident.trace, ident.fit
    k_p, k_i = design.ip_gains(fit.a, fit.b, xi=args.xi, omega_n=args.omega_n)
    out = {
        "fit": fit.as_dict(),
        "start_rpm": ident.start_rpm,
        "ip_gains": {"speed_k_p": k_p, "speed_k_i": k_i, "xi": args.xi, "omega_n": args.omega_n},
    }
    _save_outputs(args, tr, out)
    _emit(
        args,
        out,
        lambda: (
            f"settled start {ident.start_rpm:.4g} rpm at {args.i_from:g} A, step to "
            f"{args.i_to:g} A\n"
            f"G(z) = b/(z - a): a = {fit.a:.8f}, b = {fit.b:.6g} rpm/A per sample "
            f"(R² {fit.r2:.4f})\nIP gains for ξ = {args.xi}, ω_n = {args.omega_n} rad/s: "
            f"speed_k_p = {k_p:.5g}, speed_k_i = {k_i:.5g}"
        ),
    )
    return 0


def cmd_check(args: argparse.Namespace, d: Drive) -> int:
    from .check import run_checks

    only = args.only.split(",") if args.only else None
    skip = args.skip.split(",") if args.skip else None

    label = {"pass": "PASS", "fail": "FAIL", "not applicable": "N/A ", "not judged": "N/J "}

    def show(r: Any) -> None:
        if not args.json:
            print(f"{label[r.verdict]}  {r.name:<20} {r.detail}", flush=True)

    try:
        results = run_checks(
            d, only=only, skip=skip, on_result=show, rate_tolerance=args.rate_tolerance
        )
    except ValueError as exc:
        raise InvalidValue(str(exc)) from None
    failed = [r.name for r in results if not r.ok]
    na = [r.name for r in results if r.verdict == "not applicable"]
    nj = [r.name for r in results if r.verdict == "not judged"]
    if args.json:
        print(
            json.dumps(
                [
                    {
                        "name": r.name,
                        "ok": r.ok,
                        "verdict": r.verdict,
                        "detail": r.detail,
                        "seconds": r.seconds,
                    }
                    | ({"evidence": r.evidence} if r.evidence else {})
                    for r in results
                ]
            )
        )
    else:
        print(
            f"{len(results) - len(failed) - len(na) - len(nj)}/{len(results) - len(na)} passed"
            + (f"; not applicable: {', '.join(na)}" if na else "")
            + (f"; not judged (host stalls): {', '.join(nj)}" if nj else "")
            + (f"; failed: {', '.join(failed)}" if failed else "")
        )
    return 1 if failed else 0


def cmd_config(args: argparse.Namespace, d: Drive) -> int:
    from . import config_dcf

    if args.action == "save":
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", UserWarning)
            out = config_dcf.save(d, args.file, bitrate=args.bitrate)
        notes = [str(w.message) for w in caught]
        if args.json:
            out["warnings"] = notes
        for note in [] if args.json else notes:
            print(f"warning: {note}", file=sys.stderr)
        msg = f"saved {out['objects']} objects of node {out['node_id']} to {out['file']}"
        _emit(args, out, msg)
        return 0
    if args.action == "diff":
        res = config_dcf.diff(d, args.file)
        out = res.as_dict()

        def text() -> str:
            lines = [
                f"{c.name} ({c.index}): drive {c.drive:g}, file {c.file:g} {c.unit}".rstrip()
                for c in res.changes
            ]
            lines.append(f"{len(res.changes)} differ, {res.same} equal")
            return "\n".join(lines)

        _emit(args, out, text)
        return 0
    out = config_dcf.load(d, args.file, dry_run=args.dry_run, force=args.force)
    n = len(out["changes"])
    verb = "would write" if args.dry_run else "wrote"
    _emit(
        args,
        out,
        lambda: "\n".join(
            [
                f"{c['name']}: {c['drive']:g} -> {c['file']:g} {c['unit']}".rstrip()
                for c in out["changes"]
            ]
            + [f"{verb} {n} object{'s' if n != 1 else ''} (the others are equal)"]
        ),
    )
    return 0


def _config_parsers(add: Callable[..., argparse.ArgumentParser]) -> None:
    """``config save|load|diff FILE.dcf``."""
    p = add(
        "config",
        cmd_config,
        "the drive's configuration (motor, protection, gains, CiA 402 settings) as a CiA 306 "
        "DCF file: save, diff, load (checked first, all or nothing)",
    )
    p.add_argument("action", choices=["save", "load", "diff"], help="save / load / diff")
    p.add_argument("file", type=Path, metavar="FILE.dcf", help="the DCF file")
    p.add_argument(
        "--dry-run", action="store_true", help="load: check and show the changes, write nothing"
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="load: apply a gain set with poor stability margins (an unstable one never)",
    )


# --------------------------------------------------------------------------- parser
#: True while :func:`main` runs with ``--json`` anywhere on the command line: usage errors are
#: then JSON on stdout too.
_JSON_ERRORS = False


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line usage error (exit 2) instead of usage + error lines, and
    negative numbers (``-1e30``, ``-5A``, ``-inf``) taken as values, never as options."""

    def __init__(self, *a: Any, **kw: Any) -> None:
        kw.setdefault("allow_abbrev", False)  # an option is spelled in full (sub-parsers too)
        super().__init__(*a, **kw)
        self._negative_number_matcher = re.compile(r"^-(\.?\d|inf|nan)", re.IGNORECASE)

    def _parse_optional(self, arg_string: str) -> Any:
        # a negative value is never an option, also where a short option shares its first
        # letter (-inf is not "-i nf", -nan not "-n an"): the value parser refuses it in words
        if self._negative_number_matcher.match(arg_string):
            return None
        return super()._parse_optional(arg_string)

    def _get_value(self, action: argparse.Action, arg_string: str) -> Any:
        # a value its type refuses (wrong unit, not a number, nan, not whole) is an invalid
        # value (exit 7, as the same value given to `write`), not a usage error (2)
        try:
            return super()._get_value(action, arg_string)
        except argparse.ArgumentError:
            self._invalid_value = True
            raise

    def error(self, message: str) -> NoReturn:
        code = EXIT_INVALID if getattr(self, "_invalid_value", False) else 2
        self._invalid_value = False  # the shell parses again with the same parser
        text = f"{message} (see {self.prog} --help)"
        if _JSON_ERRORS:
            print(json.dumps({"error": text, "exit_code": code}))
            self.exit(code)
        self.exit(code, f"{self.prog}: error: {text}\n")


def quantity(unit: str, integer: bool = False) -> Callable[[str], float | int]:
    """argparse ``type=`` for a value in ``unit`` typed with or without a unit (``20uH``,
    ``1000rpm``, ``-5A``); a wrong dimension, nan/inf or (``integer``) a non-whole value is a
    one-line usage error. The same parser as the API's (:func:`drive_link.units.parse_value`)."""

    def parse(text: str) -> float | int:
        try:
            return units.parse_value(text, unit, integer=integer)
        except InvalidValue as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = f"value in {unit}" if unit else "number"
    return parse


def _object_value(name: str) -> Callable[[str], float | int]:
    """argparse ``type=`` for a value of the OD object ``name`` (its unit and integer type)."""
    from ._objects import default_table

    obj = default_table()[name]
    return quantity(obj.unit, integer=not obj.is_float)


#: Options every command takes, before or after the sub-command: (flags, add_argument keywords
#: without ``default``, default). The default is filled in after parsing (see :func:`_merge_bus`).
def _bus_options() -> list[tuple[tuple[str, ...], dict[str, Any], Any]]:
    return [
        *bus_options(),  # python-can's, --host/--port, --node (drive_link.cli_connect)
        (
            ("--sdo-timeout",),
            {"type": quantity("s"), "help": "SDO response timeout per frame, s (default 0.3)"},
            0.3,
        ),
        (
            ("--timeout",),
            {"type": quantity("s"), "help": "state-change timeout, s (default 3) / scan listen "
             "time, s (default 1)"},
            None,
        ),
        (("--json",), {"action": "store_true", "help": "print one JSON document"}, False),
    ]


def _timeout(args: argparse.Namespace, default: float) -> float:
    """``--timeout`` if given, else ``default`` s (a state change under frame loss needs several
    SDO round trips; a scan only listens)."""
    t = getattr(args, "timeout", None)
    return default if t is None else float(t)


_TOP = "top_"  # dest prefix of the options given before the sub-command


def _add_bus_options(p: argparse.ArgumentParser, prefix: str = "", omit: tuple = ()) -> None:
    """The bus options on ``p`` with ``SUPPRESS`` defaults (an option not given leaves no
    attribute, so the sub-command level cannot overwrite what was given before it); ``omit``:
    attribute names left out (see :func:`_bus_option_before_only`)."""
    g = p.add_argument_group("bus (unset = python-can config / CAN_* environment)")
    for flags, kw, _default in _bus_options():
        if flags[0].lstrip("-").replace("-", "_") in omit:
            continue
        dest = prefix + flags[0].lstrip("-").replace("-", "_")
        if kw.get("action") != "store_true":
            kw = {**kw, "metavar": flags[0].lstrip("-").replace("-", "_").upper()}
        g.add_argument(*flags, dest=dest, default=argparse.SUPPRESS, **kw)
    add_hidden_aliases(g, prefix + "node")  # -n/--node-id


def _bus_parent(omit: tuple = ()) -> argparse.ArgumentParser:
    p = _Parser(add_help=False)
    _add_bus_options(p, omit=omit)
    return p


def _bus_option_before_only(p: argparse.ArgumentParser, name: str, own: str) -> None:
    """Refuse bus option ``name`` after a sub-command whose own option ``own`` starts with its
    spelling (``trace --channel i_p``, a typo of ``--channels``, must not pick a bus channel):
    there it is a usage error naming both; before the sub-command it is the bus option."""
    flags = next(f for f, _kw, _d in _bus_options() if f[0] == f"--{name}")

    class _BeforeOnly(argparse.Action):
        def __call__(self, parser: Any, namespace: Any, values: Any, option_string: Any = None):
            parser.error(
                f"{option_string} is a bus option: give it before the sub-command "
                f"(drive-link {flags[0]} VALUE {parser.prog.split()[-1]} ...); did you mean {own}?"
            )

    p.add_argument(
        *flags, action=_BeforeOnly, dest=argparse.SUPPRESS, default=argparse.SUPPRESS,
        help=argparse.SUPPRESS,
    )  # fmt: skip


def _merge_bus(args: argparse.Namespace) -> None:
    """Bus options from both sides of the sub-command: the one after it wins; a sub-command
    that defines an option itself with a plain default (e.g. ``design --json``) takes the value
    given before it when its own is still the default; unset options get their defaults."""
    for flags, _kw, default in _bus_options():
        dest = flags[0].lstrip("-").replace("-", "_")
        top = getattr(args, _TOP + dest, argparse.SUPPRESS)
        if hasattr(args, _TOP + dest):
            delattr(args, _TOP + dest)
        mine = getattr(args, dest, argparse.SUPPRESS)
        if top is not argparse.SUPPRESS and (mine is argparse.SUPPRESS or mine == default):
            setattr(args, dest, top)
        elif mine is argparse.SUPPRESS:
            setattr(args, dest, default)


def _env_int(name: str) -> int | None:
    v = os.environ.get(name)
    try:
        return int(v) if v else None
    except ValueError:
        return None


def _outputs(p: argparse.ArgumentParser) -> None:
    p.add_argument("--csv", type=Path, help="save CSV here (t in s, one column per signal)")
    p.add_argument("--png", type=Path, help="save a plot here (PNG, matplotlib)")


_EPILOG = """\
values take units (20uH, 50A, 1000rpm, '-5 A'); a bare number is in the object's unit
(drive-link objects PATTERN lists names, index:sub, type, unit, limits, access).

exit codes: 1 drive refused / failed check, 2 usage, 3 bus error, 4 node not found (scan:
none), 5 timeout, 6 SDO abort, 7 invalid value (wrong unit, not a number, out of limits, unknown
object), 8 unsafe gains refused (use --force), 130 interrupted, 141 output pipe closed.
"""


def build_parser() -> argparse.ArgumentParser:
    """The ``drive-link`` argument parser."""
    bus = _bus_parent()
    ap = _Parser(
        prog="drive-link",
        description="Talk to a drive (DSP or virtual) over CAN: state, setpoints, objects,\n"
        "gains, traces, step tests, identification, configuration files, conformance.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _add_bus_options(ap, _TOP)  # accepted before the sub-command too
    sub = ap.add_subparsers(dest="cmd", metavar="COMMAND", required=True)

    def add(
        name: str, fn: Callable, help: str, needs_drive: bool = True, omit_bus: tuple = ()
    ) -> argparse.ArgumentParser:
        parent = _bus_parent(omit_bus) if omit_bus else bus
        p = sub.add_parser(name, parents=[parent], help=help, description=help, epilog=_EPILOG,
                           formatter_class=argparse.RawDescriptionHelpFormatter,
                           allow_abbrev=False)  # fmt: skip
        p.set_defaults(func=fn, needs_drive=needs_drive)
        return p

    add(
        "scan",
        cmd_scan,
        "list the nodes on the bus (SDO probe of 0x1000 on 1..127 + heartbeats)",
        False,
    )
    add("status", cmd_status, "NMT / CiA 402 state, mode, measurements, gains")
    add("enable", _state_cmd("enable"), "CiA 402: go to OPERATION ENABLED")
    add("disable", _state_cmd("disable"), "CiA 402: disable operation (power stage off)")
    add("quick-stop", _state_cmd("quick_stop"), "CiA 402: quick stop")
    add("fault-reset", _state_cmd("fault_reset"), "CiA 402: reset a fault")
    p = add(
        "mode",
        cmd_mode,
        "select speed / current / torque mode (the drive changes mode only while disabled)",
    )
    p.add_argument("mode", choices=["speed", "current", "torque"])
    p.add_argument(
        "--re-enable",
        action="store_true",
        help="if the drive is enabled in another mode: disable, switch, enable again",
    )
    p = add(
        "set-speed",
        cmd_set_speed,
        "speed mode and target_velocity (whole rpm; 1000rpm, '100 rad/s'); needs the drive "
        "enabled (--enable) unless the value is 0",
    )
    p.add_argument(
        "rpm", type=_object_value("target_velocity"), help="speed setpoint, rpm (or with a unit)"
    )
    p.add_argument("--enable", action="store_true", help="also enable the drive")
    p.add_argument(
        "--switch-mode",
        action="store_true",
        help="if the drive is enabled in another mode: disable, switch to speed, enable again",
    )
    p = add(
        "set-current",
        cmd_set_current,
        "current mode and i_p_ref (A; 50A, 500mA); needs the drive enabled (--enable) unless "
        "the value is 0",
    )
    p.add_argument(
        "amps", type=_object_value("setpoints.i_p_ref"), help="pseudo-current setpoint, A"
    )
    p.add_argument("--enable", action="store_true", help="also enable the drive")
    p.add_argument(
        "--switch-mode",
        action="store_true",
        help="if the drive is enabled in another mode: disable, switch to current, enable again",
    )
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
    p = add("live", cmd_live, "listen to the TPDOs: rates, drops, bus load, latest values")
    p.add_argument(
        "--seconds", type=quantity("s"), default=1.0, help="how long to listen, s (default 1)"
    )
    p = add("trace", cmd_trace, "capture a trace with the drive's recorder", omit_bus=("channel",))
    p.add_argument("--channels", default="i_p,i_p_ref", help="comma-separated (measurements names)")
    _bus_option_before_only(p, "channel", "--channels")
    p.add_argument(
        "--divider", type=int, default=1, help="loop samples (20 µs each) per trace sample"
    )
    p.add_argument("--length", type=int, default=None, help="samples per channel (default: all)")
    p.add_argument(
        "--pre-trigger", type=int, default=0, help="samples kept before the trigger (default 0)"
    )
    p.add_argument(
        "--trigger",
        default="immediate",
        choices=["immediate", "signal", "setpoint_step", "fault"],
        help="what starts the recording (default immediate)",
    )
    p.add_argument("--source", default="measurements.i_p", help="signal trigger source")
    p.add_argument(
        "--level",
        default=0.0,
        help="signal trigger level in the source's unit (A for i_p, rpm for speed), or with "
        "a unit (5A)",
    )
    p.add_argument(
        "--edge",
        default="rising",
        choices=["rising", "falling", "either"],
        help="signal trigger: crossing of --level (default rising)",
    )
    p.add_argument(
        "--wait", type=quantity("s"), default=None, help="seconds to wait for the trigger"
    )
    p.add_argument("--progress", action="store_true", help="progress bar even when not a terminal")
    _outputs(p)
    p = add(
        "step",
        cmd_step,
        "step test with metrics and model overlay; the drive's state, mode and setpoint are "
        "restored afterwards (also on error and Ctrl-C)",
    )
    p.add_argument("kind", choices=["current", "speed"])
    amps, rpm = _object_value("setpoints.i_p_ref"), quantity("rpm")
    p.add_argument("--from", dest="i_from", type=amps, default=15.0, help="current step start, A")
    p.add_argument("--to", dest="i_to", type=amps, default=20.0, help="current step end, A")
    p.add_argument("--delta", type=rpm, default=500.0, help="speed step, rpm")
    p.add_argument("--start", type=rpm, default=None, help="speed before the step, rpm")
    p.add_argument(
        "--divider",
        type=int,
        default=None,
        help="loop samples (20 µs each) per trace sample (default 1 current, 100 speed)",
    )
    p.add_argument(
        "--length",
        type=int,
        default=None,
        help="trace samples recorded (default 400 current, 1500 speed)",
    )
    p.add_argument(
        "--pre-trigger",
        type=int,
        default=None,
        help="trace samples before the step (default 50 current, 100 speed)",
    )
    p.add_argument("--no-enable", action="store_true", help="fail instead of enabling the drive")
    _settle_options(p)
    p.add_argument(
        "--model-a",
        type=float,
        default=None,
        help="speed model G(z) = b/(z - a): pole a per 20 µs sample (unitless; default the "
        "paper's 0.9999785)",
    )
    p.add_argument(
        "--model-b",
        type=float,
        default=None,
        help="speed model gain b, rpm/A per 20 µs sample (default the paper's 3.33715e-4)",
    )
    _outputs(p)
    p = add(
        "identify-drive",
        cmd_identify,
        "run a current step on the drive, identify G(z) = b/(z - a), suggest IP gains; the "
        "drive's state, mode and setpoint are restored afterwards",
    )
    p.add_argument(
        "--from", dest="i_from", type=amps, default=0.0, help="current before the step, A"
    )
    p.add_argument("--to", dest="i_to", type=amps, default=10.0, help="current step end, A")
    p.add_argument(
        "--divider",
        type=int,
        default=50,
        help="loop samples (20 µs each) per trace sample (default 50 = 1 ms)",
    )
    p.add_argument(
        "--length", type=int, default=2000, help="trace samples recorded (default 2000)"
    )
    p.add_argument(
        "--pre-trigger", type=int, default=100, help="trace samples before the step (default 100)"
    )
    p.add_argument(
        "--settle",
        type=quantity("s"),
        default=0.1,
        help="wait at the start current before recording, s (default 0.1)",
    )
    _settle_options(p)
    p.add_argument(
        "--xi", type=float, default=1.0, help="damping ratio ξ of the IP design (unitless)"
    )
    p.add_argument(
        "--omega-n",
        type=quantity("rad/s"),
        default=2.3,
        help="natural frequency ω_n of the IP design, rad/s (default 2.3)",
    )
    _outputs(p)
    p = add(
        "check",
        cmd_check,
        "conformance run (CiA 301/402 + OD) with pass/fail per item; item store_restore "
        "rewrites the stored parameters (--skip store_restore on a tuned drive)",
    )
    p.add_argument("--only", default=None, help="comma-separated items")
    p.add_argument("--skip", default=None, help="comma-separated items (e.g. store_restore)")
    p.add_argument(
        "--rate-tolerance",
        type=float,
        default=0.25,
        help="allowed relative rate error (unitless, 0.25 = 25 %%)",
    )
    _config_parsers(add)
    from ._cli_tools import register_tools

    register_tools(sub, bus)
    from ._cli_lss import register_lss

    register_lss(sub, bus)
    from .monitor import add_parser as add_monitor_parser

    add_monitor_parser(sub, bus)
    from .report.cli import add_parser as add_report_parser

    add_report_parser(sub, bus)
    from ._cli_design import add_parsers as add_design_parsers

    add_design_parsers(sub)
    return ap


def _settle_options(p: argparse.ArgumentParser) -> None:
    """--settle-window/--settle-timeout/--settle-tol and --brake (step, identify-drive)."""
    p.add_argument(
        "--settle-window",
        type=quantity("s"),
        default=None,
        help="the start counts as settled when it stays within --settle-tol for this long, s "
        "(default 0.3 s speed step, 0.05 s current step, 0.5 s identify-drive)",
    )
    p.add_argument(
        "--settle-timeout",
        type=quantity("s"),
        default=None,
        help="give up (exit 5, no metrics) when the start has not settled by then, s "
        "(default 15 s; 5 s current step)",
    )
    p.add_argument(
        "--settle-tol",
        type=float,
        default=None,
        help="settled band in the signal's unit: rpm (speed step: of the start; "
        "identify-drive: spread of the speed) or A (current step) (default max(2 rpm, 1 %% of "
        "the step); max(0.5 A, 5 %% of the step); 2 rpm)",
    )
    p.add_argument(
        "--brake",
        action="store_true",
        help="switch modes on the drive's own disable ramp (brakes at the current limit) "
        "instead of coasting",
    )


def _apply_step_defaults(args: argparse.Namespace) -> None:
    if getattr(args, "cmd", None) != "step":
        return
    cur = args.kind == "current"
    if args.divider is None:
        args.divider = 1 if cur else 100
    if args.length is None:
        args.length = 400 if cur else 1500
    if args.pre_trigger is None:
        args.pre_trigger = 50 if cur else 100


#: SDO abort "not in the present device state" (CiA 301): the drive refuses the write now.
_ABORT_STATE = abort_codes.DEVICE_STATE


#: The trace recorder's objects: refused while a recording is armed.
_TRACE_OBJECTS = ("trace_config", "trace_channels", "trace_data")


def _state_hint(exc: SdoAbort) -> str:
    """The fix for an object the drive refused in its present state (abort 0x08000022)."""
    from ._objects import default_table

    table = default_table()
    obj = table.by_index(exc.index, exc.subindex)
    if obj is not None and obj.name == "modes_of_operation":
        return "the mode changes only with the power stage off: run `drive-link disable` first"
    if obj is not None and obj.entry.config_only:
        return "this object is written only with the power stage off: `drive-link disable` first"
    if exc.index in PDO_PARAMETERS:
        return "PDO settings change only in PRE-OPERATIONAL: `drive-link nmt pre-operational` first"
    if obj is not None and obj.entry.object_name in _TRACE_OBJECTS:
        return "a trace recording is armed: wait for it (or `drive-link trace`) before changing it"
    return "the drive does not accept it in its present state (see `drive-link status`)"


def _fail(args: argparse.Namespace | None, message: str, code: int, prefix: str = "error: ") -> int:
    """Report one failure: one line on stderr, or JSON on stdout with ``--json``."""
    if _JSON_ERRORS or (args is not None and getattr(args, "json", False)):
        print(json.dumps({"error": message, "exit_code": code}))
    else:
        print(f"drive-link: {prefix}{message}", file=sys.stderr)
    return code


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit code (see module docstring)."""
    global _JSON_ERRORS
    argv = list(sys.argv[1:] if argv is None else argv)
    _JSON_ERRORS = "--json" in argv
    try:
        return run_quietly(lambda: _main(argv))  # `drive-link objects | head -1`: quiet end
    finally:
        _JSON_ERRORS = False


def _main(argv: list[str]) -> int:
    ap = build_parser()
    try:
        args = ap.parse_args(argv)
    except SystemExit as exc:  # usage error (printed) or --help: the exit code, no raise
        return exc.code if isinstance(exc.code, int) else 2
    _merge_bus(args)
    # Library log lines (canopen, python-can) would break the one-line-error rule.
    logging.getLogger().addHandler(logging.NullHandler())
    for name in ("canopen", "can"):
        logging.getLogger(name).setLevel(logging.CRITICAL)
    _apply_step_defaults(args)
    d: Drive | None = None
    try:
        if getattr(args, "needs_drive", False):
            d = connect_from_args(args)
            return args.func(args, d)
        return args.func(args)
    except Refused as exc:
        return _fail(args, str(exc), EXIT_UNSAFE, prefix="")
    except DriveError as exc:
        msg = str(exc)
        if isinstance(exc, SdoAbort) and exc.code == _ABORT_STATE:
            msg += f": {_state_hint(exc)}"
        for cls, code in EXIT_CODES:
            if isinstance(exc, cls):
                return _fail(args, msg, code)
        return _fail(args, msg, 1)
    except KeyboardInterrupt:
        return _fail(args, "interrupted", 130, prefix="")
    except BrokenPipeError:  # the reader of our output is gone: main() ends quietly
        raise
    except (ValueError, OSError) as exc:
        return _fail(args, str(exc), 1)
    finally:
        if d is not None:
            try:
                d.close()
            except Exception:
                pass


if __name__ == "__main__":
    sys.exit(main())
