"""Setpoints of the next simulation chunk: profile ramps, current references, stop ramps.

Profile velocity ramps the speed reference with 0x6083/0x6084 (halt: 0x6084 or 0x6085 per
0x605D); profile torque ramps i_p* with 0x6087 toward 0x6071; mode -1 steps to 0x2030:1; all
capped by 0x6073 x 0x6075. A stop ramp (quick stop, slow down, fault reaction) brakes in current
mode (:meth:`SetpointRamps.ramp_step`). Called by the pacing loop with the simulator lock held.

:class:`SetpointRamps` owns the setpoint state: the mode of operation in effect (0x6060 as
written, :attr:`~SetpointRamps.mode`), the simulator's control mode, the speed reference
(rpm) and the current reference and its target (A).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from firmware_protocol.cia402 import CW_HALT
from firmware_protocol.od import load_od

from . import cia402 as sm
from .cia402 import Cia402StateMachine
from .od_maps import MODE_PROFILE_TORQUE, MODE_PROFILE_VELOCITY, SPEED_ZERO_RPM
from .runner import TS

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
MOTOR_K_RPM = _OD.address("motor.K_rpm")
SPEED_CURRENT_LIMIT = _OD.address("speed_controller.current_limit")
SETPOINT_I_P_REF = _OD.address("setpoints.i_p_ref")
SIM_LOAD_J = _OD.address("sim_load.J")
HALT_OPTION = _OD.address("halt_option_code")
TARGET_TORQUE = _OD.address("target_torque")
MAX_CURRENT = _OD.address("max_current")
MOTOR_RATED_CURRENT = _OD.address("motor_rated_current")
PROFILE_ACCELERATION = _OD.address("profile_acceleration")
PROFILE_DECELERATION = _OD.address("profile_deceleration")
QUICK_STOP_DECELERATION = _OD.address("quick_stop_deceleration")
TORQUE_SLOPE = _OD.address("torque_slope")
TARGET_VELOCITY = _OD.address("target_velocity")

__all__ = ["SetpointRamps", "ramp_towards"]


class SetpointRamps:
    """The setpoints of the next simulation chunk and the state they ramp from.

    :param sim: the simulator (``set_mode``, ``set_speed_ref``, ``set_current_ref``).
    :param param: present parameter value at an ``(index, sub)`` address
        (:meth:`.DriveLocalNode.param`).
    :param live: the live values of the last chunk (``speed`` in rpm).
    """

    def __init__(self, sim: Any, param: Callable[[tuple[int, int]], Any], live: dict) -> None:
        self.sim = sim
        self._param = param
        self._live = live
        #: mode of operation in effect (0x6060 as written; 0x6061 shows it)
        self.mode = MODE_PROFILE_VELOCITY
        self.sim_mode = "off"  #: the simulator's control mode ("off", "speed", "current")
        self.speed_ref = 0.0  #: profile output (rpm) fed to the IP loop
        self.i_ref = 0.0  #: torque-profile output (A) in the current modes
        self.i_target = 0.0  #: where i_ref is heading (A)

    def reset(self) -> None:
        """Reset node: bridge off, references 0, profile velocity (sim lock held)."""
        self.set_sim_mode("off")
        self.sim.set_current_ref(0.0)
        self.sim.set_speed_ref(0.0)
        self.speed_ref = 0.0
        self.mode = MODE_PROFILE_VELOCITY

    def set_mode(self, mode: int) -> None:
        """0x6060 written: the mode of operation, effective at the next chunk."""
        self.mode = mode

    def bridge_off(self) -> None:
        """The simulator switched its bridge off itself (a fault reset): note it."""
        self.sim_mode = "off"

    def set_sim_mode(self, mode: str) -> None:
        """Switch the simulator to ``mode`` ("off", "speed", "current") if it is not in it."""
        if mode != self.sim_mode:
            self.sim.set_mode(mode)
            self.sim_mode = mode

    def prepare_chunk(self, st: Cia402StateMachine, n: int) -> None:
        """Mode and setpoints for the next ``n`` samples in CiA 402 state ``st`` (sim lock
        held)."""
        dt = n * TS
        if not st.torque_enabled:
            self.set_sim_mode("off")
            self.speed_ref = float(self._live.get("speed", 0.0))  # bumpless start
            self.i_ref = 0.0
            return
        mode = self.mode
        if st.ramp is not None:
            self.ramp_step(st, dt)
            return
        halt = bool(st.controlword & CW_HALT)
        param = self._param
        if mode == MODE_PROFILE_VELOCITY:
            self.set_sim_mode("speed")
            if halt:  # 0x605D: 1 slow-down ramp (0x6084), 2..4 quick-stop ramp (0x6085)
                slow = param(HALT_OPTION) == 1
                rate = param(PROFILE_DECELERATION if slow else QUICK_STOP_DECELERATION)
                self.speed_ref = ramp_towards(self.speed_ref, 0.0, rate, rate, dt)
            else:
                target = float(param(TARGET_VELOCITY))
                accel, decel = param(PROFILE_ACCELERATION), param(PROFILE_DECELERATION)
                self.speed_ref = ramp_towards(self.speed_ref, target, accel, decel, dt)
            self.sim.set_speed_ref(self.speed_ref)
        else:
            self.set_sim_mode("current")
            self.sim.set_current_ref(self.current_ref(mode, halt, dt))

    def current_ref(self, mode: int, halt: bool = False, dt: float = 0.0) -> float:
        """i_p* (A) of the current modes: profile torque follows 0x6087 (per mille of rated per
        s, 0 = step) toward target_torque, or toward 0 on halt; mode -1 steps to i_p_ref."""
        target, cap = self._current_target(mode, halt)
        if mode == MODE_PROFILE_TORQUE:
            param = self._param
            slope = param(TORQUE_SLOPE) / 1000.0 * (param(MOTOR_RATED_CURRENT) / 1000.0)  # A/s
            self.i_ref = ramp_towards(self.i_ref, target, slope, slope, dt)
        else:
            self.i_ref = target
        self.i_target = target
        return max(-cap, min(cap, self.i_ref))

    def _current_target(self, mode: int, halt: bool) -> tuple[float, float]:
        """(target, cap) of i_p* (A) in the current modes: target_torque (profile torque) or
        i_p_ref (mode -1), 0 on halt, within +-cap = 0x6073 x 0x6075."""
        param = self._param
        rated = param(MOTOR_RATED_CURRENT) / 1000.0
        cap = param(MAX_CURRENT) / 1000.0 * rated
        if mode == MODE_PROFILE_TORQUE:
            target = 0.0 if halt else param(TARGET_TORQUE) / 1000.0 * rated
        else:
            target = 0.0 if halt else float(param(SETPOINT_I_P_REF))
        return max(-cap, min(cap, target)), cap

    def current_target(self, controlword: int) -> float:
        """Where i_p* (A) of the current modes heads now, from the setpoints as last written
        (0x6071 or 0x2030:1, 0 on halt per ``controlword``), capped; the chunk loop catches up
        at its next chunk."""
        return self._current_target(self.mode, bool(controlword & CW_HALT))[0]

    def current_reached(self, controlword: int) -> bool:
        """True when i_p* got to its target as written now (a new 0x6071 is not reached until
        the demand got there)."""
        return self.i_ref == self.i_target == self.current_target(controlword)

    def ramping(self, st: Cia402StateMachine) -> bool:
        """True while a setpoint moves within a chunk (a stop ramp, a profile velocity ramp, a
        torque slope on its way): :meth:`prepare_chunk` must then run once per piece of at
        most a TPDO period, as a DSP updates its ramps every millisecond. False when the
        setpoints hold for the whole chunk (a step is applied at its start either way)."""
        if not st.torque_enabled:
            return False
        if st.ramp is not None:
            return True
        halt = bool(st.controlword & CW_HALT)
        mode = self.mode
        if mode == MODE_PROFILE_VELOCITY:
            target = 0.0 if halt else float(self._param(TARGET_VELOCITY))
            return self.speed_ref != target
        if mode == MODE_PROFILE_TORQUE:
            return self.i_ref != self._current_target(mode, halt)[0]
        return False

    def ramp_step(self, st: Cia402StateMachine, dt: float) -> None:
        """Stop ramp of quick stop / slow down / fault reaction, in every mode.

        The IP speed loop is far too slow to follow a stop ramp (its integral path has a time
        constant of about a second with the paper's gains), so the drive brakes in current
        mode: |i_p*| = J alpha / K_t for the deceleration alpha of 0x6085 (quick) or 0x6084
        (slow; 0 = use 0x6085), capped by the current limit, until |speed| < 10 rpm; then the
        ramp ends.
        """
        param = self._param
        speed = float(self._live["speed"])
        self.set_sim_mode("current")
        if abs(speed) < SPEED_ZERO_RPM:
            self.sim.set_current_ref(0.0)
            self.speed_ref = 0.0
            st.ramp_done()
            return
        decel = param(PROFILE_DECELERATION) if st.ramp == sm.RAMP_SLOW else 0
        if decel == 0:
            decel = param(QUICK_STOP_DECELERATION)
        alpha = decel * 2.0 * math.pi / 60.0  # rad/s^2
        K_t = param(MOTOR_K_RPM) * 60.0 / (2.0 * math.pi)  # N m/A (i_p)
        J = param(SIM_LOAD_J)
        rated = param(MOTOR_RATED_CURRENT) / 1000.0
        limit = min(param(SPEED_CURRENT_LIMIT), param(MAX_CURRENT) / 1000.0 * rated)
        i_brake = min(limit, J * alpha / K_t) if decel > 0 else limit
        self.sim.set_current_ref(-math.copysign(i_brake, speed))


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
