"""Stability rules on gain sets that limits and cross-object constraints cannot express.

IP speed loop (Valle et al. 2020, eq. 27): on the identified speed model
``G(z) = b / (z - a)`` (n in rpm, i_p in A, one loop sample Ts = 20 µs) the IP law
``i_p* = k_p (k_i x - n)``, ``x[k] = x[k-1] + (n* - n)`` gives the closed-loop characteristic
polynomial

    z² + d_1 z + d_2,   d_1 = k_p b (1 + k_i) - 1 - a,   d_2 = a - k_p b,

(the same d_1, d_2 as the pole placement of eqs. 28-31). The drive accepts a pair (k_p, k_i)
only if

- k_p > 0 and k_i > 0 (an IP law: without k_i there is no integral action, the pole sits at
  z = 1; k_p = 0 opens the loop), and
- Jury's conditions hold for the second-order polynomial: ``A(1) = k_p k_i b > 0``,
  ``A(-1) = 2 (1 + a) - k_p b (2 + k_i) > 0`` and ``|d_2| < 1``, i.e. both poles strictly
  inside the unit circle, and
- the slowest pole is not slower than :data:`TAU_MAX` (10 s): ``|p| <= exp(-Ts / TAU_MAX)``,
- a complex pair is damped at least :data:`ZETA_MIN` (0.3): ``zeta = -ln|p| / |ln p|``
  (the continuous-equivalent damping of ``s = ln(p) / Ts``). A stable but lightly damped pair
  (k_p = 1e-4 A/rpm, k_i = 0.68: zeta = 0.07, a 1.2 Hz ring decaying in 1.9 s) let the speed
  sag to 660 rpm after an ordinary gain change at 1000 rpm; the paper's IP design is
  overdamped ("no overshoot").
  A loop slower than that does not regulate speed (the paper's gains give 0.43 s; eq. 30 needs
  poles faster than the plant's 0.93 s for k_p > 0), and closer to z = 1 no float64 root finder
  can tell stable from unstable.

The gains are rounded to float32 first (as the drive stores them) and the rule is evaluated in
float64 on the polynomial shifted to w = z - 1, whose coefficients ``2 + d_1 = k_p b (1 + k_i) +
(1 - a)`` and ``1 + d_1 + d_2 = k_p k_i b`` carry no cancellation, so poles within 1e-5 of z = 1
are placed exactly. Abort codes: 0x06090032 for a gain that is not positive or a loop slower than
TAU_MAX (gains too low), 0x06090031 for a pair the Jury test refuses (gains far above the
paper's).
"""

from __future__ import annotations

import math

from . import paper
from .entry import ABORT_VALUE_TOO_HIGH, ABORT_VALUE_TOO_LOW, LimitError, f32

__all__ = [
    "A_IDENTIFIED",
    "B_IDENTIFIED",
    "TAU_MAX",
    "TS",
    "ZETA_MIN",
    "check_ip_speed_gains",
    "ip_characteristic",
    "ip_damping",
    "ip_poles",
    "ip_slowest_pole_margin",
]

TS = paper.TS
"""Loop sample time (s), 50 kHz."""
A_IDENTIFIED = paper.A_IDENTIFIED
"""Identified speed-model pole a (1 per sample), eq. (26)."""
B_IDENTIFIED = paper.B_IDENTIFIED
"""Identified speed-model gain b (rpm/A per sample), eq. (26)."""
TAU_MAX = 10.0
"""Slowest closed-loop time constant the IP rule accepts (s)."""
ZETA_MIN = 0.3
"""Least damping ratio of a complex closed-loop pole pair the IP rule accepts."""


def ip_damping(
    k_p: float, k_i: float, a: float = A_IDENTIFIED, b: float = B_IDENTIFIED
) -> float:
    """Damping ratio ``-ln|p| / |ln p|`` of the closed-loop pair (1.0 for real poles),
    evaluated in the shifted form ``w = z - 1`` (no cancellation near z = 1)."""
    kb = k_p * b
    B = kb * (1.0 + k_i) + (1.0 - a)
    C = kb * k_i
    disc = B * B - 4.0 * C
    if disc >= 0.0:
        return 1.0
    one_minus_d2 = (1.0 - a) + kb  # 1 - |p|^2
    ln_r = 0.5 * math.log1p(-one_minus_d2)
    theta = math.atan2(math.sqrt(-disc) / 2.0, 1.0 - B / 2.0)
    return -ln_r / math.hypot(ln_r, theta)


