"""Current-loop models of the paper: plant (eqs. 4–9), deadbeat (eq. 15), PI (eq. 22) and the
predictive law's linear part (eq. 23), the open loop ``C(z) P(z)``, the mismatched deadbeat closed
loop (eq. 16) and the PI design for a crossover and phase margin.

Units: R, R_c [Ω], L, L_c [H], fs [Hz], PI gains k_p, k_i [V/A]; Gamma [A/V].
"""

from __future__ import annotations

import math
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
from .lti import DiscreteTF
from .pars import CurrentLoopPars

__all__ = [
    "DeadbeatCoefficients",
    "closed_loop_mismatch",
    "controller_tf",
    "current_controller_tf",
    "current_loop_tf",
    "deadbeat_coefficients",
    "disturbance_tf",
    "loop_tf",
    "phi_gamma",
    "pi_current_gains",
    "pi_tf",
    "plant_tf",
    "predictive_tf",
]


def phi_gamma(R: float, L: float, fs: float = FS_DEFAULT) -> tuple[float, float]:
    """ZOH discretisation of the pseudo-current dynamics (eqs. 4–5).

    Args:
        R: phase resistance [Ω], >= 0 (R = 0 gives the limit Phi = 1, Gamma = Ts / (2 L)).
        L: phase inductance [H], > 0.
        fs: sampling frequency [Hz], > 0.

    Returns:
        ``(Phi, Gamma)``: Phi dimensionless, Gamma [A/V].
    """
    R = _non_negative("R", R)
    L = _positive("L", L)
    Ts = 1.0 / _positive("fs", fs)
    x = R * Ts / L
    Phi = math.exp(-x)
    Gamma = Ts / (2.0 * L) if x == 0.0 else -math.expm1(-x) / (2.0 * R)
    return Phi, Gamma


def plant_tf(R: float = R_TABLE2, L: float = L_TABLE2, fs: float = FS_DEFAULT) -> DiscreteTF:
    """``P(z) = Gamma / (z (z - Phi))`` [A/V], eq. (8) (one sample of computational delay)."""
    Phi, Gamma = phi_gamma(R, L, fs)
    return DiscreteTF([Gamma], [1.0, -Phi, 0.0], 1.0 / fs)


def disturbance_tf(R: float = R_TABLE2, L: float = L_TABLE2, fs: float = FS_DEFAULT) -> DiscreteTF:
    """``D(z) = -Gamma / (z - Phi)`` [A/V] from back-EMF e_L to i_p, eq. (9)."""
    Phi, Gamma = phi_gamma(R, L, fs)
    return DiscreteTF([-Gamma], [1.0, -Phi], 1.0 / fs)


@dataclass(frozen=True)
class DeadbeatCoefficients:
    """Deadbeat controller (eq. 15) for the estimates L_c, R_c.

    Difference equation (``e = i_p* - i_p`` [A], ``v`` [V] the computed line voltage)::

        v[k] = v[k-2] + (e[k] - Phi_c e[k-1]) / Gamma_c

    Attributes:
        Phi_c: exp(-R_c Ts / L_c) (dimensionless).
        Gamma_c: (1 - Phi_c) / (2 R_c) [A/V].
        b0, b1: feed-through coefficients 1/Gamma_c and -Phi_c/Gamma_c [V/A].
        tf: the controller as a :class:`DiscreteTF` [V/A].
    """

    Phi_c: float
    Gamma_c: float
    b0: float
    b1: float
    tf: DiscreteTF


def deadbeat_coefficients(
    L_c: float = L_TABLE2, R_c: float = R_TABLE2, fs: float = FS_DEFAULT
) -> DeadbeatCoefficients:
    """Deadbeat (k = 2) controller coefficients, eq. (15), from L_c [H], R_c [Ω], fs [Hz]."""
    Phi_c, Gamma_c = phi_gamma(R_c, L_c, fs)
    tf = DiscreteTF(np.array([1.0, -Phi_c, 0.0]) / Gamma_c, [1.0, 0.0, -1.0], 1.0 / fs)
    return DeadbeatCoefficients(Phi_c, Gamma_c, 1.0 / Gamma_c, -Phi_c / Gamma_c, tf)


def pi_tf(k_p: float = PI_KP_PAPER, k_i: float = PI_KI_PAPER, fs: float = FS_DEFAULT) -> DiscreteTF:
    """``C_PI(z) = k_p + k_i z / (z - 1)`` [V/A], eq. (22)."""
    k_p = _finite("k_p", k_p)
    k_i = _finite("k_i", k_i)
    _positive("fs", fs)
    return DiscreteTF([k_p + k_i, -k_p], [1.0, -1.0], 1.0 / fs)


def predictive_tf(L_c: float = L_TABLE2, fs: float = FS_DEFAULT) -> DiscreteTF:
    """Linear part of the predictive law (eq. 23): ``2 L_c fs z / (z + 1)`` [V/A]."""
    L_c = _positive("L_c", L_c)
    fs = _positive("fs", fs)
    return DiscreteTF([2.0 * L_c * fs, 0.0], [1.0, 1.0], 1.0 / fs)


