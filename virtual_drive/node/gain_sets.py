"""Gain sets and current limits: the staged set 0x20F0 applied at one sample by 0x20F1.

:meth:`GainSets.apply_gain_set` checks the staged set as a whole, against itself: each value in
the range of the object it becomes, then the cross-object rules (e.g. L_c < 2 motor.L), the IP and
current-loop admissibility rules and the cascade with all staged values in place (never one
staged value against the other active ones, so e.g. predictive control with the back-EMF
feed-forward is accepted as one set from deadbeat without it); then it applies the
current and/or speed part to the simulator and the stored 0x2010/0x2020 values together (a
refusal changes nothing). :meth:`GainSets.apply_current_limit` keeps the speed loop's i_p*
limit at min(0x2020:3, 0x6073 x 0x6075).

:class:`GainSets` owns no state of its own: the staged and the active gains live in the
parameter store (:class:`.DriveLocalNode`), the simulator holds the ones in effect.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from typing import Any

from canopen.sdo import SdoAbortedError

from firmware_protocol import abort_codes
from firmware_protocol.od import load_od

from . import plant
from .local_node import DriveLocalNode
from .params import ParamChecker

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
CURRENT_CONTROLLER_INDEX = _OD.index_of("current_controller")
SPEED_CONTROLLER_INDEX = _OD.index_of("speed_controller")
SPEED_CURRENT_LIMIT = _OD.address("speed_controller.current_limit")
GAIN_SET_INDEX = _OD.index_of("gain_set")
MAX_CURRENT = _OD.address("max_current")
MOTOR_RATED_CURRENT = _OD.address("motor_rated_current")

__all__ = ["GainSets"]

logger = logging.getLogger(__name__)

_GAIN_SET_SUBS = _OD.sub_names("gain_set")
"""gain_set sub -> name (``type`` .. ``emf_feedforward`` as in current_controller, then
``speed_k_p``, ``speed_k_i``, ``speed_current_limit``)."""


class GainSets:
    """The staged gain set 0x20F0/0x20F1 and the speed loop's current limit.

    :param node: the parameter store (0x2010, 0x2020, 0x20F0, 0x6073, 0x6075).
    :param checker: the write checks (ranges, cross-object and loop rules).
    :param sim: the simulator (``set_current_gains``, ``set_speed_gains``).
    :param sim_lock: serialises simulator calls (a set applies at one sample boundary).
    """

    def __init__(
        self,
        node: DriveLocalNode,
        checker: ParamChecker,
        sim: Any,
        sim_lock: threading.RLock,
    ) -> None:
        self.node = node
        self.checker = checker
        self.sim = sim
        self.sim_lock = sim_lock

    def apply_current_limit(self) -> None:
        """The speed loop's current limit (A) := min(0x2020:3, 0x6073 per mille of 0x6075)."""
        limit = min(self.node.param(SPEED_CURRENT_LIMIT), self._cap())
        try:
            self.sim.set_speed_gains(current_limit=limit)
        except (ValueError, TypeError) as exc:
            logger.error("current limit %.3g A refused: %s", limit, exc)

    def _cap(self) -> float:
        """0x6073 per mille of 0x6075 (A)."""
        rated = float(self.node.param(MOTOR_RATED_CURRENT)) / 1000.0
        return float(self.node.param(MAX_CURRENT)) / 1000.0 * rated

    def apply_current_limit_with(self, speed_limit: float) -> None:
        """As :meth:`apply_current_limit` with ``speed_limit`` (A) in place of 0x2020:3."""
        self.sim.set_speed_gains(current_limit=min(speed_limit, self._cap()))

    def after_limit_change(self, index: int, sub: int, value: Any) -> Callable[[], None]:
        """Write of 0x6073, 0x6075 or 0x2020:3: the follow-up that re-applies the current limit
        (0x2020:3 is first given to the simulator, which may refuse it: abort 0x06090030)."""

        def after() -> None:
            with self.sim_lock:
                self.apply_current_limit()

        if index == SPEED_CONTROLLER_INDEX:
            with self.sim_lock:
                try:
                    plant.apply(self.sim, index, sub, value)
                except plant.PlantError as exc:
                    raise SdoAbortedError(abort_codes.INVALID_VALUE) from exc
        return after

    def apply_gain_set(self, which: int) -> None:
        """0x20F1: staged 0x20F0 -> active current (1), speed (2) or both (3) at one
        boundary."""
        node, checker = self.node, self.checker
        staged = {name: node.value(GAIN_SET_INDEX, sub) for sub, name in _GAIN_SET_SUBS.items()}
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
        # (never against the other active values: predictive + feed-forward is one set), then
        # the cross-object rules and the loop rules with every staged value in place
        for name, value in changes.items():
            checker.check_range(checker.view.entry(name), value)
        checker.check_rules(changes, staged=True)
        speed_gains = staged["speed_k_p"], staged["speed_k_i"]
        if which & 2:
            checker.check_speed_gains(*speed_gains)
        checker.check_current_set({}, gains=current_kw, speed=speed_gains if which & 2 else None)
        sim = self.sim
        with self.sim_lock:
            cc, sc = CURRENT_CONTROLLER_INDEX, SPEED_CONTROLLER_INDEX
            old_current = {k: node.value(cc, s) for s, k in plant.CURRENT_KW.items()}
            try:
                if current_kw:
                    sim.set_current_gains(**current_kw)
                if speed_kw:
                    sim.set_speed_gains(**speed_kw)
                    self.apply_current_limit_with(staged["speed_current_limit"])
            except (ValueError, TypeError) as exc:
                if current_kw:  # undo a half-applied set: the old one was valid
                    sim.set_current_gains(**old_current)
                raise SdoAbortedError(abort_codes.INVALID_VALUE) from exc
            for sub, key in plant.CURRENT_KW.items():
                if key in current_kw:
                    var = node.find_object(cc, sub)
                    node.store_raw(cc, sub, var.encode_raw(current_kw[key]))
            for sub, key in plant.SPEED_KW.items():
                if key in speed_kw:
                    var = node.find_object(sc, sub)
                    node.store_raw(sc, sub, var.encode_raw(speed_kw[key]))
            node.invalidate()
        logger.info("gain set %d applied at t = %.6f s", which, sim.time)
