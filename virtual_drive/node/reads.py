"""Objects computed on read (statusword, measurements, error objects, trace data, counters).

:func:`make_live_getters` gives the table ``(index, sub) -> getter`` the LocalNode consults
before its data store; a getter returns the value in the object's Python type (or raw bytes).
A measurement's getter also carries ``live_item = (live dict, signal name)``: the TPDO engine
then reads all the measurements of a TPDO with one :func:`operator.itemgetter` call.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from firmware_protocol.od import load_od

from .od_maps import MEASUREMENTS
from .parts import DriveParts

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
ERROR_REGISTER = _OD.address("error_register")
ERROR_HISTORY_INDEX = _OD.index_of("pre_defined_error_field")
ERROR_HISTORY_COUNT = _OD.address("pre_defined_error_field.number_of_errors")
#: the standard error fields, newest first (sub 1, 2, ...)
ERROR_HISTORY_FIELDS: tuple[tuple[int, int], ...] = tuple(
    (ERROR_HISTORY_INDEX, sub) for sub in sorted(_OD.sub_names("pre_defined_error_field"))
)
MEASUREMENTS_INDEX = _OD.index_of("measurements")
STORE_STATUS = _OD.address("store_status")
#: missed event periods of TPDO 1, 2, ... (sub 1, 2, ...)
TPDO_MISSED_EVENTS: tuple[tuple[int, int], ...] = tuple(
    _OD.address(f"tpdo_missed_events.{name}")
    for _sub, name in sorted(_OD.sub_names("tpdo_missed_events").items())
)
TRACE_STATE = _OD.address("trace_config.state")
TRACE_TRIGGER_POSITION = _OD.address("trace_config.trigger_position")
TRACE_CAPACITY = _OD.address("trace_config.capacity")
TRACE_PRE_TRIGGER_FILLED = _OD.address("trace_config.pre_trigger_filled")
TRACE_DATA = _OD.address("trace_data")
SIM_INFO_TIME = _OD.address("sim_info.sim_time")
SIM_INFO_SPEED_FACTOR = _OD.address("sim_info.speed_factor")
ERROR_CODE = _OD.address("error_code")
STATUSWORD = _OD.address("statusword")
MODES_OF_OPERATION_DISPLAY = _OD.address("modes_of_operation_display")
VELOCITY_ACTUAL_VALUE = _OD.address("velocity_actual_value")
MOTOR_RATED_CURRENT = _OD.address("motor_rated_current")
MOTOR_RATED_TORQUE = _OD.address("motor_rated_torque")
TORQUE_ACTUAL_VALUE = _OD.address("torque_actual_value")
CURRENT_ACTUAL_VALUE = _OD.address("current_actual_value")
DC_LINK_VOLTAGE = _OD.address("dc_link_circuit_voltage")

__all__ = ["Measurement", "clamp_int", "make_live_getters"]


class Measurement:
    """The getter of one 0x2040 measurement: ``live[name]`` as a float. Its ``live_item``
    ``(live, name)`` lets the TPDO engine read all the measurements of a TPDO with one
    :func:`operator.itemgetter` call, and the node bring the simulation to now first."""

    __slots__ = ("_live", "_name", "live_item")

    def __init__(self, live: dict[str, float], name: str) -> None:
        self._live = live
        self._name = name
        self.live_item = (live, name)

    def __call__(self) -> float:
        return float(self._live[self._name])


def make_live_getters(d: DriveParts) -> dict[tuple[int, int], Callable[[], Any]]:
    """The live objects of drive ``d``: CiA 301 error objects, CiA 402 actual values (0x6041,
    0x6061, 0x606C rpm, 0x6077/0x6078 per mille of rated, 0x6079 mV), 0x2040 measurements, the
    recorder's read-only objects and the simulator's clock."""
    live = d.live
    param = d.node.param
    g: dict[tuple[int, int], Callable[[], Any]] = {
        ERROR_REGISTER: lambda: d.emcy.error_register,
        STORE_STATUS: lambda: int(d.parameters.store_status),
        ERROR_HISTORY_COUNT: lambda: len(d.emcy.history),
        ERROR_CODE: lambda: d.emcy.last_code,
        STATUSWORD: d.statusword,
        MODES_OF_OPERATION_DISPLAY: lambda: d.ramps.mode,
        VELOCITY_ACTUAL_VALUE: lambda: clamp_int(live["speed"], 32),
        TORQUE_ACTUAL_VALUE: lambda: clamp_int(
            live["T_e"] / (param(MOTOR_RATED_TORQUE) / 1000.0) * 1000.0, 16
        ),
        CURRENT_ACTUAL_VALUE: lambda: clamp_int(
            live["i_p"] / (param(MOTOR_RATED_CURRENT) / 1000.0) * 1000.0, 16
        ),
        DC_LINK_VOLTAGE: lambda: max(0, round(live["V_dc"] * 1000.0)),
        TRACE_STATE: lambda: d.recorder.state,
        TRACE_TRIGGER_POSITION: lambda: d.recorder.trigger_position,
        TRACE_CAPACITY: lambda: d.recorder.capacity,
        TRACE_PRE_TRIGGER_FILLED: lambda: d.recorder.pre_trigger_filled,
        TRACE_DATA: d.recorder.data_bytes,
        SIM_INFO_TIME: lambda: float(d.sim.time),
        SIM_INFO_SPEED_FACTOR: lambda: d.speed,
    }

    def missed(k: int) -> Callable[[], int]:
        return lambda: d.pdo.missed[k]

    def history(k: int) -> Callable[[], int]:
        return lambda: d.emcy.history[k] if k < len(d.emcy.history) else 0

    for k, address in enumerate(TPDO_MISSED_EVENTS):
        g[address] = missed(k)
    for k, address in enumerate(ERROR_HISTORY_FIELDS):
        g[address] = history(k)
    for sub, name in MEASUREMENTS.items():
        if name == "hall_sector":
            g[(MEASUREMENTS_INDEX, sub)] = lambda: int(live["hall_sector"])
        else:
            g[(MEASUREMENTS_INDEX, sub)] = Measurement(live, name)
    return g


def clamp_int(x: float, bits: int) -> int:
    """``round(x)`` saturated to a signed ``bits``-bit integer; 0 for NaN/inf."""
    lim = (1 << (bits - 1)) - 1
    if not math.isfinite(x):
        return 0
    return max(-lim - 1, min(lim, round(x)))
