"""Limits that keep the drive stable: subnormal REAL32, R_c, the L_c < 2L interlock against every
order of writes, configuration-only objects and the IP speed-loop rule.

Truths: the closed loops built independently with python-control (deadbeat eq. 15 on the plant
eq. 4/5; IP eq. 27 on G(z) = b/(z - a)) and their poles; CiA 301 abort codes (0x06090030/31/32,
0x08000022 for a write the present device state forbids); IEEE-754 binary32 (smallest normal
2^-126). Writes go through canopen's SdoClient.
"""

from __future__ import annotations

import math
import random
import struct

import control
import numpy as np
import pytest
from canopen.sdo import SdoAbortedError
from test_node_support import Bench

from firmware_protocol import load_od
from firmware_protocol.entry import LimitError
from firmware_protocol.stability import (
    A_IDENTIFIED,
    B_IDENTIFIED,
    TAU_MAX,
    ZETA_MIN,
    check_ip_speed_gains,
)

pytestmark = [pytest.mark.timeout(120), pytest.mark.unit]

TS = 20e-6
R, L = 0.0062, 14.8e-6
TOO_HIGH, TOO_LOW, INVALID, STATE = 0x06090031, 0x06090032, 0x06090030, 0x08000022


@pytest.fixture
def bench():
    b = Bench(speed=1.0)
    yield b
    b.close()


def abort(bench: Bench, name: str, value) -> int | None:
    try:
        bench.write(name, value)
    except SdoAbortedError as exc:
        return exc.code
    return None


def raw_abort(bench: Bench, name: str, data: bytes) -> int | None:
    e = bench.view.entry(name)
    try:
        bench.node.sdo.download(e.index, e.subindex, data)
    except SdoAbortedError as exc:
        return exc.code
    return None


# ---- subnormal REAL32 and R_c ----------------------------------------------------------------


def deadbeat_stable(L_: float, R_: float, L_c: float, R_c: float) -> bool:
    """Deadbeat (eq. 15, k = 2) on P(z) = Gamma / (z (z - Phi)), poles by python-control."""
    phi, gamma = math.exp(-R_ * TS / L_), -math.expm1(-R_ * TS / L_) / (2 * R_)
    phi_c = math.exp(-R_c * TS / L_c)
    gamma_c = -math.expm1(-R_c * TS / L_c) / (2 * R_c) if R_c > 0 else TS / (2 * L_c)
    plant = control.tf([gamma], [1, -phi, 0], TS)
    ctrl = control.tf([1, -phi_c, 0], [gamma_c, 0, -gamma_c], TS)
    poles = control.poles(control.feedback(ctrl * plant, 1))
    return bool(np.all(np.abs(poles) < 1 - 1e-12))


def test_subnormal_real32_refused_on_every_real_object(bench):
    view = bench.view
    smallest_subnormal = struct.pack("<I", 0x00000001)  # 1.4e-45
    largest_subnormal = struct.pack("<I", 0x007FFFFF)  # 1.1754942e-38
    checked = 0
    for e in view:
        if not (e.is_real and e.writable):
            continue
        before = bench.sdo(e.name).raw
        for data in (smallest_subnormal, largest_subnormal):
            assert raw_abort(bench, e.name, data) == INVALID, e.name
        assert bench.sdo(e.name).raw == before
        checked += 1
    assert checked > 40
    # the smallest normal float32 is a number like any other (R_c: below 1e-4 -> too low)
    assert raw_abort(bench, "current_controller.R_c", struct.pack("<I", 0x00800000)) == TOO_LOW


