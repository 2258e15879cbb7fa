"""The tuning view's data (drive_link.workflows.design.current_loop_response / speed_loop_response:
Bode and z-plane poles, the paper's Figs. 4, 5, 12) against python-control and scipy (test-only
oracles), built independently from the paper's equations."""

from __future__ import annotations

import math
import warnings

import control as ct
import numpy as np
import pytest
from scipy import signal

from drive_link import design

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

R, L, FS = 6.2e-3, 14.8e-6, 50e3
TS = 1 / FS


def _plant() -> ct.TransferFunction:
    Phi = math.exp(-R * TS / L)
    return ct.tf([(1 - Phi) / (2 * R)], [1, -Phi, 0], TS)  # eq. (8)


def _deadbeat(L_c: float, R_c: float) -> ct.TransferFunction:
    Phi_c = math.exp(-R_c * TS / L_c)
    Gamma_c = (1 - Phi_c) / (2 * R_c)
    return ct.tf([1, -Phi_c, 0], [Gamma_c, 0, -Gamma_c], TS)  # eq. (15)


def _same_roots(a, b, tol=1e-6) -> None:
    a, b = np.sort_complex(np.asarray(a)), np.sort_complex(np.asarray(b))
    assert a.size == b.size
    for p in a:
        assert np.min(np.abs(b - p)) < tol, (a, b)


@pytest.mark.parametrize(
    ("controller", "kw", "oracle_c"),
    [
        ("deadbeat", {"L_c": 1.5 * L, "R_c": R}, lambda: _deadbeat(1.5 * L, R)),
        ("deadbeat", {"L_c": 0.5 * L, "R_c": 2 * R}, lambda: _deadbeat(0.5 * L, 2 * R)),
        ("pi", {"k_p": 0.4647, "k_i": 0.0492}, lambda: ct.tf([0.5139, -0.4647], [1, -1], TS)),
    ],
)
def test_current_loop_bode_and_poles_match_python_control(controller, kw, oracle_c):
    r = design.current_loop_response(controller, R=R, L=L, fs=FS, n_points=300, **kw)
    loop = oracle_c() * _plant()
    w = 2 * math.pi * r.f_hz
    mag = ct.frequency_response(loop, w).magnitude
    resp = loop(np.exp(1j * w * TS))
    assert r.magnitude_db == pytest.approx(20 * np.log10(np.abs(resp)), abs=1e-6)
    assert np.abs(mag.ravel()) == pytest.approx(np.abs(resp), rel=1e-9)
    # phase: equal modulo 360° at every frequency, and continuous along the grid
    d = np.mod(r.phase_deg - np.degrees(np.angle(resp)) + 180.0, 360.0) - 180.0
    assert np.max(np.abs(d)) < 1e-6
    assert np.max(np.abs(np.diff(r.phase_deg))) < 90.0
    s = 1.0 / np.abs(1.0 + resp)
    assert r.sensitivity_db == pytest.approx(20 * np.log10(s), abs=1e-6)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cl = ct.feedback(loop, 1)
    _same_roots(r.poles, cl.poles())
    assert r.stable == bool(np.all(np.abs(cl.poles()) < 1.0))
    # margins: the smallest as a positive angle, both crossovers listed (python-control signed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, pm, _, _, wgc, _ = ct.stability_margins(ct.minreal(loop, verbose=False))
    assert r.margins.phase_margin_deg == pytest.approx(abs(pm), abs=1e-3)
    assert r.margins.gain_crossover_hz == pytest.approx(wgc / (2 * math.pi), rel=1e-4)
    d = r.as_dict()
    assert d["phase_margin_deg"] >= 0 and len(d["poles"]) == r.poles.size
    assert all(c["phase_margin_deg"] >= 0 for c in d["crossovers"])


def test_unstable_current_loop_shows_poles_outside_the_circle():
    r = design.current_loop_response("deadbeat", R=R, L=L, L_c=2.2 * L, R_c=R)
    assert not r.stable and r.max_pole_radius > 1.0
    den = (ct.feedback(_deadbeat(2.2 * L, R) * _plant(), 1)).poles()
    assert np.max(np.abs(den)) == pytest.approx(r.max_pole_radius, rel=1e-9)


def test_speed_loop_poles_are_eq27_and_bode_matches_scipy():
    a, b, kp, ki = 0.9999785, 3.33715e-4, 0.2113, 2.9994e-5
    r = design.speed_loop_response(a, b, kp, ki, n_points=200)
    # eq. (27): z² + (k_p b (1 + k_i) - 1 - a) z + (a - k_p b)
    _same_roots(r.poles, np.roots([1, kp * b * (1 + ki) - 1 - a, a - kp * b]), tol=1e-9)
    assert r.stable
    # the IP feedback path k_p (1 + k_i z/(z - 1)) times b/(z - a), with scipy
    num = np.polymul([kp * (1 + ki), -kp], [b])
    den = np.polymul([1, -1], [1, -a])
    _, h = signal.freqz(num, den, worN=2 * math.pi * r.f_hz * TS)
    # (freqz loses ~1e-7 relative near z = 1, where both poles sit)
    assert r.magnitude_db == pytest.approx(20 * np.log10(np.abs(h)), abs=1e-4)
    assert r.margins.phase_margin_deg > 0


def test_bad_input_is_a_value_error():
    with pytest.raises(ValueError):
        design.current_loop_response("deadbeat", L_c=-1.0)
    with pytest.raises(ValueError):
        design.speed_loop_response(0.99, 1e-4, float("nan"), 1e-5)
    with pytest.raises(ValueError):
        design.current_loop_response("pi", n_points=2)


def test_facade_exports_only_its_list():
    assert "current_loop_response" in design.__all__ and "speed_loop_response" in design.__all__
    for name in design.__all__:
        assert hasattr(design, name)
    assert "_margins" not in dir(design) and "np" not in dir(design)
