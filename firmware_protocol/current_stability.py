"""Admissibility rule for a current-controller gain set (0x2010, staged 0x20F0 + 0x20F1).

Valle et al. 2020: plant eq. (3) with the one-sample computation delay of eqs. (6)-(8),
``P(z) = Gamma / (z (z - Phi))``, ``Phi = exp(-R Ts / L)``, ``Gamma = (1 - Phi) / (2 R)``, built
from the drive's stored motor parameters ``motor.L`` and ``motor.R`` (on the DSP they are only
stored parameters, written with the power stage off). The closed-loop characteristic
polynomials are

- deadbeat, eq. (15) with the estimates L_c, R_c (``Phi_c``, ``Gamma_c``):
  ``z^3 - Phi z^2 + (Gamma/Gamma_c - 1) z + Phi - (Gamma/Gamma_c) Phi_c`` (for R_c = 0,
  ``Phi_c = 1``, the law's zero cancels its integrator: ``z^2 + (1 - Phi) z + Gamma/Gamma_c -
  Phi``);
- PI, eq. (22) ``C(z) = k_p + k_i z / (z - 1)``:
  ``z^3 - (1 + Phi) z^2 + (Phi + Gamma (k_p + k_i)) z - Gamma k_p``;
- predictive, eq. (23)/(25) ``C(z) = 2 L_c f_s z / (z + 1)``:
  ``z^2 + (1 - Phi) z + 2 L_c f_s Gamma - Phi``.

With R -> 0 the deadbeat and predictive polynomials both reduce to ``z^2 - 1 + L_c/L`` (after
cancelling z = 1 resp. z = 0): poles ``+-sqrt(1 - L_c/L)``, stable for 0 < L_c < 2 L (eq. 17).
A gain set is accepted only if

1. every closed-loop pole lies inside ``|z| < rho`` (below),
   ``RHO_MAX = exp(-Ts / TAU_MAX_CURRENT)`` (Schur-Cohn test on ``p(rho w)``): stable, and no
   slower than 5 ms (at least ~90 times faster than the IP speed loop's 0.43 s the cascade
   design assumes) or than twice a time constant the law itself contains, if longer: the
   motor's L/R (the deadbeat law cancels the plant pole Phi; 2.4 ms at the default motor) and,
   for the deadbeat law, L_c/R_c (its integral action acts through its zero at Phi_c, slow for
   a small R_c; R_c = 0 has none):
   ``rho = max(RHO_MAX, exp(-R Ts / (2 L)), exp(-R_c Ts / (2 L_c)))``. For deadbeat and
   predictive control this is ``~0.008 < L_c / L < ~1.992``; for PI it bounds k_p, k_i (the
   paper's k_p = 0.4647, k_i = 0.0492 have |p| <= 0.84);
2. a law without integral action has the back-EMF feed-forward on: predictive control (type 2;
   eq. (24) has no zero at z = 1, the back-EMF becomes a steady current error
   ``e_L / (L_c f_s)``; paper: "the predictive controller cannot be implemented without
   feed-forward action"; at L_c = 0.2 L the drive held only 649 of 1000 rpm) and deadbeat
   control with R_c = 0 (Phi_c = 1: the zero of eq. 15 cancels its integrator, the same law;
   at L_c = 0.27 L the speed sagged to 828 rpm at the current limit) and, as such a law
   leaves ``dV / (L_c f_s + 2 R)`` of current error for any unmodelled voltage ``dV`` (the
   back-EMF estimate's error, inverter drops), ``L_c >= NO_INTEGRAL_MIN_RATIO L`` = 0.5 L, the
   lower end of the paper's Table 1 range (deadbeat, R_c = 0, L_c = 0.22 L with the
   feed-forward ran away to 1272 rpm at 1000 rpm demanded);
3. predictive control: the non-ideality compensation of eq. (25) (estimates T_BT, T_DD, T_SD,
   V_G) shifts the current by at most ``COMP_MAX_SHARE`` (10 %) of motor.rated_current if the
   estimates are entirely wrong (an ideal inverter). Eq. (25) has no integral action, so a
   compensation voltage ``dV`` (per sample) leaves ``dV / (L_c f_s + 2 R)`` of current error;
   ``dV = 2 T_BT f_s V_dc + 2 V_G + (T_DD + T_SD) f_s e_L / 2`` with ``V_dc`` and ``e_L`` bounded
   by motor.V_dc_nominal. (T_BT = 7.2 us, T_DD + T_SD = 12.7 us at L_c = 0.2 L: bound 310 A;
   on the virtual drive i_p reached 141 A, overcurrent trip.) The other types do not use them.

REAL32 values are rounded to float32 first (as the drive stores them); the test is evaluated
in float64. Abort codes: 0x06090031 poles outside ``|z| = 1`` or compensation too large (a
value too high), 0x06090032 stable but too slow (a gain too low), 0x06090030 a law without
integral action without the feed-forward.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from .entry import (
    ABORT_INVALID_VALUE,
    ABORT_VALUE_TOO_HIGH,
    ABORT_VALUE_TOO_LOW,
    LimitError,
    f32,
)
from .enums import CONTROLLER_NAMES, ControllerType
from .stability import TS

__all__ = [
    "COMP_MAX_SHARE",
    "CURRENT_KEYS",
    "MOTOR_KEYS",
    "NO_INTEGRAL_MIN_RATIO",
    "RHO_MAX",
    "TAU_MAX_CURRENT",
    "cascade_characteristic",
    "check_cascade",
    "check_current_gains",
    "compensation_current_error",
    "current_loop_characteristic",
    "current_loop_poles",
    "schur_stable",
]

TAU_MAX_CURRENT = 5e-3
"""Slowest closed-loop time constant of the current loop the drive accepts (s)."""
RHO_MAX = math.exp(-TS / TAU_MAX_CURRENT)
"""Largest admissible closed-loop pole magnitude (1 per sample), 0.996008."""
COMP_MAX_SHARE = 0.1
NO_INTEGRAL_MIN_RATIO = 0.5
"""Least L_c / L of a law without integral action (predictive; deadbeat with R_c = 0)."""
"""Largest current error (share of motor.rated_current) eq. (25)'s compensation may cause."""

