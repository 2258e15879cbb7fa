"""The statusword 0x6041 and the velocity window / threshold timers behind its bits 10 and 12.

Bit 10 (target reached): in profile velocity |speed - target| <= 0x606D for 0x606E ms (the
target is 0 during a stop ramp or halt); in the current modes the reference reached its target
as written now (a target written since the last chunk is not reached yet) and
|i_p - i_p*| <= :data:`CURRENT_WINDOW_A`; in QUICK STOP ACTIVE the axis stopped. Bit 11
(internal limit): |i_p*| at the speed loop's current limit. Bit 12 (speed zero, profile
velocity): |speed| <= 0x606F for 0x6070 ms. Times are simulated seconds.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from firmware_protocol.cia402 import CW_HALT, OPERATION_ENABLED, QUICK_STOP_ACTIVE, SW_SPEED_ZERO

from .od_addresses import (
    SPEED_CURRENT_LIMIT,
    TARGET_VELOCITY,
    VELOCITY_THRESHOLD,
    VELOCITY_THRESHOLD_TIME,
    VELOCITY_WINDOW,
    VELOCITY_WINDOW_TIME,
)
from .od_maps import CURRENT_WINDOW_A, MODE_PROFILE_VELOCITY
from .ramps import current_target

if TYPE_CHECKING:
    from .drive_node import VirtualDrive

__all__ = [
    "held",
    "sim_now",
    "statusword",
    "update_windows",
    "velocity_reached",
    "velocity_target",
]


def statusword(d: VirtualDrive) -> int:
    """0x6041 of drive ``d`` from its CiA 402 state and live values."""
    live = d.live
    st = d.cia402
    reached = False
    limit = False
    mode_bits = 0
    if st.state == QUICK_STOP_ACTIVE:
        # CiA 402: in QUICK STOP ACTIVE (0x605A 5..8) bit 10 = the axis is stopped
        reached = st.ramp is None
    elif st.state == OPERATION_ENABLED or st.ramp is not None:
        if d._mode == MODE_PROFILE_VELOCITY:
            reached = velocity_reached(d)
            limit = abs(live["i_p_ref"]) >= 0.999 * d._param(SPEED_CURRENT_LIMIT)
        else:
            # the target as written now, not as of the last chunk: a new 0x6071 is not
            # reached until the demand got there (as velocity_reached does for 0x60FF)
            reached = (
                d._i_ref == d._i_target == current_target(d)
                and abs(live["i_p"] - live["i_p_ref"]) <= CURRENT_WINDOW_A
            )
    if d._mode == MODE_PROFILE_VELOCITY and held(
        d, d._threshold_since, d._param(VELOCITY_THRESHOLD_TIME)
    ):
        mode_bits |= SW_SPEED_ZERO
    return st.statusword(
        target_reached=reached,
        internal_limit=limit,
        warning=bool(d.hb_consumer.lost),
        mode_bits=mode_bits,
    )


def velocity_target(d: VirtualDrive) -> float:
    """Velocity (rpm) bit 10 compares with: 0 during a stop ramp or halt, else 0x60FF."""
    st = d.cia402
    if st.ramp is not None or st.controlword & CW_HALT:
        return 0.0
    return float(d._param(TARGET_VELOCITY))


def sim_now(d: VirtualDrive) -> float:
    """Simulated time (s) of the values in ``d.live``: the instant a timed tick's TPDO shows
    (``d._t_point``) while it is sent, else the simulator's clock."""
    t = d._t_point
    return float(d.sim.time) if t is None else t


def held(d: VirtualDrive, since: float | None, time_ms: int) -> bool:
    """True when a window opened at ``since`` (sim s) has lasted ``time_ms``."""
    return since is not None and sim_now(d) - since >= time_ms / 1000.0 - 1e-9


def velocity_reached(d: VirtualDrive) -> bool:
    """|speed - target| <= 0x606D continuously for 0x606E ms, for the present target."""
    if velocity_target(d) != d._window_target:
        return False  # target changed since the last chunk: not measured yet
    return held(d, d._window_since, d._param(VELOCITY_WINDOW_TIME))


def update_windows(d: VirtualDrive) -> None:
    """After a chunk (or at a timed tick's TPDO instant): restart or keep the velocity window /
    threshold timers (sim time)."""
    t = sim_now(d)
    speed = float(d.live["speed"])
    target = velocity_target(d)
    inside = abs(speed - target) <= d._param(VELOCITY_WINDOW)
    if not inside or target != d._window_target:
        d._window_since = t if inside else None
    elif d._window_since is None:
        d._window_since = t
    d._window_target = target
    if abs(speed) <= d._param(VELOCITY_THRESHOLD):
        if d._threshold_since is None:
            d._threshold_since = t
    else:
        d._threshold_since = None
