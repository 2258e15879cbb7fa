"""``drive-link design`` and ``drive-link identify`` sub-commands (offline maths, no bus).

``add_parsers(subparsers)`` registers both on the ``drive-link`` parser; every sub-parser sets
``func`` to a handler ``(argparse.Namespace) -> int`` (exit status). Bad input gives one line on
stderr and exit status 2, with nothing else printed. ``run_cli(argv)`` runs them standalone.

Examples::

    drive-link design --Lc 22.2e-6 --json              # deadbeat loop with L_c = 1.5 L
    drive-link design --controller pi --kp 0.4647 --ki 0.0492
    drive-link design --controller pi --crossover-hz 2750 --pm 45.6   # PI gains for a spec
    drive-link design --a 0.9999785 --b 3.33715e-4 --xi 1 --wn 2.3 --json   # IP speed gains
    drive-link identify --csv trace.csv --json
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import re
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from drive_link._jsonable import jsonable as _clean
from drive_link.workflows import design
from drive_link.workflows.design import analyse_current_loop
from drive_link.workflows.identify import fit_first_order
from drive_link.workflows.metrics import step_metrics


class UsageError(ValueError):
    """Bad command-line input, reported as one line; ``code`` is its exit status from the
    README's table: 7 for a value the command refuses (not a number, out of range, a design
    that cannot be met, an unreadable file), 2 (:class:`_FormError`) for the command line's form."""

    code = 7


class _FormError(UsageError):
    """A missing option or options that do not go together (exit status 2)."""

    code = 2


# --------------------------------------------------------------------------- helpers
def _num(name: str, text: str | None, *, positive: bool = False, nonneg: bool = False) -> float:
    if text is None:
        raise _FormError(f"{name} is required")
    try:
        v = float(text)
    except (TypeError, ValueError):
        raise UsageError(f"{name} must be a number (got {text!r})") from None
    if not math.isfinite(v):
        raise UsageError(f"{name} must be finite (got {text!r})")
    if positive and v <= 0.0:
        raise UsageError(f"{name} must be > 0 (got {text})")
    if nonneg and v < 0.0:
        raise UsageError(f"{name} must be >= 0 (got {text})")
    return v


def _int(name: str, text: str, *, minimum: int = 1) -> int:
    try:
        v = int(text)
    except (TypeError, ValueError):
        raise UsageError(f"{name} must be an integer (got {text!r})") from None
    if v < minimum:
        raise UsageError(f"{name} must be >= {minimum} (got {v})")
    return v


def _fmt(x: float | None, spec: str = ".4g", unit: str = "") -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "n/a"
    if isinstance(x, float) and math.isinf(x):
        return "inf"
    sep = "" if unit in ("", "%", "°") else " "
    return f"{x:{spec}}{sep}{unit}"


# --------------------------------------------------------------------------- design
def _drive_limits_problem(k_p: float, k_i: float) -> str | None:
    """None if the drive's EDS limits of 0x2020 k_p/k_i admit the gains, else one line."""
    from drive_link.link._objects import default_table

    table = default_table()
    for name, v in (("speed_controller.k_p", k_p), ("speed_controller.k_i", k_i)):
        info = table[name]
        lo, hi = info.low, info.high
        if (lo is not None and v < lo) or (hi is not None and v > hi):
            return f"{name} = {v:.6g} is outside the drive's limits [{lo}, {hi}]"
    return None


