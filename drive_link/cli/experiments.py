"""``drive-link`` commands that record from a running drive: ``live``, ``trace``, ``step``,
``identify-drive`` (each leaves the drive as found: :mod:`drive_link.workflows.steps`)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from ..link import units
from ..link.drive import Drive
from ._common import (
    AddCommand,
    _bus_option_before_only,
    _emit,
    _object_value,
    _outputs,
    _progress_bar,
    _save_outputs,
    _usable_state,
    quantity,
)

__all__ = ["add_parsers", "apply_step_defaults"]


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


def cmd_trace(args: argparse.Namespace, d: Drive) -> int:
    from ..link.trace import Trigger

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
    from ..workflows.steps import Settle

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
    from ..workflows import steps

    if args.kind == "current":
        for v in (args.i_from, args.i_to):
            d.table["setpoints.i_p_ref"].check(v)
    elif args.start is not None:
        for v in (args.start, args.start + args.delta):
            d.table["target_velocity"].check(units.parse_value(v, "rpm", integer=True))
    settle = _settle_args(args)
    _usable_state(d)
    res = _run_step(args, d, steps, settle)  # leaves the drive as found (workflows.steps)
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
    """The step test itself (drive_link.workflows.steps: settled start, drive left as found)."""
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
    from ..workflows import design
    from ..workflows.steps import Hooks, identify_speed_model

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


def add_parsers(add: AddCommand) -> None:
    """The recording commands: live, trace, step, identify-drive."""
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


def apply_step_defaults(args: argparse.Namespace) -> None:
    if getattr(args, "cmd", None) != "step":
        return
    cur = args.kind == "current"
    if args.divider is None:
        args.divider = 1 if cur else 100
    if args.length is None:
        args.length = 400 if cur else 1500
    if args.pre_trigger is None:
        args.pre_trigger = 50 if cur else 100
