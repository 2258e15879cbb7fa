"""The ``drive-link`` command: talk to a drive (DSP or virtual) from a shell.

Every command takes the bus options (--interface/--channel/--bitrate, or --host/--port for the
loopback hub; unset = python-can config/env), --node and --json. Every failure is one line on
stderr and a non-zero exit code:

1 drive refused / failed check, 2 usage, 3 bus error, 4 node not found, 5 timeout,
6 SDO abort, 7 invalid value, 8 unsafe gains refused (use --force), 130 interrupted.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn

from . import connection
from .cli_connect import connect_from_args
from .drive import GAIN_FIELDS, Drive
from .errors import (
    BusError,
    DriveError,
    DriveTimeout,
    InvalidValue,
    NodeNotFound,
    SdoAbort,
)

EXIT_CODES: list[tuple[type[BaseException], int]] = [
    (BusError, 3),
    (NodeNotFound, 4),
    (DriveTimeout, 5),
    (SdoAbort, 6),
    (InvalidValue, 7),
    (DriveError, 1),
]
EXIT_UNSAFE = 8


class Refused(DriveError):  # noqa: N818
    """A command refused to act (e.g. unsafe gains without --force)."""


class Failed(DriveError):  # noqa: N818
    """A command ran but its result is a failure (e.g. a failed check)."""


# --------------------------------------------------------------------------- output helpers
def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_jsonable(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if hasattr(x, "item") and callable(x.item):
        return _jsonable(x.item())
    if isinstance(x, bytes):
        return x.hex()
    return x


def _emit(args: argparse.Namespace, data: Any, text: str | Callable[[], str]) -> None:
    if args.json:
        print(json.dumps(_jsonable(data)))
    else:
        print(text() if callable(text) else text)


def _progress_bar(args: argparse.Namespace) -> Callable[[int, int | None], None] | None:
    if args.json or (not sys.stderr.isatty() and not getattr(args, "progress", False)):
        return None

    def bar(done: int, total: int | None) -> None:
        if total:
            frac = done / total
            n = int(30 * frac)
            sys.stderr.write(
                f"\rupload [{'#' * n}{'.' * (30 - n)}] {100 * frac:5.1f} % {done / 1024:7.1f} KiB"
            )
        else:
            sys.stderr.write(f"\rupload {done / 1024:7.1f} KiB")
        if total and done >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return bar


def _parse_value(text: str) -> float | int | str:
    try:
        return int(text, 0)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


# --------------------------------------------------------------------------- commands
def cmd_scan(args: argparse.Namespace) -> int:
    from .scan import scan

    conn = connection.acquire(
        interface=args.interface,
        channel=args.channel,
        bitrate=args.bitrate,
        host=args.host,
        port=args.port,
    )
    try:
        nodes = scan(conn.bus, timeout=_timeout(args, 1.0))
    finally:
        connection.release(conn)
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
        if not nodes:
            return "no nodes found"
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
            from .emcy import describe

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


def cmd_mode(args: argparse.Namespace, d: Drive) -> int:
    d.set_mode(args.mode)
    _emit(args, {"mode": d.mode}, f"mode {d.mode}")
    return 0


def _set_setpoint(
    args: argparse.Namespace,
    d: Drive,
    mode: str,
    write: Callable[[float], None],
    value: float,
    name: str,
    key: str,
    shown: str,
) -> int:
    """Select ``mode``, ``write(value)``, enable if ``--enable``, print the read-back ``name``
    as ``key`` (``shown`` formats it, e.g. ``"{:g} A"``) with the drive state."""
    d.set_mode(mode)
    write(value)
    if args.enable:
        d.enable(timeout=_timeout(args, 3.0))
    out = {key: d.read(name), "state": d.state}
    _emit(args, out, f"{key} {shown.format(out[key])} ({out['state']})")
    return 0


def cmd_set_speed(args: argparse.Namespace, d: Drive) -> int:
    return _set_setpoint(
        args, d, "speed", d.set_speed, args.rpm, "target_velocity", "target_velocity", "{} rpm"
    )


def cmd_set_current(args: argparse.Namespace, d: Drive) -> int:
    return _set_setpoint(
        args, d, "current", d.set_current, args.amps, "setpoints.i_p_ref", "i_p_ref", "{:g} A"
    )


def cmd_read(args: argparse.Namespace, d: Drive) -> int:
    out = {}
    for n in args.names:
        out[n] = d.read(n)
    units = {n: d.table[n].unit for n in args.names}
    _emit(
        args,
        out,
        lambda: "\n".join(
            f"{n} = {v} {units[n] if units[n] != '1' else ''}".rstrip() for n, v in out.items()
        ),
    )
    return 0


def cmd_write(args: argparse.Namespace, d: Drive) -> int:
    obj = d.table[args.name]
    value = args.value if obj.data_type == 0x09 else _parse_value(args.value)
    d.write(args.name, value)
    back = d.read(args.name) if obj.readable else value
    _emit(
        args,
        {args.name: back},
        f"{args.name} = {back} {obj.unit if obj.unit != '1' else ''}".rstrip(),
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
        val = _parse_value(v)
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

    trig = Trigger(args.trigger, args.source, args.level, args.edge)
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


def cmd_step(args: argparse.Namespace, d: Drive) -> int:
    from . import steps

    if args.kind == "current":
        res = steps.current_step(
            d,
            args.i_from,
            args.i_to,
            divider=args.divider,
            length=args.length,
            pre_trigger=args.pre_trigger,
            enable=not args.no_enable,
        )
    else:
        model = (args.model_a, args.model_b) if args.model_a is not None else None
        res = steps.speed_step(
            d,
            args.delta,
            start_rpm=args.start,
            divider=args.divider,
            length=args.length,
            pre_trigger=args.pre_trigger,
            enable=not args.no_enable,
            model=model,
        )
    out = res.summary()
    _save_outputs(args, res, out)
    m = res.metrics
    unit = out["unit"]

    def text() -> str:
        lines = [
            f"{res.kind} step {res.y_from:g} → {res.y_to:g} {unit}",
            f"  rise time         {m.rise_time * 1e3:.4g} ms",
            f"  overshoot         {m.overshoot_pct:.3g} %",
            f"  settling time     {m.settling_time * 1e3:.4g} ms",
            f"  steady-state err  {m.steady_state_error:.4g} {unit}",
        ]
        lines += [f"saved {out[k]}" for k in ("csv", "png") if k in out]
        return "\n".join(lines)

    _emit(args, out, text)
    return 0


def cmd_identify(args: argparse.Namespace, d: Drive) -> int:
    import time

    from . import design, identify
    from .steps import record_setpoint_step
    from .trace import TS

    d.set_mode("current")
    d.set_current(args.i_from)
    if d.state != "OPERATION ENABLED":
        d.enable(timeout=_timeout(args, 3.0))
    time.sleep(args.settle)
    try:
        tr = record_setpoint_step(
            d,
            ["i_p", "speed"],
            lambda: d.set_current(args.i_from),
            lambda: d.set_current(args.i_to),
            args.divider,
            args.length,
            args.pre_trigger,
            None,
        )
    finally:
        d.set_current(args.i_from)
    fit = identify.fit_first_order(
        tr.signals["measurements.i_p"], tr.signals["measurements.speed"], args.divider * TS
    )
    k_p, k_i = design.ip_gains(fit.a, fit.b, xi=args.xi, omega_n=args.omega_n)
    out = {
        "fit": fit.as_dict(),
        "ip_gains": {"speed_k_p": k_p, "speed_k_i": k_i, "xi": args.xi, "omega_n": args.omega_n},
    }
    _save_outputs(args, tr, out)
    _emit(
        args,
        out,
        lambda: (
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

    def show(r: Any) -> None:
        if not args.json:
            print(f"{'PASS' if r.ok else 'FAIL'}  {r.name:<20} {r.detail}", flush=True)

    try:
        results = run_checks(
            d, only=only, skip=skip, on_result=show, rate_tolerance=args.rate_tolerance
        )
    except ValueError as exc:
        raise InvalidValue(str(exc)) from None
    failed = [r.name for r in results if not r.ok]
    if args.json:
        print(
            json.dumps(
                [
                    {"name": r.name, "ok": r.ok, "detail": r.detail, "seconds": r.seconds}
                    for r in results
                ]
            )
        )
    else:
        print(
            f"{len(results) - len(failed)}/{len(results)} passed"
            + (f"; failed: {', '.join(failed)}" if failed else "")
        )
    return 1 if failed else 0


# --------------------------------------------------------------------------- parser
class _Parser(argparse.ArgumentParser):
    """argparse with a one-line usage error (exit 2) instead of usage + error lines."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


