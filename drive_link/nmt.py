"""NMT master commands, drive heartbeat monitor, host heartbeat producer (CiA 301 §7.2.8)."""

from __future__ import annotations

import threading
import time
from collections import deque

import can
import canopen

from .errors import BusError, DriveTimeout

#: NMT command specifiers.
NMT_COMMANDS: dict[str, int] = {
    "start": 0x01,  # → OPERATIONAL
    "stop": 0x02,  # → STOPPED
    "pre-operational": 0x80,
    "reset node": 0x81,
    "reset communication": 0x82,
}

#: Heartbeat state byte → name.
NMT_STATES: dict[int, str] = {
    0x00: "INITIALISING",
    0x04: "STOPPED",
    0x05: "OPERATIONAL",
    0x7F: "PRE-OPERATIONAL",
}


def send_nmt(network: canopen.Network, command: str, node_id: int) -> None:
    """Send an NMT command ("start", "stop", "pre-operational", "reset node",
    "reset communication") to ``node_id`` (0 = all nodes)."""
    try:
        cs = NMT_COMMANDS[command]
    except KeyError:
        raise ValueError(
            f"unknown NMT command {command!r}; one of {', '.join(NMT_COMMANDS)}"
        ) from None
    try:
        network.send_message(0x000, bytes([cs, node_id]))
    except (can.CanError, RuntimeError) as exc:
        raise BusError(f"CAN send failed: {exc}") from None


class HeartbeatMonitor:
    """Watches the heartbeat / boot-up frames (0x700 + N) of one node.

    ``state`` is the last reported NMT state, or "OFFLINE" when no heartbeat arrived within
    ``stale_factor`` × the observed period (or 1 s before a period is known).
    """

    def __init__(self, network: canopen.Network, node_id: int, stale_factor: float = 3.0):
        self.node_id = node_id
        self.cob_id = 0x700 + node_id
        self.stale_factor = stale_factor
        self._network = network
        self._cond = threading.Condition()
        self.last_state: int | None = None
        self.last_time: float | None = None  # time.monotonic()
        self.period: float | None = None  # s, smoothed interval between heartbeats
        self.boot_count = 0
        self.count = 0
        self.arrivals: deque[float] = deque(maxlen=256)  # monotonic times of recent heartbeats
        network.subscribe(self.cob_id, self._on_frame)

    def close(self) -> None:
        """Stop listening."""
        try:
            self._network.unsubscribe(self.cob_id, self._on_frame)
        except (KeyError, ValueError):
            pass

    def _on_frame(self, can_id: int, data: bytearray, timestamp: float) -> None:
        if not data:
            return
        now = time.monotonic()
        with self._cond:
            state = data[0] & 0x7F
            if state == 0x00:
                self.boot_count += 1
            elif self.last_time is not None and self.last_state not in (None, 0x00):
                dt = now - self.last_time
                self.period = dt if self.period is None else 0.8 * self.period + 0.2 * dt
            self.last_state = state
            self.last_time = now
            self.count += 1
            self.arrivals.append(now)
            self._cond.notify_all()

    @property
    def state(self) -> str:
        """NMT state name from the last heartbeat, or "OFFLINE"."""
        with self._cond:
            if self.last_time is None:
                return "OFFLINE"
            limit = max(
                self.stale_factor * (self.period or 0.0), 1.0 if self.period is None else 0.05
            )
            if time.monotonic() - self.last_time > limit:
                return "OFFLINE"
            return NMT_STATES.get(self.last_state or 0, f"0x{self.last_state:02X}")

    def wait_for(self, states: tuple[str, ...], timeout: float, after: float | None = None) -> str:
        """Wait until a heartbeat (received after monotonic time ``after``) reports one of
        ``states``; raise :class:`DriveTimeout` otherwise."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while True:
                fresh = self.last_time is not None and (after is None or self.last_time >= after)
                if fresh:
                    name = NMT_STATES.get(self.last_state or 0, "?")
                    if name in states:
                        return name
                left = deadline - time.monotonic()
                if left <= 0:
                    raise DriveTimeout(
                        f"node {self.node_id}: no heartbeat reporting {' or '.join(states)} "
                        f"within {timeout:g} s"
                    )
                self._cond.wait(left)

    def wait_boot(self, timeout: float, boots_before: int) -> None:
        """Wait for a boot-up frame (count above ``boots_before``)."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while self.boot_count <= boots_before:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise DriveTimeout(
                        f"node {self.node_id}: no boot-up message within {timeout:g} s"
                    )
                self._cond.wait(left)


class HeartbeatProducer:
    """Sends the host's own heartbeat (0x700 + host_id, state OPERATIONAL) every ``period_ms``."""

    def __init__(self, bus: can.BusABC, host_id: int, period_ms: int):
        if not 1 <= host_id <= 127:
            raise ValueError("host heartbeat node-ID must be 1..127")
        if period_ms <= 0:
            raise ValueError("heartbeat period must be > 0 ms")
        self.host_id = host_id
        self.period_ms = period_ms
        msg = can.Message(arbitration_id=0x700 + host_id, data=[0x05], is_extended_id=False)
        try:
            self._task = bus.send_periodic(msg, period_ms / 1000.0)
        except (can.CanError, OSError) as exc:
            raise BusError(f"cannot start host heartbeat: {exc}") from None

    def stop(self) -> None:
        """Stop sending."""
        try:
            self._task.stop()
        except Exception:
            pass
