"""The statusword 0x6041 and the velocity window / threshold timers behind its bits 10 and 12.

Bit 10 (target reached): in profile velocity |speed - target| <= 0x606D for 0x606E ms (the
target is 0 during a stop ramp or halt); in the current modes the reference reached its target
as written now (a target written since the last chunk is not reached yet) and
|i_p - i_p*| <= :data:`CURRENT_WINDOW_A`; in QUICK STOP ACTIVE the axis stopped. Bit 11
(internal limit): |i_p*| at the speed loop's current limit. Bit 12 (speed zero, profile
velocity): |speed| <= 0x606F for 0x6070 ms. Times are simulated seconds.

:class:`StatusWord` owns the timers: since when (sim time, s) the speed is inside the velocity
window and for which target, since when it is below the threshold, and the instant a timed
tick's TPDO shows (:attr:`StatusWord.t_point`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from firmware_protocol.cia402 import CW_HALT, OPERATION_ENABLED, QUICK_STOP_ACTIVE, SW_SPEED_ZERO
from firmware_protocol.od import load_od

from .cia402 import Cia402StateMachine
from .od_maps import CURRENT_WINDOW_A, MODE_PROFILE_VELOCITY
from .ramps import SetpointRamps

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
SPEED_CURRENT_LIMIT = _OD.address("speed_controller.current_limit")
VELOCITY_WINDOW = _OD.address("velocity_window")
VELOCITY_WINDOW_TIME = _OD.address("velocity_window_time")
VELOCITY_THRESHOLD = _OD.address("velocity_threshold")
VELOCITY_THRESHOLD_TIME = _OD.address("velocity_threshold_time")
TARGET_VELOCITY = _OD.address("target_velocity")

__all__ = ["StatusWord"]


class StatusWord:
    """0x6041 from the CiA 402 state, the setpoints and the live values, and the velocity
    window / threshold timers behind its bits 10 and 12.

    :param sim: the simulator (``time``, s).
    :param param: present parameter value at an ``(index, sub)`` address.
    :param live: the live values (``speed`` rpm, ``i_p``, ``i_p_ref`` A).
    :param ramps: the setpoints (mode of operation, current reference).
    """

    def __init__(
        self,
        sim: Any,
        param: Callable[[tuple[int, int]], Any],
        live: dict,
        ramps: SetpointRamps,
    ) -> None:
        self.sim = sim
        self._param = param
        self._live = live
        self._ramps = ramps
        # since when (sim time, s) |speed - target| <= 0x606D / |speed| <= 0x606F, and for
        # which velocity target the window was measured
        self._window_since: float | None = None
        self._window_target = 0.0
        self._threshold_since: float | None = None
        #: sim time (s) of the TPDO instant a timed tick is at (None: the simulator's clock)
        self.t_point: float | None = None

    def statusword(self, st: Cia402StateMachine, warning: bool) -> int:
        """0x6041 in CiA 402 state ``st``; ``warning``: bit 7 (a consumer heartbeat lost)."""
        live = self._live
        mode = self._ramps.mode
        reached = False
        limit = False
        mode_bits = 0
        if st.state == QUICK_STOP_ACTIVE:
            # CiA 402: in QUICK STOP ACTIVE (0x605A 5..8) bit 10 = the axis is stopped
            reached = st.ramp is None
        elif st.state == OPERATION_ENABLED or st.ramp is not None:
            if mode == MODE_PROFILE_VELOCITY:
                reached = self.velocity_reached(st)
                limit = abs(live["i_p_ref"]) >= 0.999 * self._param(SPEED_CURRENT_LIMIT)
            else:
                # the target as written now, not as of the last chunk: a new 0x6071 is not
                # reached until the demand got there (as velocity_reached does for 0x60FF)
                reached = (
                    self._ramps.current_reached(st.controlword)
                    and abs(live["i_p"] - live["i_p_ref"]) <= CURRENT_WINDOW_A
                )
        if mode == MODE_PROFILE_VELOCITY and self.held(
            self._threshold_since, self._param(VELOCITY_THRESHOLD_TIME)
        ):
            mode_bits |= SW_SPEED_ZERO
        return st.statusword(
            target_reached=reached,
            internal_limit=limit,
            warning=warning,
            mode_bits=mode_bits,
        )

    def velocity_target(self, st: Cia402StateMachine) -> float:
        """Velocity (rpm) bit 10 compares with: 0 during a stop ramp or halt, else 0x60FF."""
        if st.ramp is not None or st.controlword & CW_HALT:
            return 0.0
        return float(self._param(TARGET_VELOCITY))

    def sim_now(self) -> float:
        """Simulated time (s) of the live values: the instant a timed tick's TPDO shows
        (:attr:`t_point`) while it is sent, else the simulator's clock."""
        t = self.t_point
        return float(self.sim.time) if t is None else t

    def held(self, since: float | None, time_ms: int) -> bool:
        """True when a window opened at ``since`` (sim s) has lasted ``time_ms``."""
        return since is not None and self.sim_now() - since >= time_ms / 1000.0 - 1e-9

    def velocity_reached(self, st: Cia402StateMachine) -> bool:
        """|speed - target| <= 0x606D continuously for 0x606E ms, for the present target."""
        if self.velocity_target(st) != self._window_target:
            return False  # target changed since the last chunk: not measured yet
        return self.held(self._window_since, self._param(VELOCITY_WINDOW_TIME))

    def update_windows(self, st: Cia402StateMachine) -> None:
        """After a chunk (or at a timed tick's TPDO instant): restart or keep the velocity
        window / threshold timers (sim time)."""
        t = self.sim_now()
        speed = float(self._live["speed"])
        target = self.velocity_target(st)
        inside = abs(speed - target) <= self._param(VELOCITY_WINDOW)
        if not inside or target != self._window_target:
            self._window_since = t if inside else None
        elif self._window_since is None:
            self._window_since = t
        self._window_target = target
        if abs(speed) <= self._param(VELOCITY_THRESHOLD):
            if self._threshold_since is None:
                self._threshold_since = t
        else:
            self._threshold_since = None