CURRENT_KEYS = (
    "type",
    "L_c",
    "R_c",
    "k_p",
    "k_i",
    "T_BT",
    "T_DD",
    "T_SD",
    "V_G",
    "emf_feedforward",
)
"""Sub-indices 1..10 of 0x2010 (and 0x20F0:1..10) in order."""
MOTOR_KEYS = ("R", "L", "rated_current", "V_dc_nominal")
"""The motor.* objects (0x2000) the rule reads."""


def _zoh(R: float, L: float, Ts: float) -> tuple[float, float]:
    """``(Phi, Gamma)`` of eqs. (4), (5), Gamma in A/V, without cancellation for small R."""
    x = -R * Ts / L
    phi = math.exp(x)
    gamma = Ts / (2.0 * L) * (math.expm1(x) / x if x != 0.0 else 1.0)
    return phi, gamma


def current_loop_characteristic(
    g: Mapping[str, float], L: float, R: float, Ts: float = TS
) -> list[float]:
    """Closed-loop characteristic polynomial (highest power first) for gain set ``g``
    (keys :data:`CURRENT_KEYS`) on the motor ``L`` (H), ``R`` (Ohm)."""
    phi, gamma = _zoh(R, L, Ts)
    kind = int(g["type"])
    if kind == 0:
        phi_c, gamma_c = _zoh(float(g["R_c"]), float(g["L_c"]), Ts)
        r = gamma / gamma_c
        if phi_c == 1.0:  # R_c = 0: the law's zero at z = 1 cancels its integrator pole
            return [1.0, 1.0 - phi, r - phi]  # cubic / (z - 1)
        return [1.0, -phi, r - 1.0, phi - r * phi_c]
    if kind == 1:
        k_p, k_i = float(g["k_p"]), float(g["k_i"])
        return [1.0, -(1.0 + phi), phi + gamma * (k_p + k_i), -gamma * k_p]
    if kind == 2:
        return [1.0, 1.0 - phi, 2.0 * float(g["L_c"]) / Ts * gamma - phi]
    raise LimitError(ABORT_INVALID_VALUE, f"current controller type {kind} not in 0..2")


def current_loop_poles(
    g: Mapping[str, float], L: float, R: float, Ts: float = TS
) -> list[complex]:
    """The closed-loop poles (roots of :func:`current_loop_characteristic`)."""
    return [complex(p) for p in np.roots(current_loop_characteristic(g, L, R, Ts))]


