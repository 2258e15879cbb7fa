"""Halt bit, target reached, speed = 0 and the torque slope (CiA 402 §6.2, §10, §11).

Truths (CiA 402 / IEC 61800-7-201): controlword bit 8 (halt) in profile velocity decelerates
the axis with the halt option code 0x605D (1 = slow-down ramp 0x6084) and holds it at 0;
statusword bit 10 (target reached) = |actual velocity - target| within the velocity window
0x606D for 0x606E ms, with halt = 1 "velocity 0 reached"; bit 12 (speed) = |velocity| within the
velocity threshold 0x606F for 0x6070 ms; in QUICK STOP ACTIVE (0x605A 5..8) bit 10 = axis
stopped; in profile torque the demand changes at the torque slope 0x6087. Slopes are read from
the drive's own 50 kHz recorder, not from the host's sleep accuracy.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from canopen.profiles.p402 import State402
from test_node_support import Bench

pytestmark = [pytest.mark.timeout(120), pytest.mark.unit]

HALT = 0x0100
ENABLE = 0x000F
BIT10 = 1 << 10
BIT12 = 1 << 12
TS = 20e-6


def state_of(statusword: int) -> str:
    for state, (mask, value) in State402.SW_MASK.items():
        if statusword & mask == value:
            return state
    raise AssertionError(f"statusword 0x{statusword:04X} matches no CiA 402 state")


@pytest.fixture
def bench():
    b = Bench(speed=2.0)
    b.drive.sim.set_load(k_gen=0.0)  # a free shaft: faster spin-up, coasting would last long
    yield b
    b.close()


def arm_setpoint_trace(bench: Bench, channel: int, samples: int = 2000) -> None:
    """Record ``channel`` from the first setpoint change on (trigger mode 2)."""
    bench.write("trace_config.pre_trigger", 0)
    bench.write("trace_config.length", 1)
    bench.write("trace_config.channel_count", 1)
    bench.write("trace_channels.channel_1", channel)
    bench.write("trace_config.length", samples)
    bench.write("trace_config.trigger_mode", 2)
    bench.write("trace_config.command", 1)


def trace(bench: Bench) -> np.ndarray:
    assert bench.wait(lambda: bench.read("trace_config.state") == 3, 5.0)
    return np.frombuffer(bench.node.sdo.upload(0x2102, 0), "<f4")


def slope_of(ref: np.ndarray, target: float) -> float:
    """Slope (unit/s) of a ramp recorded from its first step on (trigger at sample 0).

    The drive moves the reference once per simulation chunk by rate × chunk length (1 ms of
    wall time, longer on a busy machine), so the record is a staircase whose step at edge k
    belongs to the chunk that ends at edge k + 1: the drop from sample 0 to after edge k took
    the samples from edge 1 to edge k + 1. A step that lands on ``target`` may be clipped."""
    edges = [int(e) + 1 for e in np.nonzero(np.diff(ref))[0]]
    full = [k for k in range(len(edges) - 1) if ref[edges[k]] != target]
    assert full, f"fewer than two full steps after the trigger in {len(ref)} samples"
    k = full[-1]
    return float(ref[edges[k]] - ref[0]) / ((edges[k + 1] - edges[0]) * TS)


def run_at(bench: Bench, rpm: int) -> None:
    bench.write("profile_acceleration", 0)
    bench.enable(3)
    bench.write("target_velocity", rpm)
    assert bench.wait(lambda: bench.read("statusword") & BIT10, 20.0)
    assert abs(bench.read("measurements.speed") - rpm) <= bench.read("velocity_window") + 2


def test_halt_decelerates_on_profile_deceleration_and_holds_zero(bench):
    bench.write("profile_deceleration", 10000)  # rpm/s
    assert bench.read("halt_option_code") == 1  # slow-down ramp
    run_at(bench, 300)
    arm_setpoint_trace(bench, 0x20400B20)  # measurements.speed_ref, 40 ms
    time.sleep(0.05)
    bench.write("controlword", ENABLE | HALT)
    sw = bench.read("statusword")
    assert state_of(sw) == "OPERATION ENABLED"  # halt is not a state change
    if abs(bench.read("measurements.speed")) > bench.read("velocity_window"):
        assert not sw & BIT10, "target reached while the axis turns"
    ref = trace(bench)
    slope = slope_of(ref, 0.0)
    assert np.all(np.diff(ref) <= 0)
    assert slope == pytest.approx(-10000.0, rel=0.1), slope
    # held at 0: speed reference 0, bit 10 = velocity 0 reached, only inside the window
    assert bench.wait(lambda: bench.read("statusword") & BIT10, 10.0)
    assert abs(bench.read("measurements.speed")) <= bench.read("velocity_window") + 2
    assert bench.read("measurements.speed_ref") == 0.0
    assert bench.read("target_velocity") == 300  # the target itself is untouched
    # halt released: back to the target
    bench.write("controlword", ENABLE)
    assert not bench.read("statusword") & BIT10
    assert bench.wait(lambda: bench.read("measurements.speed") > 250, 20.0)


def test_halt_option_quick_ramp_uses_quick_stop_deceleration(bench):
    bench.write("profile_deceleration", 500)
    bench.write("quick_stop_deceleration", 5000)
    bench.write("halt_option_code", 2)
    run_at(bench, 300)
    arm_setpoint_trace(bench, 0x20400B20, samples=2500)  # 50 ms of a 60 ms ramp
    time.sleep(0.05)
    bench.write("controlword", ENABLE | HALT)
    ref = trace(bench)
    slope = slope_of(ref, 0.0)
    assert slope == pytest.approx(-5000.0, rel=0.1), slope


def test_velocity_window_time_delays_target_reached(bench):
    bench.write("velocity_window", 20)
    bench.write("velocity_window_time", 60000)  # 60 s: never within this test
    bench.enable(3)  # target 0 at rest: inside the window, but not for 60 s yet
    time.sleep(0.3)
    assert not bench.read("statusword") & BIT10
    bench.write("velocity_window_time", 0)
    assert bench.wait(lambda: bench.read("statusword") & BIT10, 2.0)
    # window 0 rpm around target 0 with a small commanded speed: not reached
    bench.write("velocity_window", 0)
    bench.write("target_velocity", 50)
    time.sleep(0.2)
    assert not bench.read("statusword") & BIT10


def test_speed_zero_bit_uses_threshold_and_time(bench):
    bench.enable(3)
    assert bench.wait(lambda: bench.read("statusword") & BIT12, 2.0)  # at rest, 10 rpm, 0 ms
    bench.write("velocity_threshold_time", 60000)
    bench.write("target_velocity", 200)
    assert bench.wait(lambda: abs(bench.read("measurements.speed")) > 50, 20.0)
    assert not bench.read("statusword") & BIT12
    bench.write("target_velocity", 0)
    assert bench.wait(lambda: abs(bench.read("measurements.speed")) < 5, 20.0)
    time.sleep(0.2)
    assert not bench.read("statusword") & BIT12  # standing, but not for 60 s yet
    bench.write("velocity_threshold_time", 0)
    assert bench.wait(lambda: bench.read("statusword") & BIT12, 2.0)


def test_quick_stop_option_6_sets_target_reached_at_standstill(bench):
    bench.write("quick_stop_option_code", 6)
    bench.write("quick_stop_deceleration", 2000)
    run_at(bench, 300)
    bench.write("controlword", State402.CW_COMMANDS_CODE["QUICK STOP ACTIVE"])
    sw = bench.read("statusword")
    assert state_of(sw) == "QUICK STOP ACTIVE"
    assert not sw & BIT10  # still braking from 300 rpm at 2000 rpm/s (0.15 s)
    assert bench.wait(lambda: bench.read("statusword") & BIT10, 5.0)
    sw = bench.read("statusword")
    assert state_of(sw) == "QUICK STOP ACTIVE"  # option 6 stays there
    assert abs(bench.read("measurements.speed")) < 15.0
    bench.write("controlword", ENABLE)  # transition 16 back to OPERATION ENABLED
    assert state_of(bench.read("statusword")) == "OPERATION ENABLED"


def test_torque_slope_ramps_the_demand(bench):
    assert bench.read("torque_profile_type") == 0
    bench.write("torque_slope", 500)  # ‰ of rated per s: 50 A/s at 100 A rated
    bench.enable(4)
    arm_setpoint_trace(bench, 0x20400A20, samples=5000)  # measurements.i_p_ref, 100 ms
    time.sleep(0.05)
    bench.write("target_torque", 400)  # 40 A, reached after 0.8 s (0.4 s wall at speed 2)
    sw = bench.read("statusword")
    ref = trace(bench)
    slope = slope_of(ref, 40.0)
    assert np.all(np.diff(ref) >= 0)
    assert slope == pytest.approx(50.0, rel=0.1), slope
    if bench.read("measurements.i_p_ref") < 39.0:
        assert not sw & BIT10  # demand still ramping when the write returned
    assert bench.wait(lambda: bench.read("measurements.i_p_ref") == pytest.approx(40.0), 3.0)
    assert bench.wait(lambda: bench.read("statusword") & BIT10, 2.0)
    # halt in profile torque: the demand ramps back to 0 on the same slope
    bench.write("controlword", ENABLE | HALT)
    assert bench.wait(lambda: bench.read("measurements.i_p_ref") == 0.0, 2.0)
    bench.write("controlword", 0x02)  # quick stop: the free shaft spins up under 20 A


def test_a_new_torque_target_is_not_reached_before_the_demand_gets_there(bench):
    """Bit 10 in profile torque means the demand reached the target as written now (CiA 402
    §11): right after a new 0x6071 or a halt, before the drive's next millisecond tick moved
    the demand, it is not reached. The drive's pacing is held (its simulator lock) so the
    read lands in that window every time, not only when the host happens to be quick."""
    bench.write("torque_slope", 0)  # a step: reached at the next tick
    bench.enable(4)
    assert bench.wait(lambda: bench.read("statusword") & BIT10, 2.0)  # 0 A of 0 A
    with bench.drive.sim_lock:  # no tick between the write and the read
        bench.write("target_torque", 100)  # 10 A; the demand is still at 0 A
        assert not bench.read("statusword") & BIT10
    assert bench.wait(lambda: bench.read("statusword") & BIT10, 2.0)  # at 10 A now
    assert bench.read("measurements.i_p_ref") == pytest.approx(10.0)
    with bench.drive.sim_lock:
        bench.write("controlword", ENABLE | HALT)  # halt: the target is 0 A now
        assert not bench.read("statusword") & BIT10
    assert bench.wait(lambda: bench.read("statusword") & BIT10, 2.0)  # halted at 0 A
    assert bench.read("measurements.i_p_ref") == 0.0