def _design_ip(args: argparse.Namespace) -> dict[str, Any]:
    a = _num("--a", args.a)
    b = _num("--b", args.b)
    if not 0.0 < a < 1.0:
        raise UsageError(f"--a must be in (0, 1) (got {args.a})")
    if b <= 0.0:
        raise UsageError(f"--b must be > 0 (got {args.b})")
    xi = _num("--xi", args.xi, positive=True)
    wn = _num("--wn", args.wn, positive=True)
    fs = _num("--fs", args.fs, positive=True)
    try:
        ipd = design.ip_design(a, b, xi, wn, fs)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    k_p, k_i = ipd.k_p, ipd.k_i
    limits = _drive_limits_problem(k_p, k_i)
    out: dict[str, Any] = {
        "a": a,
        "b": b,
        "xi": xi,
        "wn": wn,
        "fs": fs,
        "kp": k_p,
        "ki": k_i,
        # stability from the closed-loop poles of eq. (27) with the gains as the drive holds them
        "stable": ipd.stable,
        "poles": [[float(p.real), float(p.imag)] for p in ipd.poles],
        "requested_poles": [[float(p.real), float(p.imag)] for p in ipd.requested],
        "poles_match": ipd.poles_match,
        "pole_error_rad_s": ipd.max_pole_error,
        "within_drive_limits": limits is None,
    }
    if not ipd.poles_match:
        raise UsageError(
            f"the closed loop with k_p = {k_p:.6g}, k_i = {k_i:.6g} (REAL32) does not have the "
            f"requested poles (off by {ipd.max_pole_error:.3g} rad/s): refusing this design"
        )
    if not ipd.stable:
        raise UsageError(
            f"the closed loop with k_p = {k_p:.6g}, k_i = {k_i:.6g} (REAL32) is not stable "
            f"(largest |pole| {max(abs(p) for p in ipd.poles):.9f})"
        )
    if limits is not None:
        out["limits_problem"] = limits
    # predicted speed step 0 -> 1000 rpm over 8 / (xi wn) s (ideal inner loop), sampled every 1 ms
    if out["stable"]:
        T = min(max(8.0 / (xi * wn), 0.01), 20.0)
        dec = max(1, round(fs * 1e-3))
        r = design.predicted_speed_step(
            a,
            b,
            k_p,
            k_i,
            n_samples=round(T * fs),
            w_start=0.0,
            w_final=1000.0,
            fs=fs,
            decimate=dec,
        )
        sm = step_metrics(r.t, r.speed, reference=1000.0, y_initial=0.0, y_final=1000.0)
        out["overshoot_pct"] = sm.overshoot_pct
        out["settling_time_s"] = sm.settling_time
        out["rise_time_s"] = sm.rise_time
    return out