def ip_characteristic(
    k_p: float, k_i: float, a: float = A_IDENTIFIED, b: float = B_IDENTIFIED
) -> tuple[float, float, float]:
    """Coefficients ``(1, d_1, d_2)`` of the IP loop's characteristic polynomial (eq. 27)."""
    return 1.0, k_p * b * (1.0 + k_i) - 1.0 - a, a - k_p * b


def ip_poles(
    k_p: float, k_i: float, a: float = A_IDENTIFIED, b: float = B_IDENTIFIED
) -> tuple[complex, complex]:
    """The two closed-loop poles (roots of :func:`ip_characteristic`)."""
    _, d1, d2 = ip_characteristic(k_p, k_i, a, b)
    disc = complex(d1 * d1 - 4.0 * d2) ** 0.5
    return (-d1 + disc) / 2.0, (-d1 - disc) / 2.0


def ip_slowest_pole_margin(
    k_p: float, k_i: float, a: float = A_IDENTIFIED, b: float = B_IDENTIFIED
) -> float:
    """``1 - |p|`` of the slowest closed-loop pole, computed without cancellation (> 0: inside).

    Complex pair: ``|p|^2 = d_2``, so ``1 - |p| = (1 - d_2) / (1 + |p|)``. Real poles: roots
    ``w`` of ``w^2 + B w + C`` (``z = 1 + w``), ``B = k_p b (1 + k_i) + (1 - a)``,
    ``C = k_p k_i b``; the one nearest 0 is ``-2 C / (B + sqrt(B^2 - 4 C))``."""
    kb = k_p * b
    B = kb * (1.0 + k_i) + (1.0 - a)
    C = kb * k_i
    disc = B * B - 4.0 * C
    if disc < 0.0:
        d2 = a - kb
        one_minus_d2 = (1.0 - a) + kb
        return one_minus_d2 / (1.0 + math.sqrt(max(d2, 0.0)))
    root = math.sqrt(disc)
    if B > 0.0:
        w_near = -2.0 * C / (B + root)
        w_far = (-B - root) / 2.0
    else:
        w_near = (-B + root) / 2.0
        w_far = 2.0 * C / (-B + root) if root != B else 0.0
    return min(1.0 - abs(1.0 + w_near), 1.0 - abs(1.0 + w_far))


def check_ip_speed_gains(
    k_p: float, k_i: float, a: float = A_IDENTIFIED, b: float = B_IDENTIFIED
) -> None:
    """Raise :class:`LimitError` unless (k_p, k_i) is a stable IP pair on G(z) = b/(z - a).

    ``k_p`` in A/rpm, ``k_i`` in 1/sample (the units of 0x2020:1/2).
    """
    k_p, k_i = f32(float(k_p)), f32(float(k_i))
    if not (math.isfinite(k_p) and math.isfinite(k_i)):
        raise LimitError(ABORT_VALUE_TOO_HIGH, "IP gains must be finite")
    if k_p <= 0.0 or k_i <= 0.0:
        raise LimitError(
            ABORT_VALUE_TOO_LOW,
            f"IP speed loop needs k_p > 0 and k_i > 0 (k_p = {k_p:g} A/rpm, k_i = {k_i:g})",
        )
    kb = k_p * b
    a_at_1 = kb * k_i  # A(1) = 1 + d_1 + d_2, without cancellation
    a_at_m1 = 2.0 * (1.0 + a) - kb * (2.0 + k_i)  # A(-1) = 1 - d_1 + d_2
    d2 = a - kb
    if not (a_at_1 > 0.0 and a_at_m1 > 0.0 and abs(d2) < 1.0):
        poles = ", ".join(f"{abs(p):.9f}" for p in ip_poles(k_p, k_i, a, b))
        raise LimitError(
            ABORT_VALUE_TOO_HIGH,
            f"IP speed loop unstable for k_p = {k_p:g} A/rpm, k_i = {k_i:g} (|poles| {poles})",
        )
    margin = ip_slowest_pole_margin(k_p, k_i, a, b)
    if margin < -math.expm1(-TS / TAU_MAX):
        tau = TS / -math.log1p(-margin) if 0.0 < margin < 1.0 else math.inf
        raise LimitError(
            ABORT_VALUE_TOO_LOW,
            f"IP speed loop too slow for k_p = {k_p:g} A/rpm, k_i = {k_i:g}: time constant "
            f"{tau:.3g} s > {TAU_MAX:g} s",
        )
    zeta = ip_damping(k_p, k_i, a, b)
    if zeta < ZETA_MIN:
        raise LimitError(
            ABORT_VALUE_TOO_HIGH,
            f"IP speed loop lightly damped for k_p = {k_p:g} A/rpm, k_i = {k_i:g}: zeta "
            f"{zeta:.3g} < {ZETA_MIN:g}",
        )
