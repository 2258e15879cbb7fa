"""Gains: read back, preview (stability, margins, ‖S‖∞ via drive_link.design), apply as one set,
IP design from ξ and ω_n (eqs. 28–31), store, and live-vs-stored diff.

Units: L_c H, R_c Ω, current PI k_p/k_i V/A, speed k_p A/rpm, speed k_i 1/sample (Ts = 20 µs).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from dashboard.bench import Bench, as_dict
from dashboard.models import TYPE_NAMES
from drive_link import design
from drive_link.margins_check import check_gains

#: The paper's identified speed model (Section V), used until an identification has been run.
A_PAPER = 0.9999785
B_PAPER = 3.33715e-4


def motor_RL(bench: Bench) -> tuple[float, float]:
    """(R Ω, L H) of the motor as the drive holds them (motor.R, motor.L)."""
    return float(bench.drive.read("motor.R")), float(bench.drive.read("motor.L"))


def read_gains(bench: Bench) -> dict[str, Any]:
    """The live gains read back from the drive, plus motor R, L and L_c/L."""
    with bench.lock:
        g = as_dict(bench.drive.read_gains())
        R, L = motor_RL(bench)
    g["type"] = TYPE_NAMES.get(int(g["type"]), str(g["type"]))
    g["motor_R"], g["motor_L"] = R, L
    g["L_c_over_L"] = g["L_c"] / L
    return g


def _merged(bench: Bench, changes: dict[str, float | int]) -> dict[str, Any]:
    g = read_gains(bench)
    out = dict(g)
    for k, v in changes.items():
        out[k] = TYPE_NAMES[int(v)] if k == "type" else v
    return out


def _poles(tf: design.DiscreteTF) -> list[list[float]]:
    return [[float(p.real), float(p.imag)] for p in tf.poles()]


def _phase_margin(m: design.Margins) -> tuple[float, float]:
    """(PM °, crossover Hz): the smallest |PM| over all gain crossovers, ties (within 1e-6°)
    going to the lowest crossover frequency. drive_link's own pick compares |PM| rounded to 9
    digits, so for the deadbeat loop 1/(z² − 1) float noise made it report the −60° of the
    20.8 kHz crossing instead of the +60° at 4.2 kHz (python-control, after minreal: +60°)."""
    if not m.phase_margins_deg:
        return m.phase_margin_deg, m.gain_crossover_hz
    smallest = min(abs(p) for p in m.phase_margins_deg)
    cands = [
        (hz, p)
        for p, hz in zip(m.phase_margins_deg, m.gain_crossovers_hz, strict=True)
        if abs(p) - smallest <= 1e-6
    ]
    hz, pm = min(cands)
    return pm, hz


def _margins_dict(loop: design.DiscreteTF, closed: design.DiscreteTF) -> dict[str, Any]:
    m = design.margins(loop)
    stable = design.is_stable(closed)
    pm, pm_hz = _phase_margin(m)
    return {
        "stable": stable,
        "gain_margin_dB": m.gain_margin_db,
        "phase_margin_deg": pm,
        "S_inf": m.sensitivity_peak,
        "gain_crossover_hz": pm_hz,
        "phase_crossover_hz": m.phase_crossover_hz,
        "poles": _poles(closed),
        "max_pole_radius": float(np.max(np.abs(closed.poles()))) if closed.den.size > 1 else 0.0,
    }


def preview(bench: Bench, changes: dict[str, float | int]) -> dict[str, Any]:
    """Stability, GM, PM and ‖S‖∞ of the current loop (controller on the drive's motor R, L) and
    of the speed loop (IP on the identified G(z) = b/(z − a)) with ``changes`` applied."""
    g = _merged(bench, changes)
    R, L = g["motor_R"], g["motor_L"]
    loop = design.current_loop_tf(
        g["type"], R=R, L=L, L_c=g["L_c"], R_c=g["R_c"], k_p=g["k_p"], k_i=g["k_i"]
    )
    current = _margins_dict(loop, design.feedback(loop))
    current.update(controller=g["type"], L_c=g["L_c"], L_c_over_L=g["L_c"] / L, R_c=g["R_c"])
    a, b = _ab(bench)
    kp, ki = float(g["speed_k_p"]), float(g["speed_k_i"])
    G = design.DiscreteTF([b], [1.0, -a])
    ip_fb = design.DiscreteTF([kp * (1.0 + ki), -kp], [1.0, -1.0])  # k_p (1 + k_i z/(z − 1))
    speed = _margins_dict(ip_fb * G, design.ip_closed_loop(a, b, kp, ki))
    speed.update(a=a, b=b, k_p=kp, k_i=ki)
    return {"current": current, "speed": speed}


def _ab(bench: Bench) -> tuple[float, float]:
    ident = bench.identified
    if ident:
        return float(ident["a"]), float(ident["b"])
    return A_PAPER, B_PAPER


def apply(bench: Bench, changes: dict[str, float | int], *, force: bool = False) -> dict[str, Any]:
    """Apply ``changes`` as one set (drive_link.apply_gains); returns the read-back gains.

    Checked before sending by the rule of ``drive-link set-gains`` (drive_link.margins_check) on
    the drive's motor R, L and the identified speed model: an unstable current or speed loop is
    refused always, poor margins (L_c > 1.5 L, GM < 2 dB, ‖S‖∞ > 5) unless ``force``
    (ValueError → 422, nothing applied).
    """
    with bench.lock:
        proposed = {**as_dict(bench.drive.read_gains()), **changes}
        R, L = motor_RL(bench)
    report = check_gains(proposed, R, L, _ab(bench))
    fig = report.figures
    unstable = not (fig["current_loop_stable"] and fig.get("speed_loop_stable", True))
    if unstable or (not report.ok and not force):
        hint = "" if unstable else " (force to apply anyway)"
        raise ValueError("; ".join(report.problems) + hint + "; nothing applied")
    with bench.lock:
        bench.drive.apply_gains(**changes)
    g = read_gains(bench)
    bench.emit("gains", g)
    return g


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
    """Store the live parameters in the drive (0x1010); remember what was stored."""
    with bench.lock:
        bench.drive.store()
        g = read_gains(bench)
    _stored[id(bench)] = {"gains": g, "t": time.time()}
    bench.emit("stored", g)
    return g


def stored_diff(bench: Bench) -> dict[str, Any]:
    """Live gains against the last set stored from this bench session.

    CANopen offers no read of the non-volatile copy, so "stored" is the read-back taken right
    after the last successful store from this dashboard (None before any).
    """
    live = read_gains(bench)
    st = _stored.get(id(bench))
    if st is None:
        return {"live": live, "stored": None, "stored_at": None, "differs": None}
    differs = [k for k, v in live.items() if k in st["gains"] and not _same(v, st["gains"][k])]
    return {"live": live, "stored": st["gains"], "stored_at": st["t"], "differs": differs}


def _same(a: Any, b: Any) -> bool:
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
        return (
            f"{name}: **stable** · GM {_db(m['gain_margin_dB'])} dB · "
            f"PM {'–' if not math.isfinite(pm) else f'{pm:.1f}'}° · "
            f"‖S‖∞ {m['S_inf']:.3f} · max|pole| {_radius(m['max_pole_radius'])}"
        )

    return (
        "**Before applying**  \n"
        + line(f"Current ({c['controller']}, L_c/L = {c['L_c_over_L']:.3f})", c)
        + "  \n"
        + line(f"Speed (IP, a = {s['a']:.7f}, b = {s['b']:.4g})", s)
    )


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
