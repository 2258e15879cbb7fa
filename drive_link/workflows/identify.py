"""Least-squares identification of the speed model ``G(z) = b / (z - a)`` (eq. 26, Fig. 16).

From a current-step trace (i_p [A] and speed [rpm] sampled every ``Ts``) fit
``w[n+1] = A w[n] + B i[n] + c`` with numpy ``lstsq``; ``c`` absorbs offsets (a constant load
torque, a current-sensor offset). A trace sampled every D loop samples (trace divider D, each
loop sample Ts_model = 20 µs) with the current held over the D samples gives
``A = a^D`` and ``B = b (1 - a^D) / (1 - a)``; the 50 kHz model is recovered as
``a = A^(1/D)``, ``b = B (1 - a) / (1 - A)``. The least-squares (equation-error) estimate is then
refined by Gauss–Newton on the free-run simulation error, because speed-measurement noise in the
regressor biases the one-step fit (≈5 % on 1 - a with 1 rpm of noise; < 1.5 % after refinement).
Fit quality is reported for the one-step prediction and for the free-run simulation of the
identified model (the comparison of Fig. 16): R² and RMS.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

__all__ = [
    "TS_MODEL",
    "FirstOrderFit",
    "fit_first_order",
    "identify_first_order",
    "simulate_first_order",
]

TS_MODEL = 20e-6
"""Loop sampling period of the model [s] (fs = 50 kHz)."""


@dataclass(frozen=True)
class FirstOrderFit:
    """Result of :func:`fit_first_order`.

    Attributes:
        a: pole of ``b/(z - a)`` per loop sample Ts_model (dimensionless).
        b: gain [rpm/A per loop sample].
        offset: constant term c of the decimated regression [rpm per trace sample].
        a_D, b_D: the fitted decimated model (per trace sample of D loop samples).
        D: decimation (trace samples are D loop samples apart).
        Ts: trace sample period [s]; Ts_model: loop sample period [s].
        r2: coefficient of determination of the free-run simulation (from the fitted initial
            speed) against the measured speed.
        rms: RMS error of the free-run simulation [rpm].
        one_step_rms: RMS of the one-step-ahead residuals of the least-squares stage [rpm].
        n_samples: number of trace samples used.
    """

    a: float
    b: float
    offset: float
    a_D: float
    b_D: float
    D: int
    Ts: float
    Ts_model: float
    r2: float
    rms: float
    one_step_rms: float
    n_samples: int

    @property
    def time_constant(self) -> float:
        """Mechanical time constant ``-Ts_model / ln(a)`` [s] (inf if a >= 1)."""
        return -self.Ts_model / math.log(self.a) if 0.0 < self.a < 1.0 else math.inf

    @property
    def dc_gain(self) -> float:
        """Steady-state speed per ampere ``b / (1 - a)`` [rpm/A] (inf if a >= 1)."""
        return self.b / (1.0 - self.a) if self.a < 1.0 else math.inf

    def as_dict(self) -> dict[str, float]:
        """Plain ``dict`` (JSON-friendly) including time_constant and dc_gain."""
        d = asdict(self)
        d["time_constant"] = self.time_constant
        d["dc_gain"] = self.dc_gain
        return d


def _decimation(Ts: float, Ts_model: float) -> int:
    if not (math.isfinite(Ts) and Ts > 0):
        raise ValueError(f"Ts must be a finite period > 0 s (got {Ts!r})")
    if not (math.isfinite(Ts_model) and Ts_model > 0):
        raise ValueError(f"Ts_model must be a finite period > 0 s (got {Ts_model!r})")
    D = round(Ts / Ts_model)
    if D < 1 or abs(D * Ts_model - Ts) > 1e-6 * Ts:
        raise ValueError(f"Ts = {Ts:g} s is not a whole multiple of the loop period {Ts_model:g} s")
    return D


def simulate_first_order(
    a: float, b: float, i_p: np.ndarray, w0: float, offset: float = 0.0
) -> np.ndarray:
    """Free-run ``w[n+1] = a w[n] + b i_p[n] + offset`` from ``w[0] = w0`` (units of w0)."""
    i_p = np.asarray(i_p, dtype=float)
    w = np.empty(i_p.size)
    x = float(w0)
    for n in range(i_p.size):
        w[n] = x
        x = a * x + b * i_p[n] + offset
    return w


def _output_error_refine(
    i: np.ndarray, w: np.ndarray, A: float, B: float, c: float, offset: bool, iters: int = 20
) -> tuple[float, float, float, float]:
    """Gauss–Newton on the free-run (output-error) cost from an equation-error start.

    Equation-error least squares is biased when the measured speed is noisy (the noise is in the
    regressor); minimising the simulation error over (A, B, c, w0) removes that bias.
    Returns (A, B, c, w0).
    """
    n = i.size
    w0 = float(w[0])
    il = i.tolist()

    def run(A: float, B: float, c: float, w0: float) -> tuple[np.ndarray, np.ndarray]:
        y = np.empty(n)
        J = np.empty((n, 4))
        x, sa, sb, sc, s0 = w0, 0.0, 0.0, 0.0, 1.0
        for k in range(n):
            y[k] = x
            J[k, 0], J[k, 1], J[k, 2], J[k, 3] = sa, sb, sc, s0
            sa, sb, sc, s0 = x + A * sa, il[k] + A * sb, 1.0 + A * sc, A * s0
            x = A * x + B * il[k] + c
        return y, J

    y, J = run(A, B, c, w0)
    cost = float(np.sum((w - y) ** 2))
    cols = [0, 1, 2, 3] if offset else [0, 1, 3]
    tiny = 1e-26 * float(np.sum(w**2))
    for _ in range(iters):
        if cost <= tiny:  # already exact (noise-free data)
            break
        Js = J[:, cols]
        scale = np.maximum(np.max(np.abs(Js), axis=0), 1e-300)
        step, *_ = np.linalg.lstsq(Js / scale, w - y, rcond=None)
        step = step / scale
        full = np.zeros(4)
        full[cols] = step
        lam = 1.0
        improved = False
        while lam > 1e-4:
            A1, B1, c1, w01 = (
                A + lam * full[0],
                B + lam * full[1],
                c + lam * full[2],
                w0 + lam * full[3],
            )
            if 0.0 < A1 < 1.0:
                y1, J1 = run(A1, B1, c1, w01)
                cost1 = float(np.sum((w - y1) ** 2))
                if cost1 < cost:
                    improved = True
                    break
            lam *= 0.5
        if not improved:
            break
        rel = abs(cost - cost1) / max(cost, 1e-300)
        A, B, c, w0, y, J, cost = A1, B1, c1, w01, y1, J1, cost1
        if rel < 1e-10:
            break
    return A, B, c, w0


def fit_first_order(
    i_p: np.ndarray,
    speed: np.ndarray,
    Ts: float = TS_MODEL,
    *,
    Ts_model: float = TS_MODEL,
    offset: bool = True,
    refine: bool = True,
) -> FirstOrderFit:
    """Fit ``b/(z - a)`` at the loop rate to a trace sampled every ``Ts``.

    Args:
        i_p: pseudo current [A] (the model input), one value per trace sample.
        speed: speed [rpm], same length.
        Ts: trace sample period [s]; must be a whole multiple D of ``Ts_model``.
        Ts_model: loop sample period of the model [s] (20 µs).
        offset: also fit a constant term (recommended; handles load torque and sensor offsets).
        refine: after the equation-error least squares (numpy lstsq on the one-step regression),
            refine by Gauss–Newton on the free-run simulation error, which removes the bias that
            speed-measurement noise causes in the one-step regression.

    Returns:
        :class:`FirstOrderFit`. Raises ValueError for malformed data, a trace without excitation
        (the regression is rank-deficient) or a fitted pole outside (0, 1) that cannot be turned
        into a loop-rate model.
    """
    i = np.asarray(i_p, dtype=float).ravel()
    w = np.asarray(speed, dtype=float).ravel()
    if i.size != w.size:
        raise ValueError(f"i_p and speed differ in length ({i.size} vs {w.size})")
    n_par = 3 if offset else 2
    if i.size < n_par + 2:
        raise ValueError(f"need at least {n_par + 2} samples (got {i.size})")
    if not (np.all(np.isfinite(i)) and np.all(np.isfinite(w))):
        raise ValueError("i_p and speed must be finite (no NaN/inf)")
    D = _decimation(float(Ts), float(Ts_model))
    cols = [w[:-1], i[:-1]]
    if offset:
        cols.append(np.ones(i.size - 1))
    X = np.column_stack(cols)
    y = w[1:]
    # scale columns for conditioning, then solve
    scale = np.maximum(np.max(np.abs(X), axis=0), 1e-300)
    theta, _, rank, _ = np.linalg.lstsq(X / scale, y, rcond=None)
    if rank < n_par:
        raise ValueError(
            "the trace does not excite the model (constant current or speed): "
            "capture a current step"
        )
    theta = theta / scale
    a_D, b_D = float(theta[0]), float(theta[1])
    c = float(theta[2]) if offset else 0.0
    if not 0.0 < a_D < 1.0:
        raise ValueError(
            f"fitted pole a^D = {a_D:.6g} is outside (0, 1): no stable first-order model fits"
        )
    resid = y - X @ theta
    one_step_rms = float(np.sqrt(np.mean(resid**2)))
    w_start = float(w[0])
    if refine:
        a_D, b_D, c, w_start = _output_error_refine(i, w, a_D, b_D, c, offset)
    a = a_D ** (1.0 / D)
    # b = b_D (1 - a) / (1 - a^D), computed without cancellation
    b = b_D * math.expm1(math.log(a)) / math.expm1(D * math.log(a))
    w_sim = simulate_first_order(a_D, b_D, i, w_start, c)
    err = w - w_sim
    rms = float(np.sqrt(np.mean(err**2)))
    ss = float(np.sum((w - np.mean(w)) ** 2))
    r2 = 1.0 - float(np.sum(err**2)) / ss if ss > 0 else math.nan
    return FirstOrderFit(
        a=float(a),
        b=float(b),
        offset=float(c),
        a_D=float(a_D),
        b_D=float(b_D),
        D=D,
        Ts=float(Ts),
        Ts_model=float(Ts_model),
        r2=r2,
        rms=rms,
        one_step_rms=one_step_rms,
        n_samples=int(i.size),
    )


def identify_first_order(
    i_p: np.ndarray, speed: np.ndarray, Ts: float = TS_MODEL, *, Ts_model: float = TS_MODEL
) -> tuple[float, float]:
    """``(a, b)`` of ``G(z) = b/(z - a)`` at the loop rate (eq. 26) from a current-step trace.

    ``i_p`` [A] and ``speed`` [rpm] sampled every ``Ts`` [s] (a multiple of ``Ts_model``); see
    :func:`fit_first_order` for the fit quality and the details. ``b`` is in rpm/A per loop sample.
    """
    fit = fit_first_order(i_p, speed, Ts, Ts_model=Ts_model)
    return fit.a, fit.b
