"""`drive-link report` (the console script) against a virtual drive, checked against the
paper's equations by another route: python-control's closed loops of eqs. (8), (15), (16),
(22) for the current steps and of eq. (27) for the IP step, and scipy's exact discretisation of
the virtual plant's J, B, k_gen, K_t for a, b. And the drive is left as found: speed mode at
1000 rpm, enabled. A second motor (L +30 %, R −40 %, written to the drive's motor object, which
is the virtual plant's) must be found by identify_electrical."""

from __future__ import annotations

import contextlib
import io
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import control
import numpy as np
import pytest
from scipy import signal

from drive_link import cli

pytestmark = pytest.mark.timeout(240)

TS = 20e-6
R0, L0 = 6.2e-3, 14.8e-6
DRIVE_LINK = str(Path(sys.executable).parent / "drive-link")


@pytest.fixture(scope="module")
def hub(tmp_path_factory):
    from virtual_drive.hub import Hub
    from virtual_drive.node import spawn_virtual_drive

    store = tmp_path_factory.mktemp("store") / "params.json"
    with Hub(port=0) as h:
        # 4 simulated s per wall-clock s: the speed experiments' seconds pass 4 x faster
        proc = spawn_virtual_drive(port=h.port, node_id=1, store=store, speed=4.0)
        try:
            yield h
        finally:
            proc.stop()


def dl(hub, *args: str, timeout: float = 200) -> subprocess.CompletedProcess:
    cmd = [DRIVE_LINK, args[0], "--host", "127.0.0.1", "--port", str(hub.port), *args[1:]]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)


def dl_in(hub, *args: str) -> tuple[int, str]:
    """cli.main in this process (setup and read-back: no interpreter start per call)."""
    out, err = io.StringIO(), io.StringIO()
    argv = [args[0], "--host", "127.0.0.1", "--port", str(hub.port), *args[1:]]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(argv)
    return rc, out.getvalue() + err.getvalue()


def read(hub, *names: str) -> dict:
    rc, out = dl_in(hub, "read", *names, "--json")
    assert rc == 0, out
    return json.loads(out)


def where(hub) -> tuple:
    rc, out = dl_in(hub, "status", "--json")
    assert rc == 0, out
    st = json.loads(out)
    r = read(hub, "target_velocity", "setpoints.i_p_ref", "disable_operation_option_code",
             "current_controller.type", "current_controller.L_c")
    return st["state"], st["mode"], tuple(sorted(r.items()))


def _plant(R: float, L: float) -> control.TransferFunction:
    """Eq. (8): P(z) = Γ / (z (z − Φ)), Φ = e^(−R Ts/L), Γ = (1 − Φ)/(2R) (two phases)."""
    Phi = math.exp(-R * TS / L)
    return control.tf([(1 - Phi) / (2 * R)], [1, -Phi, 0], TS)


def _deadbeat(R_c: float, L_c: float) -> control.TransferFunction:
    """Eq. (15): C(z) = (z² − Φ_c z) / (Γ_c (z² − 1))."""
    Phi_c = math.exp(-R_c * TS / L_c)
    Gamma_c = (1 - Phi_c) / (2 * R_c)
    return control.tf([1 / Gamma_c, -Phi_c / Gamma_c, 0], [1, 0, -1], TS)


def _overshoot(loop: control.TransferFunction, n: int = 400) -> float:
    _t, y = control.step_response(control.feedback(loop, 1), T=np.arange(n) * TS)
    return max(0.0, float(np.max(y)) - 1.0) * 100.0


def _metric(rep: dict, exp: str, name: str) -> dict:
    e = {x["id"]: x for x in rep["experiments"]}[exp]
    return e["metrics"][name]


