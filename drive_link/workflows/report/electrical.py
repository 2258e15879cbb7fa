"""identify_electrical: the motor's R and L measured through the drive, from one deadbeat step.

* R [Ω] from the two steady states around the step: in steady state eq. (6) gives
  v_L − e_L = 2 R i_p (two phases in series), so R = Δ(v_L − e_L) / (2 Δi_p) with the recorded
  line voltage v_L and back-EMF e_L (a difference: constant inverter drops cancel).
* L [H] from the step's shape: eq. (16) fixes the deadbeat loop's response by L_c/L (and weakly
  by R), so L is the value whose predicted response
  (:func:`drive_link.workflows.design.predicted_step` with the drive's L_c, R_c, the measured e_L
  and R) fits the measured first samples best (least squares, bounded search in (0.5 L_c, 5 L_c)).

Uncertainties (1σ) from the scatter only: the standard errors of the steady means for R; for L
the residual RMS over the sensitivity of the response to L (Gauss-Newton), plus R's share. They
leave out systematic errors: on the virtual drive (default motor and one with L +30 %, R −40 %)
R came out 0.8-1.3 % low (3-4 σ) and L within 0.2 % (about 2 σ), both well inside the verdict's
tolerance (15 % R, 10 % L).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from firmware_protocol import paper

from ...errors import DriveError
from ...link.trace import TS
from .. import design, steps
from ._base import Context, ExperimentResult, Metric, figure_png, new_figure

__all__ = ["estimate_R_L", "identify_electrical"]

I_FROM, I_TO = 10.0, 25.0  #: the measuring step, A
N_FIT = 25  #: loop samples after the step used for the fit of L
#: steps recorded at most until one has no commutation before the step (at 1000 rpm a sector
#: lasts ~125 samples, the record 300: with the default 4, one report in some tens got none)
RETRIES = 8


def _clean_end(res: steps.StepResult) -> int:
    tr = res.trace
    n = len(tr.t) - tr.trigger_index
    if res.commutation_at_s is not None:
        n = int(np.searchsorted(tr.t[tr.trigger_index:],
                                res.commutation_at_s - steps.COMMUTATION_MARGIN * TS))
    return max(n, 12)


def estimate_R_L(res: steps.StepResult) -> dict[str, float]:
    """R, L and their 1σ uncertainties from a recorded deadbeat current step (see the module
    doc); keys R, sigma_R (Ω), L, sigma_L (H), rms_A (fit residual), n_fit."""
    tr = res.trace
    k0 = tr.trigger_index
    i_p = np.asarray(tr.signals["measurements.i_p"], dtype=float)
    v = np.asarray(tr.signals["measurements.v_L"], dtype=float)
    e = np.asarray(tr.signals["measurements.e_L"], dtype=float)
    n_clean = _clean_end(res)
    pre = slice(max(0, k0 - 40), k0)
    post = slice(k0 + 10, k0 + n_clean)
    di = float(np.mean(i_p[post]) - np.mean(i_p[pre]))
    u_pre, u_post = (v - e)[pre], (v - e)[post]
    du = float(np.mean(u_post) - np.mean(u_pre))
    R = du / (2.0 * di)
    if not (math.isfinite(R) and R > 0.0):  # a disturbed record (a commutation in its windows)
        raise DriveError(
            f"the current step's record gives R = {R:.3g} Ω (Δu {du:.3g} V over Δi_p {di:.3g} A):"
            " a commutation disturbed its windows; run it again (the motor at another angle)"
        )
    se = math.sqrt(np.var(u_pre) / max(1, u_pre.size - 1)
                   + np.var(u_post) / max(1, u_post.size - 1))
    sigma_R = abs(se / (2.0 * di)) + abs(R) * 0.002
    p = res.params
    L_c, R_c = float(p["L_c"]), float(p["R_c"])
    e_L = float(np.mean(e[pre]))
    n_fit = min(N_FIT, n_clean)
    y = i_p[k0 : k0 + n_fit]
    i0 = float(np.mean(i_p[pre]))

    def model(L: float, R_: float = R) -> np.ndarray:
        return design.predicted_step("deadbeat", n_samples=n_fit, i_start=i0, i_final=res.y_to,
                                     R=max(R_, 1e-5), L=L, L_c=L_c, R_c=R_c, e_L=e_L).i_p

    def cost(log_l: float) -> float:
        return float(np.sum((model(math.exp(log_l)) - y) ** 2))

    best = optimize.minimize_scalar(cost, bounds=(math.log(0.5 * L_c), math.log(5.0 * L_c)),
                                    method="bounded", options={"xatol": 1e-5})
    L = math.exp(best.x)
    resid = model(L) - y
    s2 = float(np.sum(resid**2)) / max(1, n_fit - 1)
    h = 1e-3 * L
    J = (model(L + h) - model(L - h)) / (2 * h)
    sigma_fit = math.sqrt(s2 / max(float(np.sum(J**2)), 1e-30))
    dR = max(sigma_R, 1e-7)
    # R's share: the L that fits with R ± σ_R
    alt = optimize.minimize_scalar(
        lambda ll: float(np.sum((model(math.exp(ll), R + dR) - y) ** 2)),
        bounds=(math.log(0.5 * L_c), math.log(5.0 * L_c)), method="bounded",
        options={"xatol": 1e-5})
    sigma_L = math.hypot(sigma_fit, math.exp(alt.x) - L)
    return {"R": R, "sigma_R": sigma_R, "L": L, "sigma_L": sigma_L,
            "rms_A": math.sqrt(s2), "n_fit": float(n_fit), "i_start": i0, "e_L": e_L}


def identify_electrical(ctx: Context) -> ExperimentResult:
    """The motor's R and L through the drive (deadbeat step 10 → 25 A, the L_c in use)."""
    r = ExperimentResult("identify_electrical", "Motor R and L measured through the drive",
                         "eqs. 6, 16 (Table 2: R, L)")
    from .current import _with_gains

    d = ctx.drive
    with _with_gains(ctx, type=0):
        res = steps.current_step(d, I_FROM, I_TO, length=300, pre_trigger=50,
                                 commutation_retries=RETRIES, hooks=ctx.step_hooks(0.0, 1.0))
    est = estimate_R_L(res)
    R_od, L_od = float(res.params["R"]), float(res.params["L"])
    L_c = float(res.params["L_c"])
    r.metrics["R_ohm"] = Metric(est["R"], R_od, paper.R_TABLE2, "Ω",
                                max(0.15 * R_od, 3 * est["sigma_R"]))
    r.metrics["R_ohm_uncertainty"] = Metric(est["sigma_R"], None, None, "Ω", None)
    r.metrics["L_H"] = Metric(est["L"], L_od, paper.L_TABLE2, "H",
                              max(0.1 * L_od, 3 * est["sigma_L"]))
    r.metrics["L_H_uncertainty"] = Metric(est["sigma_L"], None, None, "H", None)
    ratio = L_c / est["L"]
    r.metrics["L_c_over_L"] = Metric(ratio, L_c / L_od, None, "1", None)
    a = design.analyse_current_loop("deadbeat", R=est["R"], L=est["L"], L_c=L_c,
                                    R_c=float(res.params["R_c"]))
    r.conditions = (f"current mode, deadbeat with the L_c in use ({L_c * 1e6:.2f} µH), "
                    f"i_p* {I_FROM:g} → {I_TO:g} A; model column: the drive's motor.R, motor.L")
    verdict = ("stable (L_c < 2 L)" if ratio < 2 else "UNSTABLE: L_c ≥ 2 L (eq. 17)")
    r.notes.append(
        f"R = {est['R'] * 1e3:.3f} ± {est['sigma_R'] * 1e3:.3f} mΩ, L = {est['L'] * 1e6:.2f} ± "
        f"{est['sigma_L'] * 1e6:.2f} µH (fit RMS {est['rms_A']:.3f} A over "
        f"{int(est['n_fit'])} samples; 1σ from the scatter only, systematic errors not "
        f"included). For the L_c in use: L_c/L = {ratio:.2f}, {verdict}; "
        f"margins with the measured R, L: GM {a['gain_margin_db']:.2f} dB, PM "
        f"{a['phase_margin_deg']:.1f}°, ‖S‖∞ {a['sensitivity_peak']:.2f}, predicted overshoot "
        f"{a['overshoot_pct']:.1f} % (L_c = L gives the two-sample deadbeat of eq. 16)."
    )
    tr = res.trace
    k0 = tr.trigger_index
    n = int(est["n_fit"])
    fit = design.predicted_step("deadbeat", n_samples=n, i_start=est["i_start"],
                                i_final=res.y_to, R=est["R"], L=est["L"], L_c=L_c,
                                R_c=float(res.params["R_c"]), e_L=est["e_L"]).i_p
    fig, (ax,) = new_figure(1)
    t_us = tr.t[k0 : k0 + n] * 1e6
    ax.plot(t_us, fit, color="tab:orange", ls="--", lw=1.0,
            label=f"eq. 16 with the fitted L = {est['L'] * 1e6:.2f} µH")
    ax.plot(t_us, tr.signals["measurements.i_p"][k0 : k0 + n], color="tab:blue", lw=1.8,
            marker=".", ms=4, label="i_p measured (A)", zorder=5)
    ax.set_xlabel("time after the step (µs)")
    ax.set_ylabel("i_p (A)")
    ax.set_title(f"R, L from the deadbeat step (L_c/L = {ratio:.2f})", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    r.figures.append(figure_png(fig))
    return r
