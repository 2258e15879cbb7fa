"""Margins of the current loops against Table 1 / Section IV-B and python-control (test oracle)."""

from __future__ import annotations

import math
import warnings

import control as ct
import numpy as np
import pytest

from drive_link import design

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

L = design.L_TABLE2
R = design.R_TABLE2


def _ct_tf(tf: design.DiscreteTF, minreal: bool = True) -> ct.TransferFunction:
    sys = ct.tf(tf.num, tf.den, tf.Ts)
    if minreal:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sys = ct.minreal(sys, verbose=False)
    return sys


def _ct_loop(controller: str, **kw: float) -> ct.TransferFunction:
    """C(z) P(z) built independently in python-control from the paper's equations."""
    Ts = 1.0 / 50e3
    z = ct.tf([1, 0], [1], Ts)
    Phi = math.exp(-R * Ts / L)
    Gamma = (1 - Phi) / (2 * R)
    P = Gamma / (z * (z - Phi))  # eq. (8)
    if controller == "deadbeat":
        L_c, R_c = kw.get("L_c", L), kw.get("R_c", R)
        Phi_c = math.exp(-R_c * Ts / L_c)
        Gamma_c = (1 - Phi_c) / (2 * R_c)
        C = (z**2 - Phi_c * z) / (Gamma_c * (z**2 - 1))  # eq. (15)
    elif controller == "pi":
        C = kw["k_p"] + kw["k_i"] * z / (z - 1)  # eq. (22)
    else:
        C = 2 * kw.get("L_c", L) * 50e3 * z / (z + 1)  # eq. (23) without feed-forward
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ct.minreal(C * P, verbose=False)


# Table 1 (deadbeat) and the PI figures of Section IV-B: (GM dB, |PM| list, ||S||inf)
TABLE1 = [
    (0.5, 12.0, (73.6, 75.6), 1.33),
    (1.0, 6.0, (60.0, 60.0), 1.99),
    (1.5, 2.5, (41.6, 41.6), 3.97),
]


@pytest.mark.parametrize(("ratio", "gm_db", "pms", "s_inf"), TABLE1)
def test_deadbeat_margins_match_table1(ratio, gm_db, pms, s_inf):
    """Table 1 lists [-x°, y°] per row; the phase margin is the smaller, as a positive angle."""
    m = design.margins(design.current_loop_tf("deadbeat", L_c=ratio * L))
    assert m.gain_margin_db == pytest.approx(gm_db, abs=0.1)
    # Table 1 lists the two crossovers' margins [-x°, y°]; compare magnitudes (±0.3°: the
    # paper rounds the 1.5 L pair, computed 41.59°/-41.37°, to ±41.6°)
    assert sorted(m.phase_margins_deg) == pytest.approx(sorted(pms), abs=0.3)
    assert m.phase_margin_deg == pytest.approx(min(pms), abs=0.3) and m.phase_margin_deg > 0
    assert len(m.gain_crossovers_hz) == 2  # both crossovers listed
    assert m.sensitivity_peak == pytest.approx(s_inf, rel=0.01)


def test_matched_deadbeat_exact_values():
    """C·P = 1/(z² - 1) exactly: GM = 2 (6.02 dB) at fs/4, PM = 60° at fs/12, ||S|| = 2."""
    m = design.margins(design.current_loop_tf("deadbeat"))
    assert m.gain_margin_db == pytest.approx(20 * math.log10(2.0), abs=1e-6)
    assert m.phase_crossover_hz == pytest.approx(50e3 / 4, rel=1e-6)
    assert m.phase_margin_deg == pytest.approx(60.0, abs=1e-6)
    assert m.gain_crossover_hz == pytest.approx(50e3 / 12, rel=1e-6)
    assert m.sensitivity_peak == pytest.approx(2.0, rel=1e-6)


def test_pi_margins_match_paper():
    m = design.margins(design.current_loop_tf("pi", k_p=0.4647, k_i=0.0492))
    assert m.gain_margin_db == pytest.approx(9.14, abs=0.02)
    assert m.phase_margin_deg == pytest.approx(45.6, abs=0.05)
    assert m.sensitivity_peak == pytest.approx(1.72, abs=0.01)


