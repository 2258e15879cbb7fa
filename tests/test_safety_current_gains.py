"""Current-controller gain sets inside the EDS limits that would trip the drive (issue 10).

Truths: the closed loops built independently with python-control from the paper's transfer
functions (plant eq. 8 P(z) = Gamma / (z (z - Phi)); deadbeat eq. 15, PI eq. 22, predictive
eq. 23 C(z) = 2 L_c f_s z / (z + 1); IP speed law eq. 27 around the closed current loop on
G(z) = b / (z - a)) and their poles; CiA 301 abort codes (0x06090011 sub-index does not exist,
0x06020000 object does not exist); the virtual drive at 1000 rpm (no trip, speed held).
Writes go through canopen's SdoClient.
"""

from __future__ import annotations

import math
import struct
import time

import control
import numpy as np
import pytest
from canopen.sdo import SdoAbortedError
from test_node_support import Bench

from firmware_protocol.current_stability import (
    RHO_MAX,
    check_cascade,
    check_current_gains,
)
from firmware_protocol.entry import LimitError
from firmware_protocol.stability import A_IDENTIFIED, B_IDENTIFIED, TAU_MAX

pytestmark = [pytest.mark.timeout(180), pytest.mark.unit]

TS = 20e-6
R, L = 0.0062, 14.8e-6
MOTOR = {"R": R, "L": L, "rated_current": 100.0, "V_dc_nominal": 48.0}
BASE = {
    "type": 0,
    "L_c": L,
    "R_c": R,
    "k_p": 0.4647,
    "k_i": 0.0492,
    "T_BT": 0.0,
    "T_DD": 0.0,
    "T_SD": 0.0,
    "V_G": 0.0,
    "emf_feedforward": 1,
}
NO_SUBINDEX, NO_OBJECT = 0x06090011, 0x06020000


def f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


def current_open_loop(g: dict, L_: float = L, R_: float = R) -> control.TransferFunction:
    """C(z) P(z) from the paper's equations (python-control, independent of the drive)."""
    phi, gamma = math.exp(-R_ * TS / L_), -math.expm1(-R_ * TS / L_) / (2 * R_)
    plant = control.tf([gamma], [1, -phi, 0], TS)
    if g["type"] == 0:
        L_c, R_c = g["L_c"], g["R_c"]
        phi_c = math.exp(-R_c * TS / L_c)
        gamma_c = -math.expm1(-R_c * TS / L_c) / (2 * R_c) if R_c > 0 else TS / (2 * L_c)
        ctrl = control.tf([1, -phi_c, 0], [gamma_c, 0, -gamma_c], TS)
        if R_c == 0:  # the zero at z = 1 cancels the integrator: the law as implemented
            ctrl = control.tf([1, 0], [gamma_c, gamma_c], TS)
    elif g["type"] == 1:
        ctrl = control.tf([g["k_p"] + g["k_i"], -g["k_p"]], [1, -1], TS)
    else:
        ctrl = control.tf([2 * g["L_c"] / TS, 0], [1, 1], TS)
    return ctrl * plant


def oracle_radius(g: dict, L_: float = L, R_: float = R) -> float:
    return float(np.max(np.abs(control.poles(control.feedback(current_open_loop(g, L_, R_), 1)))))


def cascade_radius(g: dict, k_p: float, k_i: float) -> float:
    inner = control.feedback(current_open_loop(g), 1)
    speed = control.tf([B_IDENTIFIED], [1, -A_IDENTIFIED], TS)
    ip = control.tf([k_p * (1 + k_i), -k_p], [1, -1], TS)  # i* = -k_p (k_i z/(z-1) + 1) n
    loop = control.feedback(ip * inner * speed, 1)
    return float(np.max(np.abs(control.poles(control.minreal(loop, verbose=False)))))


def accepted(g: dict, motor: dict = MOTOR) -> bool:
    try:
        check_current_gains(g, motor)
    except LimitError:
        return False
    return True


# ---- the rule against the python-control oracle ----------------------------------------------


