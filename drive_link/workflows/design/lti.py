"""Discrete-time LTI toolkit: :class:`DiscreteTF`, feedback, stability tests, margins.

Transfer functions hold polynomial coefficients in descending powers of ``z`` (numpy ``polyval``
order) and their sampling period ``Ts`` [s]. Pure numpy: python-control is a test-only oracle.

Phase-margin convention (one for the design, the CLI, the API and the GUI): at every gain
crossover ``|L(e^{jωTs})| = 1`` the margin is the angle between ``L`` and the critical point
−1, a positive angle in [0°, 180°]; the loop's phase margin is the smallest of them (the
paper's Table 1 lists the two crossovers of the deadbeat loop as ±41.6°: 41.6° here), and
every crossover is listed with its margin (:attr:`Margins.phase_margins_deg`,
:attr:`Margins.gain_crossovers_hz`). Margins alone do not prove stability: the closed-loop
poles do (:func:`is_stable`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import overload

import numpy as np

from ._common import FS_DEFAULT

__all__ = [
    "DiscreteTF",
    "Margins",
    "feedback",
    "is_stable",
    "jury_stable",
    "margins",
    "sensitivity",
]


def _trim(p: Sequence[float] | np.ndarray) -> np.ndarray:
    a = np.atleast_1d(np.asarray(p, dtype=float))
    nz = np.flatnonzero(a != 0.0)
    return a[nz[0] :] if nz.size else np.zeros(1)


@dataclass(frozen=True, eq=False, init=False)
class DiscreteTF:
    """A discrete-time transfer function ``num(z) / den(z)``.

    ``num`` and ``den`` are coefficient arrays in descending powers of ``z`` (numpy ``polyval``
    order; given as any sequence of numbers); ``Ts`` is the sampling period [s].
    """

    num: np.ndarray
    den: np.ndarray
    Ts: float

    def __init__(
        self,
        num: Sequence[float] | np.ndarray,
        den: Sequence[float] | np.ndarray,
        Ts: float = 1.0 / FS_DEFAULT,
    ) -> None:
        n, d = _trim(num), _trim(den)
        if not np.all(np.isfinite(n)) or not np.all(np.isfinite(d)):
            raise ValueError("transfer-function coefficients must be finite")
        if d.size == 1 and d[0] == 0.0:
            raise ValueError("denominator polynomial is zero")
        object.__setattr__(self, "num", n)
        object.__setattr__(self, "den", d)
        object.__setattr__(self, "Ts", Ts)

    @overload
    def __call__(self, z: complex) -> complex: ...
    @overload
    def __call__(self, z: np.ndarray) -> np.ndarray: ...

    def __call__(self, z: complex | np.ndarray) -> complex | np.ndarray:
        """Evaluate at complex ``z`` (a number or an array of them)."""
        value = np.polyval(self.num, z) / np.polyval(self.den, z)
        return value if isinstance(z, np.ndarray) else complex(value)

    def __mul__(self, other: DiscreteTF) -> DiscreteTF:
        return DiscreteTF(np.polymul(self.num, other.num), np.polymul(self.den, other.den), self.Ts)

    def freqresp(self, omega: np.ndarray) -> np.ndarray:
        """Complex response at angular frequencies ``omega`` [rad/s] (``z = e^{j omega Ts}``)."""
        return self(np.exp(1j * np.asarray(omega, dtype=float) * self.Ts))

    def poles(self) -> np.ndarray:
        """Roots of the denominator."""
        return np.roots(self.den) if self.den.size > 1 else np.zeros(0, dtype=complex)

    def zeros(self) -> np.ndarray:
        """Roots of the numerator."""
        return np.roots(self.num) if self.num.size > 1 else np.zeros(0, dtype=complex)

    def dcgain(self) -> float:
        """Value at ``z = 1`` (inf if there is a pole there)."""
        d = np.polyval(self.den, 1.0)
        return float("inf") if d == 0.0 else float(np.polyval(self.num, 1.0) / d)

    def normalized(self) -> DiscreteTF:
        """Same transfer function with a monic denominator."""
        return DiscreteTF(self.num / self.den[0], self.den / self.den[0], self.Ts)


def feedback(loop: DiscreteTF) -> DiscreteTF:
    """Unity negative-feedback closed loop ``L / (1 + L)`` (eq. 10)."""
    n = max(loop.num.size, loop.den.size)
    num = np.pad(loop.num, (n - loop.num.size, 0))
    den = np.pad(loop.den, (n - loop.den.size, 0))
    return DiscreteTF(num, den + num, loop.Ts).normalized()


def sensitivity(loop: DiscreteTF) -> DiscreteTF:
    """Sensitivity ``S = 1 / (1 + L)`` (eq. 11)."""
    n = max(loop.num.size, loop.den.size)
    num = np.pad(loop.num, (n - loop.num.size, 0))
    den = np.pad(loop.den, (n - loop.den.size, 0))
    return DiscreteTF(den, den + num, loop.Ts).normalized()


def is_stable(system: DiscreteTF | Sequence[float] | np.ndarray, *, tol: float = 1e-9) -> bool:
    """True if every root (closed-loop pole) lies inside the unit circle, ``|p| < 1 - tol``.

    ``system`` is a closed-loop :class:`DiscreteTF` (its denominator is used) or a characteristic
    polynomial in descending powers of z. Poles within ``tol`` of the circle are marginal and
    reported as not stable (root-finding cannot tell which side they are on); e.g. R_c = 0 makes
    the deadbeat controller's zero at Phi_c = 1 cancel its integrator, leaving a pole at z = 1.
    """
    den = system.den if isinstance(system, DiscreteTF) else _trim(system)
    if den.size <= 1:
        return True
    return bool(np.max(np.abs(np.roots(den))) < 1.0 - tol)


def jury_stable(coefficients: Sequence[float] | np.ndarray) -> bool:
    """Jury's stability criterion for a real polynomial (descending powers of z).

    Returns True if all roots lie strictly inside the unit circle, decided from the Jury table
    (Åström & Wittenmark, Computer-Controlled Systems, §3.2) without computing roots. Critical
    (on-circle) and singular cases are reported as not stable. Limitation: the table loses
    precision for clustered poles within ~1e-5 of z = 1 (e.g. an IP speed loop with
    ω_n < 0.5 rad/s at 50 kHz) and may then answer False; :func:`is_stable` (roots) is the
    reference, this is the paper's cross-check.
    """
    a = _trim(coefficients)
    if not np.all(np.isfinite(a)):
        raise ValueError("polynomial coefficients must be finite")
    if a.size == 1:
        if a[0] == 0.0:
            raise ValueError("polynomial is zero")
        return True
    a = a / a[0]
    if a[0] < 0:  # pragma: no cover - a[0] is 1 after normalisation
        a = -a
    n = a.size - 1
    scale = float(np.sum(np.abs(a)))
    # necessary conditions: A(1) > 0, (-1)^n A(-1) > 0 (beyond rounding: roots on the circle
    # at z = ±1 are marginal, not stable)
    eps = 1e-14 * scale
    if np.polyval(a, 1.0) <= eps or ((-1) ** n) * np.polyval(a, -1.0) <= eps:
        return False
    row = a.copy()
    while row.size > 1:
        # Schur–Cohn/Jury reduction: a_{k-1,i} = a_{k,i} - alpha_k a_{k,k-i}, alpha = a_k / a_0;
        # every leading coefficient must stay positive, beyond the reduction's rounding error
        alpha = row[-1] / row[0]
        lead = row[0]
        row = (row - alpha * row[::-1])[:-1]
        if row[0] <= 1e-13 * lead:
            return False
    return True


@dataclass(frozen=True)
class Margins:
    """Classical stability margins of an open loop ``L(z)``.

    Attributes:
        gain_margin_db: GM [dB] at the phase crossover nearest 0 dB (inf if none).
        phase_margin_deg: PM [°], a positive angle: the smallest margin over all gain
            crossovers (nan if |L| never crosses 1). At a crossover the margin is the angle
            between L and −1, ``|180° + arg L|`` with the sum wrapped to (-180°, 180°]
            (python-control's signed PM, as a magnitude).
        sensitivity_peak: ‖S‖∞ = max |1/(1+L(e^{jωTs}))| (dimensionless).
        gain_crossover_hz: frequency [Hz] of the reported PM (nan if none).
        phase_crossover_hz: frequency [Hz] of the reported GM (nan if none).
        sensitivity_peak_hz: frequency [Hz] of ‖S‖∞.
        phase_margins_deg / gain_crossovers_hz: every gain crossover in (0, fs/2) by rising
            frequency [Hz] and its margin (positive angle, as phase_margin_deg).
        gain_margins_db / phase_crossovers_hz: every phase crossover in (0, fs/2] and its GM.
    """

    gain_margin_db: float
    phase_margin_deg: float
    sensitivity_peak: float
    gain_crossover_hz: float
    phase_crossover_hz: float
    sensitivity_peak_hz: float
    phase_margins_deg: tuple[float, ...] = field(default_factory=tuple)
    gain_crossovers_hz: tuple[float, ...] = field(default_factory=tuple)
    gain_margins_db: tuple[float, ...] = field(default_factory=tuple)
    phase_crossovers_hz: tuple[float, ...] = field(default_factory=tuple)


def _bisect(f: Callable[[float], float], lo: float, hi: float, iters: int = 80) -> float:
    flo = f(lo)
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        fm = f(mid)
        if fm == 0.0:
            return mid
        if (fm > 0.0) == (flo > 0.0):
            lo, flo = mid, fm
        else:
            hi = mid
        if hi - lo <= 1e-15 * max(1.0, abs(hi)):
            break
    return 0.5 * (lo + hi)


def _golden_max(f: Callable[[float], float], lo: float, hi: float, iters: int = 80) -> float:
    g = (math.sqrt(5.0) - 1.0) / 2.0
    c, d = hi - g * (hi - lo), lo + g * (hi - lo)
    fc, fd = f(c), f(d)
    for _ in range(iters):
        if fc >= fd:
            hi, d, fd = d, c, fc
            c = hi - g * (hi - lo)
            fc = f(c)
        else:
            lo, c, fc = c, d, fd
            d = lo + g * (hi - lo)
            fd = f(d)
        if hi - lo <= 1e-14:
            break
    return 0.5 * (lo + hi)


def _wrap_deg(x: float) -> float:
    """Wrap an angle [°] into (-180, 180]."""
    y = math.fmod(x + 180.0, 360.0)
    if y <= 0.0:
        y += 360.0
    return y - 180.0


def margins(loop: DiscreteTF, *, n_grid: int = 20_000) -> Margins:
    """Gain margin, phase margin and ‖S‖∞ of the open loop ``loop`` (e.g. C·P).

    The response ``L(e^{jθ})`` is evaluated on a dense grid of θ = ω Ts in (0, π) (log-spaced near
    0, linear elsewhere); every sign change of ``|L| - 1`` (gain crossover) and of ``Im L`` with
    ``Re L < 0`` (phase crossover) is refined by bisection, and the peak of ``|S|`` by a
    golden-section search. Poles on the unit circle (integrators at z = 1, the deadbeat pole at
    z = -1) are avoided by keeping θ strictly inside (0, π). Pole/zero cancellations need no
    special care because only the frequency response is used.

    Args:
        loop: open-loop transfer function (dimensionless), with its sampling period ``Ts`` [s].
        n_grid: number of grid points (>= 100).

    Returns:
        :class:`Margins`; frequencies in Hz. Margins alone do not prove stability: check the
        closed-loop poles with :func:`is_stable`.
    """
    if n_grid < 100:
        raise ValueError("n_grid must be >= 100")
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return _margins(loop, n_grid)


def _margins(loop: DiscreteTF, n_grid: int) -> Margins:
    Ts = loop.Ts
    eps = 1e-9
    theta = np.unique(
        np.concatenate(
            [
                np.geomspace(eps, 0.05, n_grid // 4),
                np.linspace(0.05, math.pi - 0.05, n_grid // 2),
                math.pi - np.geomspace(0.05, eps, n_grid // 4),
            ]
        )
    )

    def Lz(t: float) -> complex:
        return loop(complex(np.exp(1j * t)))

    H = loop(np.exp(1j * np.asarray(theta)))
    mag = np.abs(H)
    to_hz = 1.0 / (2.0 * math.pi * Ts)

    # gain crossovers: |L| = 1
    g = np.log(np.maximum(mag, 1e-300))
    pms: list[float] = []
    wcs: list[float] = []
    for k in np.flatnonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0):
        t0 = _bisect(lambda t: math.log(abs(Lz(t))), theta[k], theta[k + 1])
        pms.append(abs(_wrap_deg(180.0 + math.degrees(np.angle(Lz(t0))))))
        wcs.append(t0 * to_hz)

    # phase crossovers: Im L = 0 with Re L < 0
    gms: list[float] = []
    wgs: list[float] = []
    im = H.imag
    for k in np.flatnonzero(np.sign(im[:-1]) * np.sign(im[1:]) < 0):
        if not (H.real[k] < 0.0 or H.real[k + 1] < 0.0):
            continue
        t0 = _bisect(lambda t: float(np.imag(Lz(t))), theta[k], theta[k + 1])
        v = Lz(t0)
        if v.real < 0.0 and abs(v.imag) <= 1e-6 * abs(v):
            gms.append(-20.0 * math.log10(abs(v)))
            wgs.append(t0 * to_hz)
    # an exact phase crossover at Nyquist (real L(-1) < 0, finite)
    den_m1 = np.polyval(loop.den, -1.0)
    if abs(den_m1) > 1e-12 * float(np.sum(np.abs(loop.den))):  # no pole at z = -1
        v_nyq = float(np.polyval(loop.num, -1.0) / den_m1)
        if v_nyq < 0.0:
            gms.append(-20.0 * math.log10(abs(v_nyq)))
            wgs.append(0.5 / Ts)

    # sensitivity peak
    S = 1.0 / np.abs(1.0 + H)
    k_pk = int(np.argmax(S))
    lo, hi = theta[max(k_pk - 1, 0)], theta[min(k_pk + 1, theta.size - 1)]
    t_pk = _golden_max(lambda t: 1.0 / abs(1.0 + Lz(t)), lo, hi)
    s_pk = max(float(S[k_pk]), 1.0 / abs(1.0 + Lz(t_pk)))
    if s_pk == float(S[k_pk]):
        t_pk = theta[k_pk]

    if pms:
        # the smallest margin; crossovers within 1e-6° of it (e.g. the matched deadbeat loop
        # 1/(z² − 1): 60° at fs/12 and at 5 fs/12) go to the lowest frequency
        smallest = min(pms)
        best = min(i for i in range(len(pms)) if pms[i] - smallest <= 1e-6)
        pm, wc = pms[best], wcs[best]
    else:
        pm, wc = float("nan"), float("nan")
    if gms:
        best = min(range(len(gms)), key=lambda i: (abs(gms[i]), wgs[i]))
        gm, wg = gms[best], wgs[best]
    else:
        gm, wg = float("inf"), float("nan")
    return Margins(
        gain_margin_db=float(gm),
        phase_margin_deg=float(pm),
        sensitivity_peak=float(s_pk),
        gain_crossover_hz=float(wc),
        phase_crossover_hz=float(wg),
        sensitivity_peak_hz=float(t_pk * to_hz),
        phase_margins_deg=tuple(float(x) for x in pms),
        gain_crossovers_hz=tuple(float(x) for x in wcs),
        gain_margins_db=tuple(float(x) for x in gms),
        phase_crossovers_hz=tuple(float(x) for x in wgs),
    )
