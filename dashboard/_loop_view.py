"""The tuning view's curves: Bode plot of the open loops and closed-loop poles (paper Figs. 4, 5,
12), computed from a gain set before it is applied.

A thin adapter of :mod:`drive_link.workflows.design`'s loop responses to uPlot's data layout, no
GUI. Units: frequency Hz, magnitude dB, phase degrees (unwrapped), poles as complex z (Ts = 20 µs).
A gain set is the dictionary of :func:`dashboard._tuning.read_gains` (``type``, ``L_c`` H,
``R_c`` Ω, ``k_p``/``k_i``
V/A, ``speed_k_p`` A/rpm, ``speed_k_i`` 1/sample, ``motor_R`` Ω, ``motor_L`` H).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from drive_link import design

__all__ = [
    "LoopView",
    "frequency_grid",
    "loop_view",
    "unit_circle",
    "z_plane_data",
]

N_POINTS = 400  #: frequencies on the log grid (drive_link.workflows.design's response grid)


@dataclass(frozen=True)
class LoopView:
    """Bode curves and closed-loop poles of one gain set.

    f_hz: log-spaced frequencies (0 < f < fs/2); current_db/current_deg: open current loop
    C(z)P(z); speed_db/speed_deg: open speed loop (IP on G(z) = b/(z − a), broken at the plant
    input); current_poles/speed_poles: closed-loop poles (complex z).
    """

    f_hz: np.ndarray
    current_db: np.ndarray
    current_deg: np.ndarray
    speed_db: np.ndarray
    speed_deg: np.ndarray
    current_poles: np.ndarray
    speed_poles: np.ndarray


def frequency_grid() -> np.ndarray:
    """The frequencies (Hz) every view is drawn on: drive_link.workflows.design's response grid."""
    return design.speed_loop_response(0.5, 1.0, 0.1, 0.1, n_points=N_POINTS).f_hz


def _finite(x: np.ndarray) -> np.ndarray:
    return np.where(np.isfinite(x), x, np.nan)


def loop_view(g: dict[str, Any], a: float, b: float) -> LoopView:
    """Bode curves and closed-loop poles of gain set ``g`` with speed model (a, b), from
    drive_link.workflows.design's ``current_loop_response`` and ``speed_loop_response``.

    :raises ValueError: a value the transfer functions cannot take (e.g. L_c ≤ 0).
    """
    cur = design.current_loop_response(
        g["type"],
        R=float(g["motor_R"]),
        L=float(g["motor_L"]),
        L_c=float(g["L_c"]),
        R_c=float(g["R_c"]),
        k_p=float(g["k_p"]),
        k_i=float(g["k_i"]),
        n_points=N_POINTS,
    )
    spd = design.speed_loop_response(
        a, b, float(g["speed_k_p"]), float(g["speed_k_i"]), n_points=N_POINTS
    )
    return LoopView(
        cur.f_hz,
        _finite(cur.magnitude_db),
        _finite(cur.phase_deg),
        _finite(spd.magnitude_db),
        _finite(spd.phase_deg),
        cur.poles,
        spd.poles,
    )


def unit_circle(n: int = 181) -> tuple[np.ndarray, np.ndarray]:
    """x (ascending, −1..1) and the upper half of the unit circle; the lower half is −y."""
    x = -np.cos(np.linspace(0.0, np.pi, n))
    return x, np.sqrt(np.clip(1.0 - x * x, 0.0, None))


def z_plane_data(*pole_sets: np.ndarray, n_circle: int = 181) -> tuple[np.ndarray, ...]:
    """uPlot data for a z-plane: (x, circle upper, circle lower, Im of set 1, Im of set 2, …).

    uPlot shares one ascending x array across series, so the circle's x samples and every pole's
    real part are merged and sorted; a series is NaN (not drawn) where it has no value.
    """
    cx, cy = unit_circle(n_circle)
    parts = [cx] + [np.real(np.asarray(p, dtype=complex)) for p in pole_sets]
    x = np.concatenate(parts)
    cols = [np.full(x.size, np.nan) for _ in range(2 + len(pole_sets))]
    cols[0][: cx.size], cols[1][: cx.size] = cy, -cy
    at = cx.size
    for k, p in enumerate(pole_sets):
        im = np.imag(np.asarray(p, dtype=complex))
        cols[2 + k][at : at + im.size] = im
        at += im.size
    order = np.argsort(x, kind="stable")
    return (x[order], *(c[order] for c in cols))
