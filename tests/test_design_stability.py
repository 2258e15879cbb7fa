"""Plant discretisation, the mismatched closed loop (eq. 16), poles and Jury's criterion."""

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


def test_phi_gamma_match_eq18_and_zoh_of_eq2():
    Phi, Gamma = design.phi_gamma(R, L, 50e3)
    # eq. (18): P(z) = 0.6729 / (z (z - 0.9917))
    assert Phi == pytest.approx(0.9917, abs=5e-5)
    assert Gamma == pytest.approx(0.6729, abs=5e-5)
    # ZOH of eq. (2): di/dt = -(R/L) i + v/(2L)  (python-control as oracle)
    cont = ct.tf([1 / (2 * L)], [1, R / L])
    disc = ct.sample_system(cont, Ts, method="zoh")
    num, den = np.atleast_1d(disc.num[0][0]), np.atleast_1d(disc.den[0][0])
    assert Phi == pytest.approx(-den[-1] / den[0], rel=1e-12)
    assert Gamma == pytest.approx(num[-1] / den[0], rel=1e-9)


def test_phi_gamma_zero_resistance_limit():
    Phi0, G0 = design.phi_gamma(0.0, L, 50e3)
    Phi1, G1 = design.phi_gamma(1e-12, L, 50e3)
    assert Phi0 == 1.0
    assert G0 == pytest.approx(Ts / (2 * L), rel=1e-12)
    assert G1 == pytest.approx(G0, rel=1e-9)
    assert Phi1 == pytest.approx(Phi0, abs=1e-9)


@pytest.mark.parametrize(
    ("R_", "L_", "fs"),
    [(R, -L, 50e3), (R, 0.0, 50e3), (-R, L, 50e3), (R, L, 0.0), (math.nan, L, 5e4)],
)
def test_phi_gamma_rejects_bad_input(R_, L_, fs):
    with pytest.raises(ValueError):
        design.phi_gamma(R_, L_, fs)


def _ct_closed_loop(L_c: float, R_c: float) -> ct.TransferFunction:
    z = ct.tf([1, 0], [1], Ts)
    Phi = math.exp(-R * Ts / L)
    Gamma = (1 - Phi) / (2 * R)
    Phi_c = math.exp(-R_c * Ts / L_c)
    Gamma_c = (1 - Phi_c) / (2 * R_c)
    P = Gamma / (z * (z - Phi))
    C = (z**2 - Phi_c * z) / (Gamma_c * (z**2 - 1))
    return ct.feedback(C * P, 1)  # no minreal: it may cancel near-equal (unequal) pairs


@pytest.mark.parametrize(("kL", "kR"), [(0.5, 1.0), (1.0, 1.0), (1.5, 1.0), (0.9, 3.0), (1.3, 0.2)])
def test_eq16_matches_feedback_of_controller_and_plant(kL, kR):
    ours = design.closed_loop_mismatch(R, L, kL * L, kR * R, 50e3)
    oracle = _ct_closed_loop(kL * L, kR * R)
    theta = np.linspace(0.01, 3.1, 25)
    z = np.exp(1j * theta)
    np.testing.assert_allclose(ours(z), oracle(z), rtol=1e-7, atol=1e-9)
    # every pole of eq. (16) is a closed-loop pole of the interconnection; the interconnection's
    # extra poles are cancelled by its own zeros (the z factors of C and P)
    p_ct = list(ct.poles(oracle))
    for p in ours.poles():
        k = int(np.argmin([abs(p - q) for q in p_ct]))
        assert abs(p - p_ct.pop(k)) < 1e-6
    for extra in p_ct:
        assert np.min(np.abs(ct.zeros(oracle) - extra)) < 1e-6
    assert ours.dcgain() == pytest.approx(1.0, rel=1e-9)  # integral action


def test_matched_deadbeat_is_two_sample_delay():
    cl = design.closed_loop_mismatch(R, L, L, R, 50e3)
    theta = np.linspace(0.01, 3.1, 40)
    np.testing.assert_allclose(cl(np.exp(1j * theta)), np.exp(-2j * theta), atol=1e-12)


def _char_poly(kL: float, kR: float = 1.0, R_: float = R) -> np.ndarray:
    return design.closed_loop_mismatch(R_, L, kL * L, kR * R_, 50e3).den


def test_jury_agrees_with_poles_over_lc_sweep():
    ratios = np.linspace(0.05, 3.0, 400)
    checked = 0
    for kR in (0.25, 0.5, 1.0, 2.0):  # R_c = 0 cancels the integrator: a pole sits at z = 1
        for r in ratios:
            den = design.closed_loop_mismatch(R, L, r * L, kR * R, 50e3).den
            radius = np.max(np.abs(np.roots(den)))
            if abs(radius - 1.0) < 1e-6:
                continue
            assert design.jury_stable(den) == (radius < 1.0), (r, kR)
            assert design.is_stable(den) == (radius < 1.0)
            checked += 1
    assert checked > 1500