def current_controller_tf(
    controller: ControllerName = "deadbeat",
    *,
    L_c: float = L_TABLE2,
    R_c: float = R_TABLE2,
    k_p: float = PI_KP_PAPER,
    k_i: float = PI_KI_PAPER,
    fs: float = FS_DEFAULT,
) -> DiscreteTF:
    """The current controller ``C(z)`` [V/A] named ``controller`` (eq. 15, 22 or 23)."""
    return controller_tf(CurrentLoopPars(controller, L_c=L_c, R_c=R_c, k_p=k_p, k_i=k_i, fs=fs))


def controller_tf(p: CurrentLoopPars) -> DiscreteTF:
    """The current controller ``C(z)`` [V/A] of loop ``p`` (eq. 15, 22 or 23)."""
    if p.controller == "deadbeat":
        return deadbeat_coefficients(p.L_c_used, p.R_c_used, p.fs).tf
    if p.controller == "pi":
        return pi_tf(p.k_p, p.k_i, p.fs)
    if p.controller == "predictive":
        return predictive_tf(p.L_c_used, p.fs)
    raise ValueError(
        f"controller must be one of {', '.join(CONTROLLERS)} (got {p.controller!r})"
    )


def loop_tf(p: CurrentLoopPars) -> DiscreteTF:
    """Open loop ``C(z) P(z)`` (dimensionless) of current loop ``p``."""
    return controller_tf(p) * plant_tf(p.R, p.L, p.fs)


def current_loop_tf(
    controller: ControllerName = "deadbeat",
    *,
    R: float = R_TABLE2,
    L: float = L_TABLE2,
    L_c: float | None = None,
    R_c: float | None = None,
    k_p: float = PI_KP_PAPER,
    k_i: float = PI_KI_PAPER,
    fs: float = FS_DEFAULT,
) -> DiscreteTF:
    """Open loop ``C(z) P(z)`` (dimensionless) of the current loop; L_c, R_c default to L, R
    (:func:`loop_tf` of a :class:`~drive_link.workflows.design.CurrentLoopPars`)."""
    return loop_tf(CurrentLoopPars(controller, R, L, L_c, R_c, k_p, k_i, fs))


def closed_loop_mismatch(
    R: float = R_TABLE2,
    L: float = L_TABLE2,
    L_c: float = L_TABLE2,
    R_c: float = R_TABLE2,
    fs: float = FS_DEFAULT,
) -> DiscreteTF:
    """Deadbeat closed loop ``I_p / I_p*`` with mismatched estimates, eq. (16).

    ``((Gamma/Gamma_c) z - Gamma Phi_c/Gamma_c) /
    (z³ - Phi z² + ((Gamma - Gamma_c)/Gamma_c) z + (Gamma_c Phi - Gamma Phi_c)/Gamma_c)``.
    Reduces to ``z^-2`` when L_c = L and R_c = R.
    """
    Phi, Gamma = phi_gamma(R, L, fs)
    Phi_c, Gamma_c = phi_gamma(R_c, L_c, fs)
    g = Gamma / Gamma_c
    num = [g, -g * Phi_c]
    den = [1.0, -Phi, g - 1.0, Phi - g * Phi_c]
    return DiscreteTF(num, den, 1.0 / fs)


def pi_current_gains(
    crossover_hz: float,
    phase_margin_deg: float,
    *,
    R: float = R_TABLE2,
    L: float = L_TABLE2,
    fs: float = FS_DEFAULT,
) -> tuple[float, float]:
    """PI current gains (eq. 22): ``|C P| = 1`` with the given phase margin at ``crossover_hz``.

    Solves ``k_p + k_i z/(z-1) = e^{j(PM - 180°)} / P(z)`` at ``z = e^{j 2π f_c Ts}`` (two real
    equations, two unknowns) with P(z) of eq. (8).

    Args:
        crossover_hz: gain-crossover frequency f_c [Hz], 0 < f_c < fs/2.
        phase_margin_deg: phase margin [°], 0 < PM < 180.
        R, L: motor resistance [Ω] and inductance [H]; fs: sampling frequency [Hz].

    Returns:
        ``(k_p, k_i)`` [V/A]. Raises ValueError when the spec needs k_p < 0 or k_i <= 0 (a PI
        cannot add phase: the spec is beyond what the plant allows).
    """
    fs = _positive("fs", fs)
    fc = _positive("crossover_hz", crossover_hz)
    if fc >= fs / 2.0:
        raise ValueError(f"crossover_hz must be below fs/2 = {fs / 2.0:g} Hz (got {fc:g})")
    pm = _finite("phase_margin_deg", phase_margin_deg)
    if not 0.0 < pm < 180.0:
        raise ValueError(f"phase_margin_deg must be in (0, 180) (got {pm:g})")
    z = np.exp(2j * math.pi * fc / fs)
    P = plant_tf(R, L, fs)(z)
    target = np.exp(1j * math.radians(pm - 180.0)) / P
    q = z / (z - 1.0)
    k_i = float(target.imag / q.imag)
    k_p = float(target.real - k_i * q.real)
    if k_i <= 0.0 or k_p < 0.0:
        raise ValueError(
            f"a PI cannot reach {pm:g}° phase margin at {fc:g} Hz on this plant "
            f"(needs k_p = {k_p:.4g}, k_i = {k_i:.4g}); lower the crossover or the margin"
        )
    return k_p, k_i
