"""Predicted current steps against python-control (forced_response) and the paper's statements."""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest

from drive_link import design

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

L = design.L_TABLE2
R = design.R_TABLE2
Ts = 20e-6
FS = 50e3


def _z() -> ct.TransferFunction:
    return ct.tf([1, 0], [1], Ts)


def _plant(R_: float = R, L_: float = L) -> tuple[float, float, ct.TransferFunction]:
    z = _z()
    Phi = math.exp(-R_ * Ts / L_)
    Gamma = (1 - Phi) / (2 * R_) if R_ > 0 else Ts / (2 * L_)
    return Phi, Gamma, Gamma / (z * (z - Phi))  # eq. (8)


def _controller(name: str, L_c: float, R_c: float, k_p: float, k_i: float) -> ct.TransferFunction:
    z = _z()
    if name == "deadbeat":
        Phi_c = math.exp(-R_c * Ts / L_c)
        Gamma_c = (1 - Phi_c) / (2 * R_c)
        return (z**2 - Phi_c * z) / (Gamma_c * (z**2 - 1))  # eq. (15)
    if name == "pi":
        return k_p + k_i * z / (z - 1)  # eq. (22)
    return 2 * L_c * FS * z / (z + 1)  # eq. (23): u (1 + z^-1) = 2 L_c fs (i* - i)


CASES = [
    ("deadbeat", 1.0, 1.0),
    ("deadbeat", 0.5, 1.0),
    ("deadbeat", 1.5, 1.0),
    ("deadbeat", 1.2, 3.0),
    ("deadbeat", 1.9, 0.5),
    ("pi", 1.0, 1.0),
    ("predictive", 1.0, 1.0),
    ("predictive", 1.3, 1.0),
]


@pytest.mark.parametrize(("name", "kL", "kR"), CASES)
def test_reference_step_matches_forced_response(name, kL, kR):
    i0, i1, n = 15.0, 20.0, 600
    ours = design.predicted_step(name, n_samples=n, i_start=i0, i_final=i1, L_c=kL * L, R_c=kR * R)
    _, _, P = _plant()
    T = ct.feedback(_controller(name, kL * L, kR * R, 0.4647, 0.0492) * P, 1)
    t = np.arange(n) * Ts
    step = ct.forced_response(T, t, np.ones(n)).outputs
    dc = float(np.real(T(1.0)))
    expected = dc * i0 + (i1 - i0) * step  # linearity: equilibrium at i0, then a step
    np.testing.assert_allclose(ours.i_p, expected, atol=1e-9 * i1)
    assert ours.stable
    assert ours.i_p_final == pytest.approx(dc * i1, rel=1e-9)


def test_matched_deadbeat_settles_in_two_samples():
    r = design.predicted_step("deadbeat", n_samples=10, i_start=15.0, i_final=20.0)
    np.testing.assert_allclose(r.i_p, [15, 15] + [20] * 8, atol=1e-9)
    # steady state before and after obeys eq. (2) with di/dt = 0: v_L = 2 R i_p
    assert r.v_L[0] == pytest.approx(2 * R * 15.0, rel=1e-9)
    assert r.v_L[-1] == pytest.approx(2 * R * 20.0, rel=1e-9)


def test_predictive_is_two_sample_delay_without_resistance():
    # the paper: with R neglected I_p / I_p* = z^-2 for the law (23)
    r = design.predicted_step("predictive", n_samples=8, i_start=0.0, i_final=30.0, R=0.0)
    np.testing.assert_allclose(r.i_p, [0, 0] + [30] * 6, atol=1e-9)


def test_deadbeat_rejects_constant_back_emf_without_feedforward():
    r = design.predicted_step("deadbeat", n_samples=50, i_start=15.0, i_final=30.0, e_L=12.0)
    np.testing.assert_allclose(r.i_p[2:], 30.0, atol=1e-9)
    assert r.v_L[-1] == pytest.approx(12.0 + 2 * R * 30.0, rel=1e-9)


