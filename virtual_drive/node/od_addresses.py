"""Where the node's objects are: ``(index, sub)`` of every object the node code addresses.

Every address is resolved from the EDS (``firmware_protocol/bldc_drive.eds``, the one home of
which index and sub-index an object has) by the object's name, once, at import: renumbering an
object in the EDS needs no edit in ``virtual_drive``. The per-tick code uses these ints and
tuples directly (no lookup by name, no dict built at run time).

Conventions: ``NAME`` is the ``(index, sub)`` tuple of a variable or sub-object (the key of the
drive's parameter cache and of the live-getter table, ``VirtualDrive._param(NAME)``);
``NAME_INDEX`` is the index of a record or array (the key of the write-handler tables);
``NAME_SUB`` is a sub-index a handler dispatches on. Unknown names fail at import
(``KeyError`` naming the closest EDS names).

>>> STATUSWORD == (0x6041, 0), TRACE_CONFIG_INDEX == 0x2100
(True, True)
"""

from __future__ import annotations

from firmware_protocol.od import load_od

__all__ = [
    "ABORT_CONNECTION_OPTION",
    "COB_ID_EMCY",
    "COB_ID_EMCY_INDEX",
    "COB_ID_SYNC",
    "COB_ID_SYNC_INDEX",
    "CONSUMER_HEARTBEAT_COUNT",
    "CONSUMER_HEARTBEAT_INDEX",
    "CONTROLWORD_INDEX",
    "CURRENT_ACTUAL_VALUE",
    "CURRENT_CONTROLLER_INDEX",
    "DC_LINK_VOLTAGE",
    "DISABLE_OPERATION_OPTION",
    "ERROR_CODE",
    "ERROR_HISTORY_COUNT",
    "ERROR_HISTORY_FIELDS",
    "ERROR_HISTORY_INDEX",
    "ERROR_REGISTER",
    "FAULT_REACTION_OPTION",
    "GAIN_SET_APPLY",
    "GAIN_SET_APPLY_INDEX",
    "GAIN_SET_INDEX",
    "HALT_OPTION",
    "IDENTITY_INDEX",
    "MAX_CURRENT",
    "MAX_CURRENT_INDEX",
    "MEASUREMENTS_INDEX",
    "MODES_OF_OPERATION_DISPLAY",
    "MODES_OF_OPERATION_INDEX",
    "MOTOR_INDEX",
    "MOTOR_K_RPM",
    "MOTOR_RATED_CURRENT",
    "MOTOR_RATED_CURRENT_INDEX",
    "MOTOR_RATED_TORQUE",
    "N_RPDO",
    "N_TPDO",
    "PDO_COB_ID_SUB",
    "PDO_EVENT_TIMER_SUB",
    "PDO_INHIBIT_TIME_SUB",
    "PDO_MAPPED_COUNT_SUB",
    "PDO_MAX_MAPPED",
    "PDO_TRANSMISSION_TYPE_SUB",
    "PRODUCER_HEARTBEAT",
    "PRODUCER_HEARTBEAT_INDEX",
    "PROFILE_ACCELERATION",
    "PROFILE_DECELERATION",
    "PROTECTION_INDEX",
    "QUICK_STOP_DECELERATION",
    "QUICK_STOP_OPTION",
    "RESTORE_DEFAULTS_INDEX",
    "SDO_SERVER_2_INDEX",
    "SDO_SERVER_2_RX",
    "SDO_SERVER_2_TX",
    "SETPOINT_I_P_REF",
    "SHUTDOWN_OPTION",
    "SIM_FAULT_INDEX",
    "SIM_FAULT_INJECT_SUB",
    "SIM_FAULT_SUPPLY_SUB",
    "SIM_INFO_INDEX",
    "SIM_INFO_MODEL_SUB",
    "SIM_INFO_SPEED_FACTOR",
    "SIM_INFO_TIME",
    "SIM_INVERTER_INDEX",
    "SIM_LOAD_INDEX",
    "SIM_LOAD_J",
    "SPEED_CONTROLLER_INDEX",
    "SPEED_CURRENT_LIMIT",
    "SPEED_CURRENT_LIMIT_SUB",
    "STATUSWORD",
    "STORE_PARAMETERS_INDEX",
    "STORE_STATUS",
    "TARGET_TORQUE",
    "TARGET_VELOCITY",
    "TORQUE_ACTUAL_VALUE",
    "TORQUE_SLOPE",
    "TPDO_MISSED_EVENTS",
    "TRACE_CAPACITY",
    "TRACE_CHANNELS_INDEX",
    "TRACE_CHANNEL_COUNT",
    "TRACE_COMMAND_SUB",
    "TRACE_CONFIG_INDEX",
    "TRACE_DATA",
    "TRACE_DIVIDER",
    "TRACE_LENGTH",
    "TRACE_PRE_TRIGGER",
    "TRACE_PRE_TRIGGER_FILLED",
    "TRACE_STATE",
    "TRACE_TRIGGER_EDGE",
    "TRACE_TRIGGER_LEVEL",
    "TRACE_TRIGGER_MODE",
    "TRACE_TRIGGER_POSITION",
    "TRACE_TRIGGER_SOURCE",
    "TRACE_TRIGGER_SOURCE_SUB",
    "VELOCITY_ACTUAL_VALUE",
    "VELOCITY_THRESHOLD",
    "VELOCITY_THRESHOLD_TIME",
    "VELOCITY_WINDOW",
    "VELOCITY_WINDOW_TIME",
    "address",
    "index_of",
    "sub_names",
]