CASES = [
    ("deadbeat", {"L_c": 0.3 * L}),
    ("deadbeat", {"L_c": 0.5 * L}),
    ("deadbeat", {"L_c": 0.8 * L, "R_c": 2 * R}),
    ("deadbeat", {"L_c": 1.2 * L, "R_c": 0.5 * R}),
    ("deadbeat", {"L_c": 1.5 * L}),
    ("deadbeat", {"L_c": 1.8 * L}),
    ("pi", {"k_p": 0.4647, "k_i": 0.0492}),
    ("pi", {"k_p": 0.2, "k_i": 0.01}),
    ("pi", {"k_p": 0.8, "k_i": 0.1}),
    ("predictive", {"L_c": 0.7 * L}),
]


@pytest.mark.parametrize(("controller", "kw"), CASES)
def test_margins_agree_with_python_control(controller, kw):
    ours = design.margins(design.current_loop_tf(controller, **kw))
    oracle = _ct_loop(controller, **kw)
    gm, pm, sm, wpc, wgc, _ = ct.stability_margins(oracle)
    if np.isinf(gm):
        assert np.isinf(ours.gain_margin_db)
    else:
        assert ours.gain_margin_db == pytest.approx(20 * math.log10(gm), abs=1e-3)
        assert ours.phase_crossover_hz == pytest.approx(wpc / (2 * math.pi), rel=1e-4)
    # one convention: the smallest margin as a positive angle (python-control: signed)
    assert ours.phase_margin_deg >= 0.0
    assert ours.phase_margin_deg == pytest.approx(abs(pm), abs=1e-3)
    assert ours.gain_crossover_hz == pytest.approx(wgc / (2 * math.pi), rel=1e-4)
    assert 1.0 / ours.sensitivity_peak == pytest.approx(sm, rel=1e-4)
    # every crossover, not only the reported one, by rising frequency
    _, pms, _, _, wcs, _ = ct.stability_margins(oracle, returnall=True)
    inside = wcs < math.pi * 50e3 * (1 - 1e-9)  # (0, fs/2): python-control may add Nyquist
    assert ours.phase_margins_deg == pytest.approx(np.abs(pms[inside]), abs=1e-3)
    assert ours.gain_crossovers_hz == pytest.approx(wcs[inside] / (2 * math.pi), rel=1e-4)


def test_margins_do_not_depend_on_uncancelled_factors():
    """Without minreal python-control's PM is wrong (-60°, notes); ours uses only the response."""
    tf = design.current_loop_tf("deadbeat")
    a = design.margins(tf)
    b = design.margins(design.DiscreteTF([1.0], [1.0, 0.0, -1.0], tf.Ts))
    assert a.phase_margin_deg == pytest.approx(b.phase_margin_deg, abs=1e-6)
    assert a.gain_margin_db == pytest.approx(b.gain_margin_db, abs=1e-6)


def test_no_crossover_gives_inf_gain_margin_and_nan_phase_margin():
    # L = 0.1 z / (z - 0.5): |L| < 1 everywhere, Im L != 0 inside (0, fs/2), L(-1) > 0
    m = design.margins(design.DiscreteTF([0.1, 0.0], [1.0, -0.5], 2e-5))
    assert math.isinf(m.gain_margin_db)
    assert math.isnan(m.phase_margin_deg)
    # |S| = |z - 0.5| / |1.1 z - 0.5| peaks at z = -1: 1.5 / 1.6
    assert m.sensitivity_peak == pytest.approx(1.5 / 1.6, rel=1e-9)


def test_phase_crossover_at_nyquist():
    # L = 0.1 / (z - 0.5) is real and negative at z = -1: GM = 15 (23.5 dB) at fs/2
    tf = design.DiscreteTF([0.1], [1.0, -0.5], 2e-5)
    m = design.margins(tf)
    # python-control 0.10.2 skips a crossover exactly at Nyquist (it reports inf), so the truth
    # here is the closed loop itself: with the gain raised by GM the pole reaches z = -1.
    gm = 10 ** (m.gain_margin_db / 20)
    assert np.roots([1.0, -0.5 + 0.1 * gm]) == pytest.approx([-1.0], abs=1e-9)
    assert m.gain_margin_db == pytest.approx(20 * math.log10(15.0), abs=1e-9)
    assert m.phase_crossover_hz == pytest.approx(25e3, rel=1e-9)


def test_margins_reject_tiny_grid():
    with pytest.raises(ValueError):
        design.margins(design.current_loop_tf("pi"), n_grid=10)
