"""What a tuning view draws (the paper's Figs. 4, 5, 12): a loop's frequency response (Bode) and
its closed-loop poles in the z-plane, for the current loop (controller, L_c, R_c, k_p, k_i on the
motor R, L) and for the IP speed loop (k_p, k_i on the speed model b/(z - a)).

Pure numpy, no bus: call it as the user types, before anything is applied. Every array is
float64; :meth:`LoopResponse.as_dict` gives a JSON-ready dict.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._common import (
    FS_DEFAULT,
    L_TABLE2,
    PI_KI_PAPER,
    PI_KP_PAPER,
    R_TABLE2,
    ControllerName,
    _positive,
)
from .current_loop import loop_tf
from .lti import DiscreteTF, Margins, feedback, is_stable, margins
from .pars import CurrentLoopPars, SpeedLoopPars
from .speed_loop import speed_closed_loop, speed_open_loop

__all__ = ["LoopResponse", "current_loop_response", "margins_summary", "speed_loop_response"]


@dataclass(frozen=True)
class LoopResponse:
    """Frequency response and closed-loop poles of one loop.

    Attributes:
        f_hz: frequency grid [Hz], log-spaced in (0, fs/2) (the Nyquist frequency excluded).
        magnitude_db: open-loop gain ``20 log10 |L(e^{j2πf Ts})|`` [dB].
        phase_deg: open-loop phase ``arg L`` [°], unwrapped along the grid.
        closed_loop_db: ``|T| = |L / (1 + L)|`` [dB] (reference to output).
        sensitivity_db: ``|S| = |1 / (1 + L)|`` [dB].
        poles: closed-loop poles in the z-plane (complex).
        zeros: closed-loop zeros in the z-plane (complex).
        stable: every closed-loop pole strictly inside the unit circle.
        max_pole_radius: largest |pole|.
        margins: :class:`drive_link.workflows.design.Margins` of the open loop (PM a positive angle,
        every
            crossover listed).
        fs: sampling frequency [Hz].
    """

    f_hz: np.ndarray
    magnitude_db: np.ndarray
    phase_deg: np.ndarray
    closed_loop_db: np.ndarray
    sensitivity_db: np.ndarray
    poles: np.ndarray
    zeros: np.ndarray
    stable: bool
    max_pole_radius: float
    margins: Margins
    fs: float

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: arrays as lists, poles/zeros as [re, im] pairs, non-finite floats None."""
        return {
            "f_hz": _floats(self.f_hz),
            "magnitude_db": _floats(self.magnitude_db),
            "phase_deg": _floats(self.phase_deg),
            "closed_loop_db": _floats(self.closed_loop_db),
            "sensitivity_db": _floats(self.sensitivity_db),
            "poles": [[float(p.real), float(p.imag)] for p in self.poles],
            "zeros": [[float(p.real), float(p.imag)] for p in self.zeros],
            "stable": self.stable,
            "max_pole_radius": self.max_pole_radius,
            "fs": self.fs,
            **margins_summary(self.margins),
        }


def _floats(a: np.ndarray) -> list[float | None]:
    return [float(x) if math.isfinite(x) else None for x in np.asarray(a, dtype=float)]


def margins_summary(m: Margins) -> dict[str, Any]:
    """The margins as the CLI, the API and the GUI report them (one convention): GM [dB] and
    its frequency, PM [°] (the smallest, positive) and its crossover [Hz], ‖S‖∞, and every
    gain crossover with its margin (``crossovers``: [{"hz", "phase_margin_deg"}], rising)."""
    return {
        "gain_margin_db": m.gain_margin_db,
        "phase_crossover_hz": m.phase_crossover_hz,
        "phase_margin_deg": m.phase_margin_deg,
        "gain_crossover_hz": m.gain_crossover_hz,
        "sensitivity_peak": m.sensitivity_peak,
        "crossovers": [
            {"hz": hz, "phase_margin_deg": pm}
            for hz, pm in zip(m.gain_crossovers_hz, m.phase_margins_deg, strict=True)
        ],
    }


def _response(loop: DiscreteTF, closed: DiscreteTF, fs: float, n_points: int) -> LoopResponse:
    if n_points < 10:
        raise ValueError(f"n_points must be >= 10 (got {n_points})")
    nyq = fs / 2.0
    f = np.geomspace(nyq * 1e-6, nyq * (1.0 - 1e-6), int(n_points))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        H = loop.freqresp(2.0 * math.pi * f)
        mag = 20.0 * np.log10(np.abs(H))
        phase = np.degrees(np.unwrap(np.angle(H)))
        T = 20.0 * np.log10(np.abs(H / (1.0 + H)))
        S = -20.0 * np.log10(np.abs(1.0 + H))
    poles = closed.poles().astype(complex)
    return LoopResponse(
        f_hz=f,
        magnitude_db=mag,
        phase_deg=phase,
        closed_loop_db=T,
        sensitivity_db=S,
        poles=poles,
        zeros=closed.zeros().astype(complex),
        stable=is_stable(closed),
        max_pole_radius=float(np.max(np.abs(poles))) if poles.size else 0.0,
        margins=margins(loop),
        fs=fs,
    )


def current_loop_response(
    controller: ControllerName = "deadbeat",
    *,
    R: float = R_TABLE2,
    L: float = L_TABLE2,
    L_c: float | None = None,
    R_c: float | None = None,
    k_p: float = PI_KP_PAPER,
    k_i: float = PI_KI_PAPER,
    fs: float = FS_DEFAULT,
    n_points: int = 400,
) -> LoopResponse:
    """Bode data of the current open loop ``C(z) P(z)`` and the closed-loop poles/zeros of
    ``I_p / I_p*`` (Figs. 4, 5: deadbeat with L_c, R_c; PI with k_p, k_i; predictive with L_c).

    R, R_c [Ω], L, L_c [H] (L_c, R_c default to L, R), k_p, k_i [V/A] (PI), fs [Hz]; the grid
    has ``n_points`` frequencies. ValueError for bad input.
    """
    p = CurrentLoopPars(controller, R, L, L_c, R_c, k_p, k_i, fs)
    loop = loop_tf(p)
    return _response(loop, feedback(loop), _positive("fs", fs), n_points)


def speed_loop_response(
    a: float,
    b: float,
    k_p: float,
    k_i: float,
    *,
    fs: float = FS_DEFAULT,
    n_points: int = 400,
) -> LoopResponse:
    """Bode data of the IP speed loop's open loop (:func:`speed_loop_tf`, broken at the plant
    input) and the poles/zeros of its closed loop ``w / w*`` (eq. 27, Fig. 12) with an ideal
    current loop.

    a (per loop sample), b [rpm/A per sample], k_p [A/rpm], k_i [1/sample], fs [Hz].
    """
    p = SpeedLoopPars(a, b, k_p, k_i, fs)
    return _response(speed_open_loop(p), speed_closed_loop(p), _positive("fs", fs), n_points)
