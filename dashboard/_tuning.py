"""Gains: read back, preview (stability, margins, ‖S‖∞ via drive_link.workflows.design), apply as
one set (drive_link.workflows.gains.apply_gains, the path ``drive-link set-gains`` takes), IP design
from ξ and ω_n (eqs. 28–31), store, and live-vs-stored diff. The dashboard only presents: every rule
and every loop model is drive_link's.

Units: L_c H, R_c Ω, current PI k_p/k_i V/A, speed k_p A/rpm, speed k_i 1/sample (Ts = 20 µs).
"""

from __future__ import annotations

import math
import time
from typing import Any

from dashboard._bench import LIVE_NAMES, Bench, as_dict
from dashboard._models import TYPE_NAMES
from drive_link import design
from drive_link.errors import InvalidValue
from drive_link.link.drive import GAIN_FIELDS
from drive_link.workflows import gains as link_gains
from firmware_protocol import paper

__all__ = [
    "A_PAPER",
    "B_PAPER",
    "DISPLAY",
    "apply",
    "design_ip",
    "diff_markdown",
    "display",
    "held",
    "motor_RL",
    "preview",
    "preview_markdown",
    "read_gains",
    "readback_markdown",
    "response",
    "store",
    "stored_diff",
]

#: The paper's identified speed model (Section V), used until an identification has been run.
A_PAPER, B_PAPER = paper.SPEED_MODEL


def motor_RL(bench: Bench) -> tuple[float, float]:
    """(R Ω, L H) of the motor as the bench holds them (read once, see :func:`held`)."""
    _g, motor = held(bench)
    return motor["R"], motor["L"]


def _hold(bench: Bench, gains: dict[str, Any], motor: dict[str, float]) -> dict[str, Any]:
    """Keep ``gains`` (a full set, drive units) and ``motor`` as the bench's known set; returns
    the set as the dashboard shows it (type by name, motor R and L, L_c/L)."""
    g = dict(gains)
    g["type"] = TYPE_NAMES.get(int(g["type"]), str(g["type"]))
    g["motor_R"], g["motor_L"] = motor["R"], motor["L"]
    g["L_c_over_L"] = g["L_c"] / motor["L"]
    bench.gains, bench.motor = g, dict(motor)
    # the operand of |i_p*| ≤ current limit, so a current setpoint need not read it
    bench.setpoints.note("speed_controller.current_limit", float(g["speed_current_limit"]))
    return dict(g)


def read_gains(bench: Bench) -> dict[str, Any]:
    """The live gains read back from the drive (13 SDO reads), plus the motor (4 reads: R, L
    and the two values the drive's rule uses); the bench keeps both (:func:`held`)."""
    with bench.lock:
        g = as_dict(bench.drive.read_gains())
        motor = link_gains.read_motor(bench.drive)
        return _hold(bench, g, motor)


def held(bench: Bench) -> tuple[dict[str, Any], dict[str, float]]:
    """(gains, motor) as the bench knows them: last read back or applied; read once when the
    bench knows none. A preview, a diff or an Apply costs no read of what is known."""
    with bench.lock:
        if bench.gains is None or bench.motor is None:
            read_gains(bench)
        assert bench.gains is not None and bench.motor is not None
        return dict(bench.gains), dict(bench.motor)


def _merged(bench: Bench, changes: dict[str, float | int]) -> dict[str, Any]:
    out, _motor = held(bench)
    for k, v in changes.items():
        out[k] = TYPE_NAMES[int(v)] if k == "type" else v
    return out


def _view(r: design.LoopResponse) -> dict[str, Any]:
    """One loop's preview: stability, margins (PM the smallest, a positive angle; every
    crossover listed), ‖S‖∞ and the closed-loop poles ([re, im])."""
    m = design.margins_summary(r.margins)
    return {
        "stable": r.stable,
        "gain_margin_dB": m["gain_margin_db"],
        "phase_margin_deg": m["phase_margin_deg"],
        "S_inf": m["sensitivity_peak"],
        "gain_crossover_hz": m["gain_crossover_hz"],
        "phase_crossover_hz": m["phase_crossover_hz"],
        "crossovers": m["crossovers"],
        "poles": [[float(p.real), float(p.imag)] for p in r.poles],
        "max_pole_radius": r.max_pole_radius,
    }


def preview(bench: Bench, changes: dict[str, float | int]) -> dict[str, Any]:
    """Stability, GM, PM and ‖S‖∞ of the current loop (controller on the drive's motor R, L) and
    of the speed loop (IP on the identified G(z) = b/(z − a)) with ``changes`` applied, and the
    verdict ``apply`` would give (``check``: refusals, warnings)."""
    g = _merged(bench, changes)
    R, L = g["motor_R"], g["motor_L"]
    cur = design.current_loop_response(
        g["type"], R=R, L=L, L_c=g["L_c"], R_c=g["R_c"], k_p=g["k_p"], k_i=g["k_i"], n_points=10
    )
    current = _view(cur)
    current.update(controller=g["type"], L_c=g["L_c"], L_c_over_L=g["L_c"] / L, R_c=g["R_c"])
    a, b = _ab(bench)
    kp, ki = float(g["speed_k_p"]), float(g["speed_k_i"])
    speed = _view(design.speed_loop_response(a, b, kp, ki, n_points=10))
    speed.update(a=a, b=b, k_p=kp, k_i=ki)
    check = link_gains.check_gains(
        {k: g[k] for k in LIVE_NAMES if k in g}, R, L, (a, b)
    )
    return {"current": current, "speed": speed, "check": check.to_dict()}


