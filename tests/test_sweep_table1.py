"""Issue 28: a Table-1-style sweep (L_c/L 0.25..2.5 x R_c/R 0.5..2, 200 runs) finds the
stability boundary of the deadbeat current loop at L_c/L ~ 2, as eq. (17) predicts.

Oracle: python-control, independently of the product's code: the plant of eq. (8)
P(z) = Gamma / (z (z - Phi)) with Phi = exp(-R Ts / L), Gamma = (1 - Phi) / (2 R) (eqs. 4, 5),
the deadbeat law of eq. (15) built with the estimates L_c, R_c, C(z) = (z^2 - Phi_c z) /
(Gamma_c (z^2 - 1)), and the poles of the closed loop C P / (1 + C P) (eq. 10, whose
denominator is eq. 16's). The sweep runs the simulator (PWM bridge, the DSP's C controller,
float32) on a 5 A current step at standstill (Fig. 8's 10 -> 15 A).
"""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest

from virtual_drive.sweep import load_spec, run_sweep

pytestmark = [pytest.mark.unit, pytest.mark.timeout(120)]

Ts = 20e-6  # s, fs = 50 kHz (paper, Sec. II)

SPEC = """
[sweep]
name = "table1"
[parameters]
"L_c/L" = { linspace = [0.25, 2.5, 20] }
"R_c/R" = { linspace = [0.5, 2.0, 10] }
[limits]
overshoot = 25
[[scenarios]]
kind = "current_step"
from = "10 A"
to = "15 A"
at = "0.5 ms"
duration = "8 ms"
settle = "1 ms"
"""


def _oracle_loop(L: float, R: float, L_c: float, R_c: float) -> ct.TransferFunction:
    """The closed deadbeat current loop C P / (1 + C P) (python-control)."""
    Phi = math.exp(-R * Ts / L)
    Gamma = (1.0 - Phi) / (2.0 * R)
    Phi_c = math.exp(-R_c * Ts / L_c)
    Gamma_c = (1.0 - Phi_c) / (2.0 * R_c)
    P = ct.tf([Gamma], [1.0, -Phi, 0.0], dt=Ts)
    C = ct.tf([1.0, -Phi_c, 0.0], [Gamma_c, 0.0, -Gamma_c], dt=Ts)
    return ct.feedback(C * P, 1)


def _oracle_radius(L: float, R: float, L_c: float, R_c: float) -> float:
    """Largest |pole| of the closed deadbeat current loop."""
    return float(np.max(np.abs(_oracle_loop(L, R, L_c, R_c).poles())))


def test_table1_sweep_finds_the_eq17_boundary(tmp_path):
    spec_path = tmp_path / "table1.toml"
    spec_path.write_text(SPEC)
    spec = load_spec(spec_path)
    assert spec.n_runs == 200
    res = run_sweep(spec, tmp_path / "out", workers=1, progress=False)
    rows = res.rows
    assert len(rows) == 200 and [r["run"] for r in rows] == list(range(200))
    judged = 0
    for r in rows:
        assert r["L_c"] == pytest.approx(r["L_c/L"] * r["L"])  # the ratio is of the run's L
        rho = _oracle_radius(r["L"], r["R"], r["L_c"], r["R_c"])
        if abs(rho - 1.0) < 0.002:
            continue  # too close to the boundary for a finite run to tell
        judged += 1
        assert r["stable"] == (rho < 1.0), (r["L_c/L"], r["R_c/R"], rho, r["fails"])
        if rho > 1.0:
            assert not r["passed"] and "unstable" in r["fails"]
    assert judged >= 190
    # per R_c/R row: the largest stable and the smallest unstable L_c/L bracket 2
    for rc in sorted({r["R_c/R"] for r in rows}):
        line = sorted((r["L_c/L"], r["stable"]) for r in rows if r["R_c/R"] == rc)
        stable = [x for x, s in line if s]
        unstable = [x for x, s in line if not s]
        assert max(stable) < 2.0 < min(unstable), (rc, line)
        assert min(unstable) - max(stable) < 0.12 + 1e-9  # adjacent grid points
    # Table 1 / Fig. 8: overshoot grows with L_c / L (less damped), none at L_c = 0.5 L
    r_c1 = {round(r["L_c/L"], 3): r for r in rows if abs(r["R_c/R"] - 1.0) < 0.09}
    ov = [r_c1[k]["overshoot"] for k in sorted(r_c1) if 0.9 < k < 1.95]
    assert ov == sorted(ov)
    # and it is the overshoot of the oracle's step response (within 1.5 % of the step)
    t = np.arange(375) * Ts
    for k, r in r_c1.items():
        if 1.0 < k < 1.85:
            loop = _oracle_loop(r["L"], r["R"], r["L_c"], r["R_c"])
            y = np.squeeze(ct.step_response(loop, t).outputs)
            info = ct.step_info(y, t, yfinal=1.0)
            assert r["overshoot"] == pytest.approx(info["Overshoot"], abs=1.5), k
    summary = (tmp_path / "out" / "summary.md").read_text()
    assert "virtual-drive sweep" in summary and "--run" in summary
    for name in ("map_pass.png", "map_overshoot.png", "histograms.png"):
        assert (tmp_path / "out" / name).stat().st_size > 10_000