def test_report_against_the_papers_equations(hub, tmp_path):
    assert dl_in(hub, "nmt", "start")[0] == 0
    rc, out = dl_in(hub, "set-speed", "1000rpm", "--enable")
    assert rc == 0, out
    before = where(hub)
    only = "current_step_deadbeat,lc_sweep,current_step_pi,identify_speed_model,speed_step"
    p = dl(hub, "report", "--only", only, "--out", str(tmp_path))
    assert p.returncode == 0, p.stdout + p.stderr
    rep = json.loads((tmp_path / "report.json").read_text())
    html = (tmp_path / "report.html").read_text()
    assert html.count("data:image/png;base64,") >= 5
    # offline: no address to fetch (the figures' base64 text may hold "http" by chance)
    text = re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]+", "", html)
    assert not re.search(r"https?://|//[\w.-]+/|<script|<link|@import", text), text[:400]
    assert set(rep) >= {"drive", "experiments"} and rep["drive"]["virtual"] is True
    for e in rep["experiments"]:
        assert set(e) == {"id", "title", "paper_ref", "verdict", "metrics"}
        for m in e["metrics"].values():
            assert set(m) == {"measured", "model", "paper", "unit", "tolerance", "verdict"}
    # deadbeat with L_c = L: the closed loop of eqs. (8), (15) is z^-2: settled at sample 2
    _t, y = control.step_response(control.feedback(_deadbeat(R0, L0) * _plant(R0, L0), 1),
                                  T=np.arange(10) * TS)
    oracle = int(np.flatnonzero(np.abs(y - 1) > 0.05)[-1]) + 1
    assert oracle == 2
    assert _metric(rep, "current_step_deadbeat", "settling_samples")["measured"] == oracle
    # L_c/L sweep: overshoot of eq. (16)'s closed loop with the mismatched L_c
    for ratio in (0.5, 1.0, 1.5, 1.9):
        want = _overshoot(_deadbeat(R0, ratio * L0) * _plant(R0, L0))
        got = _metric(rep, "lc_sweep", f"overshoot_pct_{ratio:g}L")["measured"]
        assert got == pytest.approx(want, abs=max(5.0, 0.15 * want)), ratio
    # PI (eq. 22) with the paper's gains: C = k_p + k_i z/(z − 1)
    pi = control.tf([0.4647 + 0.0492, -0.4647], [1, -1], TS)
    want = _overshoot(pi * _plant(R0, L0))
    assert 28 < want < 30
    assert _metric(rep, "current_step_pi", "overshoot_pct")["measured"] == pytest.approx(
        want, abs=3.0)
    # a, b: the virtual plant J dω/dt = K_t i_p − (B + k_gen·60/2π) ω, discretised (ZOH)
    r = read(hub, "sim_load.J", "sim_load.B", "sim_load.k_gen", "motor.K_rpm")
    k = 60 / (2 * math.pi)
    K_t, B_tot = r["motor.K_rpm"] * k, r["sim_load.B"] + r["sim_load.k_gen"] * k
    J = r["sim_load.J"]
    Ad, Bd, *_ = signal.cont2discrete(
        (np.array([[-B_tot / J]]), np.array([[K_t / J * k]]), np.eye(1), np.zeros((1, 1))), TS)
    a, b = float(Ad[0][0]), float(Bd[0][0])
    assert _metric(rep, "identify_speed_model", "a")["measured"] == pytest.approx(a, abs=2e-6)
    assert _metric(rep, "identify_speed_model", "b")["measured"] == pytest.approx(b, rel=0.06)
    # IP (eq. 27) with the designed gains: no overshoot
    kp, ki = 0.2113, 2.9994e-5
    ip = control.tf([kp * b * ki, 0], [1, kp * b * ki + kp * b - 1 - a, a - kp * b], TS)
    _t, w = control.step_response(ip, T=np.arange(0, 200_000, 50) * TS)
    assert float(np.max(w)) <= 1.0 + 1e-6
    assert _metric(rep, "speed_step", "overshoot_pct")["measured"] <= 1.0
    assert _metric(rep, "speed_step", "start_rpm")["measured"] == pytest.approx(500, abs=5)
    assert where(hub) == before  # speed mode at 1000 rpm, enabled, gains as found


def test_identify_electrical_finds_a_second_motor(hub, tmp_path):
    assert dl_in(hub, "nmt", "start")[0] == 0
    R2, L2 = 0.6 * R0, 1.3 * L0
    assert dl_in(hub, "disable")[0] == 0
    try:
        for name, v in (("motor.L", L2), ("motor.R", R2)):
            rc, out = dl_in(hub, "write", name, repr(v))
            assert rc == 0, out
        rc, out = dl_in(hub, "set-speed", "1000rpm", "--enable")
        assert rc == 0, out
        p = dl(hub, "report", "--only", "identify_electrical", "--out", str(tmp_path), "--json")
        assert p.returncode == 0, p.stdout + p.stderr
        rep = json.loads(p.stdout)
        R = _metric(rep, "identify_electrical", "R_ohm")["measured"]
        L = _metric(rep, "identify_electrical", "L_H")["measured"]
        assert R == pytest.approx(R2, rel=0.1) and L == pytest.approx(L2, rel=0.1)
        assert R != pytest.approx(R0, rel=0.2) and L != pytest.approx(L0, rel=0.15)
    finally:
        dl_in(hub, "disable")
        dl_in(hub, "write", "motor.R", repr(R0))
        dl_in(hub, "write", "motor.L", repr(L0))


def test_pwm_ripple_measured_against_the_unipolar_formula(hub, tmp_path):
    """pwm_ripple measures the ripple from the drive's edge-sampled i_p (0x2040 i_p_min,
    i_p_max, i_p_peaks). Oracle: unipolar PWM switches the output at 2 f_sw (paper Sec. IV-B:
    50 kHz per transistor, 100 kHz output); its peak-to-peak on the conducting pair (2 L in
    series) is Δi = V_dc D (1 − D) T_s / (4 L) with the duty D from the steady state, the mean
    line voltage D V_dc = K_rpm n + 2 R i_p (line back-EMF on the flat tops plus the drop)."""
    assert dl_in(hub, "nmt", "start")[0] == 0
    rc, out = dl_in(hub, "set-speed", "1000rpm", "--enable")
    assert rc == 0, out
    p = dl(hub, "report", "--only", "pwm_ripple", "--out", str(tmp_path), "--json")
    assert p.returncode == 0, p.stdout + p.stderr
    rep = json.loads(p.stdout)
    f = _metric(rep, "pwm_ripple", "ripple_freq_Hz")
    assert f["measured"] == pytest.approx(2 * 50e3) and f["verdict"] == "pass"
    names = ("measurements.speed", "measurements.i_p", "measurements.V_dc")
    reads = [read(hub, *names) for _ in range(5)]
    n, i_p, V_dc = (float(np.mean([r[k] for r in reads])) for k in names)
    m = read(hub, "motor.K_rpm", "motor.R", "motor.L")
    assert n == pytest.approx(1000, abs=10)
    D = (m["motor.K_rpm"] * n + 2 * m["motor.R"] * i_p) / V_dc
    want = V_dc * D * (1 - D) * TS / (4 * m["motor.L"])
    pp = _metric(rep, "pwm_ripple", "ripple_pp_A")
    assert pp["measured"] == pytest.approx(want, rel=0.1), (pp, want, D)
    assert pp["verdict"] == "pass"
