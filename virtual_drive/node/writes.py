"""Every write to the drive's OD: checks, then a table of handlers by object index.

:func:`before_write` decides, for one write, whether to store the value and what to do after
storing it; raising :class:`canopen.sdo.SdoAbortedError` refuses it (nothing changes). The order:

1. :data:`COMMANDS` (0x1003 clear history, 0x1010 save, 0x1011 load, 0x20F1 apply a gain set):
   handled here, never stored;
2. :data:`PRE_CHECKS` (0x6060 only in a supported mode and not while OPERATION ENABLED);
3. a ``ConfigOnly`` object while the power stage is on: 0x08000022;
4. PDO communication / mapping objects: the EDS check and the PDO engine's rules;
5. the EDS check (limits, enumerations, cross-object and stability rules: :class:`.ParamChecker`);
6. :data:`HANDLERS` by index (objects without a handler are simply stored).

A handler is ``handler(drive, sub, value) -> (store, after)``: ``store`` says whether the LocalNode
keeps the written bytes, ``after`` (or None) runs once they are stored.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Mapping
from typing import Any

from canopen import objectdictionary as odm
from canopen.sdo import SdoAbortedError

from firmware_protocol import abort_codes
from firmware_protocol.cia402 import OPERATION_ENABLED
from firmware_protocol.cob_id import check_cob_id, check_heartbeat_consumers, check_sync_cob_id
from firmware_protocol.entry import LimitError
from firmware_protocol.od import load_od

from . import plant, storage
from .od_maps import SUPPORTED_MODES
from .parts import DriveParts
from .pdo import is_pdo_config

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
ERROR_HISTORY_INDEX = _OD.index_of("pre_defined_error_field")
STORE_PARAMETERS_INDEX = _OD.index_of("store_parameters")
RESTORE_DEFAULTS_INDEX = _OD.index_of("restore_default_parameters")
COB_ID_EMCY = _OD.address("cob_id_emcy")
COB_ID_EMCY_INDEX = COB_ID_EMCY[0]
COB_ID_SYNC = _OD.address("cob_id_sync")
COB_ID_SYNC_INDEX = COB_ID_SYNC[0]
CONSUMER_HEARTBEAT_INDEX = _OD.index_of("consumer_heartbeat_time")
PRODUCER_HEARTBEAT = _OD.address("producer_heartbeat_time")
PRODUCER_HEARTBEAT_INDEX = PRODUCER_HEARTBEAT[0]
SDO_SERVER_2_INDEX = _OD.index_of("sdo_server_2")
SDO_SERVER_2_RX = _OD.address("sdo_server_2.cob_id_client_to_server")
SDO_SERVER_2_TX = _OD.address("sdo_server_2.cob_id_server_to_client")
SPEED_CONTROLLER_INDEX = _OD.index_of("speed_controller")
SPEED_CURRENT_LIMIT = _OD.address("speed_controller.current_limit")
SPEED_CURRENT_LIMIT_SUB = SPEED_CURRENT_LIMIT[1]
GAIN_SET_APPLY = _OD.address("gain_set_apply")
GAIN_SET_APPLY_INDEX = GAIN_SET_APPLY[0]
TRACE_CONFIG_INDEX = _OD.index_of("trace_config")
TRACE_CHANNELS_INDEX = _OD.index_of("trace_channels")
SIM_FAULT_INDEX = _OD.index_of("sim_fault")
SIM_FAULT_INJECT_SUB = _OD.address("sim_fault.inject")[1]
SIM_FAULT_SUPPLY_SUB = _OD.address("sim_fault.V_dc_supply")[1]
SIM_INFO_INDEX = _OD.index_of("sim_info")
SIM_INFO_MODEL_SUB = _OD.address("sim_info.model")[1]
CONTROLWORD_INDEX = _OD.index_of("controlword")
MODES_OF_OPERATION_INDEX = _OD.index_of("modes_of_operation")
MAX_CURRENT = _OD.address("max_current")
MAX_CURRENT_INDEX = MAX_CURRENT[0]
MOTOR_RATED_CURRENT = _OD.address("motor_rated_current")
MOTOR_RATED_CURRENT_INDEX = MOTOR_RATED_CURRENT[0]

__all__ = ["COMMANDS", "HANDLERS", "PRE_CHECKS", "Handler", "WriteResult", "before_write"]

logger = logging.getLogger(__name__)

WriteResult = tuple[bool, Callable[[], None] | None]
"""(store the written bytes?, follow-up to run once they are stored)."""
Handler = Callable[[DriveParts, int, Any], WriteResult]
"""``handler(drive, sub, value)``; raises SdoAbortedError to refuse the write."""


def before_write(
    d: DriveParts, index: int, sub: int, obj: odm.ODVariable, data: bytes
) -> WriteResult:
    """Check a write of ``data`` to ``index:sub`` and say whether to store it and what to do
    after storing. Raises SdoAbortedError to refuse it (nothing changes)."""
    value: Any = data if obj.data_type not in odm.NUMBER_TYPES else obj.decode_raw(data)
    command = COMMANDS.get(index)
    if command is not None:
        return command(d, sub, value)
    pre_check = PRE_CHECKS.get(index)
    if pre_check is not None:
        pre_check(d, sub, value)
    entry = d.checker.entry(index, sub)
    if entry is not None and entry.config_only and d.cia402.drive_function_on:
        raise SdoAbortedError(abort_codes.DEVICE_STATE)  # plant definition: drive function off
    if is_pdo_config(index):
        d.checker.check(index, sub, value)
        d.pdo.check_write(index, sub, value)
        return True, d.pdo.configure
    value = d.checker.check(index, sub, value)
    handler = HANDLERS.get(index)
    if handler is None:
        return True, None
    return handler(d, sub, value)


# -- commands (never stored) ------------------------------------------------------------------
def _clear_error_history(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x1003: only sub 0 := 0 (clear the pre-defined error field), CiA 301."""
    if sub != 0 or value != 0:
        raise SdoAbortedError(abort_codes.INVALID_VALUE)
    return False, d.emcy.clear_history


