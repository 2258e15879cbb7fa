"""The speed-loop experiments of the report (paper Sec. V): the identification of
G(z) = b/(z − a) (Fig. 16, eq. 26), the IP speed step (Figs. 18-19, eq. 27) and the load step
(Fig. 20). Speeds in rpm, currents in A, times in s, torque in N·m.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

from firmware_protocol import paper

from ...link.trace import TS, Trigger
from .. import identify, steps
from ..restore import leave_as_found
from ._base import Context, ExperimentResult, Metric, figure_png, new_figure

__all__ = ["identify_speed_model", "load_step", "speed_step"]

RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)
W_START, W_STEP = 500.0, 500.0  #: speed step start and size, rpm (Fig. 18: +500 rpm/div)
LOAD_EQUIV_A = 36.0  #: load step as the current it takes to hold it, A (torque = this × K_t)


def plant_ab(ctx: Context) -> tuple[float, float] | None:
    """(a, b) of eq. (26) from the virtual plant's J, B, k_gen and K_rpm, discretised exactly
    at Ts: dω/dt = (K_t i_p − (B + k_gen·60/2π) ω)/J; None on a real drive."""
    if not ctx.virtual:
        return None
    d = ctx.drive
    J = float(d.read("sim_load.J"))
    B_tot = float(d.read("sim_load.B")) + float(d.read("sim_load.k_gen")) * RPM_PER_RAD_S
    K_t = float(d.read("motor.K_rpm")) * RPM_PER_RAD_S
    a = math.exp(-B_tot * TS / J)
    b = (1.0 - a) * K_t * RPM_PER_RAD_S / B_tot
    return a, b


def identify_speed_model(ctx: Context) -> ExperimentResult:
    """Fig. 16: current step 15 → 30 A from a steady speed; least-squares b/(z − a)."""
    r = ExperimentResult("identify_speed_model", "Speed model b/(z − a)", "Fig. 16, eq. 26")
    ident = steps.identify_speed_model(ctx.drive, 15.0, 30.0, duration_s=3.0, settle_s=0.0,
                                       hooks=ctx.step_hooks(0.0, 1.0))
    fit = ident.fit
    ctx.speed_model = (fit.a, fit.b)
    model = plant_ab(ctx) or paper.SPEED_MODEL
    src = "the virtual plant's J, B, k_gen, K_t" if ctx.virtual else "the paper (eq. 26)"
    r.metrics["a"] = Metric(fit.a, model[0], 0.99997, "1", 3e-6)
    r.metrics["b"] = Metric(fit.b, model[1], paper.B_IDENTIFIED, "rpm/(A·sample)",
                            0.08 * model[1])
    r.metrics["time_constant_s"] = Metric(TS / (1 - fit.a), TS / (1 - model[0]),
                                          TS / (1 - 0.99997), "s", 0.1 * TS / (1 - model[0]))
    r.conditions = (f"current mode, i_p* 15 → 30 A from a steady {ident.start_rpm:.1f} rpm, "
                    f"3 s recorded; model column from {src}")
    tr = ident.trace
    i_p = np.asarray(tr.signals["measurements.i_p"], dtype=float)
    speed = np.asarray(tr.signals["measurements.speed"], dtype=float)
    D = tr.divider
    a_p, b_p = paper.SPEED_MODEL
    paper_curve = identify.simulate_first_order(a_p**D, b_p * (1 - a_p**D) / (1 - a_p), i_p,
                                                speed[0], 0.0)
    fig, (ax, ax2) = new_figure(2, 2.6)
    ax.plot(tr.t, paper_curve, color="tab:green", ls=":", lw=1.0,
            label=f"paper's a, b (a = {a_p}, b = {b_p:.4g})")
    ax.plot(tr.t, ident.model, color="tab:orange", ls="--", lw=1.0,
            label=f"fitted b/(z − a) (a = {fit.a:.7f}, b = {fit.b:.4g})")
    ax.plot(tr.t, speed, color="tab:blue", lw=1.8, label="speed measured (rpm)", zorder=5)
    ax.set_ylabel("speed (rpm)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    ax2.plot(tr.t, i_p, color="tab:red", lw=1.2, label="i_p (A)")
    ax2.set_ylabel("i_p (A)")
    ax2.set_xlabel("time after the step (s)")
    ax2.grid(alpha=0.3)
    r.figures.append(figure_png(fig))
    return r


def _settling(t: np.ndarray, y: np.ndarray, y0: float, y1: float, band: float = 0.02) -> float:
    out = np.flatnonzero(np.abs(y - y1) > band * abs(y1 - y0))
    if out.size == 0:
        return 0.0
    k = int(out[-1]) + 1
    return float(t[k]) if k < len(t) else math.nan


def speed_step(ctx: Context) -> ExperimentResult:
    """Figs. 18-19: IP speed step +500 rpm from a settled 500 rpm; phase-a current beside."""
    r = ExperimentResult("speed_step", "IP speed step", "Figs. 18-19, eqs. 27-31")
    res = steps.speed_step(ctx.drive, W_STEP, start_rpm=W_START, divider=100, length=2000,
                           pre_trigger=100, settle_s=0.0, model=ctx.speed_model,
                           extra=("i_a",), hooks=ctx.step_hooks(0.0, 1.0))
    tr = res.trace
    k0 = tr.trigger_index
    w = np.asarray(tr.signals["measurements.speed"], dtype=float)
    pred = np.asarray(res.predicted["measurements.speed"], dtype=float)
    t_after = tr.t[k0:]
    w1 = res.y_to
    over = max(0.0, float(np.max(w[k0:] - w1))) / abs(w1 - res.start) * 100
    over_model = max(0.0, float(np.max(pred - w1))) / abs(w1 - res.start) * 100
    r.metrics["overshoot_pct"] = Metric(over, over_model, 0.0, "%", 2.0)
    r.metrics["settling_s"] = Metric(_settling(t_after, w[k0:], res.start, w1),
                                     _settling(t_after[: len(pred)], pred, res.start, w1),
                                     2.0, "s", 0.4)
    r.metrics["start_rpm"] = Metric(res.start, W_START, None, "rpm", res.params["settle_tol_rpm"])
    g = res.params
    r.conditions = (f"speed mode, IP k_p = {g['speed_k_p']:.4g} A/rpm, k_i = "
                    f"{g['speed_k_i']:.4g} per sample, model a = {g['a']:.7f}, b = {g['b']:.4g} "
                    f"({'identified in this run' if ctx.speed_model else 'the paper'}); "
                    f"{W_START:g} → {W_START + W_STEP:g} rpm from a settled {res.start:.1f} rpm; "
                    "settling within 2 %")
    fig, (ax, ax2) = new_figure(2, 2.6)
    ax.plot(tr.t, tr.signals["measurements.speed_ref"], color="0.5", ls="--", lw=0.8,
            label="speed* (rpm)")
    ax.plot(tr.t, res.model_column(), color="tab:orange", ls="--", lw=1.0, label="model eq. 27")
    ax.plot(tr.t, w, color="tab:blue", lw=1.8, label="speed measured (rpm)", zorder=5)
    ax.set_ylabel("speed (rpm)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    ax2.plot(tr.t, tr.signals["measurements.i_a"], color="tab:red", lw=0.6,
             label="phase a current i_a (A)")
    ax2.set_ylabel("i_a (A)")
    ax2.set_xlabel("time after the step (s)")
    ax2.grid(alpha=0.3)
    ax2.legend(fontsize=8)
    r.figures.append(figure_png(fig))
    return r


def _load_response(a: float, b: float, k_p: float, k_i: float, i_load: float,
                   n: int) -> np.ndarray:
    """Speed deviation [rpm] of the IP loop (eq. 27's loop) after a load step equivalent to
    ``i_load`` A, per loop sample: W/I_L = −b (z − 1) / (z² + z(k_p b k_i + k_p b − 1 − a)
    + a − k_p b)."""
    num = [0.0, -b, b]
    den = [1.0, k_p * b * k_i + k_p * b - 1.0 - a, a - k_p * b]
    deviation: np.ndarray = signal.lfilter(num, den, np.full(n, float(i_load)))
    return deviation


def load_step(ctx: Context) -> ExperimentResult:
    """Fig. 20: a load-torque step at a settled 500 rpm (virtual drive: sim_load.T_load)."""
    r = ExperimentResult("load_step", "Load step", "Fig. 20")
    if not ctx.virtual:
        r.reason = ("not applicable: needs a load machine (the load torque is a virtual-drive "
                    "object, sim_load 0x5000); with a DC generator on the shaft, switch its "
                    "load resistor while `drive-link trace --trigger signal --source "
                    "measurements.speed` records")
        return r
    d = ctx.drive
    K_t = float(d.read("motor.K_rpm")) * RPM_PER_RAD_S
    T_step = LOAD_EQUIV_A * K_t
    divider, length, pre = 100, 2000, 250
    h = ctx.step_hooks(0.0, 1.0)
    with leave_as_found(d, settings=("sim_load.T_load",)):
        T0 = float(d.read("sim_load.T_load"))
        steps.ensure_mode(d, "speed")
        d.set_speed(W_START)
        steps.require_enabled(d, True)
        steps.wait_settled(d, "speed", W_START, 2.0, steps.Settle(0.3, 15.0), h, "rpm")
        trig = Trigger("signal", source="measurements.speed", level=W_START - 1.5, edge="falling")
        tr = steps.record(d, ["speed", "i_p", "i_a"], divider=divider, length=length,
                          pre_trigger=pre, trigger=trig,
                          action=lambda: d.write("sim_load.T_load", T0 + T_step), hooks=h)
        g = d.read_gains()
    w = np.asarray(tr.signals["measurements.speed"], dtype=float)
    k0 = tr.trigger_index
    w0 = float(np.mean(w[: max(10, k0 // 2)]))
    # load onset: the last sample before the trigger still within 0.3 rpm of the start
    near = np.flatnonzero(np.abs(w[:k0] - w0) <= 0.3)
    k_on = int(near[-1]) if near.size else 0
    t_on = float(tr.t[k_on])
    a, b = ctx.speed_model or paper.SPEED_MODEL
    n = (length - k_on) * divider
    dev = _load_response(a, b, g.speed_k_p, g.speed_k_i, T_step / K_t, n)[::divider]
    after = w[k_on:] - w0
    dip = float(-np.min(after))
    dip_model = float(-np.min(dev))
    t_rel = tr.t[k_on:] - t_on

    def recovery(y: np.ndarray, depth: float) -> float:
        out = np.flatnonzero(np.abs(y) > max(2.0, 0.1 * depth))
        return float(t_rel[min(int(out[-1]) + 1, len(t_rel) - 1)]) if out.size else 0.0

    r.metrics["dip_rpm"] = Metric(dip, dip_model, 100.0, "rpm", 0.2 * dip_model + 2)
    r.metrics["recovery_s"] = Metric(recovery(after, dip), recovery(dev[: len(after)], dip_model),
                                     2.0, "s", 0.5)
    r.conditions = (f"speed mode at a settled {w0:.1f} rpm; load torque step {T_step:.3f} N·m "
                    f"({LOAD_EQUIV_A:g} A × K_t) on the virtual shaft, put back afterwards; "
                    "recovery: back within max(2 rpm, 10 % of the dip)")
    fig, (ax, ax2) = new_figure(2, 2.6)
    ax.plot(t_rel, w0 + dev[: len(t_rel)], color="tab:orange", ls="--", lw=1.0,
            label="model (IP loop, eq. 26-27)")
    ax.plot(t_rel, after + w0, color="tab:blue", lw=1.8, label="speed measured (rpm)", zorder=5)
    ax.set_ylabel("speed (rpm)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    ax2.plot(t_rel, tr.signals["measurements.i_a"][k_on:], color="tab:red", lw=0.6,
             label="phase a current i_a (A)")
    ax2.set_ylabel("i_a (A)")
    ax2.set_xlabel("time after the load step (s)")
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3)
    r.figures.append(figure_png(fig))
    return r
