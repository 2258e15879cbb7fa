"""Issue 28: the speed scenarios' metrics (load step from a settled start: speed dip; speed
step: overshoot and 2 % settling) against the paper's speed loop built independently with
python-control: the identified plant of eq. (26), n[k+1] = a n[k] + b i_p[k] (rpm, A, one
step per Ts), under the IP law of Fig. 17 / eq. (27), i* = k_p (k_i x - n), x[k] = x[k-1] +
(n* - n[k]), with the current loop ideal (i_p = i*) and a load torque T entering as the current
T / K_t it takes. Gains: the paper's k_p = 0.2113, k_i = 2.9994e-5 (xi = 1, w_n = 2.3 rad/s).
"""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest
from lti_oracle import discrete_response

from firmware_protocol import paper
from virtual_drive.sweep import parse_spec
from virtual_drive.sweep.runner import run_one

pytestmark = [pytest.mark.unit, pytest.mark.timeout(120)]

Ts = 20e-6


def _ip_loop() -> ct.StateSpace:
    """States (n, s = x[k-1]) as deviations; inputs (n*, load current d); output n."""
    a, b = paper.A_IDENTIFIED, paper.B_IDENTIFIED
    kp, ki = paper.IP_KP, paper.IP_KI
    # x[k] = s[k] + n* - n[k];  i[k] = kp (ki x[k] - n[k]);  n[k+1] = a n[k] + b (i[k] - d)
    A = [[a - b * kp * (ki + 1.0), b * kp * ki], [-1.0, 1.0]]
    B = [[b * kp * ki, -b], [1.0, 0.0]]
    return ct.ss(A, B, [[1.0, 0.0]], [[0.0, 0.0]], dt=Ts)


def _run(scenario: dict) -> dict:
    spec = parse_spec({"scenarios": [scenario]})
    return run_one(spec.job(0))


def test_load_step_speed_dip_matches_the_ip_loop_of_eq26_27():
    T, n0, dur = 3.0, 1000.0, 1.0
    row = _run({"kind": "load_step", "speed": n0, "from": 0.0, "to": T, "at": 0.05,
                "duration": dur})  # fmt: skip
    K_t = paper.K_RPM * 60.0 / (2.0 * math.pi)
    N = round((dur - 0.05) / Ts)
    U = np.vstack([np.zeros(N), np.full(N, T / K_t)])
    y = discrete_response(_ip_loop(), U)
    dip = float(-y.min())
    assert 60.0 < dip < 75.0
    assert row["stable"] and row["passed"]
    assert row["speed_dip"] == pytest.approx(dip, rel=0.02)


def test_speed_step_overshoot_and_settling_match_the_ip_loop():
    n0, n1, dur = 1000.0, 1100.0, 3.5
    row = _run({"kind": "speed_step", "from": n0, "to": n1, "at": 0.05, "duration": dur})
    N = round((dur - 0.05) / Ts)
    U = np.vstack([np.full(N, n1 - n0), np.zeros(N)])
    t = np.arange(N) * Ts
    y = discrete_response(_ip_loop(), U)
    info = ct.step_info(y, t, yfinal=n1 - n0, SettlingTimeThreshold=0.02)
    assert 1.0 < info["SettlingTime"] < 3.0  # "settles in about 2 s" (paper, Sec. V)
    assert row["stable"]
    assert row["overshoot"] == pytest.approx(info["Overshoot"], abs=0.3)
    assert row["settling"] == pytest.approx(info["SettlingTime"], rel=0.03)
