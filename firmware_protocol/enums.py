"""Enumerated object values as IntEnum, matching the EDS ``Enum=`` keys (checked by a test).

Each class names the object(s) it applies to in :data:`ENUM_OBJECTS`.
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import IntEnum
from types import MappingProxyType

__all__ = [
    "CONTROLLER_NAMES",
    "CONTROLLER_TYPES",
    "ENUM_OBJECTS",
    "ControllerType",
    "GainSetApply",
    "ModeOfOperation",
    "SimFault",
    "SimModel",
    "StoreStatus",
    "TraceCommand",
    "TraceState",
    "TraceTriggerEdge",
    "TraceTriggerMode",
]


class ControllerType(IntEnum):
    """0x2010:1 current_controller.type (and 0x20F0:1 gain_set.type)."""

    DEADBEAT = 0  # eq. 15, k = 2
    PI = 1  # eq. 22
    PREDICTIVE = 2  # eq. 23 / eq. 25


CONTROLLER_TYPES: Mapping[str, int] = MappingProxyType(
    {c.name.lower(): int(c) for c in ControllerType}
)
"""Host-side controller name -> 0x2010:1 code: ``{"deadbeat": 0, "pi": 1, "predictive": 2}``."""
CONTROLLER_NAMES: Mapping[int, str] = MappingProxyType(
    {int(c): c.name.lower() for c in ControllerType}
)
"""0x2010:1 code -> host-side controller name (the inverse of :data:`CONTROLLER_TYPES`)."""


class ModeOfOperation(IntEnum):
    """0x6060 modes_of_operation / 0x6061 modes_of_operation_display (CiA 402)."""

    PSEUDO_CURRENT = -1  # manufacturer mode: i_p* = setpoints.i_p_ref (A)
    PROFILE_VELOCITY = 3  # IP speed loop on target_velocity (rpm)
    PROFILE_TORQUE = 4  # i_p* = target_torque / 1000 * rated current


class GainSetApply(IntEnum):
    """0x20F1 gain_set_apply: which staged set to apply atomically."""

    CURRENT = 1  # gain_set 1..10
    SPEED = 2  # gain_set 11..13
    BOTH = 3


class TraceTriggerEdge(IntEnum):
    """0x2100:7 trace_config.trigger_edge."""

    RISING = 0
    FALLING = 1
    EITHER = 2


class TraceTriggerMode(IntEnum):
    """0x2100:8 trace_config.trigger_mode."""

    IMMEDIATE = 0  # on arm
    SIGNAL = 1  # trigger_source crosses trigger_level on trigger_edge
    SETPOINT_STEP = 2
    FAULT = 3


class TraceCommand(IntEnum):
    """0x2100:9 trace_config.command."""

    STOP = 0
    ARM = 1
    FORCE_TRIGGER = 2


class TraceState(IntEnum):
    """0x2100:10 trace_config.state (read-only)."""

    IDLE = 0
    ARMED = 1  # pre-trigger filling / waiting for the trigger
    RECORDING = 2
    DONE = 3


class SimFault(IntEnum):
    """0x5010:1 sim_fault.inject (virtual drive only)."""

    NONE = 0
    OVERCURRENT = 1
    DC_OVERVOLTAGE = 2
    DC_UNDERVOLTAGE = 3


class SimModel(IntEnum):
    """0x5030:3 sim_info.model (virtual drive only)."""

    PWM_EXACT = 0
    AVERAGED = 1


class StoreStatus(IntEnum):
    """0x2060 store_status (read-only): health of the parameter store at the last boot."""

    OK = 0
    DEFAULTS = 1
    DAMAGED = 2
    UNREADABLE = 3


#: Enumeration class -> python names of the objects whose values it lists.
ENUM_OBJECTS: dict[type[IntEnum], tuple[str, ...]] = {
    ControllerType: ("current_controller.type", "gain_set.type"),
    ModeOfOperation: ("modes_of_operation", "modes_of_operation_display"),
    GainSetApply: ("gain_set_apply",),
    TraceTriggerEdge: ("trace_config.trigger_edge",),
    TraceTriggerMode: ("trace_config.trigger_mode",),
    TraceCommand: ("trace_config.command",),
    TraceState: ("trace_config.state",),
    SimFault: ("sim_fault.inject",),
    SimModel: ("sim_info.model",),
    StoreStatus: ("store_status",),
}
