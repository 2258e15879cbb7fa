"""Current- and speed-loop design maths of Valle et al., IEEE Access 2020 (pure numpy, no bus).

The facade: the names a user needs (``__all__``). The rooms behind it, one job each:

* :mod:`.pars` — :class:`CurrentLoopPars` (controller, R, L, L_c, R_c, k_p, k_i, fs) and
  :class:`SpeedLoopPars` (a, b, k_p, k_i, fs): one loop as one object, taken by
  :func:`loop_tf`, :func:`controller_tf`, :func:`predict_step`, :func:`speed_closed_loop` and
  :func:`speed_open_loop`; the keyword functions below build them;
* :mod:`.lti` — :class:`DiscreteTF`, feedback, stability tests (roots, Jury), margins;
* :mod:`.current_loop` — plant (eqs. 4–9), deadbeat (15), PI (22), predictive (23), the open
  loop ``C(z) P(z)``, the mismatched deadbeat loop (16), PI gains for a crossover and margin;
* :mod:`.step` — predicted current-loop steps (eq. 6 with the one-sample delay), eq. (25);
* :mod:`.speed_loop` — IP gains (eqs. 28–31), the closed loop (27), its open loop, the
  predicted speed step;
* :mod:`.report` — :func:`analyse_current_loop`, the JSON-ready report of one current loop;
* :mod:`.response` — what a tuning view draws: Bode data and z-plane poles.

Symbols follow the paper: ``R``, ``L`` [Ω, H] the motor's, ``L_c``, ``R_c`` the controller's
estimates, ``fs`` [Hz] (50 kHz, ``Ts = 1/fs``), ``Phi = exp(-R Ts / L)`` (eq. 4),
``Gamma = (1 - Phi) / (2 R)`` [A/V] (eq. 5), ``P(z) = Gamma / (z (z - Phi))`` (eq. 8),
``C_db(z) = (z² - Phi_c z) / (Gamma_c (z² - 1))`` (eq. 15), ``C_PI(z) = k_p + k_i z / (z - 1)``
[V/A] (eq. 22), the predictive law ``v_L(k+1) = 2 L_c fs (i_p* - i_p(k)) - v_L(k) + 2 e_L(k)``
(eq. 23: the linear controller ``2 L_c fs z / (z + 1)`` plus a back-EMF feed-forward), the speed
model ``G(z) = b / (z - a)`` [rpm/A per sample] (eq. 26) and the IP law
``u = k_p (k_i z/(z-1) (w* - w) - w)`` (closed loop eq. 27). With exact L_c and R = 0 the
predictive law gives ``I_p/I_p* = z^-2`` as the paper states. Note: the paper's eq. (24) places
``2 L fs Gamma`` as the constant term of the denominator; substituting eq. (23) into eq. (6)
gives it as the coefficient of ``z`` (the printed polynomial has a root outside the unit circle),
and the steady-state error of eq. (23) with R ≠ 0 is ≈ 1.65 % here rather than the 0.83 %
quoted in the text.

Phase margins follow one convention everywhere (design, ``drive-link design``, the dashboard's
API and GUI): the smallest margin over all gain crossovers, as a positive angle, with every
crossover listed (:func:`margins_summary`); see :mod:`.lti`.

For a tuning view (the paper's Figs. 4, 5, 12), before anything is applied::

    from drive_link import design
    r = design.current_loop_response("deadbeat", R=6.2e-3, L=14.8e-6, L_c=22.2e-6, R_c=6.2e-3)
    r.f_hz, r.magnitude_db, r.phase_deg      # Bode of C(z) P(z): Hz, dB, ° (unwrapped)
    r.closed_loop_db, r.sensitivity_db       # |T|, |S| in dB on the same grid
    r.poles, r.zeros, r.stable               # closed-loop I_p/I_p* in the z-plane (complex)
    r.margins.phase_margin_deg, r.as_dict()  # 41.4° (both crossovers in r.margins); JSON
    s = design.speed_loop_response(a=0.9999785, b=3.33715e-4, k_p=0.2113, k_i=2.9994e-5)
    s.poles                                  # eq. (27) in the z-plane; s.f_hz ... as above

``current_loop_response(controller, *, R, L, L_c, R_c, k_p, k_i, fs, n_points)`` and
``speed_loop_response(a, b, k_p, k_i, *, fs, n_points)`` both return a :class:`LoopResponse`.
"""

from __future__ import annotations

from ._common import (
    CONTROLLERS,
    FS_DEFAULT,
    L_TABLE2,
    PI_KI_PAPER,
    PI_KP_PAPER,
    R_TABLE2,
    ControllerName,
    controller_name,
)
from .current_loop import (
    closed_loop_mismatch,
    controller_tf,
    current_loop_tf,
    loop_tf,
    phi_gamma,
    pi_current_gains,
    plant_tf,
)
from .lti import DiscreteTF, Margins, feedback, is_stable, jury_stable, margins
from .pars import CurrentLoopPars, SpeedLoopPars
from .report import analyse_current_loop
from .response import (
    LoopResponse,
    current_loop_response,
    margins_summary,
    speed_loop_response,
)
from .speed_loop import (
    IPDesign,
    PredictedSpeedStep,
    ip_closed_loop,
    ip_design,
    ip_gains,
    predicted_speed_step,
    speed_closed_loop,
    speed_loop_tf,
    speed_open_loop,
)
from .step import PredictedStep, eq25_compensation, predict_step, predicted_step

__all__ = [
    "CONTROLLERS",
    "FS_DEFAULT",
    "L_TABLE2",
    "PI_KI_PAPER",
    "PI_KP_PAPER",
    "R_TABLE2",
    "ControllerName",
    "CurrentLoopPars",
    "DiscreteTF",
    "IPDesign",
    "LoopResponse",
    "Margins",
    "PredictedSpeedStep",
    "PredictedStep",
    "SpeedLoopPars",
    "analyse_current_loop",
    "closed_loop_mismatch",
    "controller_name",
    "controller_tf",
    "current_loop_response",
    "current_loop_tf",
    "eq25_compensation",
    "feedback",
    "ip_closed_loop",
    "ip_design",
    "ip_gains",
    "is_stable",
    "jury_stable",
    "loop_tf",
    "margins",
    "margins_summary",
    "phi_gamma",
    "pi_current_gains",
    "plant_tf",
    "predict_step",
    "predicted_speed_step",
    "predicted_step",
    "speed_closed_loop",
    "speed_loop_response",
    "speed_loop_tf",
    "speed_open_loop",
]
