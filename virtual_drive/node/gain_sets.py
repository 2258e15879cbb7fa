"""Gain sets and current limits: the staged set 0x20F0 applied at one sample by 0x20F1.

:func:`apply_gain_set` checks the staged values as the objects they become (limits, the
cross-object rules, the IP and current-loop stability rules, the cascade), then applies the
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

if TYPE_CHECKING:
    from .drive_node import VirtualDrive

__all__ = [
    "after_limit_change",
    "apply_current_limit",
    "apply_current_limit_with",
    "apply_gain_set",
]

logger = logging.getLogger(__name__)


def apply_current_limit(d: VirtualDrive) -> None:
    """The speed loop's current limit (A) := min(0x2020:3, 0x6073 per mille of 0x6075)."""
    rated = d._value(0x6075) / 1000.0
    cap = d._value(0x6073) / 1000.0 * rated
    limit = min(d._value(0x2020, 3), cap)
    try:
        d.sim.set_speed_gains(current_limit=limit)
    except (ValueError, TypeError) as exc:
        logger.error("current limit %.3g A refused: %s", limit, exc)


def apply_current_limit_with(d: VirtualDrive, speed_limit: float) -> None:
    """As :func:`apply_current_limit` with ``speed_limit`` (A) in place of 0x2020:3."""
    rated = d._value(0x6075) / 1000.0
    cap = d._value(0x6073) / 1000.0 * rated
    d.sim.set_speed_gains(current_limit=min(speed_limit, cap))


def after_limit_change(d: VirtualDrive, index: int, sub: int, value: Any) -> Callable[[], None]:
    """Write of 0x6073, 0x6075 or 0x2020:3: the follow-up that re-applies the current limit
    (0x2020:3 is first given to the simulator, which may refuse it: abort 0x06090030)."""

    def after() -> None:
        with d.sim_lock:
            apply_current_limit(d)

    if index == 0x2020:
        with d.sim_lock:
            try:
                plant.apply(d.sim, index, sub, value)
            except plant.PlantError as exc:
                raise SdoAbortedError(abort_codes.INVALID_VALUE) from exc
    return after


def apply_gain_set(d: VirtualDrive, which: int) -> None:
    """0x20F1: staged 0x20F0 -> active current (1), speed (2) or both (3) at one boundary."""
    staged = {sub: d._value(0x20F0, sub) for sub in range(1, 14)}
    changes: dict[str, float | int] = {}
    current_kw = {}
    speed_kw = {}
    if which & 1:
        for sub, key in plant.CURRENT_KW.items():
            current_kw[key] = staged[sub]
            changes[f"current_controller.{key}"] = staged[sub]
        changes["gain_set.L_c"] = staged[2]
    if which & 2:
        for sub, key in plant.GAIN_SET_SPEED_KW.items():
            speed_kw[key] = staged[sub]
        changes["speed_controller.current_limit"] = staged[13]
    for name, value in changes.items():
        e = d.view.entry(name)
        d.checker.check(e.index, e.subindex, value)
    d.checker.check_rules(changes, staged=True)
    if which & 2:
        d.checker.check_speed_gains(staged[11], staged[12])
    d.checker.check_current_set(
        {}, gains=current_kw, speed=(staged[11], staged[12]) if which & 2 else None
    )
    with d.sim_lock:
        old_current = {k: d._value(0x2010, s) for s, k in plant.CURRENT_KW.items()}
        try:
            if current_kw:
                d.sim.set_current_gains(**current_kw)
            if speed_kw:
                d.sim.set_speed_gains(**speed_kw)
                apply_current_limit_with(d, staged[13])
        except (ValueError, TypeError) as exc:
            if current_kw:  # undo a half-applied set: the old one was valid
                d.sim.set_current_gains(**old_current)
            raise SdoAbortedError(abort_codes.INVALID_VALUE) from exc
        store = d.node.data_store
        for sub, key in plant.CURRENT_KW.items():
            if key in current_kw:
                var = d.node._find_object(0x2010, sub)
                store.setdefault(0x2010, {})[sub] = var.encode_raw(current_kw[key])
        for sub, key in plant.SPEED_KW.items():
            if key in speed_kw:
                var = d.node._find_object(0x2020, sub)
                store.setdefault(0x2020, {})[sub] = var.encode_raw(speed_kw[key])
        d._pcache.clear()
    logger.info("gain set %d applied at t = %.6f s", which, d.sim.time)