def _cmd_design(args: argparse.Namespace) -> int:
    try:
        if args.a is not None or args.b is not None:
            result = _design_ip(args)
            if args.json:
                print(json.dumps(_clean(result), indent=2))
            else:
                print(
                    f"IP speed gains for b/(z - a), a = {result['a']:.8g}, b = {result['b']:.6g}, "
                    f"xi = {result['xi']:g}, wn = {result['wn']:g} rad/s:"
                )
                print(f"  k_p = {result['kp']:.6g} A/rpm   k_i = {result['ki']:.6g} 1/sample")
                poles = ", ".join(f"{complex(*p):.9f}" for p in result["poles"])
                print(f"  closed-loop poles (eq. 27, REAL32 gains): {poles}")
                print(
                    f"  closed loop stable: {'yes' if result['stable'] else 'NO'}, poles as "
                    f"requested: {'yes' if result['poles_match'] else 'NO'}"
                )
                if "limits_problem" in result:
                    print(f"  warning: {result['limits_problem']}")
                if "settling_time_s" in result:
                    print(
                        f"  predicted step: overshoot {_fmt(result['overshoot_pct'], '.2f', '%')}"
                        f", settling (2 %) {_fmt(result['settling_time_s'], '.3g', 's')}"
                    )
            return 0
        fs = _num("--fs", args.fs, positive=True)
        R = _num("--R", args.R, nonneg=True)
        L = _num("--L", args.L, positive=True)
        L_c = L if args.Lc is None else _num("--Lc", args.Lc, positive=True)
        R_c = R if args.Rc is None else _num("--Rc", args.Rc, nonneg=True)
        i0 = _num("--step-from", args.step_from)
        i1 = _num("--step-to", args.step_to)
        if i0 == i1:
            raise UsageError("--step-from and --step-to must differ")
        n = None if args.samples == "auto" else _int("--samples", args.samples, minimum=10)
        k_p = _num("--kp", args.kp)
        k_i = _num("--ki", args.ki)
        if args.crossover_hz is not None or args.pm is not None:
            if args.controller != "pi":
                raise _FormError("--crossover-hz/--pm design PI gains: use --controller pi")
            fc = _num("--crossover-hz", args.crossover_hz, positive=True)
            pm = _num("--pm", args.pm, positive=True)
            try:
                k_p, k_i = design.pi_current_gains(fc, pm, R=R, L=L, fs=fs)
            except ValueError as exc:
                raise UsageError(str(exc)) from None
        try:
            result = analyse_current_loop(
                args.controller,
                R=R,
                L=L,
                L_c=L_c,
                R_c=R_c,
                k_p=k_p,
                k_i=k_i,
                fs=fs,
                i_start=i0,
                i_final=i1,
                n_samples=n,
            )
        except ValueError as exc:
            raise UsageError(str(exc)) from None
    except UsageError as exc:
        print(f"drive-link design: error: {exc}", file=sys.stderr)
        return exc.code
    if args.json:
        print(json.dumps(_clean(result), indent=2))
        return 0
    r = result
    head = f"{r['controller']} current loop: R = {R:.4g} Ω, L = {L:.4g} H, fs = {fs:g} Hz"
    if r["controller"] in ("deadbeat", "predictive"):
        head += f", L_c = {L_c:.4g} H ({L_c / L:.3g} L)"
    if r["controller"] == "deadbeat":
        head += f", R_c = {R_c:.4g} Ω"
    if r["controller"] == "pi":
        head += f", k_p = {k_p:.6g}, k_i = {k_i:.6g}"
    print(head)
    jury = "stable" if r["jury_stable"] else "not stable"
    verdict = "stable" if r["stable"] else "UNSTABLE"
    if r["marginal"]:
        verdict = "MARGINAL (a pole on the unit circle, e.g. R_c = 0 cancels the integrator)"
    print(f"  closed loop: {verdict} (max |pole| = {r['max_pole_radius']:.6f}; Jury: {jury})")
    pms = (
        ", ".join(
            f"{c['phase_margin_deg']:.1f}° at {_fmt(c['hz'], '.0f', 'Hz')}" for c in r["crossovers"]
        )
        or "none"
    )
    print(
        f"  gain margin {_fmt(r['gain_margin_db'], '.2f', 'dB')} "
        f"at {_fmt(r['phase_crossover_hz'], '.0f', 'Hz')}; "
        f"phase margin {_fmt(r['phase_margin_deg'], '.1f', '°')} "
        f"at {_fmt(r['gain_crossover_hz'], '.0f', 'Hz')} (the smallest; every gain "
        f"crossover: {pms}); "
        f"‖S‖∞ = {_fmt(r['sensitivity_peak'], '.3f')}"
    )
    if r["stable"]:
        rise_us = None if r["rise_time_s"] is None else r["rise_time_s"] * 1e6
        settle_us = None if r["settling_time_s"] is None else r["settling_time_s"] * 1e6
        print(
            f"  predicted step {i0:g} → {i1:g} A: "
            f"overshoot {_fmt(r['overshoot_pct'], '.2f', '%')}, "
            f"rise (10–90 %) {_fmt(rise_us, '.3g', 'µs')}, settling (2 %) "
            f"{_fmt(settle_us, '.3g', 'µs')}, "
            f"steady-state error {_fmt(r['steady_state_error_A'], '.3g', 'A')}"
        )
    else:
        print("  no step prediction: the loop is not asymptotically stable")
    return 0


# --------------------------------------------------------------------------- identify
_UNIT = re.compile(r"\s*\[[^\]]*\]\s*$")


def _canonical(col: str) -> str:
    name = _UNIT.sub("", col).strip()
    return name.removeprefix("measurements.")


