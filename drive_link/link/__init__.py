"""Bus and protocol: one drive over CANopen, and the bus itself.

:mod:`.drive` (:class:`Drive`, on canopen's ``RemoteNode``: :mod:`._remote`), :mod:`._connection`
(one canopen ``Network`` per bus), :mod:`._sdo` / :mod:`._sdo_segmented` / :mod:`._sdo_block` /
:mod:`._sdo_client` (the locked SDO channel, block upload), :mod:`._nmt`,
:mod:`._host_heartbeat`, :mod:`._emcy`, :mod:`.cia402`, :mod:`._drive_probe`,
:mod:`.supervision` / :mod:`._rearm_writes` (survives a drive restart), :mod:`._live` (TPDO ring
buffers), :mod:`.trace` (the trace recorder), :mod:`._stop_guard` (a quick stop wins over
leave-as-found), :mod:`._gain_set` (the staged gain-set mechanism), :mod:`._rules` (the OD's
cross-object rules), :mod:`._objects` / :mod:`._od_select` / :mod:`.od_names` (objects by name
or index), :mod:`.units`, :mod:`._scan`, :mod:`.bus`, :mod:`._bus_health`, :mod:`.writers` (CSV
and PNG); the bus seen whole: :mod:`.record` (a log file), :mod:`.monitor` /
:mod:`._monitor_decode` (the live table per CAN-ID) and :mod:`._replay` / :mod:`._replay_epochs`
(a recording decoded offline). Imports nothing from :mod:`drive_link.workflows` or
:mod:`drive_link.cli`.
"""

from __future__ import annotations

import importlib
from types import ModuleType

#: The public modules.
__all__ = [
    "bus",
    "cia402",
    "drive",
    "monitor",
    "od_names",
    "record",
    "supervision",
    "trace",
    "units",
    "writers",
]


def __getattr__(name: str) -> ModuleType:
    """The public modules, imported on first use (``import drive_link.link`` stays light)."""
    if name not in __all__:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return importlib.import_module(f"{__name__}.{name}")
