"""Heartbeat producer (0x1017) and consumer (0x1016), CiA 301 §7.2.8.3.2.

Both are driven by :meth:`tick` from the node's pacing loop with a wall-clock time in seconds
(``time.monotonic()``), so their resolution is the loop period (1 ms). Received heartbeats only
record a time stamp on the notifier thread.

Consumer entries are U32: node-ID in bits 23..16, consumer time in ms in bits 15..0; time 0 or
node-ID 0 disables the entry. Monitoring of a node starts with the first heartbeat received from
it; when no heartbeat arrives within the consumer time the ``on_timeout(node_id)`` hook runs once,
and ``on_resume(node_id)`` runs when heartbeats come back.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass

__all__ = [
    "HeartbeatConsumer",
    "HeartbeatProducer",
    "decode_consumer_entry",
    "encode_consumer_entry",
]

logger = logging.getLogger(__name__)


def decode_consumer_entry(value: int) -> tuple[int, int]:
    """0x1016 sub-entry → ``(node_id, time_ms)``."""
    return (value >> 16) & 0xFF, value & 0xFFFF


def encode_consumer_entry(node_id: int, time_ms: int) -> int:
    """``(node_id, time_ms)`` → 0x1016 sub-entry value."""
    return ((node_id & 0xFF) << 16) | (time_ms & 0xFFFF)


class HeartbeatProducer:
    """Sends ``[nmt_state]`` on 0x700+N every ``period_ms`` (0 = off).

    ``send_at(cob_id, data, at)``, when given, sends it with its due time ``at`` (monotonic s)
    as its bus time, in the batch of a drive whose TPDOs carry theirs (the loopback hub): a
    heartbeat sent at once would reach the bus ahead of TPDOs due before it that are still
    waiting for the tick's write, and push them back."""

    def __init__(
        self,
        node_id: int,
        send: Callable[[int, bytes], None],
        state: Callable[[], int],
        send_at: Callable[[int, bytes, float], None] | None = None,
    ):
        self.node_id = node_id
        self._send = send
        self._send_at = send_at
        self._state = state
        self.period_ms = 0
        self._next = 0.0

    def set_period(self, period_ms: int, now: float) -> None:
        """Change the period (ms); the next heartbeat goes out one new period from ``now``."""
        self.period_ms = int(period_ms)
        self._next = now + self.period_ms / 1000.0

    def tick(self, now: float) -> None:
        if self.period_ms <= 0 or now < self._next:  # (called every pacing tick: cheap first)
            return
        state = self._state()
        if state == 0:  # INITIALISING: no heartbeat
            return
        if self._send_at is not None:
            self._send_at(0x700 + self.node_id, bytes([state]), self._next)
        else:
            self._send(0x700 + self.node_id, bytes([state]))
        period = self.period_ms / 1000.0
        self._next += period
        if self._next <= now:  # fell behind (e.g. paused): no burst of catch-up frames
            self._next = now + period


@dataclass
class _Watch:
    node_id: int
    time_ms: int
    last: float | None = None
    timed_out: bool = False


class HeartbeatConsumer:
    """Watches other nodes' heartbeats.

    :param subscribe: ``subscribe(cob_id, callback)`` on the network.
    :param unsubscribe: ``unsubscribe(cob_id, callback)``.
    :param on_timeout: called with the node-ID when its heartbeat is lost.
    :param on_resume: called with the node-ID when it comes back after a loss.
    """

    def __init__(
        self,
        subscribe: Callable,
        unsubscribe: Callable,
        on_timeout: Callable[[int], None],
        on_resume: Callable[[int], None] = lambda node_id: None,
        clock: Callable[[], float] | None = None,
    ) -> None:
        import time

        self._subscribe = subscribe
        self._unsubscribe = unsubscribe
        self._on_timeout = on_timeout
        self._on_resume = on_resume
        self._clock = clock or time.monotonic
        self._watches: dict[int, _Watch] = {}
        self._lock = threading.Lock()

    @staticmethod
    def validate(entries: list[int]) -> None:
        """Raise ValueError when two active entries watch the same node (abort 0x06040043)."""
        seen = set()
        for value in entries:
            node_id, time_ms = decode_consumer_entry(value)
            if node_id == 0 or time_ms == 0:
                continue
            if node_id in seen:
                raise ValueError(f"node {node_id} is monitored twice")
            seen.add(node_id)

    def configure(self, entries: list[int]) -> None:
        """Replace the monitored set with the 0x1016 sub-entries ``entries``."""
        self.validate(entries)
        wanted = {}
        for value in entries:
            node_id, time_ms = decode_consumer_entry(value)
            if node_id and time_ms:
                wanted[node_id] = time_ms
        with self._lock:
            for node_id in list(self._watches):
                if node_id not in wanted:
                    self._unsubscribe(0x700 + node_id, self._on_frame)
                    del self._watches[node_id]
            for node_id, time_ms in wanted.items():
                watch = self._watches.get(node_id)
                if watch is None:
                    self._watches[node_id] = _Watch(node_id, time_ms)
                    self._subscribe(0x700 + node_id, self._on_frame)
                else:
                    watch.time_ms = time_ms

    def clear(self) -> None:
        self.configure([])

    def _on_frame(self, can_id: int, data: bytes, timestamp: float) -> None:
        watch = self._watches.get(can_id - 0x700)
        if watch is None:
            return
        watch.last = self._clock()
        if watch.timed_out:
            watch.timed_out = False
            logger.info("heartbeat of node %d is back", watch.node_id)
            self._on_resume(watch.node_id)

    def tick(self, now: float) -> None:
        if not self._watches:  # (called every pacing tick: nothing to copy when none is set)
            return
        for watch in list(self._watches.values()):
            if watch.last is None or watch.timed_out:
                continue
            if now - watch.last > watch.time_ms / 1000.0:
                watch.timed_out = True
                logger.warning(
                    "heartbeat of node %d lost (%.1f ms > %d ms)",
                    watch.node_id,
                    (now - watch.last) * 1e3,
                    watch.time_ms,
                )
                self._on_timeout(watch.node_id)

    @property
    def lost(self) -> list[int]:
        """Node-IDs whose heartbeat is currently lost."""
        return [w.node_id for w in self._watches.values() if w.timed_out]
