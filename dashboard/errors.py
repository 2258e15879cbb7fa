"""Map bench and drive errors onto HTTP answers (one-line ``detail``; nothing applied)."""

from __future__ import annotations

from fastapi import HTTPException

from dashboard.security import LeaseError


def http_error(exc: Exception) -> HTTPException:
    """The HTTP status for an exception raised by a bench operation.

    422: the value was refused (ours or the drive's SDO abort 0x0609xxxx); 409: not in control,
    or the drive state forbids it; 504: the drive did not answer; 502: any other drive failure.
    """
    name = type(exc).__name__
    code = getattr(exc, "code", None)
    if isinstance(exc, LeaseError):
        return HTTPException(409, str(exc))
    if name in ("InvalidValue", "UnknownObject") or isinstance(exc, (ValueError, KeyError)):
        return HTTPException(422, str(exc).strip("'\""))
    if name == "SdoAbort" and isinstance(code, int):
        if code >> 16 == 0x0609 or code >> 16 == 0x0607:
            return HTTPException(422, str(exc))
        if code in (0x08000022, 0x08000021, 0x08000020):
            return HTTPException(409, str(exc))
        return HTTPException(502, str(exc))
    if name == "StateError":
        return HTTPException(409, str(exc))
    if name in ("DriveTimeout", "TimeoutError") or isinstance(exc, TimeoutError):
        return HTTPException(504, str(exc))
    return HTTPException(502, f"{name}: {exc}")