#: Options every command takes, before or after the sub-command: (flags, add_argument keywords
#: without ``default``, default). The default is filled in after parsing (see :func:`_merge_bus`).
def _bus_options() -> list[tuple[tuple[str, ...], dict[str, Any], Any]]:
    return [
        (("--interface",), {"help": "python-can interface (socketcan, virtual, ...)"}, None),
        (("--channel",), {"help": "python-can channel (can0, vcan0, ...)"}, None),
        (("--bitrate",), {"type": int, "help": "bit/s"}, None),
        (
            ("--host",),
            {"help": "loopback hub host (socketcand)"},
            os.environ.get("DRIVE_LINK_HOST"),
        ),
        (("--port",), {"type": int, "help": "loopback hub port"}, _env_int("DRIVE_LINK_PORT")),
        (
            ("--node",),
            {"type": int, "help": "node-ID (default 1)"},
            _env_int("DRIVE_LINK_NODE") or 1,
        ),
        (("--sdo-timeout",), {"type": float, "help": "SDO response timeout per frame, s"}, 0.3),
        (
            ("--timeout",),
            {"type": float, "help": "state-change timeout, s (default 3) / scan listen time, s "
             "(default 1)"},
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


def _add_bus_options(p: argparse.ArgumentParser, prefix: str = "") -> None:
    """The bus options on ``p`` with ``SUPPRESS`` defaults (an option not given leaves no
    attribute, so the sub-command level cannot overwrite what was given before it)."""
    g = p.add_argument_group("bus (unset = python-can config / CAN_* environment)")
    for flags, kw, _default in _bus_options():
        dest = prefix + flags[0].lstrip("-").replace("-", "_")
        g.add_argument(*flags, dest=dest, default=argparse.SUPPRESS, **kw)


def _bus_parent() -> argparse.ArgumentParser:
    p = _Parser(add_help=False)
    _add_bus_options(p)
    return p


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
    p.add_argument("--csv", type=Path, help="save CSV here")
    p.add_argument("--png", type=Path, help="save a plot here")


def build_parser() -> argparse.ArgumentParser:
    """The ``drive-link`` argument parser."""
    bus = _bus_parent()
    ap = _Parser(
        prog="drive-link",
        description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _add_bus_options(ap, _TOP)  # accepted before the sub-command too
    sub = ap.add_subparsers(dest="cmd", metavar="COMMAND", required=True)

    def add(
        name: str, fn: Callable, help: str, needs_drive: bool = True
    ) -> argparse.ArgumentParser:
        p = sub.add_parser(name, parents=[bus], help=help, description=help)
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
    add("disable", _state_cmd("disable"), "CiA 402: disable operation")
    add("quick-stop", _state_cmd("quick_stop"), "CiA 402: quick stop")
    add("fault-reset", _state_cmd("fault_reset"), "CiA 402: reset a fault")
    p = add("mode", cmd_mode, "select speed / current / torque mode")
    p.add_argument("mode", choices=["speed", "current", "torque"])
    p = add("set-speed", cmd_set_speed, "speed mode and target_velocity (rpm)")
    p.add_argument("rpm", type=float)
    p.add_argument("--enable", action="store_true", help="also enable the drive")
    p = add("set-current", cmd_set_current, "current mode and i_p_ref (A)")
    p.add_argument("amps", type=float)
    p.add_argument("--enable", action="store_true", help="also enable the drive")
    p = add("read", cmd_read, "read objects by name (e.g. current_controller.L_c)")
    p.add_argument("names", nargs="+")
    p = add("write", cmd_write, "write one object by name")
    p.add_argument("name")
    p.add_argument("value")
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
    p.add_argument("--seconds", type=float, default=1.0)
    p = add("trace", cmd_trace, "capture a trace with the drive's recorder")
    p.add_argument("--channels", default="i_p,i_p_ref", help="comma-separated (measurements names)")
    p.add_argument("--divider", type=int, default=1, help="loop samples (20 µs) per trace sample")
    p.add_argument("--length", type=int, default=None, help="samples per channel (default: all)")
    p.add_argument("--pre-trigger", type=int, default=0)
    p.add_argument(
        "--trigger", default="immediate", choices=["immediate", "signal", "setpoint_step", "fault"]
    )
    p.add_argument("--source", default="measurements.i_p", help="signal trigger source")
    p.add_argument("--level", type=float, default=0.0)
    p.add_argument("--edge", default="rising", choices=["rising", "falling", "either"])
    p.add_argument("--wait", type=float, default=None, help="seconds to wait for the trigger")
    p.add_argument("--progress", action="store_true", help="progress bar even when not a terminal")
    _outputs(p)
    p = add("step", cmd_step, "step test with metrics and model overlay")
    p.add_argument("kind", choices=["current", "speed"])
    p.add_argument("--from", dest="i_from", type=float, default=15.0, help="current step start, A")
    p.add_argument("--to", dest="i_to", type=float, default=20.0, help="current step end, A")
    p.add_argument("--delta", type=float, default=500.0, help="speed step, rpm")
    p.add_argument("--start", type=float, default=None, help="speed before the step, rpm")
    p.add_argument("--divider", type=int, default=None)
    p.add_argument("--length", type=int, default=None)
    p.add_argument("--pre-trigger", type=int, default=None)
    p.add_argument("--no-enable", action="store_true", help="fail instead of enabling the drive")
    p.add_argument("--model-a", type=float, default=None)
    p.add_argument("--model-b", type=float, default=None)
    _outputs(p)
    p = add(
        "identify-drive",
        cmd_identify,
        "run a current step on the drive, identify G(z) = b/(z - a), suggest IP gains",
    )
    p.add_argument("--from", dest="i_from", type=float, default=0.0)
    p.add_argument("--to", dest="i_to", type=float, default=10.0)
    p.add_argument("--divider", type=int, default=50)
    p.add_argument("--length", type=int, default=2000)
    p.add_argument("--pre-trigger", type=int, default=100)
    p.add_argument("--settle", type=float, default=0.1)
    p.add_argument("--xi", type=float, default=1.0)
    p.add_argument("--omega-n", type=float, default=2.3)
    _outputs(p)
    p = add(
        "check",
        cmd_check,
        "conformance run (CiA 301/402 + OD) with pass/fail per item; item store_restore "
        "rewrites the stored parameters (--skip store_restore on a tuned drive)",
    )
    p.add_argument("--only", default=None, help="comma-separated items")
    p.add_argument("--skip", default=None, help="comma-separated items (e.g. store_restore)")
    p.add_argument("--rate-tolerance", type=float, default=0.25, help="allowed relative rate error")
    try:
        from . import cli_design
    except ImportError:
        cli_design = None
    if cli_design is not None:
        cli_design.add_parsers(sub)
    return ap


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


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit code (see module docstring)."""
    ap = build_parser()
    args = ap.parse_args(argv)
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
        print(f"drive-link: {exc}", file=sys.stderr)
        return EXIT_UNSAFE
    except DriveError as exc:
        print(f"drive-link: error: {exc}", file=sys.stderr)
        for cls, code in EXIT_CODES:
            if isinstance(exc, cls):
                return code
        return 1
    except KeyboardInterrupt:
        print("drive-link: interrupted", file=sys.stderr)
        return 130
    except (ValueError, OSError) as exc:
        print(f"drive-link: error: {exc}", file=sys.stderr)
        return 1
    finally:
        if d is not None:
            try:
                d.close()
            except Exception:
                pass


if __name__ == "__main__":
    sys.exit(main())
