"""Speed loop: the IP controller on the speed model ``G(z) = b / (z - a)`` (eq. 26): gains from
ξ and ω_n (eqs. 28–31), the closed loop (eq. 27), its open loop and the predicted step.

Units: a dimensionless (per loop sample), b [rpm/A per sample], k_p [A/rpm], k_i [1/sample],
ω_n [rad/s], speeds [rpm], fs [Hz].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._common import FS_DEFAULT, _as_f32, _finite, _positive
from .lti import DiscreteTF, is_stable
from .pars import SpeedLoopPars

__all__ = [
    "IPDesign",
    "PredictedSpeedStep",
    "ip_closed_loop",
    "ip_design",
    "ip_gains",
    "ip_min_xi_omega_n",
    "ip_requested_poles",
    "predicted_speed_step",
    "speed_closed_loop",
    "speed_loop_tf",
    "speed_open_loop",
]


def ip_gains(
    a: float, b: float, xi: float = 1.0, omega_n: float = 2.3, fs: float = FS_DEFAULT
) -> tuple[float, float]:
    """IP speed-controller gains from the damping ratio and natural frequency, eqs. (28)–(31).

    Closed-loop poles of eq. (27) are placed at the roots of ``z² + d_1 z + d_2`` with
    ``d_1 = -2 e^{-ξ ω_n Ts} cos(ω_n Ts sqrt(1 - ξ²))`` (cosh for ξ > 1) and
    ``d_2 = e^{-2 ξ ω_n Ts}`` (the paper prints ``e^{-ξ ω_n Ts}``, a typo: its own gains follow from
    the squared radius). ``k_p = (a - d_2)/b`` (eq. 30), ``k_i = (d_1 + 1 + a - k_p b)/(k_p b)``
    (eq. 31), evaluated in a cancellation-free form.

    Args:
        a: speed-model pole (dimensionless, per loop sample), 0 < a < 1 typically ≈ 0.99998.
        b: speed-model gain [rpm/A per loop sample], > 0.
        xi: damping ratio ξ (> 0).
        omega_n: natural frequency ω_n [rad/s] (> 0).
        fs: loop sampling frequency [Hz].

    Returns:
        ``(k_p, k_i)``: k_p [A/rpm], k_i [1/sample], both > 0.

    Raises:
        ValueError: bad input, or a spec whose gains are not positive (ξ ω_n at or below
        :func:`ip_min_xi_omega_n`: the loop would need positive speed feedback; eq. (27) still
        places the poles, but the law is not an IP controller and the drive refuses k_p < 0).
    """
    a = _finite("a", a)
    b = _finite("b", b)
    if b == 0.0:
        raise ValueError("b must be non-zero")
    xi = _positive("xi", xi)
    omega_n = _positive("omega_n", omega_n)
    Ts = 1.0 / _positive("fs", fs)
    x = xi * omega_n * Ts
    r = math.exp(-x)
    # 1 + d1 + d2 = (1 - r)^2 + 2 r (1 - cos y)   (cosh for xi > 1)
    if xi < 1.0:
        y = omega_n * Ts * math.sqrt(1.0 - xi * xi)
        one_minus_c = 2.0 * math.sin(0.5 * y) ** 2
    elif xi > 1.0:
        y = omega_n * Ts * math.sqrt(xi * xi - 1.0)
        one_minus_c = -2.0 * math.sinh(0.5 * y) ** 2
    else:
        one_minus_c = 0.0
    one_d1_d2 = math.expm1(-x) ** 2 + 2.0 * r * one_minus_c
    a_minus_d2 = (a - 1.0) - math.expm1(-2.0 * x)
    k_p = a_minus_d2 / b if a_minus_d2 != 0.0 else 0.0
    k_i = one_d1_d2 / a_minus_d2 if a_minus_d2 != 0.0 else 0.0
    if not (k_p > 0.0 and k_i > 0.0 and math.isfinite(k_p) and math.isfinite(k_i)):
        # eq. (30): k_p > 0 needs d_2 < a, i.e. the requested poles faster than the plant pole
        need = ip_min_xi_omega_n(a, fs) if 0.0 < a < 1.0 else math.nan
        hint = (
            f"; the requested poles must be faster than the plant pole: xi * omega_n > {need:.4g}"
            " rad/s"
            if math.isfinite(need) and b > 0.0
            else ""
        )
        raise ValueError(
            f"xi = {xi:g}, omega_n = {omega_n:g} rad/s gives non-positive IP gains "
            f"(k_p = {k_p:.4g} A/rpm, k_i = {k_i:.4g} 1/sample){hint}"
        )
    return k_p, k_i


def ip_min_xi_omega_n(a: float, fs: float = FS_DEFAULT) -> float:
    """Smallest ξ ω_n [rad/s] giving k_p > 0 in eq. (30): ``d_2 = e^{-2 ξ ω_n Ts} < a``, i.e.
    ``ξ ω_n > -ln(a) fs / 2`` (the closed-loop poles must be faster than the plant pole a)."""
    a = _finite("a", a)
    if not 0.0 < a < 1.0:
        raise ValueError(f"a must be in (0, 1) (got {a!r})")
    return -math.log(a) * _positive("fs", fs) / 2.0


def ip_requested_poles(xi: float, omega_n: float, fs: float = FS_DEFAULT) -> np.ndarray:
    """The two z-plane poles eqs. (28)–(29) ask for: ``e^{s Ts}`` with
    ``s = -ξ ω_n ± ω_n sqrt(ξ² - 1)`` (complex for ξ < 1)."""
    xi = _positive("xi", xi)
    omega_n = _positive("omega_n", omega_n)
    Ts = 1.0 / _positive("fs", fs)
    root = np.sqrt(complex(xi * xi - 1.0))
    s = np.array([-xi * omega_n + omega_n * root, -xi * omega_n - omega_n * root])
    return np.exp(s * Ts)


@dataclass(frozen=True)
class IPDesign:
    """An IP design checked on the gains the drive will hold.

    ``k_p`` [A/rpm], ``k_i`` [1/sample] (eqs. 30–31, > 0), ``k_p_f32``/``k_i_f32`` the same
    rounded to REAL32 as stored in 0x2020; ``requested`` the poles asked for (eqs. 28–29);
    ``poles`` the closed-loop poles of eq. (27) computed with the REAL32 gains; ``stable`` from
    those poles (``|p| < 1``); ``poles_match`` True when each pole's continuous equivalent
    ``ln(p) fs`` lies within ``rtol`` × ω_n of the requested one.
    """

    a: float
    b: float
    xi: float
    omega_n: float
    fs: float
    k_p: float
    k_i: float
    k_p_f32: float
    k_i_f32: float
    requested: np.ndarray
    poles: np.ndarray
    stable: bool
    poles_match: bool
    max_pole_error: float  # rad/s, continuous-equivalent distance (worst pole)


def ip_design(
    a: float,
    b: float,
    xi: float = 1.0,
    omega_n: float = 2.3,
    fs: float = FS_DEFAULT,
    *,
    rtol: float = 0.01,
) -> IPDesign:
    """Gains by :func:`ip_gains` (ValueError if they are not positive), then the closed loop of
    eq. (27) rebuilt from the REAL32-rounded gains: its poles decide ``stable`` and are compared
    with the requested ones (``poles_match``)."""
    k_p, k_i = ip_gains(a, b, xi, omega_n, fs)
    kp32, ki32 = _as_f32(k_p), _as_f32(k_i)
    poles = np.sort_complex(ip_closed_loop(a, b, kp32, ki32, fs).poles().astype(complex))
    want = np.sort_complex(ip_requested_poles(xi, omega_n, fs))
    s_got = np.log(poles) * fs
    s_want = np.log(want) * fs
    # pair each requested pole with the nearest actual one (both sets hold two poles)
    err = min(
        max(abs(s_got[0] - s_want[0]), abs(s_got[1] - s_want[1])),
        max(abs(s_got[0] - s_want[1]), abs(s_got[1] - s_want[0])),
    )
    return IPDesign(
        a=float(a),
        b=float(b),
        xi=float(xi),
        omega_n=float(omega_n),
        fs=float(fs),
        k_p=k_p,
        k_i=k_i,
        k_p_f32=kp32,
        k_i_f32=ki32,
        requested=want,
        poles=poles,
        stable=bool(np.max(np.abs(poles)) < 1.0),
        poles_match=bool(err <= rtol * omega_n),
        max_pole_error=float(err),
    )


def ip_closed_loop(
    a: float, b: float, k_p: float, k_i: float, fs: float = FS_DEFAULT
) -> DiscreteTF:
    """Speed closed loop ``w / w*`` of the IP controller on ``b/(z - a)``, eq. (27)
    (:func:`speed_closed_loop` of a :class:`~drive_link.workflows.design.SpeedLoopPars`)."""
    return speed_closed_loop(SpeedLoopPars(a, b, k_p, k_i, fs))


def speed_closed_loop(p: SpeedLoopPars) -> DiscreteTF:
    """Speed closed loop ``w / w*`` of IP loop ``p``, eq. (27)."""
    kb = p.k_p * p.b
    return DiscreteTF(
        [kb * p.k_i, 0.0], [1.0, kb * p.k_i + kb - 1.0 - p.a, p.a - kb], 1.0 / p.fs
    )


@dataclass(frozen=True)
class PredictedSpeedStep:
    """Predicted IP speed-loop step: t [s], speed and speed_ref [rpm], i_p_ref [A] per sample."""

    t: np.ndarray
    speed: np.ndarray
    speed_ref: np.ndarray
    i_p_ref: np.ndarray
    stable: bool


def predicted_speed_step(
    a: float,
    b: float,
    k_p: float,
    k_i: float,
    *,
    n_samples: int,
    w_start: float = 0.0,
    w_final: float = 1000.0,
    fs: float = FS_DEFAULT,
    decimate: int = 1,
) -> PredictedSpeedStep:
    """Speed step of the IP loop (eq. 27) with an ideal inner loop, sample by sample.

    Law: ``x_i[k] = x_i[k-1] + k_i (w*[k] - w[k])``, ``i_p*[k] = k_p (x_i[k] - w[k])``,
    plant ``w[k+1] = a w[k] + b i_p*[k]`` (eq. 26); starts at equilibrium at w_start [rpm].
    Every ``decimate``-th sample is returned (the loop always runs at fs).
    """
    n = int(n_samples)
    d = int(decimate)
    if n < 1 or d < 1:
        raise ValueError("n_samples and decimate must be >= 1")
    for name, v in (("a", a), ("b", b), ("k_p", k_p), ("k_i", k_i)):
        _finite(name, v)
    _finite("w_start", w_start)
    _finite("w_final", w_final)
    fs = _positive("fs", fs)
    if k_p == 0.0 or b == 0.0:
        raise ValueError("k_p and b must be non-zero")
    w = float(w_start)
    u0 = (1.0 - a) * w / b
    x_i = u0 / k_p + w
    m = (n + d - 1) // d
    speed = np.empty(m)
    iref = np.empty(m)
    for k in range(n):
        x_i += k_i * (w_final - w)
        u = k_p * (x_i - w)
        if k % d == 0:
            speed[k // d] = w
            iref[k // d] = u
        w = a * w + b * u
    t = np.arange(m) * d / fs
    stable = is_stable(ip_closed_loop(a, b, k_p, k_i, fs))
    return PredictedSpeedStep(t, speed, np.full(m, float(w_final)), iref, stable)


def speed_loop_tf(
    a: float, b: float, k_p: float, k_i: float, fs: float = FS_DEFAULT
) -> DiscreteTF:
    """Open loop of the IP speed loop broken at the plant input [dimensionless]:
    ``k_p (1 + k_i z / (z - 1)) · b / (z - a)`` (the feedback path of the IP law on the speed
    model, eq. 26); its unity-feedback closed loop has the poles of eq. (27).

    a (per loop sample), b [rpm/A per sample], k_p [A/rpm], k_i [1/sample], fs [Hz].
    """
    return speed_open_loop(SpeedLoopPars(a, b, k_p, k_i, fs))


def speed_open_loop(p: SpeedLoopPars) -> DiscreteTF:
    """Open loop of IP speed loop ``p`` broken at the plant input (:func:`speed_loop_tf`)."""
    a, b, k_p, k_i, fs = p.a, p.b, p.k_p, p.k_i, p.fs
    for name, v in (("a", a), ("b", b), ("k_p", k_p), ("k_i", k_i)):
        _finite(name, v)
    fs = _positive("fs", fs)
    ip_feedback = DiscreteTF([k_p * (1.0 + k_i), -k_p], [1.0, -1.0], 1.0 / fs)
    return ip_feedback * DiscreteTF([b], [1.0, -a], 1.0 / fs)
