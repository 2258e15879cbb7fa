"""The tuning view's curves: Bode plot of the open loops and closed-loop poles (paper Figs. 4, 5,
12), computed from a gain set before it is applied.

Pure numpy on :mod:`drive_link.design`'s transfer functions, no GUI. Units: frequency Hz,
magnitude dB, phase degrees (unwrapped), poles as complex z (Ts = 20 µs). A gain set is the
dictionary of :func:`dashboard.tuning.read_gains` (``type``, ``L_c`` H, ``R_c`` Ω, ``k_p``/``k_i``
V/A, ``speed_k_p`` A/rpm, ``speed_k_i`` 1/sample, ``motor_R`` Ω, ``motor_L`` H).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from drive_link import design

__all__ = [
    "F_MAX_HZ",
    "F_MIN_HZ",
    "LoopView",
    "current_loop",
    "frequency_grid",
    "loop_view",
    "speed_loop",
    "unit_circle",
    "z_plane_data",
]

F_MIN_HZ = 0.1  #: low end of the Bode plot (Hz): below the speed loop's crossover
F_MAX_HZ = 24_900.0  #: high end (Hz): just under the Nyquist frequency fs/2 = 25 kHz
N_POINTS = 400  #: frequencies on the log grid


@dataclass(frozen=True)
class LoopView:
    """Bode curves and closed-loop poles of one gain set.

    f_hz: log-spaced frequencies; current_db/current_deg: open current loop C(z)P(z);
    speed_db/speed_deg: open speed loop (IP on G(z) = b/(z − a)); current_poles/speed_poles:
    closed-loop poles (complex z).
    """

    f_hz: np.ndarray
    current_db: np.ndarray
    current_deg: np.ndarray
    speed_db: np.ndarray
    speed_deg: np.ndarray
    current_poles: np.ndarray
    speed_poles: np.ndarray


def frequency_grid(n: int = N_POINTS) -> np.ndarray:
    """``n`` log-spaced frequencies from F_MIN_HZ to F_MAX_HZ (Hz)."""
    return np.geomspace(F_MIN_HZ, F_MAX_HZ, n)


def _bode(tf: design.DiscreteTF, f_hz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    h = tf.freqresp(2 * np.pi * f_hz)
    with np.errstate(divide="ignore"):
        db = 20 * np.log10(np.abs(h))
    deg = np.degrees(np.unwrap(np.angle(h)))
    return np.where(np.isfinite(db), db, np.nan), deg


def current_loop(g: dict[str, Any]) -> design.DiscreteTF:
    """Open current loop C(z)P(z) of gain set ``g`` on the drive's motor R, L."""
    return design.current_loop_tf(
        g["type"],
        R=float(g["motor_R"]),
        L=float(g["motor_L"]),
        L_c=float(g["L_c"]),
        R_c=float(g["R_c"]),
        k_p=float(g["k_p"]),
        k_i=float(g["k_i"]),
    )


def speed_loop(g: dict[str, Any], a: float, b: float) -> design.DiscreteTF:
    """Open speed loop: IP feedback k_p (1 + k_i z/(z − 1)) times G(z) = b/(z − a)."""
    kp, ki = float(g["speed_k_p"]), float(g["speed_k_i"])
    G = design.DiscreteTF([b], [1.0, -a])
    return design.DiscreteTF([kp * (1.0 + ki), -kp], [1.0, -1.0]) * G


def loop_view(g: dict[str, Any], a: float, b: float, f_hz: np.ndarray | None = None) -> LoopView:
    """Bode curves and closed-loop poles of gain set ``g`` with speed model (a, b).

    :raises ValueError: a value the transfer functions cannot take (e.g. L_c ≤ 0).
    """
    f = frequency_grid() if f_hz is None else np.asarray(f_hz, dtype=float)
    cur = current_loop(g)
    spd = speed_loop(g, a, b)
    c_db, c_deg = _bode(cur, f)
    s_db, s_deg = _bode(spd, f)
    cl_speed = design.ip_closed_loop(a, b, float(g["speed_k_p"]), float(g["speed_k_i"]))
    return LoopView(
        f, c_db, c_deg, s_db, s_deg, design.feedback(cur).poles(), np.asarray(cl_speed.poles())
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
