"""The drive's parameter set: load at boot / reset, push into the simulator, store and restore.

A stored value is used only if it is a persistent object of the right length that passes its
EDS check; a stored set that breaks a cross-object or stability rule is not applied at all
(defaults, store_status DAMAGED). 0x1010 "save" writes the persistent objects' present values
(atomically, :mod:`.storage`); 0x1011 "load" empties the store (defaults after the next reset).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

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

from . import communication, gain_sets, plant, storage
from .emcy import DATA_SET_LOST

if TYPE_CHECKING:
    from .drive_node import VirtualDrive

__all__ = [
    "load_parameters",
    "push_plant",
    "read_store",
    "restore_defaults",
    "rules_broken",
    "save_parameters",
]

logger = logging.getLogger(__name__)


def load_parameters(d: VirtualDrive) -> None:
    """Stored parameters (or defaults) into the data store and the simulator."""
    d.node.data_store.clear()
    d._pcache.clear()
    stored, d.store_status, d.store_error = read_store(d)
    for (index, sub), raw in stored.items():
        e = d.checker.entry(index, sub)
        try:
            obj = d.node._find_object(index, sub)
            if e is None or not e.persistent or 8 * len(raw) != len(obj):
                raise ValueError("not a stored parameter")
            e.check(obj.decode_raw(raw))
        except (ValueError, SdoAbortedError) as exc:
            logger.error("stored 0x%04X:%02X ignored: %s", index, sub, exc)
            continue
        d.node.data_store.setdefault(index, {})[sub] = raw
    d._pcache.clear()
    problem = rules_broken(d)
    if problem is not None:  # e.g. a store from before a rule existed: not applied at all
        logger.error("stored parameters break a rule, defaults used: %s", problem)
        d.node.data_store.clear()
        d._pcache.clear()
        d.store_status, d.store_error = StoreStatus.DAMAGED, problem
    push_plant(d)
    communication.configure_communication(d)


def rules_broken(d: VirtualDrive) -> str | None:
    """Why the present parameter set breaks a cross-object or stability rule, or None."""
    values = {
        e.name: d.node.stored(e.index, e.subindex)
        for e in d.view
        if e.data_type in odm.NUMBER_TYPES and e.bit_length
    }
    try:
        d.view.check_constraints(values)
        check_ip_speed_gains(values["speed_controller.k_p"], values["speed_controller.k_i"])
        gains = {k: values[f"current_controller.{k}"] for k in CURRENT_KEYS}
        motor = {k: values[f"motor.{k}"] for k in MOTOR_KEYS}
        check_current_gains(gains, motor)
        check_cascade(gains, motor, values["speed_controller.k_p"], values["speed_controller.k_i"])
    except LimitError as exc:
        return str(exc)
    return None


def read_store(d: VirtualDrive) -> tuple[dict[tuple[int, int], bytes], StoreStatus, str | None]:
    """The store file's values, its 0x2060 status and the error text (None if fine)."""
    return storage.load_with_status(d.store_path)


def push_plant(d: VirtualDrive) -> None:
    """Every plant/controller object's present value into the simulator."""
    with d.sim_lock:
        for index, (name, kw) in plant.SETTERS.items():
            setter = getattr(d.sim, name, None)
            if setter is None:
                continue
            values = {key: d._value(index, sub) for sub, key in kw.items()}
            try:
                setter(**values)
            except (ValueError, TypeError) as exc:
                logger.error("simulator refused %s(%s): %s", name, values, exc)
        gain_sets.apply_current_limit(d)


def save_parameters(d: VirtualDrive) -> None:
    """0x1010 "save": persistent objects' present values to the store file (atomic)."""
    if d.store_path is None:
        raise SdoAbortedError(abort_codes.STORE)
    values = {}
    for e in d.view:
        if not e.persistent:
            continue
        values[(e.index, e.subindex)] = LocalNode.get_data(d.node, e.index, e.subindex)
    try:
        storage.save(d.store_path, values)
    except OSError as exc:
        logger.error("store failed: %s", exc)
        raise SdoAbortedError(abort_codes.HARDWARE) from exc
    logger.info("parameters stored to %s", d.store_path)
    # the store now holds the parameters in use: healthy again
    d.store_status, d.store_error = StoreStatus.OK, None
    d.emcy.clear_error(DATA_SET_LOST)


def restore_defaults(d: VirtualDrive) -> None:
    """0x1011 "load": defaults apply after the next reset node / restart."""
    if d.store_path is None:
        raise SdoAbortedError(abort_codes.STORE)
    try:
        storage.save(d.store_path, {})
    except OSError as exc:
        raise SdoAbortedError(abort_codes.HARDWARE) from exc
    logger.info("defaults restored in %s (active after reset)", d.store_path)
