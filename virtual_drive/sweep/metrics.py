"""Metrics of one sweep run, computed with numpy from its :class:`~.scenarios.Trace`.

All on the sample instants (fs = 50 kHz); ``y`` is i_p (A) for a current step and the speed
(rpm) otherwise, ``r`` its reference, ``e = r - y``, the "event" is the step (or, for a
profile, the start of its final hold):

- ``stable`` (bool): no trip and the error neither exceeds the stability band nor keeps
  oscillating. The recorded time after the event is split into quarters; with ``pp1``, ``pp2``
  the peak-to-peak of ``e`` in the last two, the run is unstable if ``pp2 > band * scale`` or if
  ``pp2 > 0.02 * scale`` and ``pp2 > 0.9 * pp1`` (not decaying), the peak-to-peak taken about
  the window's least-squares line so that a slow but steady approach is not an oscillation.
  In a speed scenario the current loop is tested too: the median of |i_p* - i_p| over the
  last quarter must stay within 6 % of the current limit (at least 3 A). (Its peak-to-peak
  would not do: each commutation dips i_p by 25-40 A for a few samples in a stable loop; an
  unstable one oscillates at every sample, median 9-17 A at 100 A.) ``scale`` is |to - from| of a
  step, else max(|speed|, 1 rpm); ``band`` is ``[sweep] stability_band`` (default 0.25).
  A saturated unstable loop is a bounded limit cycle, so boundedness alone would not do.
  A run must therefore be long enough for a stable loop to settle in its first half.
- ``emcy`` (int): the trip's EMCY code (0x2310 overcurrent, 0x3210 / 0x3220 DC link), 0 none;
  ``trip_t`` (s) its time after the settling (negative: during it).
- ``overshoot`` (%): max over the samples after a step of (y - to) sign(to - from), in % of
  |to - from| (>= 0).
- ``settling`` (s): time from the step until |y - to| stays within 2 % of |to - from|
  (load step: of max(|speed|, 1 rpm)); ``inf`` if it never does within the run.
- ``peak_phase_current`` (A): largest |i_a|, |i_b|, |i_c| at the samples.
- ``ss_error`` (A or rpm): mean of e over the last 10 % of the run (signed).
- ``speed_dip`` (rpm): load step: max of (reference - speed) after the step, >= 0.
- ``tracking_error`` (rpm): profile: max |e| over the run.

A metric that does not apply to the scenario is NaN (and no limit is applied to it).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from virtual_drive.sim.params import Ts
from virtual_drive.sweep.scenarios import Scenario, Trace

__all__ = ["METRICS", "METRIC_UNITS", "compute_metrics", "is_stable"]

#: metric -> unit ("y" = the scenario's controlled variable: A or rpm)
METRIC_UNITS: dict[str, str] = {
    "stable": "bool",
    "emcy": "EMCY code",
    "trip_t": "s",
    "overshoot": "%",
    "settling": "s",
    "peak_phase_current": "A",
    "ss_error": "y",
    "speed_dip": "rpm",
    "tracking_error": "rpm",
}
METRICS: tuple[str, ...] = tuple(METRIC_UNITS)


def _scale(sc: Scenario) -> float:
    if sc.kind in ("current_step", "speed_step") and sc.final != sc.initial:
        return abs(sc.final - sc.initial)
    top = max(abs(sc.speed), *(abs(p[1]) for p in sc.points)) if sc.points else abs(sc.speed)
    return max(top, 1.0)


def _wobble(w: np.ndarray) -> float:
    """Peak-to-peak of ``w`` about its least-squares line (a slow approach or drift is
    nearly a line over a short window; an oscillation is not)."""
    x = np.arange(w.shape[0], dtype=np.float64)
    x -= x.mean()
    slope = float(np.dot(x, w - w.mean()) / np.dot(x, x))
    res = w - w.mean() - slope * x
    return float(np.max(res) - np.min(res))


def is_stable(e: np.ndarray, k_event: int, scale: float, band: float) -> bool:
    """The stability test of the module docstring on the error ``e`` after ``k_event``."""
    n = e.shape[0]
    W = (n - k_event) // 4
    if W < 4:
        return True  # too short to judge; the trip check still applies
    pp1 = _wobble(e[n - 2 * W : n - W])
    pp2 = _wobble(e[n - W :])
    if not (math.isfinite(pp1) and math.isfinite(pp2)):
        return False
    if pp2 > band * scale:
        return False
    return not (pp2 > 0.02 * scale and pp2 > 0.9 * pp1)


def compute_metrics(
    tr: Trace, sc: Scenario, band: float = 0.25, current_limit: float = 100.0
) -> dict[str, Any]:
    """The metrics of the module docstring for one run (``current_limit``: the speed
    controller's output limit, A)."""
    nan = math.nan
    n = tr.n
    tripped = tr.fault != 0
    out: dict[str, Any] = {
        "stable": False,
        "emcy": int(tr.fault),
        "trip_t": tr.fault_t if tripped else nan,
        "overshoot": nan,
        "settling": nan,
        "peak_phase_current": float(np.max(tr.i_peak)) if n else nan,
        "ss_error": nan,
        "speed_dip": nan,
        "tracking_error": nan,
    }
    scale = _scale(sc)
    e = tr.r - tr.y
    k0 = min(tr.k_event, n)
    out["stable"] = (not tripped) and n > 0 and is_stable(e, k0, scale, band)
    if out["stable"] and sc.kind != "current_step":
        W = (n - k0) // 4
        if W >= 4 and float(np.median(np.abs(tr.e_i[n - W :]))) > max(
            0.06 * current_limit, 3.0
        ):
            out["stable"] = False
    if n and not tripped:
        tail = max(1, n // 10)
        out["ss_error"] = float(np.mean(e[n - tail :]))
    after_y = tr.y[k0:]
    if sc.kind in ("current_step", "speed_step") and sc.final != sc.initial:
        d = sc.final - sc.initial
        if after_y.size:
            ov = float(np.max((after_y - sc.final) * math.copysign(1.0, d))) / abs(d) * 100.0
            out["overshoot"] = max(0.0, ov)
        out["settling"] = _settling(after_y - sc.final, 0.02 * abs(d), tripped)
    elif sc.kind == "load_step":
        out["settling"] = _settling(after_y - sc.speed, 0.02 * scale, tripped)
        if n > k0:
            out["speed_dip"] = max(0.0, float(np.max(tr.r[k0:] - tr.speed[k0:])))
    elif sc.kind == "speed_profile" and n:
        out["tracking_error"] = float(np.max(np.abs(e)))
    return out


def _settling(dev: np.ndarray, band: float, tripped: bool) -> float:
    """Time (s) after which |dev| stays <= band; inf if the last sample is outside or the
    run tripped."""
    if tripped or dev.size == 0:
        return math.inf
    outside = np.flatnonzero(np.abs(dev) > band)
    if outside.size == 0:
        return 0.0
    last = int(outside[-1])
    if last == dev.size - 1:
        return math.inf
    return (last + 1) * Ts