@pytest.mark.parametrize("kind", [0, 2])
def test_L_c_rule_matches_closed_loop_poles(kind):
    """Deadbeat and predictive: accepted ⇔ every pole inside RHO_MAX (or inside the time
    constants the law contains, if slower); never an unstable one; L_c ≥ 2 L refused."""
    seen_refused = seen_ok = 0
    for ratio in (0.001, 0.005, 0.01, 0.05, 0.2, 0.5, 1.0, 1.5, 1.9, 1.99, 1.995, 2.0, 2.5):
        for R_c in (0.0, R) if kind == 0 else (0.0,):
            g = dict(BASE, type=kind, L_c=f32(ratio * L), R_c=R_c)
            rho = oracle_radius(g, f32(L), f32(R))
            ok = accepted(g)
            bound = max(RHO_MAX, math.exp(-R * TS / (2 * L)))  # the motor's own L/R
            if R_c > 0:  # the deadbeat law's integral action, through its zero at Phi_c
                bound = max(bound, math.exp(-R_c * TS / (2 * g["L_c"])))
            if ok:
                assert rho < 1.0, (kind, ratio, R_c, rho)
                seen_ok += 1
            else:
                seen_refused += 1
            no_integral = kind == 2 or R_c == 0.0
            if no_integral and ratio < 0.5:
                assert not ok, (kind, ratio, R_c)  # L_c >= L/2 without integral action
            elif rho < bound - 1e-6:
                assert ok, (kind, ratio, R_c, rho)
            if rho > bound + 1e-6:
                assert not ok, (kind, ratio, R_c, rho)
            if ratio >= 2.0:
                assert not ok
    assert seen_ok >= 5 and seen_refused >= 4


def test_PI_rule_matches_closed_loop_poles():
    n_ok = n_bad = 0
    for k_p in (0.0, 0.1, 0.4647, 1.0, 1.5, 3.0, 100.0):
        for k_i in (0.0, 1e-3, 0.0492, 0.3, 1.0, 100.0):
            g = dict(BASE, type=1, k_p=k_p, k_i=k_i)
            if k_p == k_i == 0.0:  # no feedback at all
                assert not accepted(g)
                continue
            rho = oracle_radius(g)
            ok = accepted(g)
            if rho < RHO_MAX - 1e-6:
                assert ok, (k_p, k_i, rho)
                n_ok += 1
            elif rho > RHO_MAX + 1e-6:
                assert not ok, (k_p, k_i, rho)
                n_bad += 1
    assert n_ok >= 5 and n_bad >= 10
    assert accepted(dict(BASE, type=1))  # the paper's PI gains


def test_predictive_needs_feedforward_and_bounded_compensation():
    h5 = dict(BASE, type=2, L_c=0.2 * L, T_BT=7.2e-6, T_SD=10.4e-6, T_DD=2.3e-6)
    assert not accepted(dict(h5, emf_feedforward=0))
    assert not accepted(h5)  # feed-forward on, compensation still shifts i_p by ~310 A
    assert not accepted(dict(BASE, type=2, L_c=0.2 * L, emf_feedforward=0))  # held 649 rpm
    assert not accepted(dict(BASE, type=2, L_c=0.2 * L))  # no integral action: L_c >= L/2
    assert not accepted(dict(BASE, type=0, R_c=0.0, L_c=0.22 * L))  # ran away to 1272 rpm
    assert accepted(dict(BASE, type=2, L_c=0.5 * L))
    assert accepted(dict(BASE, type=0, R_c=0.0, L_c=0.5 * L))
    assert accepted(dict(BASE, type=2, T_BT=0.5e-6, V_G=1.0, T_DD=1e-6, T_SD=1e-6))
    # the compensation terms do not matter to the laws that do not use them
    assert accepted(dict(h5, type=0, L_c=L, emf_feedforward=0))


@pytest.mark.parametrize("kind", [0, 1, 2])
def test_cascade_rule_matches_closed_loop_poles(kind):
    limit = math.exp(-TS / TAU_MAX)
    n_bad = 0
    for g in (dict(BASE, type=kind), dict(BASE, type=kind, L_c=0.02 * L, R_c=0.0)):
        for k_p, k_i in ((0.2113, 2.9994e-5), (5.0, 0.01), (68.76, 1.0), (100.0, 1.0)):
            rho = cascade_radius(g, k_p, k_i)
            try:
                check_cascade(g, MOTOR, k_p, k_i)
                ok = True
            except LimitError:
                ok = False
            if rho < limit - 1e-7:
                assert ok, (g, k_p, k_i, rho)
            if rho > 1.0 + 1e-7:
                assert not ok, (g, k_p, k_i, rho)
                n_bad += 1
    assert n_bad >= 2


