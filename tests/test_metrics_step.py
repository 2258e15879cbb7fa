"""Step metrics against python-control's step_info and the second-order formulas."""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest

from drive_link import design
from drive_link.workflows.metrics import moving_average, step_metrics

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]


def _second_order(zeta: float, wn: float, T: float, n: int):
    sys = ct.tf([wn**2], [1, 2 * zeta * wn, wn**2])
    t = np.linspace(0.0, T, n)
    return sys, t, ct.step_response(sys, t).outputs


@pytest.mark.parametrize("zeta", [0.2, 0.45, 0.7, 1.0, 1.5])
def test_against_step_info_and_formulas(zeta):
    wn = 2 * math.pi * 100.0
    _, t, y = _second_order(zeta, wn, 0.2, 40_001)
    dt = t[1] - t[0]
    ours = step_metrics(t, y, reference=1.0, y_final=1.0)
    info = ct.step_info(y, t, final_output=1.0)
    assert ours.rise_time == pytest.approx(info["RiseTime"], abs=2 * dt)
    assert ours.settling_time == pytest.approx(info["SettlingTime"], abs=2 * dt)
    assert ours.overshoot_pct == pytest.approx(info["Overshoot"], abs=1e-3)
    assert ours.peak == pytest.approx(info["Peak"], rel=1e-9)
    assert ours.peak_time == pytest.approx(info["PeakTime"], abs=dt)
    if zeta < 1:  # textbook: Mp = exp(-zeta pi / sqrt(1 - zeta^2))
        assert ours.overshoot_pct == pytest.approx(
            100 * math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2)), abs=1e-3
        )
    else:
        assert ours.overshoot_pct == 0.0
    # default y_final (mean of the last 10 %) is the settled value here
    auto = step_metrics(t, y, reference=1.0)
    assert auto.y_final == pytest.approx(1.0, abs=1e-6)
    assert auto.steady_state_error == pytest.approx(0.0, abs=1e-6)


def test_first_order_rise_time_is_ln9_tau():
    tau = 1e-3
    t = np.linspace(0, 20 * tau, 200_001)
    y = 1 - np.exp(-t / tau)
    m = step_metrics(t, y, y_final=1.0)
    assert m.rise_time == pytest.approx(math.log(9) * tau, rel=1e-6)  # interpolated crossings
    assert m.settling_time == pytest.approx(-math.log(0.02) * tau, rel=1e-4)


def test_offset_and_negative_steps():
    wn = 2 * math.pi * 100.0
    _, t, y = _second_order(0.45, wn, 0.2, 20_001)
    ref = step_metrics(t, y, y_final=1.0)
    # a 15 A -> 20 A step with 5 ms of pre-step data
    t_pre = np.arange(-500, 0) * (t[1] - t[0])
    tt = np.concatenate([t_pre, t])
    up = np.concatenate([np.full(500, 15.0), 15.0 + 5.0 * y])
    m = step_metrics(tt, up, reference=20.0, t_step=0.0)
    assert m.y_initial == pytest.approx(15.0)
    assert m.overshoot_pct == pytest.approx(ref.overshoot_pct, rel=1e-6)
    assert m.rise_time == pytest.approx(ref.rise_time, rel=1e-6)
    assert m.settling_time == pytest.approx(ref.settling_time, rel=1e-6)
    # 20 A -> 15 A: the overshoot is the excursion below 15 A
    down = np.concatenate([np.full(500, 20.0), 20.0 - 5.0 * y])
    d = step_metrics(tt, down, reference=15.0, t_step=0.0)
    assert d.overshoot_pct == pytest.approx(ref.overshoot_pct, rel=1e-6)
    assert d.peak < 15.0


def test_steady_state_error_of_the_predictive_law():
    r = design.predicted_step("predictive", n_samples=200, i_start=15.0, i_final=20.0)
    m = step_metrics(r.t, r.i_p, reference=20.0, y_initial=r.i_p[0])
    assert m.steady_state_error == pytest.approx(20.0 - r.i_p_final, abs=1e-9)
    assert m.steady_state_error > 0.2


def test_ripple_is_removed_by_the_one_period_average():
    """The paper's ī_p: a moving average over Ts removes the 100 kHz ripple before measuring."""
    fs_s = 1e6  # record at 1 MHz: 20 points per Ts = 20 µs
    n = 4000
    t = np.arange(n) / fs_s
    k = np.floor(t / 20e-6).astype(int)
    pred = design.predicted_step("pi", n_samples=int(k.max()) + 1, i_start=15.0, i_final=20.0)
    clean = pred.i_p[k]
    # triangular ripple at 100 kHz, ±1.5 A around the average (two full periods per Ts)
    phase = (t * 100e3) % 1.0
    ripple = 1.5 * (4 * np.abs(phase - 0.5) - 1)
    noisy = clean + ripple
    ref = step_metrics(t, clean, reference=20.0, y_initial=15.0, y_final=20.0)
    raw = step_metrics(t, noisy, reference=20.0, y_initial=15.0, y_final=20.0)
    avg = step_metrics(t, noisy, reference=20.0, y_initial=15.0, y_final=20.0, average_window=20e-6)
    assert raw.overshoot_pct > ref.overshoot_pct + 20  # ripple fakes overshoot
    assert math.isnan(raw.settling_time)  # ±1.5 A never fits in a ±0.1 A band
    assert avg.overshoot_pct == pytest.approx(ref.overshoot_pct, abs=2.0)
    assert avg.settling_time == pytest.approx(ref.settling_time, abs=40e-6)


def test_moving_average():
    y = np.array([0.0, 3.0, 6.0, 9.0])
    np.testing.assert_allclose(moving_average(y, 2), [0.0, 1.5, 4.5, 7.5])
    np.testing.assert_allclose(moving_average(y, 1), y)
    with pytest.raises(ValueError):
        moving_average(y, 0)


def test_unsettled_and_unreached():
    t = np.linspace(0, 1, 101)
    y = np.where(t > 0, 1.0 + 0.5 * np.sin(40 * t), 0.0)
    m = step_metrics(t, y, y_final=1.0)
    assert math.isnan(m.settling_time)
    slow = step_metrics(t, 0.5 * t, y_final=1.0)  # never reaches 90 % of the given final
    assert math.isnan(slow.rise_time)


@pytest.mark.parametrize(
    ("t", "y", "kw"),
    [
        (np.arange(5.0), np.arange(4.0), {}),
        (np.array([0.0, 1.0, 1.0, 2.0]), np.arange(4.0), {}),
        (np.arange(4.0), np.array([0.0, math.nan, 1.0, 1.0]), {}),
        (np.arange(4.0), np.ones(4), {}),
        (np.arange(4.0), np.arange(4.0), {"settling_band": 0.0}),
        (np.arange(4.0), np.arange(4.0), {"rise_limits": (0.9, 0.1)}),
        (np.arange(4.0), np.arange(4.0), {"t_step": 10.0}),
        (np.arange(4.0), np.arange(4.0), {"average_window": -1.0}),
    ],
)
def test_bad_input(t, y, kw):
    with pytest.raises(ValueError):
        step_metrics(t, y, **kw)
