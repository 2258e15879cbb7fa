"""Gain sets and current limits: the staged set 0x20F0 applied at one sample by 0x20F1.

:func:`apply_gain_set` checks the staged set as a whole, against itself: each value in the range
of the object it becomes, then the cross-object rules (e.g. L_c < 2 motor.L), the IP and
current-loop admissibility rules and the cascade with all staged values in place (never one
staged value against the other active ones, so e.g. predictive control with the back-EMF
feed-forward is accepted as one set from deadbeat without it); then it applies the
current and/or speed part to the simulator and the stored 0x2010/0x2020 values together (a
refusal changes nothing). :func:`apply_current_limit` keeps the speed loop's i_p* limit at
min(0x2020:3, 0x6073 x 0x6075).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from canopen.sdo import SdoAbortedError

from firmware_protocol import abort_codes

from . import plant
from .od_addresses import (
    CURRENT_CONTROLLER_INDEX,
    GAIN_SET_INDEX,
    MAX_CURRENT,
    MOTOR_RATED_CURRENT,
    SPEED_CONTROLLER_INDEX,
    SPEED_CURRENT_LIMIT,
    sub_names,
)

if TYPE_CHECKING:
    from .drive_node import VirtualDrive

__all__ = [
    "after_limit_change",
    "apply_current_limit",
    "apply_current_limit_with",
    "apply_gain_set",
]

logger = logging.getLogger(__name__)

_GAIN_SET_SUBS = sub_names("gain_set")
"""gain_set sub -> name (``type`` .. ``emf_feedforward`` as in current_controller, then
``speed_k_p``, ``speed_k_i``, ``speed_current_limit``)."""


def apply_current_limit(d: VirtualDrive) -> None:
    """The speed loop's current limit (A) := min(0x2020:3, 0x6073 per mille of 0x6075)."""
    rated = d._param(MOTOR_RATED_CURRENT) / 1000.0
    cap = d._param(MAX_CURRENT) / 1000.0 * rated
    limit = min(d._param(SPEED_CURRENT_LIMIT), cap)
    try:
        d.sim.set_speed_gains(current_limit=limit)
    except (ValueError, TypeError) as exc:
        logger.error("current limit %.3g A refused: %s", limit, exc)


def apply_current_limit_with(d: VirtualDrive, speed_limit: float) -> None:
    """As :func:`apply_current_limit` with ``speed_limit`` (A) in place of 0x2020:3."""
    rated = d._param(MOTOR_RATED_CURRENT) / 1000.0
    cap = d._param(MAX_CURRENT) / 1000.0 * rated
    d.sim.set_speed_gains(current_limit=min(speed_limit, cap))


def after_limit_change(d: VirtualDrive, index: int, sub: int, value: Any) -> Callable[[], None]:
    """Write of 0x6073, 0x6075 or 0x2020:3: the follow-up that re-applies the current limit
    (0x2020:3 is first given to the simulator, which may refuse it: abort 0x06090030)."""

    def after() -> None:
        with d.sim_lock:
            apply_current_limit(d)

    if index == SPEED_CONTROLLER_INDEX:
        with d.sim_lock:
            try:
                plant.apply(d.sim, index, sub, value)
            except plant.PlantError as exc:
                raise SdoAbortedError(abort_codes.INVALID_VALUE) from exc
    return after


def apply_gain_set(d: VirtualDrive, which: int) -> None:
    """0x20F1: staged 0x20F0 -> active current (1), speed (2) or both (3) at one boundary."""
    staged = {name: d._value(GAIN_SET_INDEX, sub) for sub, name in _GAIN_SET_SUBS.items()}
    changes: dict[str, float | int] = {}
    current_kw = {}
    speed_kw = {}
    if which & 1:
        for key in plant.CURRENT_KW.values():
            current_kw[key] = staged[key]
            changes[f"current_controller.{key}"] = staged[key]
    if which & 2:
        for sub, key in plant.GAIN_SET_SPEED_KW.items():
            speed_kw[key] = staged[_GAIN_SET_SUBS[sub]]
            changes[f"speed_controller.{key}"] = speed_kw[key]
        changes["speed_controller.current_limit"] = staged["speed_current_limit"]
    # the set as a whole, against itself: each value in the range of the object it becomes
    # (never against the other active values: predictive + feed-forward is one set), then the
    # cross-object rules and the loop rules with every staged value in place
    for name, value in changes.items():
        d.checker.check_range(d.view.entry(name), value)
    d.checker.check_rules(changes, staged=True)
    speed_gains = staged["speed_k_p"], staged["speed_k_i"]
    if which & 2:
        d.checker.check_speed_gains(*speed_gains)
    d.checker.check_current_set({}, gains=current_kw, speed=speed_gains if which & 2 else None)
    with d.sim_lock:
        cc, sc = CURRENT_CONTROLLER_INDEX, SPEED_CONTROLLER_INDEX
        old_current = {k: d._value(cc, s) for s, k in plant.CURRENT_KW.items()}
        try:
            if current_kw:
                d.sim.set_current_gains(**current_kw)
            if speed_kw:
                d.sim.set_speed_gains(**speed_kw)
                apply_current_limit_with(d, staged["speed_current_limit"])
        except (ValueError, TypeError) as exc:
            if current_kw:  # undo a half-applied set: the old one was valid
                d.sim.set_current_gains(**old_current)
            raise SdoAbortedError(abort_codes.INVALID_VALUE) from exc
        store = d.node.data_store
        for sub, key in plant.CURRENT_KW.items():
            if key in current_kw:
                var = d.node._find_object(cc, sub)
                store.setdefault(cc, {})[sub] = var.encode_raw(current_kw[key])
        for sub, key in plant.SPEED_KW.items():
            if key in speed_kw:
                var = d.node._find_object(sc, sub)
                store.setdefault(sc, {})[sub] = var.encode_raw(speed_kw[key])
        d._pcache.clear()
    logger.info("gain set %d applied at t = %.6f s", which, d.sim.time)
