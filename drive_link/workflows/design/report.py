"""The current-loop report: stability, margins and the predicted step of one loop, as a
JSON-ready dict (``drive-link design``, the dashboard's preview)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from drive_link.workflows import metrics as _metrics

from ._common import FS_DEFAULT, L_TABLE2, PI_KI_PAPER, PI_KP_PAPER, R_TABLE2, ControllerName
from .current_loop import loop_tf, phi_gamma
from .lti import feedback, is_stable, jury_stable, margins
from .pars import CurrentLoopPars
from .response import margins_summary
from .step import predict_step

__all__ = ["analyse_current_loop"]


def analyse_current_loop(
    controller: ControllerName = "deadbeat",
    *,
    R: float = R_TABLE2,
    L: float = L_TABLE2,
    L_c: float | None = None,
    R_c: float | None = None,
    k_p: float = PI_KP_PAPER,
    k_i: float = PI_KI_PAPER,
    fs: float = FS_DEFAULT,
    i_start: float = 15.0,
    i_final: float = 20.0,
    n_samples: int | None = None,
) -> dict[str, Any]:
    """Stability, margins and predicted step figures of one current loop (JSON-ready dict).

    Units: R [Ω], L, L_c [H], R_c [Ω], k_p, k_i [V/A], fs [Hz], currents [A]; times in the result
    are in s, frequencies in Hz, margins in dB and degrees. ``n_samples=None`` predicts the step
    until the slowest closed-loop pole has decayed to 1e-4. L_c, R_c default to L, R.

    Keys: controller, R, L, L_c, R_c, fs, Phi, Gamma, (Phi_c, Gamma_c | k_p, k_i), stable,
    marginal (a pole within 1e-9 of the unit circle), jury_stable, max_pole_radius, poles
    ([re, im] pairs), gain_margin_db, phase_margin_deg (the smallest margin, a positive angle),
    sensitivity_peak, gain_crossover_hz, phase_crossover_hz, crossovers ([{hz,
    phase_margin_deg}] for every gain crossover), phase_margins_deg, gain_crossovers_hz (the
    same as two lists), overshoot_pct, rise_time_s,
    settling_time_s, steady_state_error_A, steady_state_error_pct, step_samples, step_from_A,
    step_to_A (step figures None unless asymptotically stable).
    """
    p = CurrentLoopPars(controller, R, L, L_c, R_c, k_p, k_i, fs).resolved()
    L_c, R_c = p.L_c_used, p.R_c_used
    loop = loop_tf(p)
    cl = feedback(loop)
    poles = cl.poles()
    stable = is_stable(cl)
    m = margins(loop)
    Phi, Gamma = phi_gamma(R, L, fs)
    out: dict[str, Any] = {
        "controller": controller,
        "R": R,
        "L": L,
        "L_c": L_c,
        "R_c": R_c,
        "fs": fs,
        "Phi": Phi,
        "Gamma": Gamma,
        "stable": stable,
        "marginal": bool(poles.size and abs(float(np.max(np.abs(poles))) - 1.0) <= 1e-9),
        "jury_stable": jury_stable(cl.den),
        "max_pole_radius": float(np.max(np.abs(poles))) if poles.size else 0.0,
        "poles": [[float(p.real), float(p.imag)] for p in poles],
        **margins_summary(m),
        "phase_margins_deg": list(m.phase_margins_deg),
        "gain_crossovers_hz": list(m.gain_crossovers_hz),
    }
    if controller == "deadbeat":
        Phi_c, Gamma_c = phi_gamma(R_c, L_c, fs)
        out["Phi_c"], out["Gamma_c"] = Phi_c, Gamma_c
    if controller == "pi":
        out["k_p"], out["k_i"] = k_p, k_i
    step: dict[str, Any] = {
        "overshoot_pct": None,
        "rise_time_s": None,
        "settling_time_s": None,
        "steady_state_error_A": None,
        "steady_state_error_pct": None,
        "step_samples": None,
    }
    if stable:
        r_max = float(np.max(np.abs(poles))) if poles.size else 0.0
        if n_samples is None:  # long enough for the slowest pole to decay to 1e-4
            n_samples = 50 if r_max < 1e-3 else math.ceil(math.log(1e-4) / math.log(r_max))
            n_samples = min(max(n_samples, 50), 200_000)
        r = predict_step(p, n_samples=n_samples, i_start=i_start, i_final=i_final)
        y0 = predict_step(p, n_samples=1, i_start=i_start, i_final=i_start).i_p_final
        sm = _metrics.step_metrics(r.t, r.i_p, reference=i_final, y_initial=y0, y_final=r.i_p_final)
        step = {
            "overshoot_pct": sm.overshoot_pct,
            "rise_time_s": sm.rise_time,
            "settling_time_s": sm.settling_time,
            "steady_state_error_A": sm.steady_state_error,
            "steady_state_error_pct": (
                100.0 * sm.steady_state_error / abs(i_final) if i_final != 0.0 else None
            ),
            "step_samples": n_samples,
        }
    out.update(step)
    out["step_from_A"], out["step_to_A"] = i_start, i_final
    return out