def test_back_emf_step_follows_eq21():
    """1 V back-EMF step, matched deadbeat, no feed-forward: eq. (21) with the printed numbers."""
    n = 1500
    r = design.predicted_step(
        "deadbeat", n_samples=n, i_start=20.0, i_final=20.0, e_L=0.0, e_L_final=1.0
    )
    z = _z()
    Cd = -0.6729 * (z - 1) * (z + 1) / (z**2 * (z - 0.9917))  # eq. (21)
    # e_L changes at sample 0 and reaches i_p one sample later (the plant's state update)
    y = ct.forced_response(Cd, np.arange(n) * Ts, np.ones(n)).outputs
    np.testing.assert_allclose(r.i_p - 20.0, y, atol=5e-3)  # the paper prints 4 digits
    dip = r.i_p.min() - 20.0
    assert dip == pytest.approx(-1.34, abs=0.01)  # notes/simulation.md: about -1.34 A
    # decays with the plant pole: time constant ~2.4 ms, rejected in about five of them
    k_pk = int(np.argmin(r.i_p))
    k_tau = k_pk + round(2.4e-3 / Ts)
    assert (r.i_p[k_tau] - 20.0) / dip == pytest.approx(math.exp(-1), abs=0.02)
    assert abs(r.i_p[k_pk + round(5 * 2.4e-3 / Ts)] - 20.0) < 0.01 * abs(dip)


def test_predictive_without_feedforward_keeps_an_error():
    """Eq. (24) has no zero at z = 1: a constant back-EMF leaves a steady-state error."""
    e = 10.0
    with_ff = design.predicted_step(
        "predictive", n_samples=200, i_start=20, i_final=20, e_L=e, feedforward=True
    )
    no_ff = design.predicted_step(
        "predictive", n_samples=200, i_start=20, i_final=20, e_L=e, feedforward=False
    )
    # oracle: the law (23) without its 2 e_L term, interconnected with eq. (6) in python-control
    Phi, Gamma, P = _plant()
    D = -Gamma / (_z() - Phi)  # eq. (9)
    C = _controller("predictive", L, R, 0, 0)
    Td = D * ct.feedback(ct.tf([1], [1], Ts), C * P)  # D / (1 + C P), eq. (12)
    Tr = ct.feedback(C * P, 1)
    expected = float(np.real(Tr(1.0))) * 20 + float(np.real(Td(1.0))) * e
    assert no_ff.i_p[-1] == pytest.approx(expected, rel=1e-9)
    assert no_ff.i_p[-1] < with_ff.i_p[-1] - 5.0  # 10 V of back-EMF costs amperes
    # with the feed-forward only the resistance error remains (I/I* DC gain as without e_L)
    assert with_ff.i_p[-1] == pytest.approx(float(np.real(Tr(1.0))) * 20, rel=1e-9)


def test_eq25_compensation_removes_the_inverter_loss_error():
    loss = 2.0  # V lost to blanking time / switch drops
    base = design.predicted_step("predictive", n_samples=100, i_start=15, i_final=30)
    lossy = design.predicted_step("predictive", n_samples=100, i_start=15, i_final=30, v_loss=loss)
    comp = design.predicted_step(
        "predictive", n_samples=100, i_start=15, i_final=30, v_loss=loss, v_comp=2 * loss
    )
    assert lossy.i_p[-1] < base.i_p[-1] - 1.0  # Fig. 14: a large steady-state error
    assert comp.i_p[-1] == pytest.approx(base.i_p[-1], rel=1e-9)  # Fig. 15
    # the deadbeat's integrator needs no compensation (Section IV-B)
    db = design.predicted_step("deadbeat", n_samples=100, i_start=15, i_final=30, v_loss=loss)
    assert db.i_p[-1] == pytest.approx(30.0, rel=1e-9)


def test_eq25_term():
    v = design.eq25_compensation(T_BT=1e-6, T_DD=1.5e-6, T_SD=0.5e-6, V_G=1.0, V_dc=48, E_L=10)
    assert v == pytest.approx(4 * 1e-6 * 48 / Ts + 10 * 2e-6 / Ts + 4 * 1.0, rel=1e-12)


def test_unstable_loop_is_flagged_and_diverges():
    r = design.predicted_step("deadbeat", n_samples=3000, L_c=2.2 * L)
    assert not r.stable
    assert r.max_pole_radius > 1.0
    assert np.max(np.abs(r.i_p - 20.0)) > 100.0


@pytest.mark.parametrize(
    "kw",
    [
        {"n_samples": 0},
        {"controller": "hysteresis"},
        {"i_start": math.nan},
        {"v_comp": 1.0},
        {"L_c": -1e-6},
        {"fs": 0.0},
    ],
)
def test_predicted_step_rejects_bad_input(kw):
    controller = kw.pop("controller", "deadbeat")
    with pytest.raises(ValueError):
        design.predicted_step(controller, **kw)