def test_R_c_zero_or_at_least_1e4_and_at_most_2R(bench):
    assert abort(bench, "current_controller.R_c", 5e-5) == TOO_LOW
    assert abort(bench, "current_controller.R_c", 2.01 * R) == TOO_HIGH
    assert abort(bench, "current_controller.R_c", 1.0) == TOO_HIGH  # inside the old [0, 1]
    # the staged set is scratch space: R_c = 1 Ω stages, the apply refuses the set as a whole
    active = bench.read("current_controller.R_c")
    assert abort(bench, "gain_set.R_c", 1.0) is None
    assert abort(bench, "gain_set_apply", 1) == TOO_HIGH
    assert bench.read("current_controller.R_c") == pytest.approx(active, rel=1e-6)
    bench.write("gain_set.R_c", active)
    # R_c = 0 removes the deadbeat law's integral action: only with the back-EMF feed-forward
    assert abort(bench, "current_controller.R_c", 0.0) == INVALID
    bench.write("current_controller.emf_feedforward", 1)
    for ok in (0.0, 1e-4, R, 2 * R):
        assert abort(bench, "current_controller.R_c", ok) is None
        assert bench.read("current_controller.R_c") == pytest.approx(ok, rel=1e-6)
    # motor.R cannot drop below R_c / 2 either (the rule binds both sides)
    assert abort(bench, "motor.R", 0.9 * R) == TOO_LOW


@pytest.mark.parametrize("L_", [1e-6, 14.8e-6, 1e-3])
@pytest.mark.parametrize("R_", [1e-4, 6.2e-3, 1.0])
def test_R_c_rule_is_on_the_stable_side(L_, R_):
    """Every (L_c, R_c) the OD accepts for a motor (R, L) gives a stable deadbeat loop, and the
    old static range [0, 1] Ohm held unstable values."""
    view = load_od()
    unstable_before = 0
    for ratio_L in (0.05, 1.0, 1.9):
        for R_c in (0.0, 1e-4, 0.5 * R_, R_, 2 * R_, 10 * R_, 200 * R_, 1.0):
            if R_c > 1.0:
                continue
            values = {
                "motor.L": L_,
                "motor.R": R_,
                "current_controller.L_c": ratio_L * L_,
                "current_controller.R_c": R_c,
            }
            try:
                view.check_constraints(values)
                view.entry("current_controller.R_c").check(R_c)
                accepted = True
            except LimitError:
                accepted = False
            stable = deadbeat_stable(L_, R_, ratio_L * L_, R_c)
            if accepted:
                # R_c = 0: the controller zero at z = 1 cancels its integrator (a bounded
                # constant mode at z = 1, not a growing one)
                assert stable or R_c == 0.0, (L_, R_, ratio_L, R_c)
            unstable_before += not stable and R_c != 0.0
    if R_ < 0.01 and L_ < 1e-4:  # low-inductance motors (this drive's)
        assert unstable_before > 0  # the static limits alone let unstable R_c through


def test_tiny_R_c_in_the_c_controller_gives_the_limit_gamma():
    """controllers.c eq. (5): Gamma_c -> Ts / (2 L_c) as R_c -> 0 (the old code divided an
    underflowed 1 - Phi_c by 2 R_c: Gamma_c = 0, then 1/Gamma_c = inf and an overcurrent trip)."""
    from virtual_drive.sim import Simulator

    sim = Simulator()
    for R_c in (1.4e-45, 1e-38, 1e-20, 1e-8, 0.0):
        sim.set_current_gains(R_c=R_c)
        assert sim._loop.cc.Gamma_c == pytest.approx(TS / (2 * L), rel=1e-6), R_c
    for R_c in (1e-4, R, 1.0):
        sim.set_current_gains(R_c=R_c)
        exact = -math.expm1(-R_c * TS / L) / (2 * R_c)
        assert sim._loop.cc.Gamma_c == pytest.approx(exact, rel=1e-6), R_c
    # and the loop regulates with it (no trip): 15 A in current mode for 50 ms
    sim.set_current_gains(R_c=1.4e-45)
    sim.set_mode("current")
    sim.set_current_ref(15.0)
    sim.run(2500)
    assert sim.fault is None
    assert sim.state["i_p"] == pytest.approx(15.0, abs=1.5)


# ---- configuration-only objects ------------------------------------------------------------


