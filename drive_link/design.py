"""Current- and speed-loop design maths of Valle et al., IEEE Access 2020 (pure numpy).

Everything here is a pure function of numbers: no bus, no drive, no python-control (which the
tests use only as an independent oracle). Discrete transfer functions are :class:`DiscreteTF`
objects holding polynomial coefficients in descending powers of ``z``.

Symbols follow the paper:

* ``R`` [Ω], ``L`` [H]: motor phase resistance and inductance; ``R_c``, ``L_c``: the controller's
  estimates of them.
* ``fs`` [Hz] sampling frequency (50 kHz), ``Ts = 1/fs`` [s].
* ``Phi = exp(-R Ts / L)`` (eq. 4), ``Gamma = (1 - Phi) / (2 R)`` [A/V] (eq. 5).
* Plant with one sample of computational delay ``P(z) = Gamma / (z (z - Phi))`` (eq. 8).
* Deadbeat controller ``C_db(z) = (z² - Phi_c z) / (Gamma_c (z² - 1))`` [V/A] (eq. 15).
* PI controller ``C_PI(z) = k_p + k_i z / (z - 1)`` [V/A] (eq. 22).
* Predictive law ``v_L(k+1) = 2 L_c fs (i_p* - i_p(k)) - v_L(k) + 2 e_L(k)`` (eq. 23), i.e. the
  linear controller ``2 L_c fs z / (z + 1)`` plus a back-EMF feed-forward ``2 z / (z + 1)``.
  With exact L_c and R = 0 this gives ``I_p/I_p* = z^-2`` as the paper states. Note: the
  paper's eq. (24) places ``2 L fs Gamma`` as the constant term of the denominator; substituting
  eq. (23) into eq. (6) gives it as the coefficient of ``z`` instead (the printed polynomial has
  a root outside the unit circle), and the steady-state error of eq. (23) with R ≠ 0 is
  ≈ 1.65 % here rather than the 0.83 % quoted in the text.
* Speed model ``G(z) = b / (z - a)`` [rpm/A per sample] (eq. 26) and IP controller
  ``u = k_p (k_i z/(z-1) (w* - w) - w)`` whose closed loop is eq. 27; gains from eqs. 28–31.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from drive_link import metrics as _metrics

FS_DEFAULT = 50_000.0
"""Default sampling (and PWM) frequency [Hz]; Ts = 20 µs."""

R_TABLE2 = 6.2e-3
"""Motor phase resistance of Table 2 [Ω]."""

L_TABLE2 = 14.8e-6
"""Motor phase inductance of Table 2 [H]."""

PI_KP_PAPER = 0.4647
"""The paper's PI current gain k_p,i [V/A] (Section IV-B)."""

PI_KI_PAPER = 0.0492
"""The paper's PI current gain k_i,i [V/A per sample] (Section IV-B)."""

ControllerName = Literal["deadbeat", "pi", "predictive"]
CONTROLLERS: tuple[str, ...] = ("deadbeat", "pi", "predictive")