def _boundary(R_: float) -> float:
    lo, hi = 1.5, 2.5
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if design.jury_stable(_char_poly(mid, 1.0, R_)):
            lo = mid
        else:
            hi = mid
    assert np.max(np.abs(np.roots(_char_poly(lo * 0.999, 1.0, R_)))) < 1.0
    assert np.max(np.abs(np.roots(_char_poly(hi * 1.001, 1.0, R_)))) > 1.0
    return lo


def test_stability_boundary_at_two_L():
    # R = R_c = 0 (eq. 17): eq. (16) keeps a pole at z = 1 cancelled by its zero; the remaining
    # poles are stable iff 0 < L_c < 2 L
    for k, expected in ((0.01, True), (1.0, True), (1.999, True), (2.001, False), (2.5, False)):
        q, rem = np.polydiv(_char_poly(k, 0.0, 0.0), [1.0, -1.0])
        assert np.max(np.abs(rem)) < 1e-12
        assert design.jury_stable(q) == expected
        assert design.is_stable(q) == expected
    # the full loop: the boundary tends to 2 L as R -> 0 and stays within 1 % of it with the
    # motor's real resistance (Fig. 4: R hardly matters)
    assert _boundary(1e-4) == pytest.approx(2.0, rel=1e-3)
    assert _boundary(R) == pytest.approx(2.0, rel=0.01)


def test_jury_agrees_with_roots_on_random_polynomials():
    rng = np.random.default_rng(7)
    n_stable = 0
    for _ in range(600):
        deg = int(rng.integers(1, 7))
        roots = []
        while len(roots) < deg:
            if deg - len(roots) >= 2 and rng.random() < 0.5:
                r, ph = rng.uniform(0.0, 1.3), rng.uniform(0.0, math.pi)
                roots += [r * np.exp(1j * ph), r * np.exp(-1j * ph)]
            else:
                roots.append(rng.uniform(-1.3, 1.3))
        radius = max(abs(x) for x in roots)
        if abs(radius - 1.0) < 1e-3:
            continue
        coeffs = np.real(np.poly(roots)) * rng.uniform(0.1, 10.0)
        assert design.jury_stable(coeffs) == (radius < 1.0), roots
        n_stable += radius < 1.0
    assert 50 < n_stable < 550


def test_jury_marginal_cases_are_not_stable():
    assert not design.jury_stable([1.0, 0.0, -1.0])  # z = ±1
    assert not design.jury_stable([1.0, 0.0, 1.0])  # z = ±j
    assert design.jury_stable([1.0, 0.0, 0.0])  # double pole at the origin
    assert not design.is_stable([1.0, -1.0])
    with pytest.raises(ValueError):
        design.jury_stable([1.0, math.nan])


def test_zero_resistance_estimate_cancels_the_integrator():
    """R_c = 0: Phi_c = 1, so C_db's zero at z = 1 cancels its integrator (a pole stays at 1)."""
    cl = design.closed_loop_mismatch(R, L, L, 0.0, 50e3)
    assert np.min(np.abs(np.roots(cl.den) - 1.0)) < 1e-6
    assert not design.is_stable(cl)
    assert not design.jury_stable(cl.den)
    report = design.analyse_current_loop("deadbeat", R_c=0.0)
    assert report["marginal"] is True
    assert report["overshoot_pct"] is None
    # a tiny but non-zero R_c keeps the integrator: asymptotically stable again
    assert design.is_stable(design.closed_loop_mismatch(R, L, L, 1e-4, 50e3))


def test_slow_but_stable_poles_are_stable():
    # IP loops: poles within 1e-4 .. 1e-6 of z = 1 are still inside the circle (specs with
    # xi * wn below the plant pole's -ln(a) fs / 2 give negative gains and are refused)
    for wn in (1.0, 2.3, 10.0):
        for xi in (0.7, 1.0, 1.5):
            k_p, k_i = design.ip_gains(0.9999785, 3.33715e-4, xi, wn, 50e3)
            cl = design.ip_closed_loop(0.9999785, 3.33715e-4, k_p, k_i)
            assert design.is_stable(cl)
            assert design.jury_stable(cl.den)
    # a slower plant (a = 1 - 1e-7), omega_n = 0.1 rad/s: double pole at 1 - 2e-6; the roots
    # still resolve it
    k_p, k_i = design.ip_gains(1.0 - 1e-7, 3.33715e-4, 1.0, 0.1, 50e3)
    assert design.is_stable(design.ip_closed_loop(1.0 - 1e-7, 3.33715e-4, k_p, k_i))