def test_configuration_objects_only_with_the_power_stage_off(bench):
    view = bench.view
    config = [e for e in view if e.config_only]
    names = {e.name for e in config}
    assert {"motor.R", "motor.L", "motor.K_rpm", "motor.pole_pairs"} <= names
    assert {"protection.overcurrent_trip", "motor_rated_current"} <= names
    present = {e.name: bench.read(e.name) for e in config}
    for name, value in present.items():  # power stage off: accepted
        assert abort(bench, name, value) is None, name
    bench.enable(-1)
    bench.write("setpoints.i_p_ref", 10.0)
    for name, value in present.items():
        assert abort(bench, name, value) == STATE, name
    assert abort(bench, "motor.K_rpm", 1.0) == STATE  # the issue's -563 rpm / 1311 A write
    # live objects stay writable while running
    assert abort(bench, "setpoints.i_p_ref", 12.0) is None
    assert abort(bench, "sim_load.T_load", 0.1) is None
    # during a stop ramp the power stage is on too (the ramp needs a turning motor)
    assert bench.wait(lambda: bench.read("measurements.speed") > 50.0, 10.0)
    bench.write("quick_stop_option_code", 6)
    bench.write("quick_stop_deceleration", 1)  # 1 rpm/s: the ramp lasts
    bench.write("controlword", 0x02)
    assert bench.drive.cia402.ramp is not None
    assert abort(bench, "motor.L", L) == STATE
    bench.write("controlword", 0x00)  # disable voltage: power stage off
    assert abort(bench, "motor.L", L) is None


# ---- L_c < 2 L interlock against every order of writes -------------------------------------


def test_staged_L_c_checked_at_apply_and_motor_L_against_the_active_L_c(bench):
    """The staged set 0x20F0 is scratch space (a staged value against its own range only); the
    set as a whole meets L_c < 2L when gain_set_apply applies it, and nothing changes when it
    does not. motor.L is held against the active L_c."""
    active = bench.read("current_controller.L_c")
    assert abort(bench, "gain_set.L_c", 2 * L) is None  # staged: not yet a gain the loop runs
    assert abort(bench, "gain_set_apply", 1) == TOO_HIGH
    assert bench.read("current_controller.L_c") == pytest.approx(active, rel=1e-6)
    bench.write("gain_set.L_c", 25e-6)  # < 2 x 14.8 uH
    assert abort(bench, "gain_set_apply", 1) is None
    assert bench.read("current_controller.L_c") == pytest.approx(25e-6, rel=1e-6)
    assert abort(bench, "motor.L", 12e-6) == TOO_LOW  # 2 x 12 = 24 < active 25
    bench.write("current_controller.L_c", 20e-6)
    assert abort(bench, "motor.L", 9.9e-6) == TOO_LOW  # active 20 uH > 2 x 9.9
    bench.write("motor.L", 10.5e-6)  # active L_c 20 uH < 21 uH
    assert bench.read("motor.L") == pytest.approx(10.5e-6)


def test_interlock_holds_for_random_write_orders(bench):
    """A seeded random walk of writes of motor.L, L_c, staged L_c and gain-set applies: after
    every step the drive holds the active L_c < 2L (in the object dictionary and in the
    controller); an apply of a staged L_c ≥ 2L is refused and changes nothing."""
    rng = random.Random(20260223)
    accepted = refused = 0
    for _ in range(150):
        op = rng.choice(("motor.L", "current_controller.L_c", "gain_set.L_c", "apply"))
        if op == "apply":
            code = abort(bench, "gain_set_apply", 1)
        else:
            code = abort(bench, op, rng.choice((1e-6, 5e-6, 8e-6, 14.8e-6, 20e-6, 40e-6, 1e-4)))
        if code is None:
            accepted += 1
        else:  # 0x06090030: the set, with the new value in place, fails the current loop's
            # admissibility (e.g. L_c < L/2 without the feed-forward) rather than L_c < 2L
            assert code in (TOO_HIGH, TOO_LOW, INVALID), hex(code)
            refused += 1
        motor_L = bench.read("motor.L")
        if op == "apply" and bench.read("gain_set.L_c") >= 2 * motor_L:
            assert code == TOO_HIGH
        assert bench.read("current_controller.L_c") < 2 * motor_L
        assert bench.drive.sim.current.L_c < 2 * bench.drive.sim.motor.L
    assert accepted > 20 and refused > 20


# ---- IP speed loop --------------------------------------------------------------------------


