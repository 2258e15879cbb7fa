"""Map bench and drive errors onto HTTP answers (one-line ``detail``; nothing applied).

The mapping goes by exception class (drive_link's :mod:`drive_link.errors` hierarchy) and by
the CiA 301 abort code (:mod:`firmware_protocol.abort_codes`), never by class-name strings.
"""

from __future__ import annotations

from fastapi import HTTPException

from dashboard._security import LeaseError
from drive_link.errors import DriveTimeout, InvalidValue, SdoAbort, StateError, UnknownObject
from firmware_protocol import abort_codes

__all__ = ["CONFLICT_ABORTS", "http_error"]

CONFLICT_ABORTS: frozenset[int] = frozenset(
    {abort_codes.STORE, abort_codes.LOCAL_CONTROL, abort_codes.DEVICE_STATE}
)
"""Abort codes meaning "not now" (the drive's state forbids it): HTTP 409."""

_VALUE_CLASSES = (0x0609, 0x0607)  # abort code high words: value / data-type refusals


def http_error(exc: Exception) -> HTTPException:
    """The HTTP status for an exception raised by a bench operation.

    422: the value was refused (ours or the drive's SDO abort 0x0609xxxx / 0x0607xxxx); 409: not
    in control, or the drive state forbids it (0x0800002x); 504: the drive did not answer; 502:
    any other drive failure.
    """
    if isinstance(exc, LeaseError):
        return HTTPException(409, str(exc))
    if isinstance(exc, (InvalidValue, UnknownObject, ValueError, KeyError)):
        return HTTPException(422, str(exc).strip("'\""))
    if isinstance(exc, SdoAbort):
        if exc.code >> 16 in _VALUE_CLASSES:
            return HTTPException(422, str(exc))
        if exc.code in CONFLICT_ABORTS:
            return HTTPException(409, str(exc))
        return HTTPException(502, str(exc))
    if isinstance(exc, StateError):
        return HTTPException(409, str(exc))
    if isinstance(exc, (DriveTimeout, TimeoutError)):
        return HTTPException(504, str(exc))
    return HTTPException(502, f"{type(exc).__name__}: {exc}")
