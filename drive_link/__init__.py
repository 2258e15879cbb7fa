"""Host library for the BLDC drive: CANopen master (NMT, heartbeat, CiA 402, SDO, PDO streams,
trace recorder), step tests, control design and the ``drive-link`` command.

>>> from drive_link import Drive, scan, DriveError, ModeOfOperation

The public names are those of ``__all__``: the :class:`Drive` and what it returns, the errors,
the enumerations of the object dictionary (IntEnums from :mod:`firmware_protocol.enums`), the
gain facade (:func:`check_gains`, :func:`apply_gains`) and the design facade
(:mod:`drive_link.workflows.design`). The gain and design names are imported on first use, so
``import drive_link`` stays light.

Public modules (scripts import from them; documented in ``docs/architecture.md``):
:mod:`~drive_link.link.drive`, :mod:`~drive_link.errors`, :mod:`~drive_link.link.trace`,
:mod:`~drive_link.workflows.gains`, :mod:`~drive_link.workflows.design`,
:mod:`~drive_link.workflows.steps`,
:mod:`~drive_link.workflows.identify`, :mod:`~drive_link.workflows.metrics`,
:mod:`~drive_link.link.units`,
:mod:`~drive_link.workflows.restore`, :mod:`~drive_link.workflows.config_dcf`,
:mod:`~drive_link.link.record`,
:mod:`~drive_link.workflows.check`, :mod:`~drive_link.link.bus`, :mod:`~drive_link.link.cia402`,
:mod:`~drive_link.link.supervision`, :mod:`~drive_link.cli` (``drive-link``) and
:mod:`~drive_link.cli.connect` (the bus options every command line shares). Modules whose name
starts with ``_`` (the SDO client, connection, NMT, TPDO decoding, the CLI's tools …) are
implementation and may change without notice.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from firmware_protocol.enums import (
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

from ._jsonable import jsonable
from .errors import (
    BusError,
    DriveError,
    DriveTimeout,
    InvalidValue,
    NodeNotFound,
    SdoAbort,
    StateError,
    UnknownObject,
)
from .link._emcy import Emcy
from .link._live import LiveStreams
from .link._objects import ObjectInfo, ObjectTable
from .link._scan import NodeInfo, scan
from .link.drive import Drive, Gains
from .link.supervision import SupervisionError
from .link.trace import Trace, Trigger

if TYPE_CHECKING:  # the lazy names below, as the type checker sees them
    from .workflows import design
    from .workflows.gains import GainCheck, GainResult, GainsRefused, apply_gains, check_gains

#: Names loaded on first use: name → module (relative to this package).
_LAZY = {
    "design": ".workflows.design",
    "GainCheck": ".workflows.gains",
    "GainResult": ".workflows.gains",
    "GainsRefused": ".workflows.gains",
    "apply_gains": ".workflows.gains",
    "check_gains": ".workflows.gains",
}

__all__ = [
    "BusError",
    "ControllerType",
    "Drive",
    "DriveError",
    "DriveTimeout",
    "Emcy",
    "GainCheck",
    "GainResult",
    "GainSetApply",
    "Gains",
    "GainsRefused",
    "InvalidValue",
    "LiveStreams",
    "ModeOfOperation",
    "NodeInfo",
    "NodeNotFound",
    "ObjectInfo",
    "ObjectTable",
    "SdoAbort",
    "SimFault",
    "SimModel",
    "StateError",
    "StoreStatus",
    "SupervisionError",
    "Trace",
    "TraceCommand",
    "TraceState",
    "TraceTriggerEdge",
    "TraceTriggerMode",
    "Trigger",
    "UnknownObject",
    "apply_gains",
    "check_gains",
    "design",
    "jsonable",
    "scan",
]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'drive_link' has no attribute {name!r}")
    mod = importlib.import_module(module, __name__)
    value = mod if module.rpartition(".")[2] == name else getattr(mod, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
