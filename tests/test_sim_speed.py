"""Speed loop and mechanics of the virtual drive against eq. (26)-(31) (python-control oracle)
and identification of the simulated current-to-speed response."""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import control
import numpy as np
import pytest
from lti_oracle import discrete_response

from virtual_drive.sim import Simulator

pytestmark = [pytest.mark.timeout(120), pytest.mark.unit]

Ts = 20e-6
A_ID, B_ID = 0.9999785, 3.33715e-4


def ip_gains(xi, wn, a, b):
    """Eq. (28)-(31) with d2 = exp(-2 xi wn Ts) (the printed d2 is a typo)."""
    d1 = -2 * np.exp(-xi * wn * Ts) * np.cos(wn * Ts * np.sqrt(max(1 - xi**2, 0.0)))
    d2 = np.exp(-2 * xi * wn * Ts)
    kp = (a - d2) / b
    ki = (d1 + 1 + a - kp * b) / (kp * b)
    return kp, ki


def test_paper_gains_follow_from_a_b():
    kp, ki = ip_gains(1.0, 2.3, A_ID, B_ID)
    assert kp == pytest.approx(0.2113, rel=2e-3)
    assert ki == pytest.approx(2.9994e-5, rel=5e-3)


def test_identification_recovers_a_b():
    """15 -> 30 A current step (Fig. 16), least squares on n[k+1] = a n[k] + b i_p[k]."""
    sim = Simulator(model="averaged")
    sim.set_mode("current")
    sim.set_current_ref(15.0)
    sim.set_speed(15.0 * B_ID / (1 - A_ID))  # start at the 15 A equilibrium
    sim.run(20_000, record=False)
    sim.set_current_ref(30.0)
    r = sim.run(150_000)
    n, i = r["speed"].astype(float), r["i_p"].astype(float)
    X = np.column_stack([n[:-1], i[:-1]])
    (a, b), *_ = np.linalg.lstsq(X, n[1:], rcond=None)
    assert 1 - a == pytest.approx(1 - A_ID, rel=0.05)
    assert b == pytest.approx(B_ID, rel=0.05)
    # the same via the step's final value and time constant
    gain = (n[-1] - n[0]) / 15.0
    assert gain == pytest.approx(B_ID / (1 - A_ID), rel=0.05)


def _speed_sim(model="averaged"):
    """Steady at 500 rpm: current mode at the equilibrium current, then a bumpless switch."""
    sim = Simulator(model=model)
    sim.set_speed(500.0)
    sim.set_mode("current")
    sim.set_current_ref(500.0 * (1 - A_ID) / B_ID)
    sim.run(2_000, record=False)
    sim.set_mode("speed")
    sim.set_speed_ref(500.0)
    sim.run(5_000, record=False)
    return sim


def test_ip_speed_step_no_overshoot_settles_in_about_2s():
    sim = _speed_sim()
    sim.set_speed_ref(1000.0)
    r = sim.run(150_000)
    w = r["speed"].astype(float)
    assert w.max() < 1000.0 + 0.01 * 500.0  # no overshoot (xi = 1)
    outside = np.nonzero(np.abs(w - 1000.0) > 0.02 * 500.0)[0]
    t_settle = (outside[-1] + 1) * Ts
    assert 1.5 < t_settle < 3.0  # paper: about 2 s
    # oracle: eq. (27) with the identified a, b and the paper's gains
    kp, ki = 0.2113, 2.9994e-5
    cl = control.tf(
        [kp * B_ID * ki, 0], [1, kp * B_ID * ki + kp * B_ID - 1 - A_ID, A_ID - kp * B_ID], Ts
    )
    y = discrete_response(cl, np.full(150_000, 500.0))  # lfilter: forced_response's Python loop
    np.testing.assert_allclose(w - 500.0, y, atol=0.04 * 500.0)
    assert np.abs(r["i_p"]).max() <= 100.0 + 1e-3  # current limit


def test_load_step_rejected_in_about_2s():
    sim = _speed_sim()
    sim.set_load(T_load=2.0)  # N m
    r = sim.run(150_000)
    w = r["speed"].astype(float)
    dip = 500.0 - w.min()
    assert 10.0 < dip < 200.0
    outside = np.nonzero(np.abs(w - 500.0) > 0.1 * dip)[0]
    assert outside[-1] * Ts < 3.0
    assert w[-1] == pytest.approx(500.0, abs=0.02 * dip)
    # the extra current carries the load: K_t delta i = T_load
    K_t = 0.0125 * 60 / (2 * np.pi)
    di = r["i_p"][-1000:].mean() - r["i_p"][:10].mean()
    assert di == pytest.approx(2.0 / K_t, rel=0.05)


def test_speed_loop_pwm_model_short():
    """The same loop with the PWM-exact model tracks the averaged one (0.2 s)."""
    res = {}
    for model in ("pwm", "averaged"):
        sim = _speed_sim(model)
        sim.set_speed_ref(600.0)
        res[model] = sim.run(10_000)["speed"]
    np.testing.assert_allclose(res["pwm"], res["averaged"], atol=1.0)
