"""Host library for the BLDC drive: CANopen master (NMT, heartbeat, CiA 402, SDO, PDO streams,
trace recorder), step tests, control design and the ``drive-link`` command.

>>> from drive_link import Drive, scan, DriveError
"""

from .drive import Drive, Gains
from .emcy import Emcy
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
from .scan import NodeInfo, scan
from .trace import Trace, Trigger

__all__ = [
    "BusError",
    "Drive",
    "DriveError",
    "DriveTimeout",
    "Emcy",
    "Gains",
    "InvalidValue",
    "NodeInfo",
    "NodeNotFound",
    "SdoAbort",
    "StateError",
    "Trace",
    "Trigger",
    "UnknownObject",
    "scan",
]
