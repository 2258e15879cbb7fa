"""The host's side of the heartbeat protocol for one session: its own heartbeat producer, the
drive's consumer time for it (0x1016 sub1) and NMT commands confirmed by the drive's heartbeat.

:class:`HostHeartbeat` owns the producer (0x700 + ``host_id``, state OPERATIONAL, CiA 301
§7.2.8.3.2) and whether this session configured the drive's consumer;
:func:`confirm_nmt` repeats an unconfirmed NMT command until a heartbeat reports its state.
"""

from __future__ import annotations

import time

import can
import canopen

from ..errors import DriveTimeout, InvalidValue, StateError
from ._nmt import HeartbeatMonitor, HeartbeatProducer, send_command

__all__ = [
    "CONSUMER_MIN_MS",
    "FIRST_HEARTBEAT_S",
    "NMT_CONFIRM",
    "HostHeartbeat",
    "confirm_nmt",
]

CONSUMER_MIN_MS = 1000
"""Shortest default heartbeat consumer time (ms) :meth:`Drive.configure_heartbeat_consumer`
sets: max(CONSUMER_MIN_MS, 3 x the host producer period). 3 x 100 ms was too tight: at load 25
the host's producer thread stalled > 300 ms and the drive quick-stopped with the host alive."""
#: NMT commands confirmed by the next heartbeat, and the state it must report
NMT_CONFIRM = {"start": "OPERATIONAL", "stop": "STOPPED", "pre-operational": "PRE-OPERATIONAL"}
#: How long Drive.nmt waits for the drive's first heartbeat before it can confirm a command, s.
FIRST_HEARTBEAT_S = 1.5


class HostHeartbeat:
    """This host's heartbeat producer on ``bus`` (extra beats sent through ``network``)."""

    def __init__(self, network: canopen.Network, bus: can.BusABC) -> None:
        self._network = network
        self._bus = bus
        self._producer: HeartbeatProducer | None = None
        #: node-ID of the host heartbeat (0x700 + host_id); None: none produced yet
        self.host_id: int | None = None
        #: True once this session set the drive's consumer for it (undone on close)
        self.consumer_configured = False

    @property
    def producing(self) -> bool:
        """True while the periodic heartbeat runs."""
        return self._producer is not None and self.host_id is not None

    def start(self, host_id: int, period_ms: int) -> None:
        """Produce the heartbeat of ``host_id`` every ``period_ms`` ms."""
        self.host_id = host_id
        self._producer = HeartbeatProducer(self._bus, host_id, int(period_ms))

    def send_now(self) -> None:
        """One heartbeat now (besides the periodic ones), if this host produces one."""
        if self._producer is None or self.host_id is None:
            return
        self._network.send_message(0x700 + self.host_id, bytes([0x05]))

    def restart(self) -> None:
        """Start the heartbeat again (its periodic task may have died with a bus error)."""
        if self._producer is None or self.host_id is None:
            return
        period = self._producer.period_ms
        self._producer.stop()
        self._producer = HeartbeatProducer(self._bus, self.host_id, period)

    def stop(self) -> None:
        """Stop producing."""
        if self._producer:
            self._producer.stop()
            self._producer = None

    def consumer_entry(self, timeout_ms: int | None = None) -> int:
        """The drive's 0x1016 sub1 value watching this host: ``host_id << 16 | time`` with
        ``timeout_ms`` (default max(:data:`CONSUMER_MIN_MS`, 3 × the producer period)).
        :class:`StateError` without a producer, :class:`InvalidValue` outside 1..65535 ms."""
        if self._producer is None or self.host_id is None:
            raise StateError("no host heartbeat is produced (connect with heartbeat_ms)")
        default = max(CONSUMER_MIN_MS, 3 * self._producer.period_ms)
        t = int(timeout_ms if timeout_ms is not None else default)
        if not 0 < t <= 0xFFFF:
            raise InvalidValue(f"heartbeat consumer time {t} ms outside 1..65535")
        return (self.host_id << 16) | t


def confirm_nmt(
    master: canopen.nmt.NmtMaster, heartbeat: HeartbeatMonitor, command: str, node_id: int
) -> None:
    """Send ``command`` with ``master`` and, for start/stop/pre-operational, repeat it until a
    heartbeat sent after it reports the target state (:class:`DriveTimeout` otherwise). An NMT
    command has no answer (CiA 301): on a lossy bus it is lost silently; it is idempotent in
    its target state. Resets are confirmed by the boot-up (the caller waits for it)."""
    send_command(master, command)
    target = NMT_CONFIRM.get(command)
    if target is None:
        return
    if not heartbeat.last_time:
        # a one-shot command may run before the drive's first heartbeat arrived: wait for
        # one (a producer time is at most about 1 s in practice); none → nothing confirms
        try:
            heartbeat.wait_for(tuple(NMT_CONFIRM.values()), FIRST_HEARTBEAT_S)
        except DriveTimeout:
            return
    period = heartbeat.producer_time or 0.1
    deadline = time.monotonic() + max(3.0, 6 * period)
    while True:
        sent = time.monotonic()
        try:
            heartbeat.wait_for((target,), max(0.3, 2.5 * period), after=sent)
            return
        except DriveTimeout:
            if time.monotonic() >= deadline:
                raise DriveTimeout(
                    f"node {node_id}: NMT {command} not confirmed by a heartbeat "
                    f"reporting {target} within {deadline - sent + 2.5 * period:.1f} s"
                ) from None
        send_command(master, command)
