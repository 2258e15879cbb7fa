"""Limits that turn a run's metrics into pass / fail.

``[limits]`` applies to every scenario; a scenario's own ``limits`` table overrides single
keys. Keys (each an upper bound on the metric's absolute value; a number is in the unit shown,
a string may carry another unit: ``settling = "3 ms"``):

| key | unit |
|---|---|
| overshoot | % |
| settling | s |
| peak_phase_current | A |
| ss_error | A (current step) or rpm (speed scenarios) |
| speed_dip | rpm |
| tracking_error | rpm |
| trip | bool: true allows a trip (default false: any trip fails the run) |
| stable | bool: false accepts an unstable run (default true) |

A limit on a metric that does not apply to the scenario (NaN) is not checked.
"""

from __future__ import annotations

import math
from typing import Any

from virtual_drive.sweep.units import SpecError, to_si

__all__ = ["LIMIT_UNITS", "resolve_limits", "severity", "verdict"]

LIMIT_UNITS: dict[str, str] = {
    "overshoot": "percent",
    "settling": "s",
    "peak_phase_current": "A",
    "ss_error": "y",
    "speed_dip": "rpm",
    "tracking_error": "rpm",
}


def resolve_limits(global_: dict[str, Any], own: dict[str, Any], unit: str, where: str) -> dict:
    """Effective limits of a scenario whose controlled variable is in ``unit`` ("A"/"rpm"):
    numeric bounds in the units of the table above, plus ``trip`` and ``stable`` flags."""
    merged = {**global_, **own}
    out: dict[str, Any] = {"trip": False, "stable": True}
    for key, val in merged.items():
        w = f"{where}.limits.{key}"
        if key in ("trip", "stable"):
            if not isinstance(val, bool):
                raise SpecError(f"{w} must be true or false, got {val!r}")
            out[key] = val
            continue
        if key not in LIMIT_UNITS:
            raise SpecError(f"{w}: unknown limit (known: {[*LIMIT_UNITS, 'trip', 'stable']})")
        si = unit if LIMIT_UNITS[key] == "y" else LIMIT_UNITS[key]
        if si == "percent":
            v = to_si(val, "percent", w)  # a bare number is in %
        else:
            v = to_si(val, si, w)
        if v < 0:
            raise SpecError(f"{w} must be >= 0, got {val!r}")
        out[key] = v
    return out


def verdict(metrics: dict[str, Any], limits: dict[str, Any]) -> list[str]:
    """Reasons the run fails (empty: it passes), e.g. ``["unstable", "overshoot>20"]``."""
    fails: list[str] = []
    if limits.get("stable", True) and not metrics["stable"]:
        fails.append("unstable")
    if metrics["emcy"] and not limits.get("trip", False):
        fails.append(f"trip 0x{int(metrics['emcy']):04X}")
    for key in LIMIT_UNITS:
        if key not in limits:
            continue
        v = metrics.get(key, math.nan)
        if v is None or (isinstance(v, float) and math.isnan(v)):
            continue
        if abs(v) > limits[key]:
            fails.append(f"{key}>{limits[key]:g}")
    return fails


def severity(metrics: dict[str, Any], limits: dict[str, Any], fails: list[str]) -> float:
    """How far a run is from passing: inf for unstable / trip / error, else the largest
    |metric| / limit (a passing run is <= 1)."""
    if any(f == "unstable" or f.startswith(("trip", "error")) for f in fails):
        return math.inf
    worst = 0.0
    for key in LIMIT_UNITS:
        if key not in limits:
            continue
        v = metrics.get(key, math.nan)
        if v is None or (isinstance(v, float) and math.isnan(v)):
            continue
        lim = limits[key]
        r = math.inf if lim == 0 and v != 0 else (0.0 if lim == 0 else abs(v) / lim)
        worst = max(worst, r)
    return worst
