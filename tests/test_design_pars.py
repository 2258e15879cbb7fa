"""One loop as one object (drive_link.workflows.design.CurrentLoopPars / SpeedLoopPars): the loop it
describes is the paper's. Truth: python-control (test-only oracle) building eq. (8)'s plant
with eq. (22)'s PI law, and the IP law of eq. (27) on eq. (26)'s model, by its own route."""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

from drive_link import design

pytestmark = pytest.mark.unit

R, L, FS = 6.2e-3, 14.8e-6, 50e3
TS = 1 / FS


def _same_roots(a: np.ndarray, b: np.ndarray) -> bool:
    return np.allclose(np.sort_complex(a), np.sort_complex(b), atol=1e-9)


def test_current_loop_pars_give_the_papers_pi_loop():
    Phi = math.exp(-R * TS / L)
    P = control.tf([(1 - Phi) / (2 * R)], [1, -Phi, 0], TS)
    C = control.tf([0.4647 + 0.0492, -0.4647], [1, -1], TS)
    want = control.poles(control.feedback(C * P, 1))
    p = design.CurrentLoopPars("pi", R=R, L=L, k_p=0.4647, k_i=0.0492, fs=FS)
    assert _same_roots(design.feedback(design.loop_tf(p)).poles(), want)
    # the keyword facade is the same loop
    kw = design.current_loop_tf("pi", R=R, L=L, k_p=0.4647, k_i=0.0492, fs=FS)
    assert _same_roots(kw.poles(), design.loop_tf(p).poles())
    # estimates default to the motor's
    assert p.resolved().L_c == L and p.resolved().R_c == R
    step = design.predict_step(p, n_samples=400, i_start=15.0, i_final=20.0)
    assert step.i_p_final == pytest.approx(20.0, rel=1e-9)  # integral action: no error


def test_speed_loop_pars_give_the_ip_loop_of_eq_27():
    a, b, k_p, k_i = 0.9999785, 3.33715e-4, 0.2113, 2.9994e-5
    G = control.tf([b], [1, -a], TS)
    ip = control.tf([k_p * (1 + k_i), -k_p], [1, -1], TS)
    want = control.poles(control.feedback(ip * G, 1))
    p = design.SpeedLoopPars(a, b, k_p, k_i, FS)
    assert _same_roots(design.speed_closed_loop(p).poles(), want)
    assert _same_roots(design.speed_open_loop(p).poles(), control.poles(ip * G))