# ---- on the drive -----------------------------------------------------------------------------


def run_up(b: Bench, rpm: int = 1000) -> None:
    b.nmt(0x01)
    b.write("profile_acceleration", 5000)
    b.write("target_velocity", rpm)
    b.enable(3)
    assert b.wait(lambda: abs(b.read("velocity_actual_value") - rpm) <= 20, timeout=30.0)


def code_of(b: Bench, name: str, value) -> int | None:
    try:
        b.write(name, value)
    except SdoAbortedError as exc:
        return exc.code
    return None


@pytest.fixture
def bench():
    b = Bench(speed=2.0)
    yield b
    b.close()


def test_h5_gain_set_refused_in_every_order_and_the_drive_keeps_1000_rpm(bench):
    """The set that tripped the drive (predictive, L_c = 0.2 L, T_BT 7.2 µs, T_SD 10.4 µs,
    T_DD 2.3 µs, no feed-forward) cannot be made active by direct writes in any order nor by
    staging + apply; what is accepted on the way keeps 1000 rpm without a trip."""
    b = bench
    run_up(b)
    bad = {
        "L_c": f32(0.2 * L),
        "T_BT": 7.2e-6,
        "T_SD": 10.4e-6,
        "T_DD": 2.3e-6,
        "emf_feedforward": 0,
        "type": 2,
    }
    orders = [list(bad), list(reversed(bad)), ["type", "emf_feedforward", "L_c", "T_BT"]]
    for order in orders:
        for key in order:
            code_of(b, f"current_controller.{key}", bad[key])
        active = {k: b.read(f"current_controller.{k}") for k in bad}
        assert active != bad
        assert accepted({**BASE, **{k: b.read(f"current_controller.{k}") for k in BASE}})
        for key in ("type", "T_BT", "T_SD", "T_DD", "emf_feedforward", "L_c"):  # back
            code_of(b, f"current_controller.{key}", BASE[key])
    for key, value in bad.items():
        assert code_of(b, f"gain_set.{key}", value) is None  # staging is scratch space
    before = {k: b.read(f"current_controller.{k}") for k in BASE}
    assert code_of(b, "gain_set_apply", 1) is not None
    assert {k: b.read(f"current_controller.{k}") for k in BASE} == before
    time.sleep(1.0)
    assert not b.read("statusword") & 0x08
    assert abs(b.read("velocity_actual_value") - 1000) <= 50


def test_predictive_with_feedforward_holds_speed(bench):
    """What the rule accepts for the predictive law runs: L_c = 0.5 L with the feed-forward."""
    b = bench
    run_up(b)
    assert code_of(b, "current_controller.emf_feedforward", 1) is None
    assert code_of(b, "current_controller.L_c", f32(0.5 * L)) is None
    assert code_of(b, "current_controller.type", 2) is None
    time.sleep(1.5)
    assert not b.read("statusword") & 0x08
    assert abs(b.read("velocity_actual_value") - 1000) <= 50


def test_missing_subindex_and_object_aborts(bench):
    """CiA 301: 0x06090011 for a sub-index that does not exist (also any sub-index but 0 of a
    VAR), 0x06020000 for an object that does not exist; reads and writes alike."""
    sdo = bench.node.sdo
    for index, sub in ((0x6007, 0x06), (0x605B, 0x12), (0x6075, 0x13), (0x20F1, 0x03),
                       (0x2010, 0x0B), (0x1016, 0x7F)):
        with pytest.raises(SdoAbortedError) as exc:
            sdo.download(index, sub, b"\x00\x00")
        assert exc.value.code == NO_SUBINDEX, hex(index)
        with pytest.raises(SdoAbortedError) as exc:
            sdo.upload(index, sub)
        assert exc.value.code == NO_SUBINDEX, hex(index)
    with pytest.raises(SdoAbortedError) as exc:
        sdo.download(0x2345, 0, b"\x00")
    assert exc.value.code == NO_OBJECT
    assert sdo.upload(0x6007, 0)  # sub-index 0 of a VAR still answers
