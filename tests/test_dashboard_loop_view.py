"""The tuning view's curves (dashboard._loop_view on drive_link.workflows.design) against
python-control (test-only oracle): Bode magnitude/phase of the open current and speed loops and the
closed-loop poles, for each controller law, and the z-plane data layout uPlot needs (one ascending x
array)."""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest

from dashboard import _loop_view as loop_view

pytestmark = pytest.mark.unit

TS, R, L = 20e-6, 6.2e-3, 14.8e-6
A, B = 0.9999785, 3.33715e-4
BASE = dict(R_c=R, k_p=0.4647, k_i=0.0492, speed_k_p=0.2113, speed_k_i=2.9994e-5)


def oracle_current(kind: str, L_c: float) -> ct.TransferFunction:
    Phi, Gamma = math.exp(-R * TS / L), (1 - math.exp(-R * TS / L)) / (2 * R)
    P = ct.tf([Gamma], [1, -Phi, 0], TS)  # eq. 16: one sample of computation delay
    if kind == "deadbeat":
        Pc, Gc = math.exp(-R * TS / L_c), (1 - math.exp(-R * TS / L_c)) / (2 * R)
        C = ct.tf([1, -Pc, 0], [Gc, 0, -Gc], TS)
    elif kind == "pi":
        C = ct.tf([BASE["k_p"] + BASE["k_i"], -BASE["k_p"]], [1, -1], TS)
    else:
        return None
    return C * P


@pytest.mark.parametrize(("kind", "ratio"), [("deadbeat", 1.0), ("deadbeat", 1.5), ("pi", 1.0)])
def test_bode_and_poles_match_python_control(kind, ratio):
    g = dict(BASE, type=kind, L_c=ratio * L, motor_R=R, motor_L=L)
    v = loop_view.loop_view(g, A, B)
    pick = np.searchsorted(v.f_hz, [1.0, 50.0, 700.0, 4000.0, 20_000.0])
    f = v.f_hz[pick]
    loop = oracle_current(kind, ratio * L)
    h = ct.frequency_response(loop, 2 * np.pi * f).complex.ravel()
    assert v.current_db[pick] == pytest.approx(20 * np.log10(np.abs(h)), abs=1e-6)
    d = np.angle(np.exp(1j * np.radians(v.current_deg[pick])) / h)  # same phase modulo 360°
    assert np.abs(d) == pytest.approx(0.0, abs=1e-6)
    want = np.sort_complex(ct.poles(ct.feedback(loop, 1)))
    assert np.sort_complex(v.current_poles) == pytest.approx(want, abs=1e-7)


def test_speed_loop_matches_python_control():
    g = dict(BASE, type="deadbeat", L_c=L, motor_R=R, motor_L=L)
    v = loop_view.loop_view(g, A, B)
    pick = np.searchsorted(v.f_hz, [0.1, 1.0, 10.0, 100.0])
    f = v.f_hz[pick]
    kp, ki = BASE["speed_k_p"], BASE["speed_k_i"]
    G = ct.tf([B], [1, -A], TS)
    # IP (paper eqs. 26-27): u = k_p (k_i/(1 − z⁻¹) e − ω); the loop seen at the plant input
    loop = ct.tf([kp * (1 + ki), -kp], [1, -1], TS) * G
    h = ct.frequency_response(loop, 2 * np.pi * f).complex.ravel()
    assert v.speed_db[pick] == pytest.approx(20 * np.log10(np.abs(h)), abs=1e-6)
    inner = ct.feedback(G, kp)  # the P part acts on the measured speed only
    cl = ct.feedback(ct.tf([kp * ki, 0], [1, -1], TS) * inner, 1)  # the I part on the error
    want = np.sort_complex(ct.poles(ct.minreal(cl, verbose=False)))
    assert np.sort_complex(v.speed_poles) == pytest.approx(want, abs=1e-9)


def test_z_plane_data_is_one_ascending_x_with_gaps():
    p1 = np.array([0.5 + 0.5j, 0.5 - 0.5j, 0.0])
    p2 = np.array([0.9])
    x, up, down, s1, s2 = loop_view.z_plane_data(p1, p2, n_circle=11)
    assert np.all(np.diff(x) >= 0) and x.size == 11 + 4
    circle = np.isfinite(up)
    assert np.allclose(up[circle] ** 2 + x[circle] ** 2, 1.0)
    assert np.allclose(down, -up, equal_nan=True)
    got1 = np.sort_complex(x[np.isfinite(s1)] + 1j * s1[np.isfinite(s1)])
    assert got1 == pytest.approx(np.sort_complex(p1))
    assert x[np.isfinite(s2)] == pytest.approx([0.9]) and s2[np.isfinite(s2)] == pytest.approx([0])