def response(bench: Bench, changes: dict[str, float | int], n_points: int = 200) -> dict[str, Any]:
    """Bode data (open loop dB and °, |T| and |S| dB over f Hz) and closed-loop poles/zeros in
    the z-plane of the current loop and of the IP speed loop with ``changes`` applied (the
    paper's Figs. 4, 5, 12;
    drive_link.workflows.design.current_loop_response/speed_loop_response)."""
    g = _merged(bench, changes)
    cur = design.current_loop_response(
        g["type"],
        R=g["motor_R"],
        L=g["motor_L"],
        L_c=g["L_c"],
        R_c=g["R_c"],
        k_p=g["k_p"],
        k_i=g["k_i"],
        n_points=n_points,
    )
    a, b = _ab(bench)
    kp, ki = float(g["speed_k_p"]), float(g["speed_k_i"])
    speed = design.speed_loop_response(a, b, kp, ki, n_points=n_points)
    return {
        "current": {**cur.as_dict(), "controller": g["type"], "L_c": g["L_c"], "R_c": g["R_c"]},
        "speed": {**speed.as_dict(), "a": a, "b": b, "k_p": kp, "k_i": ki},
    }


def _ab(bench: Bench) -> tuple[float, float]:
    ident = bench.identified
    if ident:
        return float(ident["a"]), float(ident["b"])
    return A_PAPER, B_PAPER


def apply(bench: Bench, changes: dict[str, float | int], *, force: bool = False) -> dict[str, Any]:
    """Apply ``changes`` as one set through :func:`drive_link.workflows.gains.apply_gains` (the rule
    of ``drive-link set-gains``) on the identified speed model; returns the applied set (its
    :class:`~drive_link.workflows.gains.GainResult`), which the bench then holds and every page
    shows.

    The set and the motor the check starts from are the ones the bench holds (:func:`held`):
    only what changes is staged. An unstable set, or one the drive's rule refuses, is refused
    always; poor margins (L_c > 1.5 L, GM < 2 dB, ‖S‖∞ > 5) unless ``force`` (GainsRefused, a
    ValueError → 422, nothing applied).
    """
    with bench.lock:
        g, motor = held(bench)
        previous = {k: g[k] for k in GAIN_FIELDS}
        try:
            res = link_gains.apply_gains(
                bench.drive, changes, force=force, speed_model=_ab(bench),
                previous=previous, motor=motor,
            )
        except InvalidValue:
            raise  # refused before sending: what the bench holds is still the drive's
        except Exception:
            bench.gains = None  # the drive refused or did not answer: read it next time
            raise
        out = _hold(bench, res.gains, motor)
    bench.emit("gains", out)
    return out


def design_ip(
    bench: Bench, xi: float, omega_n: float, a: float | None = None, b: float | None = None
) -> dict[str, Any]:
    """IP gains (k_p A/rpm, k_i 1/sample) from ξ and ω_n (rad/s) on a, b (default: identified)."""
    a0, b0 = _ab(bench)
    a = a0 if a is None else float(a)
    b = b0 if b is None else float(b)
    k_p, k_i = design.ip_gains(a, b, xi, omega_n)
    return {"speed_k_p": k_p, "speed_k_i": k_i, "a": a, "b": b, "xi": xi, "omega_n": omega_n}


_stored: dict[int, dict[str, Any]] = {}


def store(bench: Bench) -> dict[str, Any]:
    """Store the live parameters in the drive (0x1010); remember what was stored (read back)."""
    with bench.lock:
        bench.drive.store()
        g = read_gains(bench)
    _stored[id(bench)] = {"gains": g, "t": time.time()}
    bench.emit("stored", g)
    return g


def stored_diff(bench: Bench, *, fresh: bool = False) -> dict[str, Any]:
    """Live gains against the last set stored from this bench session.

    CANopen offers no read of the non-volatile copy, so "stored" is the read-back taken right
    after the last successful store from this dashboard (None before any); "live" is the set
    the bench holds (:func:`held`), read from the drive first with ``fresh``.
    """
    live = read_gains(bench) if fresh else held(bench)[0]
    st = _stored.get(id(bench))
    if st is None:
        return {"live": live, "stored": None, "stored_at": None, "differs": None}
    differs = [k for k, v in live.items() if k in st["gains"] and not _same(v, st["gains"][k])]
    return {"live": live, "stored": st["gains"], "stored_at": st["t"], "differs": differs}


