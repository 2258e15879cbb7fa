"""NMT master commands, drive heartbeat monitor, host heartbeat producer (CiA 301 §7.2.8).

Commands are sent by canopen's :class:`~canopen.nmt.NmtMaster` (``RemoteNode.nmt``; the codes
and state names are canopen's ``NMT_COMMANDS`` / ``NMT_STATES``). The node's *state* is kept
by our :class:`HeartbeatMonitor`, not by ``NmtMaster.state``, because under loss and latency
canopen's tracking does not do the job:

- ``NmtMaster.state`` is the last heartbeat, or the state the last *sent* command implies, for
  ever: a node that went silent still reads "OPERATIONAL"; there is no OFFLINE, and a command
  lost on the bus is reported as obeyed;
- ``wait_for_heartbeat`` / ``wait_for_bootup`` clear a flag and wait for the next frame, so a
  boot-up that arrives between the reset command and the wait is missed (we count boot-ups),
  and a heartbeat already in flight before a command counts as its confirmation (we require a
  heartbeat received *after* the command, :meth:`HeartbeatMonitor.wait_for`);
- a node without heartbeat (0x1017 = 0) has no state at all; we fall back to its TPDOs and
  SDO answers.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable

import can
import canopen
from canopen import nmt as _canopen_nmt

from ..errors import BusError, DriveError, DriveTimeout, SdoAbort

__all__ = [
    "DEFAULT_PERIOD",
    "FIRST_HEARTBEAT_WAIT_MAX",
    "NMT_COMMANDS",
    "NMT_STATES",
    "HeartbeatMonitor",
    "HeartbeatProducer",
    "send_command",
    "send_nmt",
]

#: Command name (as the CLI spells it) → NMT command specifier (canopen's codes).
NMT_COMMANDS: dict[str, int] = {
    name: _canopen_nmt.NMT_COMMANDS[key]
    for name, key in (
        ("start", "OPERATIONAL"),
        ("stop", "STOPPED"),
        ("pre-operational", "PRE-OPERATIONAL"),
        ("reset node", "RESET"),
        ("reset communication", "RESET COMMUNICATION"),
    )
}

#: Heartbeat state byte → name (canopen's names of the CiA 301 states).
NMT_STATES: dict[int, str] = {
    code: _canopen_nmt.NMT_STATES[code] for code in (0x00, 0x04, 0x05, 0x7F)
}


def send_command(master: canopen.nmt.NmtMaster, command: str) -> None:
    """Send an NMT command ("start", "stop", "pre-operational", "reset node",
    "reset communication") with canopen's ``NmtMaster`` (its node-ID; 0 = all nodes)."""
    try:
        cs = NMT_COMMANDS[command]
    except KeyError:
        raise ValueError(
            f"unknown NMT command {command!r}; one of {', '.join(NMT_COMMANDS)}"
        ) from None
    try:
        try:
            master.send_command(cs)
        except KeyError:  # canopen logs the old state by name: a heartbeat had an odd state byte
            master.network.send_message(0x000, bytes([cs, master.id]))
    except (can.CanError, RuntimeError) as exc:
        raise BusError(f"CAN send failed: {exc}") from None


def send_nmt(network: canopen.Network, command: str, node_id: int) -> None:
    """Send an NMT command to ``node_id`` (0 = all nodes) on ``network``; see
    :func:`send_command`."""
    master = _canopen_nmt.NmtMaster(node_id)
    master.network = network
    send_command(master, command)


#: Longest wait for a first heartbeat in a fresh session (s); a slower producer (0x1017 up to
#: 60 s) is covered by the SDO / PDO fallback of :meth:`HeartbeatMonitor.resolve`.
FIRST_HEARTBEAT_WAIT_MAX = 3.0
#: Period assumed while neither 0x1017 nor two heartbeats are known (s).
DEFAULT_PERIOD = 1.0


