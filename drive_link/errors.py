"""Exceptions raised by :mod:`drive_link`.

Every failure the host library can meet is a :class:`DriveError` subclass whose ``str()`` is one
line a user can act on (the CLI prints exactly that line and exits non-zero).
"""

from __future__ import annotations

#: SDO abort codes, CiA 301 §7.2.4.3.17 (table 22), with their meaning.
ABORT_MEANINGS: dict[int, str] = {
    0x05030000: "toggle bit not alternated",
    0x05040000: "SDO protocol timed out",
    0x05040001: "client/server command specifier not valid or unknown",
    0x05040002: "invalid block size",
    0x05040003: "invalid sequence number",
    0x05040004: "CRC error",
    0x05040005: "out of memory",
    0x06010000: "unsupported access to an object",
    0x06010001: "attempt to read a write-only object",
    0x06010002: "attempt to write a read-only object",
    0x06020000: "object does not exist in the object dictionary",
    0x06040041: "object cannot be mapped to the PDO",
    0x06040042: "number and length of objects to be mapped would exceed PDO length",
    0x06040043: "general parameter incompatibility",
    0x06040047: "general internal incompatibility in the device",
    0x06060000: "access failed due to a hardware error",
    0x06070010: "data type does not match, length of service parameter does not match",
    0x06070012: "data type does not match, length of service parameter too high",
    0x06070013: "data type does not match, length of service parameter too low",
    0x06090011: "sub-index does not exist",
    0x06090030: "invalid value for parameter",
    0x06090031: "value of parameter written too high",
    0x06090032: "value of parameter written too low",
    0x06090036: "maximum value is less than minimum value",
    0x060A0023: "resource not available: SDO connection",
    0x08000000: "general error",
    0x08000020: "data cannot be transferred or stored to the application",
    0x08000021: "data cannot be transferred or stored to the application because of local control",
    0x08000022: "data cannot be transferred or stored to the application "
    "because of the present device state",
    0x08000023: "object dictionary dynamic generation failed or no object dictionary is present",
    0x08000024: "no data available",
}


class DriveError(Exception):
    """Base class of every error raised by drive_link (one-line message)."""


class BusError(DriveError):
    """The CAN bus could not be opened or a frame could not be sent."""


class NodeNotFound(DriveError):  # noqa: N818
    """No node answered at the requested node-ID."""


class DriveTimeout(DriveError):  # noqa: N818
    """The drive did not answer, or did not reach a requested state, in time."""


class SdoAbort(DriveError):  # noqa: N818
    """The drive aborted an SDO transfer (it refused a read or write).

    Attributes: ``code`` (U32 abort code), ``index``, ``subindex``, ``name`` (OD name or "").
    """

    def __init__(self, code: int, index: int, subindex: int, name: str = "", action: str = ""):
        self.code = code
        self.index = index
        self.subindex = subindex
        self.name = name
        self.meaning = ABORT_MEANINGS.get(code, "unknown abort code")
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