def _same(a: object, b: object) -> bool:
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-12)
    return a == b


def _radius(r: float) -> str:
    """A pole radius with enough digits to tell it from 1 (0.99995, not 1.0000)."""
    if not math.isfinite(r):
        return "–"
    if abs(1.0 - r) < 1e-3:
        return f"{r:.6f}".rstrip("0") if r != 1.0 else "1 (on the unit circle)"
    return f"{r:.4f}"


#: gain-set entries in display units: name → (label, factor, unit, format)
DISPLAY = {
    "L_c": ("L_c", 1e6, "µH", ".4g"),
    "R_c": ("R_c", 1e3, "mΩ", ".4g"),
    "k_p": ("PI k_p", 1.0, "V/A", ".4g"),
    "k_i": ("PI k_i", 1.0, "V/A", ".4g"),
    "speed_k_p": ("IP k_p", 1.0, "A/rpm", ".4g"),
    "speed_k_i": ("IP k_i", 1.0, "1/sample", ".5g"),
    "motor_L": ("motor L", 1e6, "µH", ".4g"),
    "motor_R": ("motor R", 1e3, "mΩ", ".4g"),
    "L_c_over_L": ("L_c/L", 1.0, "", ".4f"),
    "T_BT": ("T_BT", 1e6, "µs", ".4g"),
    "T_DD": ("T_DD", 1e6, "µs", ".4g"),
    "T_SD": ("T_SD", 1e6, "µs", ".4g"),
    "V_G": ("V_G", 1.0, "V", ".4g"),
    "speed_current_limit": ("speed current limit", 1.0, "A", ".4g"),
}


def display(name: str, value: Any) -> str:
    """A gain-set value in the OD's display unit (``L_c 14.8 µH``)."""
    _label, factor, unit, fmt = DISPLAY.get(name, (name, 1.0, "", ".6g"))
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return f"{format(float(value) * factor, fmt)} {unit}".strip()
    return str(value)


def _db(x: float) -> str:
    return "∞" if not math.isfinite(x) else f"{x:.2f}"


def preview_markdown(p: dict[str, Any]) -> str:
    """The preview as GUI markdown."""
    c, s = p["current"], p["speed"]

    def line(name: str, m: dict[str, Any]) -> str:
        if not m["stable"]:  # margins and ‖S‖∞ of an unstable loop mean nothing
            return f"{name}: **UNSTABLE** · max|pole| {_radius(m['max_pole_radius'])}"
        pm = m["phase_margin_deg"]
        pm_txt = "–" if pm is None or not math.isfinite(pm) else f"{pm:.1f}"
        every = m.get("crossovers") or []
        at = (
            " (" + ", ".join(f"{x['phase_margin_deg']:.1f}° at {_hz(x['hz'])}" for x in every) + ")"
            if len(every) > 1
            else ""
        )
        return (
            f"{name}: **stable** · GM {_db(m['gain_margin_dB'])} dB · "
            f"PM {pm_txt}°{at} · "
            f"‖S‖∞ {m['S_inf']:.3f} · max|pole| {_radius(m['max_pole_radius'])}"
        )

    check = p.get("check") or {}
    verdict = "".join(
        f"  \n{tag} {msg}"
        for tag, key in (("**Refused:**", "refusals"), ("**Needs force:**", "warnings"))
        for msg in check.get(key, [])
    )
    return (
        "**Before applying**  \n"
        + line(f"Current ({c['controller']}, L_c/L = {c['L_c_over_L']:.3f})", c)
        + "  \n"
        + line(f"Speed (IP, a = {s['a']:.7f}, b = {s['b']:.4g})", s)
        + verdict
    )


def _hz(f: float) -> str:
    return f"{f / 1e3:.1f} kHz" if f >= 1e3 else f"{f:.3g} Hz"


def readback_markdown(g: dict[str, Any]) -> str:
    """The read-back gains as GUI markdown."""
    return (
        "**Read back from the drive**  \n"
        f"type {g['type']} · L_c {g['L_c'] * 1e6:.4g} µH (L_c/L {g['L_c_over_L']:.4f}) · "
        f"R_c {g['R_c'] * 1e3:.4g} mΩ  \n"
        f"PI k_p {g['k_p']:.4g} · k_i {g['k_i']:.4g} · "
        f"IP k_p {g['speed_k_p']:.4g} A/rpm · k_i {g['speed_k_i']:.5g}"
    )


def diff_markdown(d: dict[str, Any]) -> str:
    """Live vs stored as GUI markdown."""
    if d["stored"] is None:
        return (
            "**Stored:** nothing stored from this session yet (CANopen cannot read the stored copy)"
        )
    if not d["differs"]:
        return "**Stored:** live values equal the stored ones"
    rows = ", ".join(
        f"{DISPLAY.get(k, (k,))[0]}: live {display(k, d['live'][k])} / "
        f"stored {display(k, d['stored'][k])}"
        for k in d["differs"]
    )
    return f"**Live ≠ stored:** {rows}"
