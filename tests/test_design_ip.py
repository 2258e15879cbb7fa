"""IP speed gains (eqs. 27–31) and PI current-gain design, against python-control and the paper."""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest
from lti_oracle import discrete_response

from drive_link import design
from drive_link.workflows.metrics import step_metrics

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

Ts = 20e-6
A_PAPER = 0.9999785  # printed rounded as 0.99997 (see docs/overview.md)
B_PAPER = 3.33715e-4


def _ip_loop(a: float, b: float, k_p: float, k_i: float) -> ct.StateSpace:
    """w/w* from the block diagram (Fig. 17): u = k_p (k_i z/(z-1) (w* - w) - w), w = b/(z-a) u.

    Built as an interconnection of state-space blocks (python-control), so no pole/zero
    cancellation is needed.
    """
    G = ct.ss([[a]], [[b]], [[1.0]], [[0.0]], Ts, inputs="u", outputs="w", name="G")
    # integral part k_i z/(z-1) on e = w* - w:  s[k+1] = s[k] + k_i e[k],  y = s + k_i e
    Ci = ct.ss([[1.0]], [[k_i]], [[1.0]], [[k_i]], Ts, inputs="e", outputs="y", name="I")
    S = ct.summing_junction(inputs=["r", "-w"], output="e", dt=Ts, name="err")
    U = ct.ss(
        np.zeros((0, 0)),
        np.zeros((0, 2)),
        np.zeros((1, 0)),
        [[k_p, -k_p]],
        Ts,
        inputs=["y", "w"],
        outputs="u",
        name="P_part",
    )
    return ct.interconnect([G, Ci, S, U], inputs="r", outputs="w", dt=Ts)


def test_ip_gains_reproduce_the_paper():
    k_p, k_i = design.ip_gains(A_PAPER, B_PAPER, xi=1.0, omega_n=2.3, fs=50e3)
    assert k_p == pytest.approx(0.2113, rel=5e-4)
    assert k_i == pytest.approx(2.9994e-5, rel=1e-3)


@pytest.mark.parametrize(("xi", "wn"), [(1.0, 2.3), (0.7, 5.0), (0.4, 20.0), (1.5, 3.0)])
def test_ip_poles_have_the_requested_damping_and_frequency(xi, wn):
    k_p, k_i = design.ip_gains(A_PAPER, B_PAPER, xi, wn, 50e3)
    T = _ip_loop(A_PAPER, B_PAPER, k_p, k_i)
    poles = ct.poles(T)
    assert poles.size == 2
    if xi <= 1.0:
        # continuous-equivalent s = ln(p)/Ts: -xi wn ± j wn sqrt(1 - xi²)
        s = np.log(poles.astype(complex)) / Ts
        assert np.mean(-s.real) == pytest.approx(xi * wn, rel=1e-3)
        if xi < 1.0:
            wns, zetas, _ = ct.damp(T, doprint=False)
            assert wns == pytest.approx([wn, wn], rel=1e-3)
            assert zetas == pytest.approx([xi, xi], rel=1e-3)
    else:
        s = np.sort(np.log(np.real(poles)) / Ts)
        expected = np.sort(
            [-xi * wn - wn * math.sqrt(xi**2 - 1), -xi * wn + wn * math.sqrt(xi**2 - 1)]
        )
        assert s == pytest.approx(expected, rel=1e-3)
    # eq. (27) agrees with the block diagram
    theta = np.geomspace(1e-6, 3.0, 30)
    z = np.exp(1j * theta)
    np.testing.assert_allclose(
        design.ip_closed_loop(A_PAPER, B_PAPER, k_p, k_i)(z), T(z), rtol=1e-6, atol=1e-9
    )


def test_ip_step_matches_forced_response_and_the_paper_settling():
    k_p, k_i = design.ip_gains(A_PAPER, B_PAPER, 1.0, 2.3, 50e3)
    n = 150_000  # 3 s at 50 kHz
    dec = 50
    r = design.predicted_speed_step(
        A_PAPER, B_PAPER, k_p, k_i, n_samples=n, w_start=0.0, w_final=1000.0, decimate=dec
    )
    T = _ip_loop(A_PAPER, B_PAPER, k_p, k_i)
    y = discrete_response(T, np.full(n, 1000.0))  # T stepped by lfilter (C), not in Python
    np.testing.assert_allclose(r.speed, y[::dec], atol=1e-6 * 1000)
    assert r.stable
    m = step_metrics(r.t, r.speed, reference=1000.0, y_initial=0.0, y_final=1000.0)
    assert m.overshoot_pct < 0.5  # "there is no overshoot"
    assert 1.5 < m.settling_time < 3.0  # "it settles in about 2 s"


def test_ip_gains_reject_bad_input():
    for args in [
        (A_PAPER, 0.0),
        (A_PAPER, math.nan),
        (A_PAPER, B_PAPER, -1.0),
        (A_PAPER, B_PAPER, 1, 0),
    ]:
        with pytest.raises(ValueError):
            design.ip_gains(*args)


def test_pi_design_recovers_the_paper_gains():
    loop = ct.tf([0.4647 + 0.0492, -0.4647], [1, -1], Ts) * ct.tf(
        design.plant_tf().num, design.plant_tf().den, Ts
    )
    _, pm, _, _, wgc, _ = ct.stability_margins(loop)
    k_p, k_i = design.pi_current_gains(wgc / (2 * math.pi), pm)
    assert k_p == pytest.approx(0.4647, rel=1e-6)
    assert k_i == pytest.approx(0.0492, rel=1e-6)


@pytest.mark.parametrize(("fc", "pm"), [(1000.0, 60.0), (2000.0, 50.0), (500.0, 75.0)])
def test_pi_design_meets_the_spec(fc, pm):
    k_p, k_i = design.pi_current_gains(fc, pm)
    z = ct.tf([1, 0], [1], Ts)
    P = ct.tf(design.plant_tf().num, design.plant_tf().den, Ts)
    _, pm_ct, _, _, wgc, _ = ct.stability_margins((k_p + k_i * z / (z - 1)) * P)
    assert pm_ct == pytest.approx(pm, abs=1e-6)
    assert wgc / (2 * math.pi) == pytest.approx(fc, rel=1e-6)
    assert design.is_stable(design.feedback(design.current_loop_tf("pi", k_p=k_p, k_i=k_i)))


def test_pi_design_rejects_unreachable_specs():
    with pytest.raises(ValueError, match="cannot reach"):
        design.pi_current_gains(10_000.0, 80.0)
    with pytest.raises(ValueError):
        design.pi_current_gains(30_000.0, 45.0)  # above Nyquist
    with pytest.raises(ValueError):
        design.pi_current_gains(1000.0, 190.0)
