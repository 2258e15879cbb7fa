"""Opening a python-can bus from user settings.

Bus choice is configuration, never code: any argument left ``None`` is filled in by python-can from
its config file (``~/.canrc``, ``can.ini``) and environment (``CAN_INTERFACE``, ``CAN_CHANNEL``,
``CAN_BITRATE``). ``host``/``port`` is a shortcut for the project's loopback hub (socketcand
rawmode on 127.0.0.1).
"""

from __future__ import annotations

import socket
from typing import Any

import can

from ..errors import BusError
from ._nmt import NMT_STATES

__all__ = [
    "HUB_CHANNEL",
    "NMT_STATES",
    "bus_settings",
    "open_bus",
]

# NMT_STATES (re-exported): a heartbeat's state byte (& 0x7F) → its CiA 301 name, for code
# outside drive_link that reads heartbeats off the bus itself (the dashboard's node list).

#: Channel name the loopback hub serves (socketcand "bus name").
HUB_CHANNEL = "vcan0"


def bus_settings(
    interface: str | None = None,
    channel: str | int | None = None,
    bitrate: int | None = None,
    host: str | None = None,
    port: int | None = None,
    **extra: Any,
) -> dict[str, Any]:
    """Keyword arguments for :class:`can.Bus` (``None`` = python-can default)."""
    kw: dict[str, Any] = {k: v for k, v in extra.items() if v is not None}
    if host is not None or port is not None:
        if interface not in (None, "socketcand"):
            raise BusError(f"--host/--port select the socketcand hub, not interface {interface!r}")
        kw.update(
            interface="socketcand",
            host=host or "127.0.0.1",
            port=int(port) if port is not None else 29536,
            channel=channel if channel is not None else HUB_CHANNEL,
            tcp_tune=True,
        )
    else:
        if interface is not None:
            kw["interface"] = interface
        if channel is not None:
            kw["channel"] = channel
    if bitrate is not None:
        kw["bitrate"] = int(bitrate)
    return kw


def open_bus(**settings: Any) -> can.BusABC:
    """Open a python-can bus; see :func:`bus_settings` for the arguments.

    Raises :class:`BusError` with one line when the bus cannot be opened.
    """
    kw = bus_settings(**settings)
    if kw.get("interface") == "socketcand" and "host" in kw:
        _probe_tcp(kw["host"], int(kw.get("port", 29536)))
        kw["interface"] = "vdhub"  # same protocol, the project's lean client (issue 11)
    try:
        return can.Bus(**kw)
    except Exception as exc:  # python-can raises many kinds (OSError, CanError, ValueError, ...)
        desc = ", ".join(
            f"{k}={v}" for k, v in kw.items() if k in ("interface", "channel", "host", "port")
        )
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise BusError(f"cannot open CAN bus ({desc or 'python-can defaults'}): {msg}") from None


def _probe_tcp(host: str, port: int, timeout: float = 2.0) -> None:
    """Fail fast if nothing listens (python-can's socketcand retries silently for 10 s)."""
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as exc:
        raise BusError(
            f"cannot open CAN bus: no hub at {host}:{port} ({exc.strerror or exc})"
        ) from None