def schur_stable(coeffs: Sequence[float], rho: float = 1.0) -> bool:
    """True if every root of the real polynomial ``coeffs`` (highest power first) lies strictly
    inside ``|z| < rho`` (Schur-Cohn-Jury reduction on ``p(rho w)``; no root finder)."""
    n = len(coeffs) - 1
    c = [float(a) * rho ** (n - i) for i, a in enumerate(coeffs)]
    if not all(math.isfinite(a) for a in c) or c[0] == 0.0:
        return False
    while len(c) > 1:
        c = [a / c[0] for a in c]
        if abs(c[-1]) >= 1.0:
            return False
        m = len(c) - 1
        c = [c[i] - c[-1] * c[m - i] for i in range(m)]
    return True


def compensation_current_error(
    g: Mapping[str, float], R: float, V_dc: float, Ts: float = TS
) -> float:
    """Steady current error (A) eq. (25)'s compensation causes on an ideal inverter, with the
    DC link and the back-EMF at ``V_dc`` (V); 0 for the types that do not use it."""
    if int(g["type"]) != 2:
        return 0.0
    fs = 1.0 / Ts
    dV = (
        2.0 * float(g["T_BT"]) * fs * V_dc
        + 2.0 * float(g["V_G"])
        + 0.5 * (float(g["T_DD"]) + float(g["T_SD"])) * fs * V_dc
    )
    return dV / (float(g["L_c"]) * fs + 2.0 * R)


def check_current_gains(
    g: Mapping[str, float], motor: Mapping[str, float], Ts: float = TS
) -> None:
    """Raise :class:`LimitError` unless gain set ``g`` (keys :data:`CURRENT_KEYS`: L_c H, R_c
    Ohm, k_p/k_i V/A, T_* s, V_G V) is admissible on ``motor`` (keys :data:`MOTOR_KEYS`: R Ohm,
    L H, rated_current A, V_dc_nominal V). See the module docstring for the rule."""
    ints = ("type", "emf_feedforward")
    g = {k: (int(v) if k in ints else f32(float(v))) for k, v in g.items()}
    L, R = f32(float(motor["L"])), f32(float(motor["R"]))
    if not all(math.isfinite(float(v)) for v in g.values()) or not (L > 0.0 and R >= 0.0):
        raise LimitError(ABORT_INVALID_VALUE, "current gains and motor.L/R must be finite")
    kind = int(g["type"])
    if kind in (0, 2) and not g["L_c"] > 0.0:
        raise LimitError(ABORT_VALUE_TOO_LOW, "L_c must be > 0")
    poly = current_loop_characteristic(g, L, R, Ts)
    rho = max(RHO_MAX, math.exp(-R * Ts / (2.0 * L)))
    if kind == 0 and g["R_c"] > 0.0:
        rho = max(rho, math.exp(-g["R_c"] * Ts / (2.0 * g["L_c"])))
    if not schur_stable(poly, rho):
        radius = max(abs(p) for p in current_loop_poles(g, L, R, Ts))
        what = "PI" if kind == ControllerType.PI else CONTROLLER_NAMES[kind]
        detail = (
            f"L_c/L = {g['L_c'] / L:.4g}"
            if kind != 1
            else f"k_p = {g['k_p']:g} V/A, k_i = {g['k_i']:g} V/A"
        )
        if radius >= 1.0 or not schur_stable(poly, 1.0):
            raise LimitError(
                ABORT_VALUE_TOO_HIGH,
                f"{what} current loop unstable ({detail}, largest |pole| {radius:.6f})",
            )
        raise LimitError(
            ABORT_VALUE_TOO_LOW,
            f"{what} current loop too slow ({detail}, largest |pole| {radius:.6f} > "
            f"{rho:.6f}: time constant > max({TAU_MAX_CURRENT * 1e3:g} ms, 2 L/R))",
        )
    if (kind == 2 or (kind == 0 and g["R_c"] == 0.0)) and not g["emf_feedforward"]:
        what = "predictive control (eq. 25)" if kind == 2 else "deadbeat control with R_c = 0"
        raise LimitError(
            ABORT_INVALID_VALUE,
            f"{what} has no integral action and needs the back-EMF feed-forward "
            "(emf_feedforward = 1): without it the back-EMF is a steady current error",
        )
    if (kind == 2 or (kind == 0 and g["R_c"] == 0.0)) and g["L_c"] < NO_INTEGRAL_MIN_RATIO * L:
        raise LimitError(
            ABORT_VALUE_TOO_LOW,
            f"a law without integral action needs L_c >= {NO_INTEGRAL_MIN_RATIO:g} L "
            f"(L_c/L = {g['L_c'] / L:.3g}): any unmodelled voltage dV leaves dV / (L_c f_s + 2 R)"
            " of current error",
        )
    if kind == 2:
        err = compensation_current_error(g, R, f32(float(motor["V_dc_nominal"])), Ts)
        limit = COMP_MAX_SHARE * f32(float(motor["rated_current"]))
        if not err <= limit:
            raise LimitError(
                ABORT_VALUE_TOO_HIGH,
                f"eq. (25) compensation (T_BT, T_DD, T_SD, V_G) may shift the current by "
                f"{err:.3g} A > {COMP_MAX_SHARE:.0%} of rated current ({limit:.3g} A)",
            )


