"""Setpoints of the next simulation chunk: profile ramps, current references, stop ramps.

Profile velocity ramps the speed reference with 0x6083/0x6084 (halt: 0x6084 or 0x6085 per
0x605D); profile torque ramps i_p* with 0x6087 toward 0x6071; mode -1 steps to 0x2030:1; all
capped by 0x6073 x 0x6075. A stop ramp (quick stop, slow down, fault reaction) brakes in current
mode (:func:`ramp_step`). Called by the pacing loop with the simulator lock held.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from firmware_protocol.cia402 import CW_HALT

from . import cia402 as sm
from .od_addresses import (
    HALT_OPTION,
    MAX_CURRENT,
    MOTOR_K_RPM,
    MOTOR_RATED_CURRENT,
    PROFILE_ACCELERATION,
    PROFILE_DECELERATION,
    QUICK_STOP_DECELERATION,
    SETPOINT_I_P_REF,
    SIM_LOAD_J,
    SPEED_CURRENT_LIMIT,
    TARGET_TORQUE,
    TARGET_VELOCITY,
    TORQUE_SLOPE,
)
from .od_maps import MODE_PROFILE_TORQUE, MODE_PROFILE_VELOCITY, SPEED_ZERO_RPM
from .runner import TS

if TYPE_CHECKING:
    from .drive_node import VirtualDrive

__all__ = [
    "current_ref",
    "current_target",
    "prepare_chunk",
    "ramp_step",
    "ramp_towards",
    "ramping",
    "set_sim_mode",
]


def set_sim_mode(d: VirtualDrive, mode: str) -> None:
    """Switch the simulator to ``mode`` ("off", "speed", "current") if it is not in it."""
    if mode != d._sim_mode:
        d.sim.set_mode(mode)
        d._sim_mode = mode


def prepare_chunk(d: VirtualDrive, n: int) -> None:
    """Mode and setpoints for the next ``n`` samples (sim lock held)."""
    st = d.cia402
    dt = n * TS
    if not st.torque_enabled:
        set_sim_mode(d, "off")
        d._speed_ref = float(d.live.get("speed", 0.0))  # bumpless start
        d._i_ref = 0.0
        return
    mode = d._mode
    if st.ramp is not None:
        ramp_step(d, dt)
        return
    halt = bool(st.controlword & CW_HALT)
    if mode == MODE_PROFILE_VELOCITY:
        set_sim_mode(d, "speed")
        if halt:  # 0x605D: 1 slow-down ramp (0x6084), 2..4 quick-stop ramp (0x6085)
            slow = d._param(HALT_OPTION) == 1
            rate = d._param(PROFILE_DECELERATION if slow else QUICK_STOP_DECELERATION)
            d._speed_ref = ramp_towards(d._speed_ref, 0.0, rate, rate, dt)
        else:
            target = float(d._param(TARGET_VELOCITY))
            accel, decel = d._param(PROFILE_ACCELERATION), d._param(PROFILE_DECELERATION)
            d._speed_ref = ramp_towards(d._speed_ref, target, accel, decel, dt)
        d.sim.set_speed_ref(d._speed_ref)
    else:
        set_sim_mode(d, "current")
        d.sim.set_current_ref(current_ref(d, mode, halt, dt))


def current_ref(d: VirtualDrive, mode: int, halt: bool = False, dt: float = 0.0) -> float:
    """i_p* (A) of the current modes: profile torque follows 0x6087 (per mille of rated per s,
    0 = step) toward target_torque, or toward 0 on halt; mode -1 steps to i_p_ref."""
    target, cap = _current_target(d, mode, halt)
    if mode == MODE_PROFILE_TORQUE:
        slope = d._param(TORQUE_SLOPE) / 1000.0 * (d._param(MOTOR_RATED_CURRENT) / 1000.0)  # A/s
        d._i_ref = ramp_towards(d._i_ref, target, slope, slope, dt)
    else:
        d._i_ref = target
    d._i_target = target
    return max(-cap, min(cap, d._i_ref))


def _current_target(d: VirtualDrive, mode: int, halt: bool) -> tuple[float, float]:
    """(target, cap) of i_p* (A) in the current modes: target_torque (profile torque) or
    i_p_ref (mode -1), 0 on halt, within +-cap = 0x6073 x 0x6075."""
    rated = d._param(MOTOR_RATED_CURRENT) / 1000.0
    cap = d._param(MAX_CURRENT) / 1000.0 * rated
    if mode == MODE_PROFILE_TORQUE:
        target = 0.0 if halt else d._param(TARGET_TORQUE) / 1000.0 * rated
    else:
        target = 0.0 if halt else float(d._param(SETPOINT_I_P_REF))
    return max(-cap, min(cap, target)), cap


def current_target(d: VirtualDrive) -> float:
    """Where i_p* (A) of the current modes heads now, from the setpoints as last written
    (0x6071 or 0x2030:1, 0 on halt), capped; the chunk loop catches up at its next chunk."""
    halt = bool(d.cia402.controlword & CW_HALT)
    return _current_target(d, d._mode, halt)[0]


def ramping(d: VirtualDrive) -> bool:
    """True while a setpoint moves within a chunk (a stop ramp, a profile velocity ramp, a
    torque slope on its way): :func:`prepare_chunk` must then run once per piece of at most a
    TPDO period, as a DSP updates its ramps every millisecond. False when the setpoints hold
    for the whole chunk (a step is applied at its start either way)."""
    st = d.cia402
    if not st.torque_enabled:
        return False
    if st.ramp is not None:
        return True
    halt = bool(st.controlword & CW_HALT)
    mode = d._mode
    if mode == MODE_PROFILE_VELOCITY:
        target = 0.0 if halt else float(d._param(TARGET_VELOCITY))
        return d._speed_ref != target
    if mode == MODE_PROFILE_TORQUE:
        return d._i_ref != _current_target(d, mode, halt)[0]
    return False


def ramp_step(d: VirtualDrive, dt: float) -> None:
    """Stop ramp of quick stop / slow down / fault reaction, in every mode.

    The IP speed loop is far too slow to follow a stop ramp (its integral path has a time
    constant of about a second with the paper's gains), so the drive brakes in current mode:
    |i_p*| = J alpha / K_t for the deceleration alpha of 0x6085 (quick) or 0x6084 (slow; 0 = use
    0x6085), capped by the current limit, until |speed| < 10 rpm; then the ramp ends.
    """
    st = d.cia402
    speed = float(d.live["speed"])
    set_sim_mode(d, "current")
    if abs(speed) < SPEED_ZERO_RPM:
        d.sim.set_current_ref(0.0)
        d._speed_ref = 0.0
        st.ramp_done()
        return
    decel = d._param(PROFILE_DECELERATION) if st.ramp == sm.RAMP_SLOW else 0
    if decel == 0:
        decel = d._param(QUICK_STOP_DECELERATION)
    alpha = decel * 2.0 * math.pi / 60.0  # rad/s^2
    K_t = d._param(MOTOR_K_RPM) * 60.0 / (2.0 * math.pi)  # N m/A (i_p)
    J = d._param(SIM_LOAD_J)
    rated = d._param(MOTOR_RATED_CURRENT) / 1000.0
    limit = min(d._param(SPEED_CURRENT_LIMIT), d._param(MAX_CURRENT) / 1000.0 * rated)
    i_brake = min(limit, J * alpha / K_t) if decel > 0 else limit
    d.sim.set_current_ref(-math.copysign(i_brake, speed))


def ramp_towards(x: float, target: float, accel: float, decel: float, dt: float) -> float:
    """Move ``x`` toward ``target`` at ``accel``/``decel`` (units/s; 0 = step) for ``dt`` s."""
    if x == target:
        return x
    speeding_up = abs(target) > abs(x) and (
        x == 0 or math.copysign(1, x) == math.copysign(1, target)
    )
    rate = accel if speeding_up else decel
    if rate <= 0:
        return target
    step = rate * dt
    if abs(target - x) <= step:
        return target
    return x + math.copysign(step, target - x)
