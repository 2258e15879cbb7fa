"""The emulated CAN buses of the loopback hub (:mod:`virtual_drive.hub`) and the clients on them.

A :class:`Bus` (one socketcand channel) owns its timing: the frames its clients have waiting,
arbitration (lowest identifier wins among the oldest pending frame of each client, so each
sender's order is kept), the time each frame occupies it (:func:`firmware_protocol.can_bits.
frame_bits_fast` ``/ bitrate``), its recent occupancy (a ``sendat`` frame stated in the past
takes an idle gap of then), the spacing of each sender's frames of one CAN-ID, and the delivery
of completed frames to every other client, at the time :class:`~virtual_drive.hub_faults.
FaultInjection` gives. A :class:`Client` is one connection: its socket and session (the hub's
fields) and its queue, spacing and output buffer (the bus's fields). :class:`HubCounters` holds
the frame counts all buses of one hub add to. Only the hub's thread calls any of this: no locks.
"""

from __future__ import annotations

import socket
from bisect import bisect_right
from collections import deque
from collections.abc import Sequence
from typing import TypeAlias

from firmware_protocol.can_bits import arbitration_key, frame_bits_fast
from virtual_drive.hub_faults import FaultInjection
from virtual_drive.hub_protocol import CommandSplitter, frame_line, rtr_line

__all__ = [
    "CLOSED",
    "RAW",
    "SPACING_HOLD_S",
    "WAIT_MODE",
    "WAIT_OPEN",
    "Bus",
    "Client",
    "Delivery",
    "HubCounters",
    "QueuedFrame",
    "idle_gap",
    "spacing_floor",
]

#: a frame waiting for the bus: (arrival, arbitration key, sequence, CAN-ID, data (bytes, or the
#: DLC of a remote frame), is_extended, bits on the bus, stated time); times monotonic s
QueuedFrame: TypeAlias = tuple[float, int, int, int, "bytes | int", bool, int, float]
#: a frame that completed on the bus: (due, sender, CAN-ID, data or DLC, is_extended)
Delivery: TypeAlias = "tuple[float, Client, int, bytes | int, bool]"

#: session states of a client: waiting for ``< open BUS >``, for ``< rawmode >``, in rawmode,
#: closed
WAIT_OPEN, WAIT_MODE, RAW, CLOSED = range(4)


class Client:
    """A connected socketcand client (see the module docstring for who owns which field)."""

    __slots__ = (
        "bus",
        "bus_end",
        "errors",
        "events",
        "fd",
        "outbuf",
        "parses_elements",
        "peer",
        "queue",
        "ready_at",
        "sock",
        "spacing",
        "splitter",
        "state",
    )

    def __init__(self, sock: socket.socket, peer: tuple[str, int]) -> None:
        self.sock = sock
        self.fd = sock.fileno()
        self.events = 0  # epoll events registered for it
        self.peer = peer
        self.state = WAIT_OPEN
        self.splitter = CommandSplitter()
        self.outbuf = bytearray()
        self.ready_at = 0.0  # monotonic time before which frames are held back (see Hub)
        self.parses_elements = False  # asked < features >: takes frames glued to < ok >
        #: (arrival, key, seq, id, data, ext, bits, stated time) waiting for the bus
        self.queue: deque[QueuedFrame] = deque()
        self.bus: Bus | None = None
        self.bus_end = 0.0  # monotonic time its last frame left the bus
        self.errors = 0
        #: CAN-ID -> (stated time, end on the bus, stated gap to the one before or None) of
        #: this client's last frame with that ID: see :func:`spacing_floor`
        self.spacing: dict[int, tuple[float, float, float | None]] = {}

    def on_bus(self) -> Bus:
        """Its bus (set at ``< open BUS >``, so always there in rawmode)."""
        bus = self.bus
        if bus is None:
            raise RuntimeError(f"client {self.peer} has not opened a bus")
        return bus


class HubCounters:
    """Frame counts of one hub, added to by all its buses (since the hub was made)."""

    __slots__ = ("busy_s", "dropped", "forwarded", "late", "overrun", "received")

    def __init__(self) -> None:
        self.received = 0  #: valid frames received from clients
        #: ``sendat`` frames that reached the hub more than SPACING_HOLD_S after their stated
        #: time (the host stalled their sender or the hub): past the hold, their spacing on the
        #: bus is no longer the sender's
        self.late = 0
        self.forwarded = 0  #: frames that completed on the bus and went to the other clients
        self.dropped = 0  #: frames lost by fault injection
        self.overrun = 0  #: frame copies not queued because a client's output buffer was full
        self.busy_s = 0.0  #: emulated bus time used by frames, s


