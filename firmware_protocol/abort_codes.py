"""SDO abort codes (CiA 301 §7.2.4.3.17, table 22): the one home for the drive and the host.

The codes are canopen's named constants (:mod:`canopen.sdo.constants`, ``ABORT_*``) under
shorter names; the meanings are canopen's own table
(:attr:`canopen.sdo.exceptions.SdoAbortedError.CODES`), lower-cased to fit inside a sentence,
with CiA 301 v4.2's wording where canopen 2.4.1 keeps an older one (:data:`CIA301_WORDING`).
Every code CiA 301 table 22 defines is in canopen's table; the drive defines no
manufacturer-specific codes. The drive (``virtual_drive.node``), the DSP header
(``OD_ABORT_*``) and the host (``drive_link``) all import the names below.

>>> meaning(INVALID_VALUE)
'invalid value for parameter'
>>> meaning(0x12345678)
'unknown abort code'
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from canopen.sdo import constants as _c
from canopen.sdo.exceptions import SdoAbortedError

__all__ = [
    "BLOCK_SIZE",
    "CIA301_WORDING",
    "COMMAND",
    "CRC",
    "DEVICE_STATE",
    "GENERAL",
    "HARDWARE",
    "INTERNAL_INCOMPATIBLE",
    "INVALID_VALUE",
    "LENGTH",
    "LENGTHS",
    "LENGTH_TOO_HIGH",
    "LENGTH_TOO_LOW",
    "LOCAL_CONTROL",
    "MAX_BELOW_MIN",
    "MEANINGS",
    "NO_DATA",
    "NO_OBJECT",
    "NO_OD",
    "NO_SUBINDEX",
    "OUT_OF_MEMORY",
    "PARAM_INCOMPATIBLE",
    "PDO_CANNOT_MAP",
    "PDO_LENGTH_EXCEEDED",
    "READ_WRITE_ONLY",
    "RESOURCE",
    "SEQUENCE",
    "STORE",
    "TIMEOUT",
    "TOGGLE_BIT",
    "UNSUPPORTED_ACCESS",
    "VALUE_REFUSED",
    "VALUE_TOO_HIGH",
    "VALUE_TOO_LOW",
    "WRITE_READ_ONLY",
    "meaning",
]

TOGGLE_BIT: int = _c.ABORT_TOGGLE_NOT_ALTERNATED
"""Toggle bit not alternated (segmented transfer)."""
TIMEOUT: int = _c.ABORT_TIMED_OUT
"""SDO protocol timed out."""
COMMAND: int = _c.ABORT_INVALID_COMMAND_SPECIFIER
"""Client/server command specifier not valid or unknown."""
BLOCK_SIZE: int = _c.ABORT_INVALID_BLOCK_SIZE
"""Invalid block size (block mode)."""
SEQUENCE: int = _c.ABORT_INVALID_SEQUENCE_NUMBER
"""Invalid sequence number (block mode)."""
CRC: int = _c.ABORT_CRC_ERROR
"""CRC error (block mode)."""
OUT_OF_MEMORY: int = _c.ABORT_OUT_OF_MEMORY
"""Out of memory."""
UNSUPPORTED_ACCESS: int = _c.ABORT_UNSUPPORTED_ACCESS
"""Unsupported access to an object."""
READ_WRITE_ONLY: int = _c.ABORT_READ_WRITEONLY
"""Attempt to read a write-only object."""
WRITE_READ_ONLY: int = _c.ABORT_WRITE_READONLY
"""Attempt to write a read-only object."""
NO_OBJECT: int = _c.ABORT_NOT_IN_OD
"""Object does not exist in the object dictionary."""
PDO_CANNOT_MAP: int = _c.ABORT_PDO_CANNOT_MAP
"""Object cannot be mapped to the PDO."""
PDO_LENGTH_EXCEEDED: int = _c.ABORT_PDO_LENGTH_EXCEEDED
"""Number and length of the objects to be mapped would exceed the PDO length (64 bits)."""
PARAM_INCOMPATIBLE: int = _c.ABORT_PARAMETER_INCOMPATIBLE
"""General parameter incompatibility (e.g. two heartbeat-consumer entries for one node)."""
INTERNAL_INCOMPATIBLE: int = _c.ABORT_INTERNAL_INCOMPATIBILITY
"""General internal incompatibility in the device."""
HARDWARE: int = _c.ABORT_HARDWARE_ERROR
"""Access failed due to a hardware error (e.g. the parameter store could not be read)."""
LENGTH: int = _c.ABORT_LENGTH_NOT_MATCHED
"""Data type does not match, length of service parameter does not match."""
LENGTH_TOO_HIGH: int = _c.ABORT_LENGTH_TOO_HIGH
"""Data type does not match, length of service parameter too high."""
LENGTH_TOO_LOW: int = _c.ABORT_LENGTH_TOO_LOW
"""Data type does not match, length of service parameter too low."""
NO_SUBINDEX: int = _c.ABORT_NO_SUBINDEX
"""Sub-index does not exist."""
INVALID_VALUE: int = _c.ABORT_INVALID_VALUE
"""Invalid value for parameter (NaN, inf, not integral, not in the enumeration, ...)."""
VALUE_TOO_HIGH: int = _c.ABORT_VALUE_TOO_HIGH
"""Value of parameter written too high."""
VALUE_TOO_LOW: int = _c.ABORT_VALUE_TOO_LOW
"""Value of parameter written too low."""
MAX_BELOW_MIN: int = _c.ABORT_MAXIMUM_LESS_THAN_MINIMUM
"""Maximum value is less than minimum value."""
RESOURCE: int = _c.ABORT_NO_SDO_CONNECTION
"""Resource not available: SDO connection."""
GENERAL: int = _c.ABORT_GENERAL_ERROR
"""General error."""
STORE: int = _c.ABORT_STORE_APPLICATION
"""Data cannot be transferred or stored to the application (e.g. no parameter file)."""
LOCAL_CONTROL: int = _c.ABORT_APPLICATION_LOCAL_CONTROL
"""... because of local control."""
DEVICE_STATE: int = _c.ABORT_APPLICATION_DEVICE_STATE
"""... because of the present device state (e.g. a ConfigOnly object while enabled)."""
NO_OD: int = _c.ABORT_OD_GENERATION
"""Object dictionary dynamic generation failed or no object dictionary is present."""
NO_DATA: int = _c.ABORT_NO_DATA_AVAILABLE
"""No data available."""

LENGTHS: tuple[int, int, int] = (LENGTH, LENGTH_TOO_HIGH, LENGTH_TOO_LOW)
"""The three "data type does not match" codes."""
VALUE_REFUSED: tuple[int, int, int, int] = (
    INVALID_VALUE,
    VALUE_TOO_HIGH,
    VALUE_TOO_LOW,
    PARAM_INCOMPATIBLE,
)
"""Codes with which the drive refuses a value (nothing is stored)."""

CIA301_WORDING: Mapping[int, str] = MappingProxyType(
    {
        # canopen 2.4.1 keeps DS 301 v4.0's "value range of parameter exceeded"; CiA 301 v4.2
        # (and this drive: NaN, enumeration, COB-ID rules) use the code for any invalid value.
        INVALID_VALUE: "invalid value for parameter",
        READ_WRITE_ONLY: "attempt to read a write-only object",
        WRITE_READ_ONLY: "attempt to write a read-only object",
        NO_OBJECT: "object does not exist in the object dictionary",
        RESOURCE: "resource not available: SDO connection",
    }
)
"""Codes whose CiA 301 v4.2 wording differs from canopen's text."""


def _lower_first(text: str) -> str:
    return text[:1].lower() + text[1:] if text[:2] != text[:2].upper() else text


MEANINGS: Mapping[int, str] = MappingProxyType(
    {
        **{code: _lower_first(text) for code, text in SdoAbortedError.CODES.items()},
        **CIA301_WORDING,
    }
)
"""Abort code -> meaning (lower-case first letter, to read inside a sentence)."""


def meaning(code: int) -> str:
    """The meaning of an SDO abort code; ``"unknown abort code"`` for one CiA 301 does not list."""
    return MEANINGS.get(code, "unknown abort code")
