"""What the live plots send: decimated windows (at most a few hundred points per series) and
the data's freshness. No viser here: plain arrays in, plain arrays out.

Units: t in s (host clock, as Drive.live stamps frames), values in the series' own units.
"""

from __future__ import annotations

import math
import time

import numpy as np
import numpy.typing as npt

__all__ = ["STALE_AFTER_S", "data_age_s", "decimate", "freshness_text", "min_span_envelope"]

STALE_AFTER_S = 0.5  #: the live view says "stale" when the newest sample is older than this (s)


def decimate(
    t: np.ndarray, cols: list[np.ndarray], buckets: int = 100
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Keep, per time bucket (``buckets`` over t's span), the samples where each series has its
    minimum and maximum, every sample where a series changes step-wise across a bucket edge
    is kept through the bucket's last sample, and always the first and last sample: the drawn
    line keeps every peak and the newest value. Returns (t, cols) at the kept indices (sorted,
    unique); inputs shorter than 3 × ``buckets`` come back unchanged."""
    n = len(t)
    if n <= 3 * buckets:
        return t, cols
    edges = np.linspace(t[0], t[-1], buckets + 1)
    b = np.searchsorted(edges, t, side="right") - 1
    np.clip(b, 0, buckets - 1, out=b)
    new_bucket = np.empty(n, dtype=bool)  # no np.r_ (slow): this runs 24 times/s
    new_bucket[0] = True
    np.not_equal(b[1:], b[:-1], out=new_bucket[1:])
    starts = np.flatnonzero(new_bucket)
    ends = np.append(starts[1:], n)
    keep = [np.array([0, n - 1]), ends - 1]
    lengths = ends - starts
    width = int(lengths.max())
    grid: np.ndarray | None = None  # per bucket, one row of sample indices (padded)
    pad: np.ndarray | None = None  # True where a row runs past its bucket's end
    seg: npt.NDArray[np.intp] | None = None  # each sample's bucket number
    if width * len(starts) <= 2 * n:  # buckets of similar length: one padded row each
        grid = starts[:, None] + np.arange(width)
        pad = grid >= ends[:, None]
        np.minimum(grid, n - 1, out=grid)
    else:
        seg = np.repeat(np.arange(len(starts)), lengths)
    for c in cols:
        ok = np.isfinite(c)
        finite = c if ok.all() else np.where(ok, c, np.nanmean(c) if ok.any() else 0.0)
        if grid is not None and pad is not None:  # argmin/argmax: first extremum of each row
            rows = finite[grid]
            rows[pad] = np.inf
            keep.append(starts + rows.argmin(axis=1))
            rows[pad] = -np.inf
            keep.append(starts + rows.argmax(axis=1))
        elif seg is not None:
            keep.append(starts + _argext(finite, starts, seg, np.minimum))
            keep.append(starts + _argext(finite, starts, seg, np.maximum))
    mask = np.zeros(n, dtype=bool)  # sorted and unique, without np.unique's sort
    mask[np.concatenate(keep)] = True
    idx = np.flatnonzero(mask)
    return t[idx], [c[idx] for c in cols]


def _argext(
    v: np.ndarray, starts: npt.NDArray[np.intp], seg: npt.NDArray[np.intp], ufunc: np.ufunc
) -> npt.NDArray[np.intp]:
    """Per segment (``seg``: each sample's segment number, segments starting at ``starts``) the
    index of its first min (ufunc=np.minimum) or max, relative to its start (vectorised: no
    Python loop over the segments; every segment holds its extremum, so each has a hit)."""
    ext = ufunc.reduceat(v, starts)
    hits = np.flatnonzero(v == ext[seg])
    s = seg[hits]
    first = np.empty(len(s), dtype=bool)
    first[:1] = True
    np.not_equal(s[1:], s[:-1], out=first[1:])
    return hits[first] - starts


def min_span_envelope(n: int, *series: np.ndarray, min_span: float) -> np.ndarray:
    """``n`` values whose first and last are the centre of ``series`` ∓ ``min_span``/2 (the
    centre snapped to ``min_span``/10 so the axis stays still at steady state), the rest the
    centre: drawn invisibly, it makes uPlot's y auto-scale at least ``min_span`` wide (units of
    the series) without hiding larger swings."""
    lo = min(float(c.min()) for c in series)
    hi = max(float(c.max()) for c in series)
    q = min_span / 10
    centre = round((lo + hi) / 2 / q) * q
    out = np.full(n, centre, dtype=np.float64)
    out[0], out[-1] = centre - min_span / 2, centre + min_span / 2
    return out


def data_age_s(newest_t: float | None, now: float | None = None) -> float | None:
    """Seconds since the newest sample (host clock, ≥ 0), or None before any sample."""
    if newest_t is None or not math.isfinite(newest_t):
        return None
    return max(0.0, (time.time() if now is None else now) - newest_t)


def freshness_text(age_s: float | None, push_age_s: float | None = None) -> tuple[bool, str]:
    """(stale, text) for the page: fresh data shows its age in s; data older than
    STALE_AFTER_S, no data at all, or plots not refreshed for that long show "STALE". Ages
    in s."""
    if age_s is None:
        return True, "STALE · no live data yet"
    if push_age_s is not None and push_age_s > STALE_AFTER_S and age_s <= STALE_AFTER_S:
        return True, f"STALE · plots not refreshed for {push_age_s:.1f} s"
    if age_s > STALE_AFTER_S:
        return True, f"STALE · newest data {age_s:.1f} s old"
    return False, f"live · data {age_s:.2f} s old"
