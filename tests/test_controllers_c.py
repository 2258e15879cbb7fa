"""The portable controllers (virtual_drive/csrc/controllers.c): DSP-portability rules, the laws
against the paper's transfer functions, and the float32 speed integrator."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import control
import numpy as np
import pytest
from lti_oracle import discrete_response
from scipy import signal
from virtual_drive._core import ffi, lib

pytestmark = pytest.mark.timeout(60)

CSRC = Path(__file__).resolve().parents[1] / "virtual_drive" / "csrc"
R, L, Ts = 6.2e-3, 14.8e-6, 20e-6


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc not installed")
def test_compiles_as_strict_c99_float32(tmp_path):
    flags = [
        "-std=c99",
        "-Wall",
        "-Wextra",
        "-Werror",
        "-pedantic",
        "-Wdouble-promotion",
        "-fsingle-precision-constant",
    ]
    res = subprocess.run(
        ["gcc", *flags, "-c", str(CSRC / "controllers.c"), "-o", str(tmp_path / "c.o")],
        capture_output=True,
        text=True,
    )
    assert res.returncode == 0, res.stderr


@pytest.mark.unit
def test_source_rules():
    for name in ("controllers.c", "controllers.h"):
        text = (CSRC / name).read_text()
        code = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
        assert not re.search(r"\bdouble\b", code), name
        assert "uint8_t" not in code and "int8_t" not in code, name
        assert not re.search(r"\b(malloc|calloc|realloc|free)\b", code), name
        includes = re.findall(r"#include\s*[<\"]([^>\"]+)[>\"]", code)
        assert set(includes) <= {"math.h", "controllers.h"}, includes


def _current(type_, Lc=L, Rc=R, kp=0.4647, ki=0.0492, ff=0):
    c = ffi.new("cc_current_t *")
    assert lib.cc_current_configure(c, type_, Ts, Lc, Rc, kp, ki, 0, 0, 0, 0, ff) == 0
    lib.cc_current_reset(c, 0.0)
    return c


@pytest.mark.unit
def test_configure_rejects_bad_values_and_keeps_state():
    c = _current(0)
    before = (c.Phi_c, c.Gamma_c, c.L_c)
    for bad in (0.0, -1e-6, float("nan"), float("inf")):
        assert lib.cc_current_configure(c, 0, Ts, bad, R, 0.4, 0.05, 0, 0, 0, 0, 0) == -1
    assert (c.Phi_c, c.Gamma_c, c.L_c) == before


@pytest.mark.unit
@pytest.mark.parametrize("Lc", [L, 0.5 * L, 1.5 * L])
def test_deadbeat_law_is_eq15(Lc):
    """Output of the C law for a random error sequence = lfilter of eq. (15) built here."""
    rng = np.random.default_rng(1)
    e = rng.normal(0.0, 0.5, 400)
    c = _current(0, Lc=Lc)
    v = np.array([lib.cc_current_step(c, float(x), 0.0, 0.0, 1e6) * 1e6 for x in e])
    Phic = np.exp(-R * Ts / Lc)
    Gamc = (1 - Phic) / (2 * R)
    ref = signal.lfilter([1 / Gamc, -Phic / Gamc], [1, 0, -1], e)
    np.testing.assert_allclose(v, ref, rtol=2e-4, atol=2e-3 * np.abs(ref).max())


@pytest.mark.unit
def test_pi_law_is_eq22():
    rng = np.random.default_rng(2)
    e = rng.normal(0.0, 1.0, 400)
    kp, ki = 0.4647, 0.0492
    c = _current(1, kp=kp, ki=ki)
    v = np.array([lib.cc_current_step(c, float(x), 0.0, 0.0, 1e6) * 1e6 for x in e])
    ref = signal.lfilter([kp + ki, -kp], [1, -1], e)  # k_p + k_i z/(z-1)
    np.testing.assert_allclose(v, ref, rtol=1e-4, atol=1e-4 * np.abs(ref).max())


@pytest.mark.unit
def test_ip_closed_loop_is_eq27():
    """IP controller in the C code closing the loop on b/(z - a) = eq. (27) from python-control."""
    a, b, kp, ki = 0.9999785, 3.33715e-4, 0.2113, 2.9994e-5
    s = ffi.new("cc_speed_t *")
    assert lib.cc_speed_configure(s, kp, ki, 1e4) == 0
    lib.cc_speed_reset(s, 0.0, 0.0)
    n = 100_000
    w = 0.0
    out = np.empty(n)
    for k in range(n):
        out[k] = w
        i = lib.cc_speed_step(s, 500.0, w)
        w = a * w + b * i
    cl = control.tf([kp * b * ki, 0], [1, kp * b * ki + kp * b - 1 - a, a - kp * b], Ts)
    y = discrete_response(cl, np.full(n, 500.0))
    np.testing.assert_allclose(out, y, atol=0.5)  # rpm on a 500 rpm step
    assert out.max() < 500.0 * 1.002  # xi = 1: no overshoot


@pytest.mark.unit
def test_ip_float32_integrator_does_not_stall():
    """At 1000 rpm holding ~211 A of integral, a 0.5 rpm error adds k_p k_i e = 3.2e-6 A per
    sample.  The naive float32 forms (x = sum e in rpm*samples, or q += k_p k_i e in A) lose
    every increment; the compensated C integrator keeps them (oracle: float64 sum)."""
    kp, ki = np.float32(0.2113), np.float32(2.9994e-5)
    w, e, n = 1000.0, 0.5, 200_000
    i0 = 211.0
    s = ffi.new("cc_speed_t *")
    lib.cc_speed_configure(s, kp, ki, 1e4)
    lib.cc_speed_reset(s, i0, w)
    for _ in range(n):
        out = lib.cc_speed_step(s, w + e, w)
    exact = i0 + n * float(kp) * float(ki) * e  # float64 oracle
    assert exact - i0 == pytest.approx(0.634, rel=0.01)
    assert out == pytest.approx(exact, abs=2e-4)
    # naive float32, paper's form: x += e, i* = k_p (k_i x - w)
    x = np.float32((i0 / float(kp) + w) / float(ki))
    x0 = x
    q = np.float32(i0 + float(kp) * w)
    q0 = q
    inc = np.float32(kp * ki * np.float32(e))
    for _ in range(2000):
        x = np.float32(x + np.float32(e))
        q = np.float32(q + inc)
    assert x == x0 and q == q0  # both naive forms stall completely


@pytest.mark.unit
def test_current_saturation_and_realizable_reference():
    """m is clipped to +-1; after clipping the stored error is the one that gives the applied
    voltage (Hanus conditioning), so the next unsaturated output is the linear law's."""
    c = _current(0)
    m = lib.cc_current_step(c, 100.0, 0.0, 0.0, 48.0)
    assert m == 1.0 and c.saturated == 1
    assert c.u1 == pytest.approx(48.0)
    assert c.e1 == pytest.approx(48.0 * c.Gamma_c, rel=1e-5)  # u = e/Gamma_c for the 1st step