def _store_parameters(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x1010: "save" stores the persistent objects."""
    if value != storage.SAVE_SIGNATURE:
        raise SdoAbortedError(abort_codes.STORE)
    d.parameters.save()
    return False, None


def _restore_defaults(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x1011: "load" restores the defaults (after the next reset)."""
    if value != storage.LOAD_SIGNATURE:
        raise SdoAbortedError(abort_codes.STORE)
    d.parameters.restore_defaults()
    return False, None


def _apply_gain_set(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x20F1: apply the staged gain set 0x20F0 (1 current, 2 speed, 3 both)."""
    d.checker.check(GAIN_SET_APPLY_INDEX, sub, value)
    d.gains.apply_gain_set(int(value))
    return False, None


COMMANDS: Mapping[int, Handler] = {
    ERROR_HISTORY_INDEX: _clear_error_history,
    STORE_PARAMETERS_INDEX: _store_parameters,
    RESTORE_DEFAULTS_INDEX: _restore_defaults,
    GAIN_SET_APPLY_INDEX: _apply_gain_set,
}
"""Objects whose write is a command: handled before any value check, never stored."""


# -- checks before the EDS check ------------------------------------------------------------
def _check_mode(d: DriveParts, sub: int, value: Any) -> None:
    """0x6060: not while OPERATION ENABLED (0x08000022); a supported mode (0x06090030)."""
    if d.cia402.state == OPERATION_ENABLED:
        raise SdoAbortedError(abort_codes.DEVICE_STATE)
    if value not in SUPPORTED_MODES:
        raise SdoAbortedError(abort_codes.INVALID_VALUE)


PRE_CHECKS: Mapping[int, Callable[[DriveParts, int, Any], None]] = {
    MODES_OF_OPERATION_INDEX: _check_mode
}
"""Checks that precede the EDS check (their abort code wins)."""


# -- handlers after the EDS check ----------------------------------------------------------
def _limit_error_to_abort(fn: Callable[[], None]) -> None:
    try:
        fn()
    except LimitError as exc:
        raise SdoAbortedError(exc.abort_code) from exc


def _heartbeat_consumers(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x1016: node-ID 1..127, one entry per node, reserved bits 0 (CiA 301)."""
    entries = d.comm.consumer_entries(sub, value)
    _limit_error_to_abort(lambda: check_heartbeat_consumers(entries, own_node_id=d.node_id))
    return True, lambda: d.hb_consumer.configure(entries)


def _heartbeat_producer(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x1017: producer heartbeat time (ms), effective at once."""
    return True, lambda: d.hb_producer.set_period(value, time.monotonic())


def _emcy_cob_id(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x1014: EMCY COB-ID (CiA 301 rules: :func:`firmware_protocol.cob_id.check_cob_id`)."""
    _limit_error_to_abort(lambda: check_cob_id("emcy", value, d.node.param(COB_ID_EMCY)))
    return True, lambda: d.emcy.set_cob_id(value)


def _sync_cob_id(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x1005: the SYNC this node consumes (:func:`firmware_protocol.cob_id.check_sync_cob_id`)."""
    _limit_error_to_abort(lambda: check_sync_cob_id(value))
    return True, lambda: d.comm.bind_sync(value)


def _sdo_server2(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x1201: the second SDO server's COB-IDs; rebinds it."""
    if (SDO_SERVER_2_INDEX, sub) in (SDO_SERVER_2_RX, SDO_SERVER_2_TX):
        old = d.node.value(SDO_SERVER_2_INDEX, sub)
        _limit_error_to_abort(lambda: check_cob_id("sdo", value, old))
    return True, d.comm.bind_sdo2


def _controlword(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x6040: the CiA 402 state machine."""
    return True, lambda: d.cia402.write_controlword(value)


def _mode(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x6060: the mode of operation, effective at the next chunk."""
    return True, lambda: d.ramps.set_mode(int(value))


def _current_limit(d: DriveParts, sub: int, value: Any, index: int) -> WriteResult:
    """0x6073 / 0x6075: the speed loop's current limit follows."""
    return True, d.gains.after_limit_change(index, sub, value)


def _plant(index: int) -> Handler:
    """Handler of a plant/controller object ``index`` (:data:`plant.SETTERS`): the simulator
    takes the value at a chunk boundary or refuses it (abort 0x06090030)."""

    def handler(d: DriveParts, sub: int, value: Any) -> WriteResult:
        with d.sim_lock:
            try:
                plant.apply(d.sim, index, sub, value)
            except plant.PlantError as exc:
                logger.info("0x%04X:%02X = %r refused: %s", index, sub, value, exc)
                raise SdoAbortedError(abort_codes.INVALID_VALUE) from exc
        return True, None

    return handler


def _speed_controller(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x2020: gains go to the simulator; sub 3 (current limit) also re-applies the limit."""
    if sub == SPEED_CURRENT_LIMIT_SUB:
        return _current_limit(d, sub, value, SPEED_CONTROLLER_INDEX)
    return _plant(SPEED_CONTROLLER_INDEX)(d, sub, value)


def _trace_channel(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x2101: a trace channel is a 0x2040 measurement (or 0)."""
    d.trace.check_channel(value)
    return True, None


def _sim_fault(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x5010: 1 inject (0 none, 1 overcurrent, 2 overvoltage, 3 undervoltage), 2 supply V."""
    with d.sim_lock:
        try:
            if sub == SIM_FAULT_INJECT_SUB:
                d.sim.inject_fault(int(value))
            elif sub == SIM_FAULT_SUPPLY_SUB:
                d.sim.set_supply_voltage(float(value))
        except ValueError as exc:
            raise SdoAbortedError(abort_codes.INVALID_VALUE) from exc
    return True, None


def _sim_info(d: DriveParts, sub: int, value: Any) -> WriteResult:
    """0x5030:3: the simulation model (0 PWM-exact, 1 averaged), switched after the store."""
    if sub != SIM_INFO_MODEL_SUB:
        return True, None
    fn = getattr(d.sim, "set_model", None)
    if fn is None:
        raise SdoAbortedError(abort_codes.DEVICE_STATE)

    def after() -> None:
        with d.sim_lock:
            fn("pwm" if value == 0 else "averaged")

    return True, after


HANDLERS: Mapping[int, Handler] = {
    **{index: _plant(index) for index in plant.SETTERS},
    COB_ID_EMCY_INDEX: _emcy_cob_id,
    COB_ID_SYNC_INDEX: _sync_cob_id,
    CONSUMER_HEARTBEAT_INDEX: _heartbeat_consumers,
    PRODUCER_HEARTBEAT_INDEX: _heartbeat_producer,
    SDO_SERVER_2_INDEX: _sdo_server2,
    SPEED_CONTROLLER_INDEX: _speed_controller,
    TRACE_CONFIG_INDEX: lambda d, sub, value: d.trace.write(sub, value),
    TRACE_CHANNELS_INDEX: _trace_channel,
    SIM_FAULT_INDEX: _sim_fault,
    SIM_INFO_INDEX: _sim_info,
    CONTROLWORD_INDEX: _controlword,
    MODES_OF_OPERATION_INDEX: _mode,
    MAX_CURRENT_INDEX: lambda d, sub, value: _current_limit(d, sub, value, MAX_CURRENT_INDEX),
    MOTOR_RATED_CURRENT_INDEX: lambda d, sub, value: _current_limit(
        d, sub, value, MOTOR_RATED_CURRENT_INDEX
    ),
}
"""Object index -> what a checked write does; objects not listed are only stored."""
