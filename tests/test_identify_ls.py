"""Least-squares identification of b/(z - a) (eq. 26) from synthetic current-step traces.

Truth: the model simulated at the 50 kHz loop rate by scipy.signal (dlsim, and lfilter for the
long records), then decimated like a trace capture, with measurement noise added.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import signal

from drive_link.workflows.identify import (
    fit_first_order,
    identify_first_order,
    simulate_first_order,
)

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

A = 0.9999785
B = 3.33715e-4
Ts = 20e-6


def _current(n_loop: int, step_at: int, i0: float = 15.0, i1: float = 30.0) -> np.ndarray:
    i = np.full(n_loop, i0)
    i[step_at:] = i1
    return i


def _speed_lfilter(i: np.ndarray, w0: float, a: float = A, b: float = B, load: float = 0.0):
    """w[k+1] = a w[k] + b i[k] - load, w[0] = w0, at the loop rate (scipy.signal.lfilter)."""
    y, _ = signal.lfilter([0.0, 1.0], [1.0, -a], b * i - load, zi=[w0])
    return y


def test_lfilter_truth_agrees_with_dlsim():
    n = 3000
    i = _current(n, 1000)
    sys = (np.array([[A]]), np.array([[B]]), np.array([[1.0]]), np.array([[0.0]]), Ts)
    _, y, _ = signal.dlsim(sys, i, x0=[200.0])
    np.testing.assert_allclose(_speed_lfilter(i, 200.0), y[:, 0], rtol=1e-12)


def test_dlsim_trace_at_loop_rate_exact():
    n = 6000
    i = _current(n, 1500)
    sys = (np.array([[A]]), np.array([[B]]), np.array([[1.0]]), np.array([[0.0]]), Ts)
    _, y, _ = signal.dlsim(sys, i, x0=[240.0])
    fit = fit_first_order(i, y[:, 0], Ts)
    assert fit.D == 1
    assert 1 - fit.a == pytest.approx(1 - A, rel=1e-6)
    assert fit.b == pytest.approx(B, rel=1e-6)
    assert fit.r2 == pytest.approx(1.0, abs=1e-9)
    assert identify_first_order(i, y[:, 0], Ts) == pytest.approx((fit.a, fit.b))


@pytest.mark.parametrize("D", [50, 500, 1000])
def test_decimated_trace_converts_back_to_the_loop_rate(D):
    """A trace every D loop samples (Fig. 16: 14 s) gives a^D, b(1-a^D)/(1-a); we undo it."""
    n_trace = 14.0 / (D * Ts)
    n_trace = int(min(n_trace, 3000))
    n_loop = n_trace * D
    i = _current(n_loop, step_at=(n_trace // 10) * D)
    w = _speed_lfilter(i, w0=230.0)
    fit = fit_first_order(i[::D], w[::D], D * Ts)
    assert fit.D == D
    assert fit.a_D == pytest.approx(A**D, rel=1e-9)
    assert 1 - fit.a == pytest.approx(1 - A, rel=1e-5)
    assert fit.b == pytest.approx(B, rel=1e-5)
    assert fit.rms < 1e-6 * np.max(w)


def test_noisy_trace_with_offset_and_initial_speed():
    """Ripple on i_p, noise on speed, a constant load torque, and a start away from rest."""
    rng = np.random.default_rng(3)
    D = 500  # 10 ms per trace sample, 14 s like Fig. 16
    n_trace = 1400
    i = _current(n_trace * D, step_at=140 * D)
    load = 2e-3  # rpm per loop sample lost to a constant load torque
    w = _speed_lfilter(i, w0=300.0, load=load)
    i_meas = i[::D] + rng.normal(0.0, 0.5, n_trace)  # A
    w_meas = w[::D] + rng.normal(0.0, 1.0, n_trace)  # rpm
    fit = fit_first_order(i_meas, w_meas, D * Ts)
    assert 1 - fit.a == pytest.approx(1 - A, rel=0.03)
    assert fit.b == pytest.approx(B, rel=0.02)
    # the plain one-step least squares is biased by the speed noise; the refinement removes it
    raw = fit_first_order(i_meas, w_meas, D * Ts, refine=False)
    assert abs(raw.a - A) > 3 * abs(fit.a - A)
    # the offset term absorbs the load: per trace sample -load (1 - a^D)/(1 - a)
    assert fit.offset == pytest.approx(-load * (1 - A**D) / (1 - A), rel=0.3)
    assert fit.r2 > 0.99
    assert fit.rms < 3.0
    # without the offset term the load corrupts b (what the offset handling is for)
    no_off = fit_first_order(i_meas, w_meas, D * Ts, offset=False)
    assert abs(no_off.b - B) > abs(fit.b - B)


def test_step_between_trace_samples_costs_little():
    D = 500
    n_trace = 1400
    i = _current(n_trace * D, step_at=140 * D + 217)
    w = _speed_lfilter(i, w0=230.0)
    fit = fit_first_order(i[::D], w[::D], D * Ts)
    assert 1 - fit.a == pytest.approx(1 - A, rel=0.01)
    assert fit.b == pytest.approx(B, rel=0.01)


def test_fit_quality_flags_a_wrong_model():
    """Speed from a lightly damped 2nd-order system: the first-order fit must show it."""
    D = 100
    n = 2000
    i = _current(n * D, 200 * D)[::D]
    t = np.arange(n) * D * Ts
    w = 230 + 200 * (i - 15) / 15 * (1 - np.exp(-t / 0.5) * np.cos(2 * np.pi * 2.0 * t))
    good = fit_first_order(i, _speed_lfilter(np.repeat(i, D), 230.0)[::D], D * Ts)
    bad = fit_first_order(i, w, D * Ts)
    assert good.r2 > 0.999
    assert bad.r2 < good.r2 - 0.02
    assert bad.rms > 100 * good.rms


def test_simulate_first_order_is_the_model():
    i = np.array([1.0, 2.0, 3.0])
    w = simulate_first_order(0.5, 2.0, i, w0=4.0, offset=1.0)
    assert list(w) == [4.0, 0.5 * 4 + 2 * 1 + 1, 0.5 * (0.5 * 4 + 2 * 1 + 1) + 2 * 2 + 1]


@pytest.mark.parametrize(
    ("i", "w", "Ts_", "match"),
    [
        (np.full(100, 15.0), np.full(100, 230.0), Ts, "excite"),
        (np.ones(100), np.ones(99), Ts, "length"),
        (np.array([1.0, math.nan, 2, 3, 4, 5]), np.arange(6.0), Ts, "finite"),
        (np.arange(100.0), np.arange(100.0), 30e-6, "multiple"),
        (np.arange(3.0), np.arange(3.0), Ts, "at least"),
        (np.arange(100.0), 1.01 ** np.arange(100.0), Ts, "outside"),
        (np.arange(100.0), np.arange(100.0), -Ts, "period"),
    ],
)
def test_bad_traces_raise_clear_errors(i, w, Ts_, match):
    with pytest.raises(ValueError, match=match):
        fit_first_order(i, w, Ts_)
