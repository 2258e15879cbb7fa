"""The gain-set check (drive_link.workflows.gains.check_gains: `set-gains` and the dashboard)
against python-control (test-only oracle): closed-loop poles of the paper's deadbeat loop (eq. 15 on
eq. 8) and of the PI loop (eq. 22), and the rule L_c ≤ 1.5 L without force."""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

from drive_link.workflows.gains import check_gains

pytestmark = pytest.mark.unit

R, L, TS = 6.2e-3, 14.8e-6, 20e-6
PAPER = dict(type=0, L_c=L, R_c=R, k_p=0.4647, k_i=0.0492, speed_k_p=0.2113, speed_k_i=2.9994e-5)


def _phi_gamma(r, ind):
    phi = math.exp(-r * TS / ind)
    return phi, (1 - phi) / (2 * r)


def oracle_stable(gains) -> bool:
    Phi, Gamma = _phi_gamma(R, L)
    P = control.tf([Gamma], [1, -Phi, 0], TS)
    if gains["type"] == 0:
        Phi_c, Gamma_c = _phi_gamma(gains["R_c"], gains["L_c"])
        C = control.tf([1, -Phi_c, 0], [Gamma_c, 0, -Gamma_c], TS)
    else:
        C = gains["k_p"] + gains["k_i"] * control.tf([1, 0], [1, -1], TS)
    return bool(np.all(np.abs(control.poles(control.feedback(C * P, 1))) < 1))


@pytest.mark.parametrize("ratio", [0.3, 0.8, 1.0, 1.4, 1.6, 1.95, 2.05, 3.0])
def test_deadbeat_L_c_range(ratio):
    g = {**PAPER, "L_c": ratio * L}
    rep = check_gains(g, R, L, (0.9999785, 3.33715e-4))
    assert rep.figures["current_loop_stable"] == oracle_stable(g) == (ratio < 2.0)
    assert rep.ok == (ratio <= 1.5)
    if ratio > 1.5:
        assert any("> 1.5 L" in p for p in rep.problems)
    if ratio >= 2.0:
        assert any("unstable" in p for p in rep.problems)


def test_pi_paper_gains_pass_and_speed_loop_checked():
    g = {**PAPER, "type": 1}
    assert oracle_stable(g)
    assert check_gains(g, R, L, (0.9999785, 3.33715e-4)).ok
    bad = {**PAPER, "speed_k_p": -1.0}
    rep = check_gains(bad, R, L, (0.9999785, 3.33715e-4))
    assert not rep.ok and any("speed loop" in p for p in rep.problems)


def test_table_1_row_l_c_1_5_l_passes_with_the_drive_s_float32_l():
    """Table 1's L_c = 1.5 L (22.2 µH) is the edge of the rule; the drive reports L as REAL32
    (1.4799999917e-05 H), which must not turn 22.2 µH into a refused 1.5000000008 L."""
    L32 = float(np.float32(L))
    assert 22.2e-6 / L32 > 1.5
    assert check_gains({**PAPER, "L_c": 22.2e-6}, R, L32, (0.9999785, 3.33715e-4)).ok
    assert not check_gains({**PAPER, "L_c": 22.3e-6}, R, L32, (0.9999785, 3.33715e-4)).ok
