"""The paper's inconsistencies, each computed here (not copied): what the paper prints, what its
equations give, which one the product reproduces and why. Pure computation (no drive).

Symbols as in the paper; Table 2's motor (R = 6.2 mΩ, L = 14.8 µH), Ts = 20 µs.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from firmware_protocol import paper

from .. import design, metrics

__all__ = ["inconsistencies"]


def _fig16() -> dict[str, Any]:
    rows = []
    for a in (0.99997, paper.A_IDENTIFIED):
        b = paper.B_IDENTIFIED
        tau = paper.TS / -math.log(a)
        rows.append((a, tau, 15.0 * b / (1 - a)))
    txt = "; ".join(f"a = {a}: τ = {tau:.2f} s, 98 % after {4 * tau:.1f} s, a 15 → 30 A step "
                    f"raises the speed by {rise:.0f} rpm" for a, tau, rise in rows)
    return {
        "id": "fig16_vs_a_b",
        "printed": "Fig. 16: speed over 0-14 s on a 200-600 rpm axis for the 15 → 30 A step, "
                   "with a = 0.99997, b = 3.33715e-4 (eq. 26)",
        "computed": txt,
        "reproduced": "the printed a, b (a = 0.9999785, from which the printed IP gains "
                      "follow): the virtual drive's J and B are derived from them, so its "
                      "Fig. 16 settles in about 4 s; the paper's figure cannot follow from "
                      "its own a, b",
    }


def _eq23() -> dict[str, Any]:
    R, L, fs = paper.R_TABLE2, paper.L_TABLE2, paper.FS
    p = design.predicted_step("predictive", n_samples=2000, i_start=15.0, i_final=30.0, R=R, L=L,
                              L_c=L, feedforward=True)
    err = (30.0 - p.i_p_final) / 30.0 * 100
    k2 = L * fs / (2 * R)
    k1 = L * fs / R
    return {
        "id": "eq23_error",
        "printed": "eq. (23) substituted in eq. (6): a steady-state error of 0.83 %",
        "computed": f"the closed loop of eq. (23) with eq. (6), Γ = (1−Φ)/(2R) (two phases in "
                    f"series): {err:.2f} % (= 1/(1 + L f_s/(2R)) = {100 / (1 + k2):.2f} %); "
                    f"0.83 % is 1/(1 + L f_s/R) = {100 / (1 + k1):.2f} %, the single-phase Γ",
        "reproduced": f"{err:.2f} %: the drive's plant is eq. (6) with 2R and 2L in series",
    }


def _eq7() -> dict[str, Any]:
    R, L = paper.R_TABLE2, paper.L_TABLE2
    Phi, Gamma = design.phi_gamma(R, L)
    Phi_d = np.array([[Phi, Gamma], [0.0, 0.0]])
    C = np.array([1.0, 0.0])
    z = 0.3 + 0.4j
    inv = np.linalg.inv(z * np.eye(2) - Phi_d)
    printed = C @ inv @ np.array([Gamma, 0.0])
    negated = C @ inv @ np.array([-Gamma, 0.0])
    d_eq = -Gamma / (z - Phi)
    return {
        "id": "eq7_gamma_w",
        "printed": "eq. (7): Γ_w = [Γ, 0]ᵀ, and D(z) = C(zI − Φ_d)⁻¹Γ_w = −Γ/(z − Φ)",
        "computed": f"at z = {z}: C(zI − Φ_d)⁻¹[Γ, 0]ᵀ = {printed:.4f}, −Γ/(z − Φ) = {d_eq:.4f}; "
                    f"with Γ_w = [−Γ, 0]ᵀ: {negated:.4f}",
        "reproduced": "Γ_w = [−Γ, 0]ᵀ: eq. (6) subtracts e_L, so D(z) = −Γ/(z − Φ) as printed",
    }


def _pi16() -> dict[str, Any]:
    p = design.predicted_step("pi", n_samples=400, i_start=15.0, i_final=20.0,
                              k_p=paper.PI_KP, k_i=paper.PI_KI)
    y = np.concatenate([np.full(50, 15.0), p.i_p])

    def over(n: int) -> float:
        avg = metrics.moving_average(y, n)[50:]
        return max(0.0, float(np.max(avg) - 20.0)) / 5.0 * 100

    one = over(1)
    need = next((n for n in range(1, 200) if over(n) <= 16.0), None)
    return {
        "id": "pi_overshoot_16pct",
        "printed": "Fig. 13: PI (eq. 22, k_p = 0.4647, k_i = 0.0492) overshoots about 16 %, "
                   "measured through a moving average over Ts",
        "computed": f"the linear loop with these gains: {one:.1f} % per sample (a one-sample "
                    f"average changes nothing); a moving average needs {need} samples to bring "
                    f"it to 16 % ({over(need or 1):.1f} %)",
        "reproduced": f"{one:.1f} % (the printed margins 9.14 dB / 45.6° are reproduced by the "
                      "same loop); the 16 % is not explained by the filter the paper names",
    }


def _eq24_d2() -> dict[str, Any]:
    R, L, fs = paper.R_TABLE2, paper.L_TABLE2, paper.FS
    Phi, Gamma = design.phi_gamma(R, L)
    printed = np.roots([1.0, 1 - Phi, -Phi, 2 * L * fs * Gamma])
    a, b = paper.SPEED_MODEL
    w, xi, ts = paper.IP_OMEGA_N, paper.IP_XI, paper.TS
    kp_printed = (a - math.exp(-xi * w * ts)) / b
    kp_two = (a - math.exp(-2 * xi * w * ts)) / b
    return {
        "id": "eq24_eq29",
        "printed": "eq. (24)'s denominator z³ + (1−Φ)z² − Φz + 2Lf_sΓ; eq. (29) d₂ = "
                   "e^(−ξω_nT_s) with k_p = 0.2113",
        "computed": f"eq. (24)'s printed roots have |z| up to {np.max(np.abs(printed)):.3f} "
                    f"(unstable); eq. (30) with d₂ = e^(−ξω_nT_s) gives k_p = {kp_printed:.4g}, "
                    f"with e^(−2ξω_nT_s) k_p = {kp_two:.4f}",
        "reproduced": "2Lf_sΓ on the z term (the derivation) and d₂ = e^(−2ξω_nT_s), the "
                      "only form that gives the printed gains",
    }


def inconsistencies() -> list[dict[str, Any]]:
    """Each inconsistency: id, what the paper prints, what its equations give, which one the
    product reproduces."""
    return [_fig16(), _eq23(), _eq7(), _pi16(), _eq24_d2()]
