"""Predicted current-loop step responses (linear model, eq. 6 with the one-sample delay) and
the predictive law's non-ideality compensation (eq. 25).

Units: currents [A], voltages [V], times [s], R [Ω], L [H], fs [Hz].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ._common import (
    CONTROLLERS,
    FS_DEFAULT,
    L_TABLE2,
    PI_KI_PAPER,
    PI_KP_PAPER,
    R_TABLE2,
    ControllerName,
    _finite,
    _non_negative,
    _positive,
)
from .current_loop import phi_gamma
from .pars import CurrentLoopPars

__all__ = ["PredictedStep", "eq25_compensation", "predict_step", "predicted_step"]


def _controller_parts(
    controller: ControllerName,
    L_c: float,
    R_c: float,
    k_p: float,
    k_i: float,
    fs: float,
    feedforward: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Controller ``u = (N_eps eps + N_e e_L + N_c v_comp) / den`` (same monic denominator)."""
    if controller == "deadbeat":
        Phi_c, Gamma_c = phi_gamma(R_c, L_c, fs)
        den = np.array([1.0, 0.0, -1.0])
        n_eps = np.array([1.0, -Phi_c, 0.0]) / Gamma_c
        n_e = den.copy() if feedforward else np.zeros(3)
        n_c = np.zeros(3)
    elif controller == "pi":
        den = np.array([1.0, -1.0])
        n_eps = np.array([k_p + k_i, -k_p])
        n_e = den.copy() if feedforward else np.zeros(2)
        n_c = np.zeros(2)
    elif controller == "predictive":
        # v(k+1) = 2 L_c fs (i* - i(k)) - v(k) + 2 e_L(k) [+ eq. 25 terms]:  u (1 + z^-1) = ...
        den = np.array([1.0, 1.0])
        n_eps = np.array([2.0 * _positive("L_c", L_c) * fs, 0.0])
        n_e = np.array([2.0, 0.0]) if feedforward else np.zeros(2)
        n_c = np.array([1.0, 0.0])
    else:
        raise ValueError(f"controller must be one of {', '.join(CONTROLLERS)} (got {controller!r})")
    return den, n_eps, n_e, n_c


