"""Health of the CAN controller behind a python-can bus: error frames and bus state.

SocketCAN delivers the controller's error reports as error frames (``is_error_frame``; python-can
enables them on its socketcan bus unless ``ignore_rx_error_frames``): the error class is in the
CAN-ID (``linux/can/error.h``: 0x40 bus-off, 0x100 restarted, 0x04 controller problem with the
details in data byte 1). Other python-can backends report the state through ``bus.state`` when
they implement it. Names follow docs/contracts.md: ``ERROR_ACTIVE``, ``ERROR_PASSIVE``,
``BUS_OFF``, ``UNKNOWN``.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import threading

import can

__all__ = [
    "BUS_OFF",
    "ERROR_ACTIVE",
    "ERROR_PASSIVE",
    "UNKNOWN",
    "BusHealth",
    "socketcan_link_state",
    "state_from_error_frame",
]

ERROR_ACTIVE = "ERROR_ACTIVE"
ERROR_PASSIVE = "ERROR_PASSIVE"
BUS_OFF = "BUS_OFF"
UNKNOWN = "UNKNOWN"

# linux/can/error.h: error class (in the CAN-ID) and controller status (data[1])
CAN_ERR_CRTL = 0x004
CAN_ERR_BUSOFF = 0x040
CAN_ERR_RESTARTED = 0x100
CAN_ERR_CRTL_RX_WARNING = 0x04
CAN_ERR_CRTL_TX_WARNING = 0x08
CAN_ERR_CRTL_RX_PASSIVE = 0x10
CAN_ERR_CRTL_TX_PASSIVE = 0x20
CAN_ERR_CRTL_ACTIVE = 0x40

#: ``ip -details link`` CAN state → our name.
_IP_STATES = {
    "ERROR-ACTIVE": ERROR_ACTIVE,
    "ERROR-WARNING": ERROR_ACTIVE,  # still error active, counters above 96
    "ERROR-PASSIVE": ERROR_PASSIVE,
    "BUS-OFF": BUS_OFF,
}


def state_from_error_frame(msg: can.Message) -> str | None:
    """Bus state an error frame reports, or None if it does not report a state change."""
    cls = msg.arbitration_id
    if cls & CAN_ERR_BUSOFF:
        return BUS_OFF
    if cls & CAN_ERR_RESTARTED:
        return ERROR_ACTIVE
    if cls & CAN_ERR_CRTL and len(msg.data) > 1:
        d1 = msg.data[1]
        if d1 & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE):
            return ERROR_PASSIVE
        if d1 & (CAN_ERR_CRTL_ACTIVE | CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING):
            return ERROR_ACTIVE
    return None


def socketcan_link_state(channel: str, timeout: float = 5.0) -> str:
    """State of a SocketCAN interface from ``ip -details -json link show``: the controller's
    state for a real CAN device, ``ERROR_ACTIVE`` for an up virtual one (vcan/vxcan have no
    error states), ``UNKNOWN`` otherwise (down, no ``ip``, not a CAN link)."""
    ip = shutil.which("ip") or next(
        (p for p in ("/usr/sbin/ip", "/sbin/ip", "/usr/bin/ip") if os.path.exists(p)), None
    )
    if ip is None or not channel:
        return UNKNOWN
    try:
        out = subprocess.run(
            [ip, "-details", "-json", "link", "show", "dev", str(channel)],
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        link = json.loads(out.stdout)[0]
    except (OSError, subprocess.SubprocessError, ValueError, IndexError, KeyError):
        return UNKNOWN
    info = link.get("linkinfo", {})
    can_state = info.get("info_data", {}).get("state")
    if can_state:
        return _IP_STATES.get(can_state, UNKNOWN)
    if info.get("info_kind") in ("vcan", "vxcan") and "UP" in link.get("flags", []):
        return ERROR_ACTIVE
    return UNKNOWN


def _reports_state(bus: can.BusABC) -> bool:
    """Whether the backend implements ``bus.state`` (the base class only returns ACTIVE)."""
    return type(bus).state is not can.BusABC.state


class BusHealth(can.Listener):
    """Counts error frames and tracks the bus state (thread-safe; add to the bus's Notifier).

    :attr:`state` is, in this order: the last state an error frame reported; the backend's
    ``bus.state`` if it implements one; for SocketCAN the interface's state as ``ip`` shows
    it (looked up once); else ``UNKNOWN``.
    """

    def __init__(self, bus: can.BusABC):
        self._bus = bus
        self._lock = threading.Lock()
        self.error_frames = 0
        self._frame_state: str | None = None
        self._link_state: str | None = None

    def on_message_received(self, msg: can.Message) -> None:
        if not msg.is_error_frame:
            return
        st = state_from_error_frame(msg)
        with self._lock:
            self.error_frames += 1
            if st is not None:
                self._frame_state = st

    @property
    def state(self) -> str:
        """"ERROR_ACTIVE", "ERROR_PASSIVE", "BUS_OFF" or "UNKNOWN"."""
        with self._lock:
            if self._frame_state is not None:
                return self._frame_state
        bus = self._bus
        if _reports_state(bus):
            try:
                st = bus.state
            except Exception:
                return UNKNOWN
            return {
                can.BusState.ACTIVE: ERROR_ACTIVE,
                can.BusState.PASSIVE: ERROR_PASSIVE,
                can.BusState.ERROR: BUS_OFF,
            }.get(st, UNKNOWN)
        if type(bus).__name__ == "SocketcanBus":
            if self._link_state is None:
                self._link_state = socketcan_link_state(str(getattr(bus, "channel", "")))
            return self._link_state
        return UNKNOWN

    def snapshot(self) -> dict[str, str | int]:
        """``{"bus_state": ..., "bus_error_frames": ...}`` for :meth:`Drive.status`."""
        return {"bus_state": self.state, "bus_error_frames": self.error_frames}