#: intervals a late ``sendat`` frame looks past for an idle gap before it waits for the bus
#: (a bus full since its stated time has no gap: the search ends there, not at the backlog's end)
_GAP_SCAN = 32

#: longest a frame is held past its arrival to keep its sender's spacing (s): several frame
#: times at 125 kbit/s, so arbitration delays never shorten a gap; no persistent lag
SPACING_HOLD_S = 0.005

_NO_CLIENTS: tuple[Client, ...] = ()


def idle_gap(bus: Bus, t: float, duration: float) -> tuple[int, float] | None:
    """``(index, start)`` of an idle stretch of ``duration`` s at or after ``t`` (monotonic s)
    that ends before the bus's :attr:`Bus.free_at`, in its occupancy; None: no such stretch
    within :data:`_GAP_SCAN` frames."""
    starts, ends = bus.busy_start, bus.busy_end
    i = bisect_right(ends, t)  # the first frame still on the bus after t
    n = len(starts)
    limit = bus.free_at
    for _ in range(_GAP_SCAN):
        if t + duration > limit:
            return None
        if i >= n or starts[i] >= t + duration:
            return i, t
        t = ends[i]
        i += 1
    return None


def spacing_floor(client: Client, head: QueuedFrame, bitrate: float) -> float:
    """Earliest start (monotonic s) of ``client``'s queue head that keeps it as far after its
    last frame with the same CAN-ID, end to end on the bus, as the smaller of the two last
    stated gaps (its own and the previous one): a sender's spacing (a TPDO's inhibit time)
    is not eaten by arbitration delays (a frame held back one frame time while the next one
    goes on time, or a late batch moved up to the backdate limit in one piece). Both stated
    gaps are at least the sender's minimum, so their minimum is a spacing it asked for; a
    longer gap (after a pause) lets a delay recover. 0: no earlier frame with that ID. Plain
    ``send`` frames are stated at their arrival."""
    last = client.spacing.get(head[3])
    if last is None:
        return 0.0
    gap = head[7] - last[0]
    keep = gap if last[2] is None or gap < last[2] else last[2]
    floor = last[1] + keep - head[6] / bitrate
    # held back at most SPACING_HOLD_S past its arrival: an arbitration delay is a few frame
    # times; a longer hold would stay with every later frame of a stream at its minimum
    # spacing (and everything the sender queues behind it)
    return floor if floor - head[0] <= SPACING_HOLD_S else 0.0


def _head_arrival(client: Client) -> float:
    return client.queue[0][0]