def _current_loop_tf(
    g: Mapping[str, float], L: float, R: float, Ts: float = TS
) -> tuple[np.ndarray, np.ndarray]:
    """``(N_L, D_L)`` of the current open loop C(z) P(z) (highest power first); the closed
    current loop i_p / i_p* is ``N_L / (D_L + N_L)``."""
    phi, gamma = _zoh(R, L, Ts)
    kind = int(g["type"])
    if kind == 0:
        phi_c, gamma_c = _zoh(float(g["R_c"]), float(g["L_c"]), Ts)
        if phi_c == 1.0:  # the zero at z = 1 cancels the integrator (see above)
            c_num, c_den = np.array([1.0, 0.0]) / gamma_c, np.array([1.0, 1.0])
        else:
            c_num, c_den = np.array([1.0, -phi_c, 0.0]) / gamma_c, np.array([1.0, 0.0, -1.0])
    elif kind == 1:
        k_p, k_i = float(g["k_p"]), float(g["k_i"])
        c_num, c_den = np.array([k_p + k_i, -k_p]), np.array([1.0, -1.0])
    else:
        c_num, c_den = np.array([2.0 * float(g["L_c"]) / Ts, 0.0]), np.array([1.0, 1.0])
    return c_num * gamma, np.polymul(c_den, [1.0, -phi, 0.0])


def cascade_characteristic(
    g: Mapping[str, float],
    L: float,
    R: float,
    k_p: float,
    k_i: float,
    a: float | None = None,
    b: float | None = None,
    Ts: float = TS,
) -> np.ndarray:
    """Characteristic polynomial of the IP speed loop (eq. 27, speed model ``b / (z - a)``)
    around the closed current loop of gain set ``g``:
    ``(z - 1)(z - a)(D_L + N_L) + k_p b ((1 + k_i) z - 1) N_L`` (k_p A/rpm, k_i 1/sample)."""
    from .stability import A_IDENTIFIED, B_IDENTIFIED

    a = A_IDENTIFIED if a is None else a
    b = B_IDENTIFIED if b is None else b
    n_l, d_l = _current_loop_tf(g, L, R, Ts)
    closed = np.polyadd(d_l, n_l)
    left = np.polymul(np.polymul([1.0, -1.0], [1.0, -a]), closed)
    right = np.polymul(k_p * b * np.array([1.0 + k_i, -1.0]), n_l)
    return np.polyadd(left, right)


def check_cascade(
    g: Mapping[str, float], motor: Mapping[str, float], k_p: float, k_i: float, Ts: float = TS
) -> None:
    """Raise :class:`LimitError` unless the speed loop (k_p A/rpm, k_i 1/sample) is stable
    around the current loop ``g`` on ``motor`` (keys as :func:`check_current_gains`).

    :func:`firmware_protocol.stability.check_ip_speed_gains` assumes an ideal current loop
    (i_p = i_p*); a fast speed loop around a slow current loop is not (k_p = 68.8 A/rpm,
    k_i = 1 around a deadbeat loop with L_c = 1.2e-8 H: overcurrent trip). Every closed-loop
    pole of the cascade must lie inside ``|z| <= exp(-Ts / TAU_MAX)`` (10 s, the speed rule's
    bound); abort 0x06090031 otherwise.
    """
    from .stability import TAU_MAX

    ints = ("type", "emf_feedforward")
    g = {k: (int(v) if k in ints else f32(float(v))) for k, v in g.items()}
    L, R = f32(float(motor["L"])), f32(float(motor["R"]))
    poly = cascade_characteristic(g, L, R, f32(float(k_p)), f32(float(k_i)), Ts=Ts)
    radius = float(max(abs(np.roots(poly)))) if np.all(np.isfinite(poly)) else math.inf
    if not radius <= math.exp(-Ts / TAU_MAX):
        raise LimitError(
            ABORT_VALUE_TOO_HIGH,
            f"speed loop (k_p = {k_p:g} A/rpm, k_i = {k_i:g}) unstable around this current "
            f"loop (largest cascade |pole| {radius:.7f})",
        )
