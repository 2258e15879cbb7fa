"""The drive's CANopen object dictionary: EDS (source of truth), Python view, generated C header.

Workflow: edit ``bldc_drive.eds`` (CiA 306; units in ``Unit=``, enumerations in ``Enum=``),
run ``python -m firmware_protocol.generate`` to rewrite ``bldc_drive_od.h`` (DSP firmware) and
``OD.md`` (reference), commit all three. ``--check`` fails when they drift; the tests run it.
Cross-object rules the EDS cannot express live in :mod:`firmware_protocol.constraints`; the IP
speed-loop stability rule in :mod:`firmware_protocol.stability`, COB-ID / heartbeat-consumer
rules in :mod:`firmware_protocol.cob_id`, the EMCY codes in :mod:`firmware_protocol.emcy_codes`
(all rendered into ``OD.md`` and the header). Custom EDS keys: ``ConfigOnly=1`` (write only
with the power stage off, abort 0x08000022), ``MinNonZero=`` (0 or at least this).

This package is the one home of every protocol fact; other packages import, never copy:
:mod:`~firmware_protocol.abort_codes` (SDO abort codes and meanings, on canopen's table),
:mod:`~firmware_protocol.emcy_codes` (EMCY codes sent and their meanings),
:mod:`~firmware_protocol.enums` (enumerated object values, the controller-type names),
:mod:`~firmware_protocol.cia402` (statusword/controlword), :mod:`~firmware_protocol.cia301`
(the store/restore signatures),
:mod:`~firmware_protocol.index_ranges` (which part of the OD an index is in, PDO parameter
bases), :mod:`~firmware_protocol.paper` (Table 2 motor, Ts, the speed model a/b, the paper's
gains) and the objects' limits
(``load_od().entry(name).low/.high``: the dashboard's pydantic models and the simulator's
parameter checks read them). The renderers behind ``generate`` (``_c_header``, ``_markdown``,
``_strict_eds``) are private.

>>> from firmware_protocol import load_od
>>> od = load_od()
>>> od.entry("current_controller.L_c").unit
'H'
>>> hex(od.od_reference("measurements.i_p"))
'0x20400120'
"""

from . import abort_codes, emcy_codes, index_ranges, paper
from .constraints import CONSTRAINTS, Constraint
from .entry import LimitError
from .enums import (
    CONTROLLER_NAMES,
    CONTROLLER_TYPES,
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
    "CONTROLLER_NAMES",
    "CONTROLLER_TYPES",
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
    "abort_codes",
    "emcy_codes",
    "index_ranges",
    "load_od",
    "paper",
]