# --------------------------------------------------------------------------- input checks
def _positive(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0 (got {value!r})")
    return v


def _non_negative(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v) or v < 0.0:
        raise ValueError(f"{name} must be a finite number >= 0 (got {value!r})")
    return v


def _finite(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite number (got {value!r})")
    return v


# --------------------------------------------------------------------------- polynomials / TFs
def _trim(p: Sequence[float] | np.ndarray) -> np.ndarray:
    a = np.atleast_1d(np.asarray(p, dtype=float))
    nz = np.flatnonzero(a != 0.0)
    return a[nz[0] :] if nz.size else np.zeros(1)


@dataclass(frozen=True, eq=False)
class DiscreteTF:
    """A discrete-time transfer function ``num(z) / den(z)``.

    ``num`` and ``den`` are coefficient arrays in descending powers of ``z`` (numpy ``polyval``
    order); ``Ts`` is the sampling period [s].
    """

    num: np.ndarray
    den: np.ndarray
    Ts: float = 1.0 / FS_DEFAULT

    def __post_init__(self) -> None:
        num, den = _trim(self.num), _trim(self.den)
        if not np.all(np.isfinite(num)) or not np.all(np.isfinite(den)):
            raise ValueError("transfer-function coefficients must be finite")
        if den.size == 1 and den[0] == 0.0:
            raise ValueError("denominator polynomial is zero")
        object.__setattr__(self, "num", num)
        object.__setattr__(self, "den", den)

    def __call__(self, z: complex | np.ndarray) -> complex | np.ndarray:
        """Evaluate at complex ``z``."""
        return np.polyval(self.num, z) / np.polyval(self.den, z)

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


# --------------------------------------------------------------------------- plant and controllers
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
    if controller == "deadbeat":
        return deadbeat_coefficients(L_c, R_c, fs).tf
    if controller == "pi":
        return pi_tf(k_p, k_i, fs)
    if controller == "predictive":
        return predictive_tf(L_c, fs)
    raise ValueError(f"controller must be one of {', '.join(CONTROLLERS)} (got {controller!r})")


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
    """Open loop ``C(z) P(z)`` (dimensionless) of the current loop; L_c, R_c default to L, R."""
    C = current_controller_tf(
        controller,
        L_c=L if L_c is None else L_c,
        R_c=R if R_c is None else R_c,
        k_p=k_p,
        k_i=k_i,
        fs=fs,
    )
    return C * plant_tf(R, L, fs)


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


# --------------------------------------------------------------------------- stability
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


# --------------------------------------------------------------------------- margins
@dataclass(frozen=True)
class Margins:
    """Classical stability margins of an open loop ``L(z)``.

    Attributes:
        gain_margin_db: GM [dB] at the phase crossover nearest 0 dB (inf if none).
        phase_margin_deg: PM [°] at the gain crossover with the smallest |PM|
            (nan if |L| never crosses 1); ``180° + arg L`` wrapped to (-180°, 180°].
        sensitivity_peak: ‖S‖∞ = max |1/(1+L(e^{jωTs}))| (dimensionless).
        gain_crossover_hz: frequency [Hz] of the reported PM (nan if none).
        phase_crossover_hz: frequency [Hz] of the reported GM (nan if none).
        sensitivity_peak_hz: frequency [Hz] of ‖S‖∞.
        phase_margins_deg / gain_crossovers_hz: every gain crossover in (0, fs/2) and its PM.
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

    def Lz(t: float | np.ndarray) -> complex | np.ndarray:
        return loop(np.exp(1j * np.asarray(t)))

    H = Lz(theta)
    mag = np.abs(H)
    to_hz = 1.0 / (2.0 * math.pi * Ts)

    # gain crossovers: |L| = 1
    g = np.log(np.maximum(mag, 1e-300))
    pms: list[float] = []
    wcs: list[float] = []
    for k in np.flatnonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0):
        t0 = _bisect(lambda t: math.log(abs(Lz(t))), theta[k], theta[k + 1])
        pms.append(_wrap_deg(180.0 + math.degrees(np.angle(Lz(t0)))))
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
        v = np.polyval(loop.num, -1.0) / den_m1
        if v < 0.0:
            gms.append(-20.0 * math.log10(abs(v)))
            wgs.append(0.5 / Ts)

    # sensitivity peak
    S = 1.0 / np.abs(1.0 + H)
    k = int(np.argmax(S))
    lo, hi = theta[max(k - 1, 0)], theta[min(k + 1, theta.size - 1)]
    t_pk = _golden_max(lambda t: 1.0 / abs(1.0 + Lz(t)), lo, hi)
    s_pk = max(float(S[k]), 1.0 / abs(1.0 + Lz(t_pk)))
    if s_pk == float(S[k]):
        t_pk = theta[k]

    if pms:
        best = min(range(len(pms)), key=lambda i: (round(abs(pms[i]), 9), wcs[i]))
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


# --------------------------------------------------------------------------- predicted responses
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
    n = int(n_samples)
    if n < 1:
        raise ValueError(f"n_samples must be >= 1 (got {n_samples!r})")
    for name, v in (("i_start", i_start), ("i_final", i_final), ("e_L", e_L)):
        _finite(name, v)
    _finite("v_loss", v_loss)
    _finite("v_comp", v_comp)
    if v_comp != 0.0 and controller != "predictive":
        raise ValueError("v_comp (eq. 25) applies to the predictive controller only")
    L_c = L if L_c is None else L_c
    R_c = R if R_c is None else R_c
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


# --------------------------------------------------------------------------- speed loop (IP)
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


def _as_f32(x: float) -> float:
    return float(np.float32(x))


def ip_closed_loop(
    a: float, b: float, k_p: float, k_i: float, fs: float = FS_DEFAULT
) -> DiscreteTF:
    """Speed closed loop ``w / w*`` of the IP controller on ``b/(z - a)``, eq. (27)."""
    kb = k_p * b
    return DiscreteTF([kb * k_i, 0.0], [1.0, kb * k_i + kb - 1.0 - a, a - kb], 1.0 / fs)


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


# --------------------------------------------------------------------------- PI current design
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


# --------------------------------------------------------------------------- loop report
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
    ([re, im] pairs), gain_margin_db, phase_margin_deg, sensitivity_peak, gain_crossover_hz,
    phase_crossover_hz, phase_margins_deg, gain_crossovers_hz, overshoot_pct, rise_time_s,
    settling_time_s, steady_state_error_A, steady_state_error_pct, step_samples, step_from_A,
    step_to_A (step figures None unless asymptotically stable).
    """
    L_c = L if L_c is None else L_c
    R_c = R if R_c is None else R_c
    # plant, controller parameters and sampling rate shared by the loop and its step predictions
    setup: dict[str, Any] = {
        "R": R,
        "L": L,
        "L_c": L_c,
        "R_c": R_c,
        "k_p": k_p,
        "k_i": k_i,
        "fs": fs,
    }
    loop = current_loop_tf(controller, **setup)
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
        "gain_margin_db": m.gain_margin_db,
        "phase_margin_deg": m.phase_margin_deg,
        "sensitivity_peak": m.sensitivity_peak,
        "gain_crossover_hz": m.gain_crossover_hz,
        "phase_crossover_hz": m.phase_crossover_hz,
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
        r = predicted_step(
            controller, n_samples=n_samples, i_start=i_start, i_final=i_final, **setup
        )
        y0 = predicted_step(
            controller, n_samples=1, i_start=i_start, i_final=i_start, **setup
        ).i_p_final
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
