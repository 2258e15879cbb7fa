"""The drive's parameter set: load at boot / reset, push into the simulator, store and restore.

A stored value is used only if it is a persistent object of the right length that passes its
EDS check; a stored set that breaks a cross-object or stability rule is not applied at all
(defaults, store_status DAMAGED). 0x1010 "save" writes the persistent objects' present values
(atomically, :mod:`.storage`); 0x1011 "load" empties the store (defaults after the next reset).

:class:`ParameterSet` owns the store file (its path) and what the last load found in it
(0x2060 ``store_status`` and the error text); the values themselves live in the parameter
store (:class:`.DriveLocalNode`).
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from canopen import objectdictionary as odm
from canopen.node.local import LocalNode
from canopen.sdo import SdoAbortedError

from firmware_protocol import abort_codes
from firmware_protocol.current_stability import (
    CURRENT_KEYS,
    MOTOR_KEYS,
    check_cascade,
    check_current_gains,
)
from firmware_protocol.entry import LimitError
from firmware_protocol.enums import StoreStatus
from firmware_protocol.stability import check_ip_speed_gains

from . import plant, storage
from .emcy import DATA_SET_LOST, EmcyManager
from .gain_sets import GainSets
from .local_node import DriveLocalNode
from .params import ParamChecker

__all__ = ["ParameterSet"]

logger = logging.getLogger(__name__)


class ParameterSet:
    """Load, push, store and restore the drive's parameter set.

    :param node: the parameter store.
    :param checker: the write checks (entries, the OD view's cross-object rules).
    :param store_path: parameter file for 0x1010/0x1011 (None: store refused, 0x08000020).
    :param sim: the simulator the plant/controller objects go to.
    :param sim_lock: serialises simulator calls.
    :param emcy: EMCY bookkeeping (0x6310 "data set lost" cleared by a good store).
    :param gains: the gain sets (the speed loop's current limit).
    :param configure_communication: applies the communication objects after a load.
    """

    def __init__(
        self,
        node: DriveLocalNode,
        checker: ParamChecker,
        store_path: Path | None,
        sim: Any,
        sim_lock: threading.RLock,
        emcy: EmcyManager,
        gains: GainSets,
        configure_communication: Callable[[], None],
    ) -> None:
        self.node = node
        self.checker = checker
        self.view = checker.view
        self.store_path = store_path
        self.sim = sim
        self.sim_lock = sim_lock
        self.emcy = emcy
        self.gains = gains
        self._configure_communication = configure_communication
        self.store_error: str | None = None  #: why the last load did not use the store
        self.store_status = StoreStatus.DEFAULTS  #: 0x2060, set by every parameter load
        if store_path is not None:
            storage.remove_stale_temps(store_path)  # left by a kill during a store

    def load(self) -> None:
        """Stored parameters (or defaults) into the data store and the simulator."""
        node = self.node
        node.data_store.clear()
        node.invalidate()
        stored, self.store_status, self.store_error = self.read_store()
        for (index, sub), raw in stored.items():
            e = self.checker.entry(index, sub)
            try:
                obj = node.find_object(index, sub)
                if e is None or not e.persistent or 8 * len(raw) != len(obj):
                    raise ValueError("not a stored parameter")
                e.check(obj.decode_raw(raw))
            except (ValueError, SdoAbortedError) as exc:
                logger.error("stored 0x%04X:%02X ignored: %s", index, sub, exc)
                continue
            node.data_store.setdefault(index, {})[sub] = raw
        node.invalidate()
        problem = self.rules_broken()
        if problem is not None:  # e.g. a store from before a rule existed: not applied at all
            logger.error("stored parameters break a rule, defaults used: %s", problem)
            node.data_store.clear()
            node.invalidate()
            self.store_status, self.store_error = StoreStatus.DAMAGED, problem
        self.push_plant()
        self._configure_communication()

    def rules_broken(self) -> str | None:
        """Why the present parameter set breaks a cross-object or stability rule, or None."""
        values = {
            e.name: self.node.stored(e.index, e.subindex)
            for e in self.view
            if e.data_type in odm.NUMBER_TYPES and e.bit_length
        }
        try:
            self.view.check_constraints(values)
            k_p, k_i = values["speed_controller.k_p"], values["speed_controller.k_i"]
            check_ip_speed_gains(k_p, k_i)
            gains = {k: values[f"current_controller.{k}"] for k in CURRENT_KEYS}
            motor = {k: values[f"motor.{k}"] for k in MOTOR_KEYS}
            check_current_gains(gains, motor)
            check_cascade(gains, motor, k_p, k_i)
        except LimitError as exc:
            return str(exc)
        return None

    def read_store(self) -> tuple[dict[tuple[int, int], bytes], StoreStatus, str | None]:
        """The store file's values, its 0x2060 status and the error text (None if fine)."""
        return storage.load_with_status(self.store_path)

    def push_plant(self) -> None:
        """Every plant/controller object's present value into the simulator."""
        with self.sim_lock:
            for index, (name, kw) in plant.SETTERS.items():
                setter = getattr(self.sim, name, None)
                if setter is None:
                    continue
                values = {key: self.node.value(index, sub) for sub, key in kw.items()}
                try:
                    setter(**values)
                except (ValueError, TypeError) as exc:
                    logger.error("simulator refused %s(%s): %s", name, values, exc)
            self.gains.apply_current_limit()

    def save(self) -> None:
        """0x1010 "save": persistent objects' present values to the store file (atomic)."""
        if self.store_path is None:
            raise SdoAbortedError(abort_codes.STORE)
        values = {}
        for e in self.view:
            if not e.persistent:
                continue
            values[(e.index, e.subindex)] = LocalNode.get_data(self.node, e.index, e.subindex)
        try:
            storage.save(self.store_path, values)
        except OSError as exc:
            logger.error("store failed: %s", exc)
            raise SdoAbortedError(abort_codes.HARDWARE) from exc
        logger.info("parameters stored to %s", self.store_path)
        # the store now holds the parameters in use: healthy again
        self.store_status, self.store_error = StoreStatus.OK, None
        self.emcy.clear_error(DATA_SET_LOST)

    def restore_defaults(self) -> None:
        """0x1011 "load": defaults apply after the next reset node / restart."""
        if self.store_path is None:
            raise SdoAbortedError(abort_codes.STORE)
        try:
            storage.save(self.store_path, {})
        except OSError as exc:
            raise SdoAbortedError(abort_codes.HARDWARE) from exc
        logger.info("defaults restored in %s (active after reset)", self.store_path)
