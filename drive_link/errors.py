"""Exceptions raised by :mod:`drive_link`.

Every failure the host library can meet is a :class:`DriveError` subclass whose ``str()`` is one
line a user can act on (the CLI prints exactly that line and exits non-zero).
"""

from __future__ import annotations

from collections.abc import Mapping

from firmware_protocol import abort_codes

__all__ = [
    "ABORT_MEANINGS",
    "BusError",
    "DriveError",
    "DriveTimeout",
    "InvalidValue",
    "NodeNotFound",
    "SdoAbort",
    "StateError",
    "UnknownObject",
]

ABORT_MEANINGS: Mapping[int, str] = abort_codes.MEANINGS
"""SDO abort code -> meaning, CiA 301 table 22 (from :mod:`firmware_protocol.abort_codes`)."""


class DriveError(Exception):
    """Base class of every error raised by drive_link (one-line message)."""


class BusError(DriveError):
    """The CAN bus could not be opened or a frame could not be sent."""


class NodeNotFound(DriveError):  # noqa: N818
    """No node answered at the requested node-ID."""


class DriveTimeout(DriveError):  # noqa: N818
    """The drive did not answer, or did not reach a requested state, in time."""


class NodeGone(DriveTimeout):
    """The drive's heartbeat stopped for the host's consumer time (3 producer periods, at least
    2 s): the node is gone (dead, unpowered or cut off the bus). A call to it fails after one SDO
    response timeout (:mod:`drive_link.link.supervision`)."""


class SdoAbort(DriveError):  # noqa: N818
    """The drive aborted an SDO transfer (it refused a read or write).

    Attributes: ``code`` (U32 abort code), ``index``, ``subindex``, ``name`` (OD name or "").
    """

    def __init__(self, code: int, index: int, subindex: int, name: str = "", action: str = ""):
        self.code = code
        self.index = index
        self.subindex = subindex
        self.name = name
        self.meaning = abort_codes.meaning(code)
        where = (
            f"{name} (0x{index:04X}:{subindex:02X})" if name else f"0x{index:04X}:{subindex:02X}"
        )
        verb = f"{action} " if action else ""
        super().__init__(f"drive refused {verb}{where}: SDO abort 0x{code:08X} ({self.meaning})")


class InvalidValue(DriveError, ValueError):  # noqa: N818
    """A value is outside the object's type or limits (checked before sending)."""


class UnknownObject(DriveError, KeyError):  # noqa: N818
    """The name is not an object of the drive's object dictionary."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else "unknown object"


class StateError(DriveError):
    """A CiA 402 transition could not be made (fault, refused, wrong state)."""
