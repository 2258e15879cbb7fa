"""IP speed design (eqs. 27–31) refuses specs whose gains are not positive, and its stability
claim comes from the closed-loop poles of the gains as the drive holds them (REAL32).

Oracle: python-control builds the loop of Fig. 17 from state-space blocks (no use of eq. 27) and
gives its poles; the gains for the refusal cases are recomputed here from eqs. (28)–(31) as
printed in the paper (with the squared radius for d_2)."""

from __future__ import annotations

import json
import math

import control as ct
import numpy as np
import pytest

from drive_link import design
from drive_link.cli.design import run_cli
from drive_link.workflows.design import speed_loop

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

FS = 50e3
Ts = 1 / FS
A = 0.9999785
B = 3.33715e-4


def _paper_gains(a: float, b: float, xi: float, wn: float) -> tuple[float, float]:
    """Eqs. (28)–(31) literally (complex cos covers xi > 1)."""
    d1 = -2 * math.exp(-xi * wn * Ts) * np.cos(wn * Ts * np.sqrt(complex(1 - xi * xi))).real
    d2 = math.exp(-2 * xi * wn * Ts)
    kp = (a - d2) / b
    ki = (d1 + 1 + a - kp * b) / (kp * b)
    return kp, ki


def _loop_poles(a: float, b: float, k_p: float, k_i: float) -> np.ndarray:
    G = ct.ss([[a]], [[b]], [[1.0]], [[0.0]], Ts, inputs="u", outputs="w")
    Ci = ct.ss([[1.0]], [[k_i]], [[1.0]], [[k_i]], Ts, inputs="e", outputs="y")
    S = ct.summing_junction(inputs=["r", "-w"], output="e", dt=Ts)
    U = ct.ss(
        np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), [[k_p, -k_p]], Ts,
        inputs=["y", "w"], outputs="u",
    )
    T = ct.interconnect([G, Ci, S, U], inputs="r", outputs="w", dt=Ts)
    return np.sort_complex(ct.poles(T).astype(complex))


def test_issue_case_xi_half_wn_one_is_refused(capsys):
    kp, ki = _paper_gains(A, B, 0.5, 1.0)
    assert kp < 0 and ki < 0  # the oracle agrees the spec needs negative gains
    with pytest.raises(ValueError, match="non-positive IP gains"):
        design.ip_gains(A, B, 0.5, 1.0)
    rc = run_cli(["design", "--a", str(A), "--b", str(B), "--xi", "0.5", "--wn", "1"])
    out, err = capsys.readouterr()
    assert rc == 7 and out == ""  # an invalid value (README's exit-code table)
    assert err.count("\n") == 1 and "xi * omega_n > 0.5375" in err


@pytest.mark.parametrize("seed", range(3))
def test_random_specs_are_refused_exactly_when_the_gains_are_not_positive(seed):
    rng = np.random.default_rng(seed)
    refused = accepted = 0
    for _ in range(40):
        a = 1.0 - 10 ** rng.uniform(-7, -3)
        b = 10 ** rng.uniform(-5, -2)
        xi = rng.uniform(0.3, 2.0)
        wn = 10 ** rng.uniform(-1.5, 2.5)
        kp, _ = _paper_gains(a, b, xi, wn)
        if xi * wn < 0.999 * speed_loop.ip_min_xi_omega_n(a, FS):
            assert kp < 0
            with pytest.raises(ValueError):
                design.ip_design(a, b, xi, wn, FS)
            refused += 1
            continue
        if xi * wn < 1.001 * speed_loop.ip_min_xi_omega_n(a, FS):
            continue  # too close to the boundary to tell the sign in floating point
        d = design.ip_design(a, b, xi, wn, FS)
        accepted += 1
        assert d.k_p > 0 and d.k_i > 0
        assert d.k_p == pytest.approx(kp, rel=1e-4)  # the literal form loses digits (a ≈ d_2)
        oracle = _loop_poles(a, b, d.k_p_f32, d.k_i_f32)
        # the oracle's poles are inside the unit circle, and equal the requested ones
        assert np.max(np.abs(oracle)) < 1.0
        assert d.stable
        s_oracle = np.log(oracle) * FS
        s_want = np.sort_complex(np.log(speed_loop.ip_requested_poles(xi, wn, FS)) * FS)
        err = min(
            np.max(np.abs(s_oracle - s_want)), np.max(np.abs(s_oracle - s_want[::-1]))
        )
        assert err <= 0.01 * wn
        assert d.poles_match
    assert refused > 0 and accepted > 0


def test_stability_claim_follows_the_poles_of_the_given_gains():
    """A loop is called stable by the poles of the gains passed, not by the spec they came
    from: a hand-made gain pair that python-control finds unstable is reported unstable."""
    d = design.ip_design(A, B, 1.0, 2.3, FS)
    bad_ki = -3 * d.k_i  # integral of the wrong sign
    assert np.max(np.abs(_loop_poles(A, B, d.k_p, bad_ki))) > 1.0
    assert not design.is_stable(design.ip_closed_loop(A, B, d.k_p, bad_ki, FS))


def test_cli_prints_poles_from_the_real32_gains(capsys):
    rc = run_cli(["design", "--a", str(A), "--b", str(B), "--xi", "0.7", "--wn", "5", "--json"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    r = json.loads(out)
    assert r["stable"] is True and r["poles_match"] is True and r["within_drive_limits"]
    got = np.sort_complex(np.array([complex(*p) for p in r["poles"]]))
    oracle = _loop_poles(A, B, float(np.float32(r["kp"])), float(np.float32(r["ki"])))
    np.testing.assert_allclose(got, oracle, atol=1e-9)
