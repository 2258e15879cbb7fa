"""Step-response figures of merit for sampled signals (pure numpy).

Works on any array with a time base: a predicted response, a simulator record, a trace capture.
Rise time is 10–90 % of the step (thresholds configurable), overshoot is relative to the step
size, settling time uses a band relative to the step size (2 % by default), and steady-state
error is reference minus final value. Switching ripple can be removed first with a moving
average over one sampling period, as the paper's ī_p (Section IV-B, Fig. 13).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["StepMetrics", "moving_average", "step_metrics"]


@dataclass(frozen=True)
class StepMetrics:
    """Figures of merit of one step.

    Attributes:
        y_initial: value before the step (unit of y).
        y_final: final value (mean of the last ``final_fraction`` of the record) (unit of y).
        rise_time: time from the lower to the upper threshold crossing [s] (nan if never reached).
        overshoot_pct: peak excursion beyond y_final in % of |y_final - y_initial| (>= 0).
        peak: extreme value in the step direction (unit of y); peak_time [s] after the step.
        settling_time: time after the step after which y stays within the band around y_final [s]
            (nan if it never settles within the record).
        steady_state_error: reference - y_final (unit of y; nan without a reference).
    """

    y_initial: float
    y_final: float
    rise_time: float
    overshoot_pct: float
    peak: float
    peak_time: float
    settling_time: float
    steady_state_error: float

    def as_dict(self) -> dict[str, float]:
        """Plain ``dict`` (JSON-friendly)."""
        return asdict(self)


def moving_average(y: np.ndarray, window: int) -> np.ndarray:
    """Causal moving average over ``window`` samples (the first samples average what exists).

    Args:
        y: signal (any unit).
        window: number of samples (>= 1); 1 returns a float copy.
    """
    w = int(window)
    if w < 1:
        raise ValueError(f"window must be >= 1 sample (got {window!r})")
    y = np.asarray(y, dtype=float)
    c = np.cumsum(np.concatenate([[0.0], y]))
    out = np.empty_like(y)
    idx = np.arange(1, y.size + 1)
    lo = np.maximum(idx - w, 0)
    out[:] = (c[idx] - c[lo]) / (idx - lo)
    return out


def _crossing_time(t: np.ndarray, s: np.ndarray, level: float) -> float:
    """First time the (step-direction normalised) signal s reaches ``level``, interpolated."""
    hit = np.flatnonzero(s >= level)
    if hit.size == 0:
        return math.nan
    k = int(hit[0])
    if k == 0:
        return float(t[0])
    s0, s1 = s[k - 1], s[k]
    frac = (level - s0) / (s1 - s0) if s1 != s0 else 1.0
    return float(t[k - 1] + frac * (t[k] - t[k - 1]))


def step_metrics(
    t: np.ndarray,
    y: np.ndarray,
    *,
    reference: float | None = None,
    t_step: float | None = None,
    y_initial: float | None = None,
    y_final: float | None = None,
    settling_band: float = 0.02,
    rise_limits: tuple[float, float] = (0.1, 0.9),
    final_fraction: float = 0.1,
    average_window: float | None = None,
) -> StepMetrics:
    """Rise time, overshoot, settling time and steady-state error of a step response.

    Args:
        t: sample times [s], strictly increasing, same length as y.
        y: response (any unit, e.g. A or rpm).
        reference: final reference value (unit of y) for the steady-state error.
        t_step: time of the step [s]; default t[0]. Samples before it give y_initial.
        y_initial: value before the step; default mean of the samples before t_step, else y[0].
        y_final: final value; default mean of the last ``final_fraction`` of the samples.
        settling_band: half-width of the settling band, fraction of |y_final - y_initial|.
        rise_limits: lower/upper fractions of the step for the rise time (default 10 %, 90 %).
        final_fraction: fraction (0, 1] of the record averaged for the default y_final.
        average_window: if given, a moving average over this duration [s] (e.g. one Ts, the
            paper's ī_p) is applied first to remove switching ripple.

    Returns:
        :class:`StepMetrics`. Raises ValueError for malformed input or a zero-size step.
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if t.ndim != 1 or y.ndim != 1 or t.size != y.size:
        raise ValueError("t and y must be 1-D arrays of the same length")
    if t.size < 2:
        raise ValueError("need at least 2 samples")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise ValueError("t and y must be finite")
    dt = np.diff(t)
    if np.any(dt <= 0):
        raise ValueError("t must be strictly increasing")
    if not 0.0 < settling_band < 1.0:
        raise ValueError(f"settling_band must be in (0, 1) (got {settling_band!r})")
    lo_f, hi_f = rise_limits
    if not 0.0 <= lo_f < hi_f <= 1.0:
        raise ValueError(f"rise_limits must satisfy 0 <= low < high <= 1 (got {rise_limits!r})")
    if not 0.0 < final_fraction <= 1.0:
        raise ValueError(f"final_fraction must be in (0, 1] (got {final_fraction!r})")
    if average_window is not None:
        if not math.isfinite(average_window) or average_window <= 0:
            raise ValueError(f"average_window must be > 0 s (got {average_window!r})")
        n_win = max(1, round(average_window / float(np.median(dt))))
        y = moving_average(y, n_win)
    ts = float(t[0]) if t_step is None else float(t_step)
    before = t < ts
    after = ~before
    if not np.any(after):
        raise ValueError("t_step is after the last sample")
    if y_initial is None:
        y0 = float(np.mean(y[before])) if np.any(before) else float(y[0])
    else:
        y0 = float(y_initial)
    ta, ya = t[after], y[after]
    if y_final is None:
        n_tail = max(1, math.ceil(final_fraction * ya.size))
        yf = float(np.mean(ya[-n_tail:]))
    else:
        yf = float(y_final)
    step = yf - y0
    if step == 0.0 or not math.isfinite(step):
        raise ValueError("the response has no step (y_final equals y_initial)")
    s = (ya - y0) / step  # 0 → 1 in the step direction
    t_lo = _crossing_time(ta, s, lo_f)
    t_hi = _crossing_time(ta, s, hi_f)
    rise = t_hi - t_lo if math.isfinite(t_lo) and math.isfinite(t_hi) else math.nan
    k_pk = int(np.argmax(s))
    overshoot = max(0.0, float(s[k_pk]) - 1.0) * 100.0
    outside = np.flatnonzero(np.abs(s - 1.0) > settling_band)
    if outside.size == 0:
        settling = float(ta[0] - ts)
    elif outside[-1] == s.size - 1:
        settling = math.nan
    else:
        settling = float(ta[outside[-1] + 1] - ts)
    sse = math.nan if reference is None else float(reference) - yf
    return StepMetrics(
        y_initial=y0,
        y_final=yf,
        rise_time=rise,
        overshoot_pct=overshoot,
        peak=float(ya[k_pk]),
        peak_time=float(ta[k_pk] - ts),
        settling_time=settling,
        steady_state_error=sse,
    )