def _observer_form(
    den: np.ndarray, nums: Sequence[np.ndarray]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Observer-canonical realisation of ``[N_1 … N_p] / den`` (proper, monic ``den``)."""
    m = den.size - 1
    A = np.zeros((m, m))
    A[:, 0] = -den[1:]
    A[: m - 1, 1:] += np.eye(m - 1)
    B = np.zeros((m, len(nums)))
    D = np.zeros(len(nums))
    for j, n in enumerate(nums):
        n = np.pad(np.asarray(n, dtype=float), (m + 1 - len(n), 0))
        D[j] = n[0]
        B[:, j] = n[1:] - den[1:] * n[0]
    C = np.zeros(m)
    C[0] = 1.0
    return A, B, C, D


@dataclass(frozen=True)
class PredictedStep:
    """Sample-by-sample linear prediction of a current-loop reference step.

    Attributes:
        t: time [s] from the step (t[0] = 0 is the sample at which i_p* changes).
        i_p: pseudo current [A] sampled at t.
        i_p_ref: reference [A] (i_final for every sample).
        v_L: line voltage applied by the inverter during each sample [V] (the previous output).
        u: controller output computed at each sample [V].
        stable: closed-loop poles inside the unit circle.
        i_p_final: equilibrium of i_p for the new reference [A] (what a stable loop settles to;
            i_final for the deadbeat and PI laws, which have integral action).
        max_pole_radius: largest closed-loop pole magnitude (settling ∝ radius^k).
    """

    t: np.ndarray
    i_p: np.ndarray
    i_p_ref: np.ndarray
    v_L: np.ndarray
    u: np.ndarray
    stable: bool
    i_p_final: float = math.nan
    max_pole_radius: float = math.nan


def predicted_step(
    controller: ControllerName = "deadbeat",
    *,
    n_samples: int = 100,
    i_start: float = 15.0,
    i_final: float = 20.0,
    R: float = R_TABLE2,
    L: float = L_TABLE2,
    L_c: float | None = None,
    R_c: float | None = None,
    k_p: float = PI_KP_PAPER,
    k_i: float = PI_KI_PAPER,
    fs: float = FS_DEFAULT,
    e_L: float = 0.0,
    feedforward: bool = False,
    v_loss: float = 0.0,
    v_comp: float = 0.0,
    e_L_final: float | None = None,
) -> PredictedStep:
    """Predicted response of i_p to a reference step i_start → i_final (linear model, eq. 6).

    The plant is eq. (6) with the one-sample computational delay:
    ``i_p[k+1] = Phi i_p[k] + Gamma (v_L[k] - e_L - v_loss)``, ``v_L[k+1] = u[k]``, where ``u`` is
    the deadbeat (eq. 15), PI (eq. 22) or predictive (eq. 23/25) law using the estimates L_c, R_c.
    The loop starts at its exact equilibrium for reference i_start (so a loop without integral
    action starts with its steady-state error) and the reference steps at sample 0.

    Args:
        controller: "deadbeat", "pi" or "predictive".
        n_samples: samples to predict (>= 1), each Ts = 1/fs [s].
        i_start, i_final: reference before / after the step [A].
        R, L: true motor resistance [Ω] and inductance [H]; L_c, R_c: controller estimates
            (default: equal to R, L).
        k_p, k_i: PI gains [V/A] (PI only).
        fs: sampling frequency [Hz].
        e_L: constant line back-EMF [V] (disturbance, eq. 9).
        feedforward: add the exact back-EMF feed-forward (Fig. 3; the ``2 e_L(k)`` term of eq. 23
            for the predictive law). Default False, like the drive's
            ``current_controller.emf_feedforward`` default; eq. (23) as printed needs True.
        v_loss: constant voltage lost in the inverter (blanking time, switch drops) [V].
        v_comp: the predictive law's non-ideality compensation term of eq. (25) [V]
            (see :func:`eq25_compensation`); predictive only.
        e_L_final: back-EMF after sample 0 [V] (default e_L): a back-EMF step, e.g. to see the
            disturbance response of eq. (12)/(21) with i_start = i_final.

    Returns:
        :class:`PredictedStep` (float64 arrays of length n_samples).
    """
    return predict_step(
        CurrentLoopPars(controller, R, L, L_c, R_c, k_p, k_i, fs),
        n_samples=n_samples,
        i_start=i_start,
        i_final=i_final,
        e_L=e_L,
        feedforward=feedforward,
        v_loss=v_loss,
        v_comp=v_comp,
        e_L_final=e_L_final,
    )


def predict_step(
    p: CurrentLoopPars,
    *,
    n_samples: int = 100,
    i_start: float = 15.0,
    i_final: float = 20.0,
    e_L: float = 0.0,
    feedforward: bool = False,
    v_loss: float = 0.0,
    v_comp: float = 0.0,
    e_L_final: float | None = None,
) -> PredictedStep:
    """:func:`predicted_step` of current loop ``p`` (the other arguments as there)."""
    controller, R, L, fs = p.controller, p.R, p.L, p.fs
    k_p, k_i = p.k_p, p.k_i
    n = int(n_samples)
    if n < 1:
        raise ValueError(f"n_samples must be >= 1 (got {n_samples!r})")
    for name, v in (("i_start", i_start), ("i_final", i_final), ("e_L", e_L)):
        _finite(name, v)
    _finite("v_loss", v_loss)
    _finite("v_comp", v_comp)
    if v_comp != 0.0 and controller != "predictive":
        raise ValueError("v_comp (eq. 25) applies to the predictive controller only")
    L_c, R_c = p.L_c_used, p.R_c_used
    Phi, Gamma = phi_gamma(R, L, fs)
    ff = bool(feedforward)
    den, n_eps, n_e, n_c = _controller_parts(controller, L_c, R_c, k_p, k_i, fs, ff)
    Ac, Bc, Cc, Dc = _observer_form(den, [n_eps, n_e, n_c])
    m = Ac.shape[0]
    # state X = [i_p, v_L(applied), x_c]; inputs w = [i_ref, e_L, v_loss, v_comp]
    A = np.zeros((2 + m, 2 + m))
    Bw = np.zeros((2 + m, 4))
    A[0, 0], A[0, 1] = Phi, Gamma
    Bw[0, 1], Bw[0, 2] = -Gamma, -Gamma
    # u = Cc x_c + Dc[0] (r - i) + Dc[1] e + Dc[2] c
    A[1, 0] = -Dc[0]
    A[1, 2:] = Cc
    Bw[1, 0], Bw[1, 1], Bw[1, 3] = Dc[0], Dc[1], Dc[2]
    A[2:, 0] = -Bc[:, 0]
    A[2:, 2:] = Ac
    Bw[2:, 0], Bw[2:, 1], Bw[2:, 3] = Bc[:, 0], Bc[:, 1], Bc[:, 2]
    w0 = np.array([i_start, e_L, v_loss, v_comp], dtype=float)
    e1 = e_L if e_L_final is None else _finite("e_L_final", e_L_final)
    w1 = np.array([i_final, e1, v_loss, v_comp], dtype=float)
    eye = np.eye(2 + m)
    try:
        X = np.linalg.solve(eye - A, Bw @ w0)
    except np.linalg.LinAlgError:  # closed-loop pole exactly at z = 1: start from rest
        X = np.zeros(2 + m)
    radius = float(np.max(np.abs(np.linalg.eigvals(A))))
    stable = radius < 1.0
    try:
        i_p_final = float(np.linalg.solve(eye - A, Bw @ w1)[0])
    except np.linalg.LinAlgError:
        i_p_final = math.nan
    bw1 = Bw @ w1
    i_p = np.empty(n)
    v_L = np.empty(n)
    u = np.empty(n)
    for k in range(n):
        i_p[k] = X[0]
        v_L[k] = X[1]
        u[k] = Cc @ X[2:] + Dc[0] * (i_final - X[0]) + Dc[1] * e1 + Dc[2] * v_comp
        X = A @ X + bw1
    t = np.arange(n) / fs
    return PredictedStep(t, i_p, np.full(n, float(i_final)), v_L, u, stable, i_p_final, radius)


def eq25_compensation(
    *,
    T_BT: float = 0.0,
    T_DD: float = 0.0,
    T_SD: float = 0.0,
    V_G: float = 0.0,
    V_dc: float = 48.0,
    E_L: float = 0.0,
    fs: float = FS_DEFAULT,
) -> float:
    """Non-ideality compensation term of the predictive law, eq. (25) [V].

    ``4 T_BT V_dc / Ts + E_L (T_DD + T_SD) fs + 4 V_G`` with times in s, voltages in V.
    """
    for name, v in (("T_BT", T_BT), ("T_DD", T_DD), ("T_SD", T_SD), ("V_G", V_G)):
        _non_negative(name, v)
    fs = _positive("fs", fs)
    return 4.0 * T_BT * V_dc * fs + _finite("E_L", E_L) * (T_DD + T_SD) * fs + 4.0 * V_G
