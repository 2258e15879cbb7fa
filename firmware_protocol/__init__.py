"""The drive's CANopen object dictionary: EDS (source of truth), Python view, generated C header.

Workflow: edit ``bldc_drive.eds`` (CiA 306; units in ``Unit=``, enumerations in ``Enum=``),
run ``python -m firmware_protocol.generate`` to rewrite ``bldc_drive_od.h`` (DSP firmware) and
``OD.md`` (reference), commit all three. ``--check`` fails when they drift; the tests run it.
Cross-object rules the EDS cannot express live in :mod:`firmware_protocol.constraints`.

>>> from firmware_protocol import load_od
>>> od = load_od()
>>> od.entry("current_controller.L_c").unit
'H'
>>> hex(od.od_reference("measurements.i_p"))
'0x20400120'
"""

from .constraints import CONSTRAINTS, Constraint
from .entry import LimitError
from .enums import (
    ControllerType,
    GainSetApply,
    ModeOfOperation,
    SimFault,
    SimModel,
    StoreStatus,
    TraceCommand,
    TraceState,
    TraceTriggerEdge,
    TraceTriggerMode,
)
from .od import EDS_PATH, Entry, ObjectDictionaryView, load_od

__all__ = [
    "CONSTRAINTS",
    "EDS_PATH",
    "Constraint",
    "ControllerType",
    "Entry",
    "GainSetApply",
    "LimitError",
    "ModeOfOperation",
    "ObjectDictionaryView",
    "SimFault",
    "SimModel",
    "StoreStatus",
    "TraceCommand",
    "TraceState",
    "TraceTriggerEdge",
    "TraceTriggerMode",
    "load_od",
]