def read_trace_csv(
    path: str | Path, current_col: str = "i_p", speed_col: str = "speed"
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Read ``t`` [s], i_p [A] and speed [rpm] from a CSV file.

    Accepts a plain header ``t,i_p,speed`` or the trace-capture format (``t [s]``,
    ``measurements.i_p [A]`` ...): units in brackets and a ``measurements.`` prefix are ignored;
    lines starting with ``#`` are skipped. Raises UsageError with one line on any problem.
    """
    p = Path(path)
    try:
        text = p.read_text()
    except OSError as exc:
        raise UsageError(f"cannot read {path}: {exc.strerror or exc}") from None
    rows = [r for r in csv.reader(line for line in text.splitlines() if not line.startswith("#"))]
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    if len(rows) < 2:
        raise UsageError(f"{path}: no data rows")
    header = [_canonical(c) for c in rows[0]]
    want = {"t": ("t", "time"), "i": (_canonical(current_col),), "w": (_canonical(speed_col),)}
    idx: dict[str, int] = {}
    for key, names in want.items():
        for n in names:
            if n in header:
                idx[key] = header.index(n)
                break
        else:
            raise UsageError(f"{path}: no column {names[0]!r} (columns: {', '.join(header)})")
    data = np.empty((len(rows) - 1, 3))
    for r_i, row in enumerate(rows[1:], start=2):
        for j, key in enumerate(("t", "i", "w")):
            try:
                data[r_i - 2, j] = float(row[idx[key]])
            except (IndexError, ValueError):
                raise UsageError(f"{path}: line {r_i}: bad or missing {key!r} value") from None
    if not np.all(np.isfinite(data)):
        raise UsageError(f"{path}: non-finite values in the data")
    return data[:, 0], data[:, 1], data[:, 2]


def _cmd_identify(args: argparse.Namespace) -> int:
    try:
        fs = _num("--fs", args.fs, positive=True)
        Ts_model = 1.0 / fs
        t, i_p, w = read_trace_csv(args.csv, args.current_col, args.speed_col)
        if t.size < 5:
            raise UsageError(f"{args.csv}: need at least 5 samples (got {t.size})")
        dt = np.diff(t)
        if np.any(dt <= 0):
            raise UsageError(f"{args.csv}: t is not strictly increasing")
        Ts = float(np.median(dt))
        if np.max(np.abs(dt - Ts)) > 0.01 * Ts:
            raise UsageError(f"{args.csv}: t is not uniformly sampled")
        if args.divider is not None:
            D = _int("--divider", args.divider)
        else:
            D = max(1, round(Ts / Ts_model))
            if abs(D * Ts_model - Ts) > 1e-3 * Ts:
                raise UsageError(
                    f"{args.csv}: sample period {Ts:g} s is not a multiple of 1/fs = {Ts_model:g} s"
                )
        try:
            fit = fit_first_order(
                i_p, w, D * Ts_model, Ts_model=Ts_model, offset=not args.no_offset
            )
        except ValueError as exc:
            raise UsageError(f"{args.csv}: {exc}") from None
        result = fit.as_dict()
        if args.xi is not None or args.wn is not None:
            xi = _num("--xi", args.xi if args.xi is not None else "1", positive=True)
            wn = _num("--wn", args.wn if args.wn is not None else "2.3", positive=True)
            try:
                k_p, k_i = design.ip_gains(fit.a, fit.b, xi, wn, fs)
            except ValueError as exc:
                raise UsageError(str(exc)) from None
            result.update({"xi": xi, "wn": wn, "kp": k_p, "ki": k_i})
    except UsageError as exc:
        print(f"drive-link identify: error: {exc}", file=sys.stderr)
        return exc.code
    if args.json:
        print(json.dumps(_clean(result), indent=2))
        return 0
    print(
        f"speed model b/(z - a) at {fs:g} Hz from {fit.n_samples} samples "
        f"(every {fit.D} loop samples, {fit.Ts:g} s):"
    )
    print(f"  a = {fit.a:.9f}   b = {fit.b:.6g} rpm/A per sample   offset = {fit.offset:.4g} rpm")
    print(
        f"  time constant {_fmt(fit.time_constant, '.4g', 's')}, "
        f"DC gain {_fmt(fit.dc_gain, '.4g', 'rpm/A')}"
    )
    print(
        f"  fit: R² = {fit.r2:.5f}, RMS {fit.rms:.4g} rpm (free run), "
        f"one-step RMS {fit.one_step_rms:.4g} rpm"
    )
    if "kp" in result:
        print(
            f"  IP gains (xi = {result['xi']:g}, wn = {result['wn']:g} rad/s): "
            f"k_p = {result['kp']:.6g} A/rpm, k_i = {result['ki']:.6g} 1/sample"
        )
    return 0


# --------------------------------------------------------------------------- registration
# argparse takes "-1e-6" for an option (its negative-number pattern has no exponent); these
# sub-commands have no option that looks like a number, so any signed number is a value.
_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|nan)$", re.IGNORECASE)


def _one_line_errors(parser: argparse.ArgumentParser) -> None:
    """Make ``parser`` report usage errors as one line on stderr and exit with status 2."""
    prog = parser.prog

    def error(message: str) -> NoReturn:
        print(f"{prog}: error: {message}", file=sys.stderr)
        raise SystemExit(2)

    parser.error = error  # type: ignore[method-assign]
    parser._negative_number_matcher = _NEGATIVE_NUMBER


def add_parsers(subparsers: argparse._SubParsersAction) -> None:
    """Register the ``design`` and ``identify`` sub-commands; each sets ``func``."""
    d = subparsers.add_parser(
        "design",
        allow_abbrev=False,
        help="current-loop stability/margins/step prediction, PI or IP gain design",
        description=(
            "Analyse a current loop (deadbeat eq. 15, PI eq. 22, predictive eq. 23) for motor "
            "R, L and controller estimates L_c, R_c: closed-loop stability, gain/phase margins, "
            "‖S‖∞ and the predicted step. With --a/--b: IP speed gains (eqs. 28–31)."
        ),
    )
    d.add_argument("--R", default=str(design.R_TABLE2), help="motor resistance [Ω] (6.2e-3)")
    d.add_argument("--L", default=str(design.L_TABLE2), help="motor inductance [H] (14.8e-6)")
    d.add_argument("--Lc", default=None, help="controller's inductance estimate L_c [H] (= L)")
    d.add_argument("--Rc", default=None, help="controller's resistance estimate R_c [Ω] (= R)")
    d.add_argument("--fs", default="50000", help="sampling frequency [Hz] (50000)")
    d.add_argument("--controller", choices=design.CONTROLLERS, default="deadbeat")
    d.add_argument("--kp", default=str(design.PI_KP_PAPER), help="PI k_p [V/A] (0.4647)")
    d.add_argument("--ki", default=str(design.PI_KI_PAPER), help="PI k_i [V/A] (0.0492)")
    d.add_argument("--crossover-hz", default=None, help="design PI gains for this crossover [Hz]")
    d.add_argument("--pm", default=None, help="... and this phase margin [°]")
    d.add_argument("--step-from", default="15", help="predicted step start [A] (15)")
    d.add_argument("--step-to", default="20", help="predicted step end [A] (20)")
    d.add_argument("--samples", default="auto", help="predicted step length [samples] (auto)")
    d.add_argument("--a", default=None, help="speed model pole a (per loop sample)")
    d.add_argument("--b", default=None, help="speed model gain b [rpm/A per loop sample]")
    d.add_argument("--xi", default="1", help="IP damping ratio ξ (1)")
    d.add_argument("--wn", default="2.3", help="IP natural frequency ω_n [rad/s] (2.3)")
    d.add_argument("--json", action="store_true", help="print JSON")
    d.set_defaults(func=_cmd_design)
    _one_line_errors(d)

    i = subparsers.add_parser(
        "identify",
        allow_abbrev=False,
        help="least-squares speed model b/(z - a) from a current-step trace CSV",
        description=(
            "Fit w[k+1] = a w[k] + b i_p[k] (+ offset) to a CSV with columns t, i_p, speed "
            "(or as saved by the trace capture); decimated traces are converted to the loop rate."
        ),
    )
    i.add_argument("--csv", required=True, help="trace file (t [s], i_p [A], speed [rpm])")
    i.add_argument("--current-col", default="i_p", help="current column name (i_p)")
    i.add_argument("--speed-col", default="speed", help="speed column name (speed)")
    i.add_argument("--fs", default="50000", help="loop sampling frequency [Hz] (50000)")
    i.add_argument("--divider", default=None, help="loop samples per trace sample (from t)")
    i.add_argument("--no-offset", action="store_true", help="fit without a constant term")
    i.add_argument("--xi", default=None, help="also design IP gains with this ξ")
    i.add_argument("--wn", default=None, help="also design IP gains with this ω_n [rad/s]")
    i.add_argument("--json", action="store_true", help="print JSON")
    i.set_defaults(func=_cmd_identify)
    _one_line_errors(i)


def run_cli(argv: Sequence[str] | None = None) -> int:
    """Run ``design``/``identify`` as ``drive-link`` would; returns the exit status."""
    parser = argparse.ArgumentParser(prog="drive-link", allow_abbrev=False)
    sub = parser.add_subparsers(dest="command", required=True)
    add_parsers(sub)
    try:
        args = parser.parse_args(list(argv) if argv is not None else None)
    except SystemExit as exc:  # argparse already printed its message
        return int(exc.code or 0) if not isinstance(exc.code, str) else 2
    return int(args.func(args))


__all__ = ["add_parsers", "analyse_current_loop", "read_trace_csv", "run_cli"]