class Bus:
    """One emulated CAN bus (one socketcand channel) of a hub.

    bitrate: bit/s; faults: the hub's fault injection; counters: the hub's frame counts;
    wall_offset: Unix time minus monotonic time of the hub (the frames' timestamps).
    """

    __slots__ = (
        "_bitrate",
        "_counters",
        "_faults",
        "_mono_offset",
        "_seq",
        "_wall_offset",
        "busy_end",
        "busy_start",
        "deliveries",
        "free_at",
        "last_due",
        "name",
        "receivers",
        "senders",
    )

    def __init__(
        self,
        name: str,
        bitrate: int,
        faults: FaultInjection,
        counters: HubCounters,
        wall_offset: float,
        mono_offset: float,
    ) -> None:
        self.name = name
        self.receivers: list[Client] = []  # clients in rawmode
        self.senders: list[Client] = []  # clients with frames waiting for the bus
        self.free_at = 0.0  # monotonic time the bus becomes idle
        self.deliveries: deque[Delivery] = deque()  # due non-decreasing
        self.last_due = 0.0
        #: the bus's recent occupancy: frame i was on it from busy_start[i] to busy_end[i]
        #: (monotonic s, sorted, never overlapping; the last max_backdate_s are kept), so a
        #: frame stated in the past can take an idle gap of then (see :meth:`advance`)
        self.busy_start: list[float] = []
        self.busy_end: list[float] = []
        self._bitrate = bitrate
        self._faults = faults
        self._counters = counters
        self._wall_offset = wall_offset
        self._mono_offset = mono_offset
        self._seq = 0  # arrival order of the frames queued on this bus (arbitration ties)

    # ---------------------------------------------------------------- clients

    def join(self, client: Client) -> None:
        """``client`` (in rawmode) receives the frames other clients send on this bus."""
        self.receivers.append(client)

    def leave(self, client: Client) -> None:
        """``client`` receives no more frames (the frames it sent stay queued: they were on
        their way to the bus)."""
        if client in self.receivers:
            self.receivers.remove(client)

    def pending(self) -> int:
        """Frames received and not yet forwarded or dropped."""
        return len(self.deliveries) + sum(len(c.queue) for c in list(self.senders))

    # ---------------------------------------------------------------- frames in

    def enqueue(
        self,
        client: Client,
        frames: list[tuple[int, bytes, bool]] | list[tuple[int, int, bool]],
        now: float,
    ) -> None:
        """Queue ``frames`` (id, data or a remote frame's DLC, is_extended) of ``client`` for the
        bus, arrived ``now``."""
        self._queue(client, [(now, can_id, data, ext) for can_id, data, ext in frames])

    def enqueue_timed(
        self,
        client: Client,
        frames: list[tuple[float, int, bytes, bool]],
        now: float,
        max_backdate_s: float,
    ) -> None:
        """Queue ``sendat`` frames ``(unix_time, id, data, is_extended)``: each arrives at its
        stated time, but never before a frame of this client still waiting for the bus (its
        order is kept), never more than ``max_backdate_s`` ago and never after ``now`` (see
        :mod:`virtual_drive.hub_protocol`). A frame of the client that is already on the bus
        does not hold it back: it starts when the bus is free, as a CAN controller's other
        transmit mailbox would."""
        queue = client.queue
        lo = now - max_backdate_s
        if queue and queue[-1][0] > lo:
            lo = queue[-1][0]
        mono_offset = self._mono_offset
        if frames and now - (frames[0][0] + mono_offset) > SPACING_HOLD_S:  # (in stated order)
            late = now - SPACING_HOLD_S - mono_offset
            self._counters.late += sum(1 for f in frames if f[0] < late)
        timed = []
        # a batch stated before the backdate limit moves up as a whole, keeping its spacing
        # (one frame at the limit, the rest after it as stated), not all onto the limit
        shift = max(0.0, lo - (frames[0][0] + mono_offset)) if frames else 0.0
        for stamp, can_id, data, ext in frames:
            stated = stamp + mono_offset
            arrival = stated + shift
            if arrival < lo:
                arrival = lo
            elif arrival > now:
                arrival = now
            lo = arrival
            timed.append((arrival, can_id, data, ext, stated))
        self._queue(client, timed)

    def _queue(
        self,
        client: Client,
        frames: Sequence[tuple[float, int, bytes | int, bool]]
        | Sequence[tuple[float, int, bytes | int, bool, float]],
    ) -> None:
        """Append ``(arrival, id, data, is_extended[, stated])`` to ``client``'s queue."""
        queue = client.queue
        if not queue:
            self.senders.append(client)
        seq = self._seq
        for arrival, can_id, data, ext, *stated in frames:
            seq += 1
            if isinstance(data, int):  # a remote frame: data is its DLC
                rtr, payload = True, b""
            else:
                rtr, payload = False, data
            queue.append(
                (
                    arrival,
                    # the RTR bit follows the identifier: recessive (1) in a remote frame, so a
                    # data frame with the same identifier wins
                    arbitration_key(can_id, ext) << 1 | rtr,
                    seq,
                    can_id,
                    data,
                    ext,
                    frame_bits_fast(can_id, payload, ext),
                    # the time its sender stated (a sendat moved up to the backdate limit
                    # keeps it: its spacing to the next one is the sender's)
                    stated[0] if stated else arrival,
                )
            )
        self._seq = seq
        self._counters.received += len(frames)

    # ---------------------------------------------------------------- time

    def next_wake(self, batch_s: float) -> float | None:
        """When the hub must wake for this bus (monotonic s), or None: when its first pending
        delivery is due, or, if the next frame waiting for the bus will be due within
        ``batch_s`` after that, then (so both go out in one write per client). Arbitration
        needs no wake of its own: :meth:`advance` computes each frame's start from the bus's
        free time and the arrivals, not from the time it runs."""
        t = None
        senders = self.senders
        if senders:
            head = senders[0] if len(senders) == 1 else min(senders, key=_head_arrival)
            start = max(self.free_at, head.queue[0][0])
            t = start + head.queue[0][6] / self._bitrate + self._faults.delay_s
        if self.deliveries:
            due = self.deliveries[0][0]
            if t is None or t > due + batch_s:
                t = due
        return t

    def advance(
        self, now: float, max_backdate_s: float, max_outbuf: int
    ) -> list[Client] | tuple[Client, ...]:
        """Run the bus up to ``now``: arbitrate, occupy, schedule delivery, deliver what is due
        into the receivers' output buffers (at most ``max_outbuf`` bytes each, else the copy is
        an overrun). Returns the clients whose output buffer was empty before: the hub writes
        them out."""
        senders = self.senders
        deliveries = self.deliveries
        if not senders and (not deliveries or deliveries[0][0] > now):
            return _NO_CLIENTS  # most wakes: nothing on this bus to do
        bitrate = self._bitrate
        faults = self._faults
        counters = self._counters
        old = now - max_backdate_s
        if self.busy_end and self.busy_end[0] < old - 0.25:  # forget what no sendat reaches
            k = bisect_right(self.busy_end, old)  # (a quarter second at a time)
            del self.busy_start[:k], self.busy_end[:k]
        while senders:
            if len(senders) == 1:  # the usual case: no arbitration to decide
                winner = senders[0]
                start = winner.queue[0][0]
                if start < self.free_at:
                    start = self.free_at
                if start > now:
                    break
            else:
                start = max(self.free_at, min(c.queue[0][0] for c in senders))
                if start > now:
                    break
                chosen: Client | None = None
                best = None
                for c in senders:
                    arrival, key, seq = c.queue[0][:3]
                    if arrival <= start and (best is None or (key, seq) < best):
                        best = (key, seq)
                        chosen = c
                assert chosen is not None  # start is the earliest arrival: someone is there
                winner = chosen
            head = winner.queue[0]
            floor = spacing_floor(winner, head, bitrate)
            if start < floor - 1e-9:  # its spacing is not over: compete again from then
                winner.queue[0] = (floor, *head[1:])
                continue
            arrival, _, _, can_id, data, ext, bits, stated = winner.queue.popleft()
            if not winner.queue:
                senders.remove(winner)
            duration = bits / bitrate
            gap = None
            if start > arrival and start > winner.bus_end and self.busy_end:
                # the bus was taken at its stated time by a frame that reached the hub first
                # (a batch stated in the past arrives after frames sent meanwhile): an idle
                # gap since then is where it was on the bus, as its sender stated; its own
                # earlier frames stay before it
                gap = idle_gap(self, max(arrival, winner.bus_end), duration)
            if gap is not None:
                i, start = gap
                end = start + duration
                self.busy_start.insert(i, start)
                self.busy_end.insert(i, end)
            else:
                end = start + duration
                self.free_at = end
                self.busy_start.append(start)
                self.busy_end.append(end)
            winner.bus_end = end
            last = winner.spacing.get(can_id)
            winner.spacing[can_id] = (stated, end, None if last is None else stated - last[0])
            counters.busy_s += duration
            if faults.drops():
                counters.dropped += 1
                continue
            due = faults.delivery_due(end, self.last_due)
            self.last_due = due
            deliveries.append((due, winner, can_id, data, ext))
        touched: list[Client] = []
        wall_offset = self._wall_offset
        receivers = self.receivers
        while deliveries and deliveries[0][0] <= now:
            due, sender, can_id, data, ext = deliveries.popleft()
            if isinstance(data, int):  # a remote frame (its DLC)
                line = rtr_line(can_id, data, ext, due + wall_offset)
            else:
                line = frame_line(can_id, data, ext, due + wall_offset)
            for c in receivers:
                if c is sender:
                    continue
                outbuf = c.outbuf
                if not outbuf:
                    touched.append(c)
                elif len(outbuf) >= max_outbuf:
                    counters.overrun += 1
                    continue
                outbuf += line
            counters.forwarded += 1
        return touched