def ip_closed_loop_poles(k_p: float, k_i: float) -> np.ndarray:
    """IP (Fig. 17) on G(z) = b/(z - a) built with python-control: i = k_p (k_i x - n) with
    x = z/(z - 1) e; poles of the closed loop from the reference to the speed."""
    a, b = A_IDENTIFIED, B_IDENTIFIED
    G = control.tf([b], [1, -a], TS)
    inner = control.feedback(G, k_p)  # the -k_p n path
    integ = control.tf([k_p * k_i, 0], [1, -1], TS)
    return control.poles(control.feedback(integ * inner, 1))


@pytest.mark.filterwarnings("ignore")  # scipy warns on the tiny-gain pairs' coefficients
def test_ip_rule_matches_the_closed_loop_poles():
    """Accepted iff every pole is inside the unit circle, the slowest is not slower than
    TAU_MAX and a complex pair is damped at least ZETA_MIN (zeta = -ln|p| / |ln p|); pairs
    whose slowest pole lies within 1e-8 of that bound are skipped (float64 root
    finding of a near-double root at z = 1 is only that accurate)."""
    bound = math.exp(-TS / TAU_MAX)
    rng = random.Random(7)
    pairs = [(0.2113, 2.9994e-5), (100.0, 1.0), (5000.0, 0.01), (6000.0, 0.5), (1e-6, 1e-9)]
    pairs += [(10 ** rng.uniform(-4, 4), 10 ** rng.uniform(-8, 1)) for _ in range(80)]
    pairs += [(10 ** rng.uniform(3.5, 5), 10 ** rng.uniform(-3, 1)) for _ in range(20)]
    seen = {"ok": 0, "unstable": 0, "slow": 0, "lightly damped": 0}
    for k_p, k_i in pairs:
        poles = ip_closed_loop_poles(np.float32(k_p), np.float32(k_i))
        slowest = float(np.max(np.abs(poles)))
        if abs(slowest - bound) < 1e-8:
            continue
        pairs_ = [np.log(complex(p)) for p in poles if abs(complex(p).imag) > 1e-12]
        zeta = min((-z.real / abs(z) for z in pairs_), default=1.0)  # complex pairs only
        if abs(zeta - ZETA_MIN) < 1e-3:
            continue
        try:
            check_ip_speed_gains(k_p, k_i)
            code = None
        except LimitError as exc:
            code = exc.abort_code
        if slowest > 1.0 + 1e-8:
            assert code == TOO_HIGH, (k_p, k_i, slowest)
            seen["unstable"] += 1
        elif slowest > bound:
            assert code in (TOO_LOW, TOO_HIGH), (k_p, k_i, slowest)
            seen["slow"] += 1
        elif zeta < ZETA_MIN:
            assert code == TOO_HIGH, (k_p, k_i, zeta)
            seen["lightly damped"] += 1
        else:
            assert code is None, (k_p, k_i, slowest)
            seen["ok"] += 1
    assert min(seen.values()) > 10, seen
    for k_p, k_i in ((0.0, 1e-5), (0.2, 0.0), (-0.1, 1e-5)):
        with pytest.raises(LimitError) as info:
            check_ip_speed_gains(k_p, k_i)
        assert info.value.abort_code == TOO_LOW


def test_speed_gains_written_and_applied_are_checked(bench):
    assert abort(bench, "speed_controller.k_i", 0.0) == TOO_LOW
    assert abort(bench, "speed_controller.k_p", 0.0) == TOO_LOW
    assert bench.read("speed_controller.k_i") == pytest.approx(2.9994e-5)
    assert bench.read("speed_controller.k_p") == pytest.approx(0.2113)
    assert abort(bench, "speed_controller.k_p", 0.15) is None  # stable pair
    # staged pair: order-free staging, checked as a whole at apply
    bench.write("gain_set.speed_k_p", 0.0)
    bench.write("gain_set.speed_k_i", 1e-5)
    assert abort(bench, "gain_set_apply", 2) == TOO_LOW
    assert bench.read("speed_controller.k_p") == pytest.approx(0.15)
    bench.write("gain_set.speed_k_p", 0.3)
    assert abort(bench, "gain_set_apply", 2) is None
    assert bench.drive.sim.speed.k_p == pytest.approx(0.3)