_OD = load_od()


def address(name: str) -> tuple[int, int]:
    """``(index, sub)`` of the EDS object ``name`` (e.g. ``"trace_config.state"``)."""
    e = _OD.entry(name)
    return e.index, e.subindex


def index_of(object_name: str) -> int:
    """Index of the EDS object (record, array or variable) called ``object_name``."""
    for e in _OD:
        if e.object_name == object_name:
            return e.index
    raise KeyError(f"no object named {object_name!r} in the drive OD")


def sub_names(object_name: str) -> dict[int, str]:
    """Sub-index -> sub-object name of a record (sub 0 ``highest_sub_index`` left out)."""
    subs = {e.subindex: e.sub_name for e in _OD if e.object_name == object_name and e.subindex}
    if not subs:
        raise KeyError(f"no record named {object_name!r} in the drive OD")
    return subs


# -- CiA 301 communication objects ---------------------------------------------------------------
ERROR_REGISTER = address("error_register")
ERROR_HISTORY_INDEX = index_of("pre_defined_error_field")
ERROR_HISTORY_COUNT = address("pre_defined_error_field.number_of_errors")
#: the standard error fields, newest first (sub 1, 2, ...)
ERROR_HISTORY_FIELDS: tuple[tuple[int, int], ...] = tuple(
    (ERROR_HISTORY_INDEX, sub) for sub in sorted(sub_names("pre_defined_error_field"))
)
STORE_PARAMETERS_INDEX = index_of("store_parameters")
RESTORE_DEFAULTS_INDEX = index_of("restore_default_parameters")
COB_ID_EMCY = address("cob_id_emcy")
COB_ID_EMCY_INDEX = COB_ID_EMCY[0]
COB_ID_SYNC = address("cob_id_sync")
COB_ID_SYNC_INDEX = COB_ID_SYNC[0]
CONSUMER_HEARTBEAT_INDEX = index_of("consumer_heartbeat_time")
CONSUMER_HEARTBEAT_COUNT = address("consumer_heartbeat_time.highest_sub_index")
PRODUCER_HEARTBEAT = address("producer_heartbeat_time")
PRODUCER_HEARTBEAT_INDEX = PRODUCER_HEARTBEAT[0]
SDO_SERVER_2_INDEX = index_of("sdo_server_2")
IDENTITY_INDEX = index_of("identity")
SDO_SERVER_2_RX = address("sdo_server_2.cob_id_client_to_server")
SDO_SERVER_2_TX = address("sdo_server_2.cob_id_server_to_client")
N_RPDO = int(_OD.device_info["NrOfRXPDO"])
N_TPDO = int(_OD.device_info["NrOfTXPDO"])
PDO_COB_ID_SUB = address("tpdo1_communication.cob_id")[1]
PDO_TRANSMISSION_TYPE_SUB = address("tpdo1_communication.transmission_type")[1]
PDO_INHIBIT_TIME_SUB = address("tpdo1_communication.inhibit_time")[1]
PDO_EVENT_TIMER_SUB = address("tpdo1_communication.event_timer")[1]
PDO_MAPPED_COUNT_SUB = address("tpdo1_mapping.number_of_mapped_objects")[1]
PDO_MAX_MAPPED = len(sub_names("tpdo1_mapping"))
"""Mapping entries a PDO has (sub 1..8)."""
for _kind, _n in (("rpdo", N_RPDO), ("tpdo", N_TPDO)):  # every PDO: the same sub-indices
    for _k in range(1, _n + 1):
        if (
            address(f"{_kind}{_k}_communication.cob_id")[1] != PDO_COB_ID_SUB
            or address(f"{_kind}{_k}_communication.transmission_type")[1]
            != PDO_TRANSMISSION_TYPE_SUB
            or address(f"{_kind}{_k}_communication.inhibit_time")[1] != PDO_INHIBIT_TIME_SUB
            or len(sub_names(f"{_kind}{_k}_mapping")) != PDO_MAX_MAPPED
        ):
            raise ValueError(f"{_kind.upper()}{_k}'s parameters are laid out unlike TPDO1's")