class HeartbeatMonitor:
    """Watches the heartbeat / boot-up frames (0x700 + N) of one node.

    ``state`` is the NMT state the node reports:

    - from its last heartbeat while heartbeats keep coming: a heartbeat is stale after
      max(``stale_factor`` × T, T + 1 s), T the producer period (0x1017, or the observed one),
      so a host that is busy for up to a second does not call a running node "OFFLINE";
    - in a fresh session (a one-shot CLI call) before the first heartbeat: it waits for one
      up to 1.5 × T + 0.3 s after the monitor started (T read from 0x1017 once, the wait capped
      at :data:`FIRST_HEARTBEAT_WAIT_MAX`);
    - with no heartbeat at all (0x1017 = 0, or a slow producer): "OPERATIONAL" if the node's
      TPDOs (default COB-IDs 0x180/0x280/0x380/0x480 + N, sent only in OPERATIONAL) arrive
      while it waits (at least 0.25 s), else "PRE-OPERATIONAL" if the node answers SDO (aborts
      included: SDO is served in PRE-OPERATIONAL and OPERATIONAL, CiA 301 §7.3.2.2), else
      "OFFLINE". This fallback answer is kept for 1 s.

    The SDO look-ups need :meth:`attach_reader`; without it only heartbeats count.
    """

    def __init__(self, network: canopen.Network, node_id: int, stale_factor: float = 3.0):
        self.node_id = node_id
        self.cob_id = 0x700 + node_id
        self.stale_factor = stale_factor
        self._network = network
        self._cond = threading.Condition()
        self.started = time.monotonic()
        self.last_state: int | None = None
        self.last_time: float | None = None  # time.monotonic()
        self.period: float | None = None  # s, smoothed interval between heartbeats
        self.producer_time: float | None = None  # s, 0x1017 as read (0 = off), None = unknown
        self.pdo_count = 0  # TPDOs received from the node (default COB-IDs)
        self.boot_count = 0
        self.count = 0
        self.arrivals: deque[float] = deque(maxlen=256)  # monotonic times of recent heartbeats
        self._read: Callable[[str], float | int | str | bytes] | None = None
        self._fallback: tuple[float, str] | None = None  # (monotonic time, state) without heartbeat
        self._pdo_cobs = tuple(base + node_id for base in (0x180, 0x280, 0x380, 0x480))
        network.subscribe(self.cob_id, self._on_frame)
        for cob in self._pdo_cobs:
            network.subscribe(cob, self._on_pdo)

    def attach_reader(self, read: Callable[[str], float | int | str | bytes]) -> None:
        """Let the monitor read objects by name (``Drive.read``): 0x1017 for the first-heartbeat
        wait and device_type as the "answers SDO" probe."""
        self._read = read

    def close(self) -> None:
        """Stop listening."""
        subs = [(self.cob_id, self._on_frame)] + [(c, self._on_pdo) for c in self._pdo_cobs]
        for cob, cb in subs:
            try:
                self._network.unsubscribe(cob, cb)
            except (KeyError, ValueError):
                pass

    def _on_pdo(self, can_id: int, data: bytearray, timestamp: float) -> None:
        self.pdo_count += 1  # no clock read: up to thousands of TPDOs/s

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

    def _expected_period(self) -> float:
        """T in s: the larger of 0x1017 (if read and on) and the observed period."""
        known = [p for p in (self.producer_time, self.period) if p]
        return max(known) if known else DEFAULT_PERIOD

    def stale_after(self) -> float:
        """Seconds without a heartbeat after which the node counts as "OFFLINE"."""
        t = self._expected_period()
        return max(self.stale_factor * t, t + 1.0)

    def _heartbeat_state(self) -> str | None:
        """State from heartbeats ("OFFLINE" when they stopped), None if none was ever seen."""
        with self._cond:
            if self.last_time is None:
                return None
            if time.monotonic() - self.last_time > self.stale_after():
                return "OFFLINE"
            return NMT_STATES.get(self.last_state or 0, f"0x{self.last_state:02X}")

    def _read_producer_time(self) -> None:
        if self.producer_time is not None or self._read is None:
            return
        try:
            ms = self._read("producer_heartbeat_time")
            self.producer_time = int(ms) / 1000.0
        except (DriveError, KeyError, ValueError, TypeError):
            pass

    def _answers_sdo(self) -> bool:
        if self._read is None:
            return False
        try:
            self._read("device_type")
        except SdoAbort:
            return True  # an abort is an answer
        except (DriveError, KeyError):
            return False
        return True

    def resolve(self) -> str:
        """The node's NMT state (see the class docstring); may wait for a first heartbeat and
        read by SDO (never while holding the lock: the answers come on the notifier thread)."""
        st = self._heartbeat_state()
        if st is not None:
            return st
        cached = self._fallback
        if cached is not None and time.monotonic() - cached[0] < 1.0:
            return cached[1]
        st = self._resolve_without_heartbeat()
        if self.last_time is None:  # still no heartbeat: the answer came from the fallback
            self._fallback = (time.monotonic(), st)
        return st

    def _resolve_without_heartbeat(self) -> str:
        pdos = self.pdo_count
        self._read_producer_time()  # SDO, outside the lock
        t = self.producer_time
        window = min(1.5 * (t or DEFAULT_PERIOD) + 0.3, FIRST_HEARTBEAT_WAIT_MAX) if t != 0 else 0.0
        now = time.monotonic()
        deadline = max(self.started + window, now + 0.25) if self.pdo_count == pdos else now
        with self._cond:
            while self.last_time is None:
                left = deadline - time.monotonic()
                if left <= 0:
                    break
                self._cond.wait(left)
        st = self._heartbeat_state()
        if st is not None:
            return st
        if self.pdo_count > pdos:
            return "OPERATIONAL"
        return "PRE-OPERATIONAL" if self._answers_sdo() else "OFFLINE"

    @property
    def state(self) -> str:
        """NMT state name (see :meth:`resolve`)."""
        return self.resolve()

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