# -- manufacturer objects --------------------------------------------------------------------------
MOTOR_INDEX = index_of("motor")
MOTOR_K_RPM = address("motor.K_rpm")
CURRENT_CONTROLLER_INDEX = index_of("current_controller")
SPEED_CONTROLLER_INDEX = index_of("speed_controller")
SPEED_CURRENT_LIMIT = address("speed_controller.current_limit")
SPEED_CURRENT_LIMIT_SUB = SPEED_CURRENT_LIMIT[1]
SETPOINT_I_P_REF = address("setpoints.i_p_ref")
MEASUREMENTS_INDEX = index_of("measurements")
PROTECTION_INDEX = index_of("protection")
STORE_STATUS = address("store_status")
#: missed event periods of TPDO 1, 2, ... (sub 1, 2, ...)
TPDO_MISSED_EVENTS: tuple[tuple[int, int], ...] = tuple(
    address(f"tpdo_missed_events.{name}")
    for _sub, name in sorted(sub_names("tpdo_missed_events").items())
)
GAIN_SET_INDEX = index_of("gain_set")
GAIN_SET_APPLY = address("gain_set_apply")
GAIN_SET_APPLY_INDEX = GAIN_SET_APPLY[0]
TRACE_CONFIG_INDEX = index_of("trace_config")
TRACE_CHANNEL_COUNT = address("trace_config.channel_count")
TRACE_DIVIDER = address("trace_config.divider")
TRACE_LENGTH = address("trace_config.length")
TRACE_PRE_TRIGGER = address("trace_config.pre_trigger")
TRACE_TRIGGER_SOURCE = address("trace_config.trigger_source")
TRACE_TRIGGER_SOURCE_SUB = TRACE_TRIGGER_SOURCE[1]
TRACE_TRIGGER_LEVEL = address("trace_config.trigger_level")
TRACE_TRIGGER_EDGE = address("trace_config.trigger_edge")
TRACE_TRIGGER_MODE = address("trace_config.trigger_mode")
TRACE_COMMAND_SUB = address("trace_config.command")[1]
TRACE_STATE = address("trace_config.state")
TRACE_TRIGGER_POSITION = address("trace_config.trigger_position")
TRACE_CAPACITY = address("trace_config.capacity")
TRACE_PRE_TRIGGER_FILLED = address("trace_config.pre_trigger_filled")
TRACE_CHANNELS_INDEX = index_of("trace_channels")
TRACE_DATA = address("trace_data")

# -- virtual-drive-only objects --------------------------------------------------------------------
SIM_LOAD_INDEX = index_of("sim_load")
SIM_LOAD_J = address("sim_load.J")
SIM_FAULT_INDEX = index_of("sim_fault")
SIM_FAULT_INJECT_SUB = address("sim_fault.inject")[1]
SIM_FAULT_SUPPLY_SUB = address("sim_fault.V_dc_supply")[1]
SIM_INVERTER_INDEX = index_of("sim_inverter")
SIM_INFO_INDEX = index_of("sim_info")
SIM_INFO_TIME = address("sim_info.sim_time")
SIM_INFO_SPEED_FACTOR = address("sim_info.speed_factor")
SIM_INFO_MODEL_SUB = address("sim_info.model")[1]

# -- CiA 402 drive profile objects -----------------------------------------------------------------
ABORT_CONNECTION_OPTION = address("abort_connection_option_code")
ERROR_CODE = address("error_code")
CONTROLWORD_INDEX = index_of("controlword")
STATUSWORD = address("statusword")
QUICK_STOP_OPTION = address("quick_stop_option_code")
SHUTDOWN_OPTION = address("shutdown_option_code")
DISABLE_OPERATION_OPTION = address("disable_operation_option_code")
HALT_OPTION = address("halt_option_code")
FAULT_REACTION_OPTION = address("fault_reaction_option_code")
MODES_OF_OPERATION_INDEX = index_of("modes_of_operation")
MODES_OF_OPERATION_DISPLAY = address("modes_of_operation_display")
VELOCITY_ACTUAL_VALUE = address("velocity_actual_value")
VELOCITY_WINDOW = address("velocity_window")
VELOCITY_WINDOW_TIME = address("velocity_window_time")
VELOCITY_THRESHOLD = address("velocity_threshold")
VELOCITY_THRESHOLD_TIME = address("velocity_threshold_time")
TARGET_TORQUE = address("target_torque")
MAX_CURRENT = address("max_current")
MAX_CURRENT_INDEX = MAX_CURRENT[0]
MOTOR_RATED_CURRENT = address("motor_rated_current")
MOTOR_RATED_CURRENT_INDEX = MOTOR_RATED_CURRENT[0]
MOTOR_RATED_TORQUE = address("motor_rated_torque")
TORQUE_ACTUAL_VALUE = address("torque_actual_value")
CURRENT_ACTUAL_VALUE = address("current_actual_value")
DC_LINK_VOLTAGE = address("dc_link_circuit_voltage")
PROFILE_ACCELERATION = address("profile_acceleration")
PROFILE_DECELERATION = address("profile_deceleration")
QUICK_STOP_DECELERATION = address("quick_stop_deceleration")
TORQUE_SLOPE = address("torque_slope")
TARGET_VELOCITY = address("target_velocity")
