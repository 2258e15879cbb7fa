"""Loopback CAN hub: a shared, bit-rate-paced CAN bus between processes, without SocketCAN.

Any number of processes join with python-can's built-in ``socketcand`` interface::

    with Hub(port=0, bitrate=1_000_000) as hub:
        bus = can.Bus(interface="socketcand", host="127.0.0.1", port=hub.port,
                      channel="vcan0", tcp_tune=True)

The hub speaks socketcand "rawmode" (see :mod:`virtual_drive.hub_protocol`) on 127.0.0.1 only.
Each ``< open NAME >`` channel is its own bus. On a bus, every frame is forwarded to every OTHER
client in one global order. Frames are paced like a real CAN bus: a frame waiting for the bus
competes in arbitration (lowest identifier wins among the oldest pending frame of each client,
so each sender's order is kept), occupies the bus for
:func:`firmware_protocol.can_bits.frame_bits` ``/ bitrate`` seconds (exact bit stuffing), and
is delivered when the bus has finished it (plus an optional injected delay with uniform jitter,
like a USB adapter: ``delay_s`` ± ``jitter_s``, never reordering frames, as CAN never does).
Frames can be dropped with a seeded RNG for fault tests. A client that asks ``< features >`` may
send ``< sendat <time> ... >`` (the virtual drive's batched ticks): such a frame competes for the
bus from its stated time instead of its arrival (see :mod:`virtual_drive.hub_protocol`). A batch
stated in the past may reach the hub after a frame another client sent later (a host's SDO
request during the drive's tick): its frames then take the bus's idle time at their stated
instants (the hub keeps the last :attr:`Hub.max_backdate_s` of bus occupancy), as they did on a
real bus, instead of queueing after that frame and delaying the next one (an SDO reply).

One background thread runs an ``epoll`` loop over all sockets; no locks are needed.
The ``virtual-drive hub`` command is :mod:`virtual_drive.hub_cli`; the launcher that starts a hub
with virtual drives is :mod:`virtual_drive.launch`.
"""

from __future__ import annotations

import logging
import math
import random
import select
import socket
import threading
import time
from bisect import bisect_right
from collections import deque
from dataclasses import dataclass

from firmware_protocol.can_bits import arbitration_key, frame_bits_fast
from virtual_drive.hub_protocol import (
    FEATURES_REPLY,
    SENDAT_MAX_BACKDATE_S,
    CommandSplitter,
    ProtocolError,
    format_error,
    frame_line,
    parse_channel,
    parse_send_fields,
    parse_sendat_fields,
    parse_sendrtr_fields,
    rtr_line,
    scan_sendats,
    scan_sends,
)

__all__ = ["DEFAULT_PORT", "Hub", "HubStats"]

#: Port used by ``virtual-drive hub`` when none is given.
DEFAULT_PORT = 29536

_log = logging.getLogger(__name__)
_LOOPBACK_NAMES = ("127.0.0.1", "localhost")
_QUICKACK = getattr(socket, "TCP_QUICKACK", None)  # Linux only
_BIND_ADDRESS = "127.0.0.1"
_EPOLLIN = select.EPOLLIN
_EPOLLOUT = select.EPOLLOUT

# --------------------------------------------------------------------------------------------
# Hub state
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class HubStats:
    """Counters of a running hub (a snapshot; all counts since start)."""

    clients: int  #: clients connected now
    clients_total: int  #: connections accepted
    clients_dropped: int  #: clients the hub disconnected for bad input
    frames_received: int  #: valid frames received from clients
    frames_forwarded: int  #: frames that completed on the bus and went to the other clients
    frames_dropped: int  #: frames lost by fault injection (drop_rate)
    frames_overrun: int  #: frame copies not queued because a client's output buffer was full
    frames_pending: int  #: frames received, not yet forwarded or dropped
    protocol_errors: int  #: bad elements answered with ``< error ... >``
    bus_busy_s: float  #: emulated bus time used by frames, s (all channels)

    @property
    def received(self) -> int:
        """Alias of :attr:`frames_received`."""
        return self.frames_received

    @property
    def forwarded(self) -> int:
        """Alias of :attr:`frames_forwarded`."""
        return self.frames_forwarded

    @property
    def dropped(self) -> int:
        """Alias of :attr:`frames_dropped`."""
        return self.frames_dropped


_WAIT_OPEN, _WAIT_MODE, _RAW, _CLOSED = range(4)


class _Client:
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

    def __init__(self, sock: socket.socket, peer: tuple) -> None:
        self.sock = sock
        self.fd = sock.fileno()
        self.events = 0  # epoll events registered for it
        self.peer = peer
        self.state = _WAIT_OPEN
        self.splitter = CommandSplitter()
        self.outbuf = bytearray()
        self.ready_at = 0.0  # monotonic time before which frames are held back (see Hub)
        self.parses_elements = False  # asked < features >: takes frames glued to < ok >
        #: (arrival, key, seq, id, data, ext, bits, stated time) waiting for the bus
        self.queue: deque = deque()
        self.bus: _Bus | None = None
        self.bus_end = 0.0  # monotonic time its last frame left the bus
        self.errors = 0
        #: CAN-ID -> (stated time, end on the bus, stated gap to the one before or None) of
        #: this client's last frame with that ID: see :func:`_spacing_floor`
        self.spacing: dict[int, tuple[float, float, float | None]] = {}


class _Bus:
    """One emulated CAN bus (one socketcand channel)."""

    __slots__ = (
        "busy_end",
        "busy_start",
        "deliveries",
        "free_at",
        "last_due",
        "name",
        "receivers",
        "senders",
    )

    def __init__(self, name: str) -> None:
        self.name = name
        self.receivers: list[_Client] = []  # clients in rawmode
        self.senders: list[_Client] = []  # clients with frames waiting for the bus
        self.free_at = 0.0  # monotonic time the bus becomes idle
        self.deliveries: deque = deque()  # (due, sender, frame), due non-decreasing
        self.last_due = 0.0
        #: the bus's recent occupancy: frame i was on it from busy_start[i] to busy_end[i]
        #: (monotonic s, sorted, never overlapping; the last max_backdate_s are kept), so a
        #: frame stated in the past can take an idle gap of then (see Hub._advance)
        self.busy_start: list[float] = []
        self.busy_end: list[float] = []


#: intervals a late ``sendat`` frame looks past for an idle gap before it waits for the bus
#: (a bus full since its stated time has no gap: the search ends there, not at the backlog's end)
_GAP_SCAN = 32


def _idle_gap(bus: _Bus, t: float, duration: float) -> tuple[int, float] | None:
    """``(index, start)`` of an idle stretch of ``duration`` s at or after ``t`` (monotonic s)
    that ends before the bus's :attr:`_Bus.free_at`, in its occupancy; None: no such stretch
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


#: longest a frame is held past its arrival to keep its sender's spacing (s): several frame
#: times at 125 kbit/s, so arbitration delays never shorten a gap; no persistent lag
SPACING_HOLD_S = 0.005


def _spacing_floor(client: _Client, head: tuple, bitrate: float) -> float:
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


def _head_arrival(client: _Client) -> float:
    return client.queue[0][0]


class Hub:
    """A loopback CAN hub speaking socketcand rawmode on 127.0.0.1.

    host: must be "127.0.0.1" or "localhost" (anything else raises ValueError).
    port: TCP port, 0 for an ephemeral one (read :attr:`port` after :meth:`start`).
    bitrate: emulated bit rate, bit/s (1 .. 1e9; real classical CAN is at most 1e6).
    drop_rate: probability 0..1 that a frame is lost for all receivers (it still uses bus time).
    delay_s: extra delivery delay, s (≥ 0), added after the frame completed on the bus.
    jitter_s: per-frame jitter of that delay, s (≥ 0): each frame is due at
        max(previous due time on its bus, end on the bus + delay_s + U(−jitter_s, +jitter_s)),
        and never before it has completed on the bus; so frames keep their order.
    seed: seed of the drop and jitter RNGs (reproducible fault patterns; the jitter draws do
        not change which frames are dropped).
    """

    #: After ``< rawmode >`` is acknowledged, frames for that client wait this long (s), so
    #: python-can's handshake ``recv`` sees ``< ok >`` alone and not glued to a frame (it reads
    #: once and compares the whole read; on a loaded host a client took longer than 50 ms to
    #: make that read and failed "Expected '< ok >' got: '< ok >< frame …'"). A client that
    #: asked ``< features >`` parses element by element (the project's lean client): no hold.
    #: The hold also ends at the client's first element in rawmode (python-can sends only
    #: after its handshake read): a request sent at once gets its answer at once.
    handshake_hold_s = 0.3
    #: A ``sendat`` frame stated longer ago than this (s) arrives this long ago
    #: (:data:`hub_protocol.SENDAT_MAX_BACKDATE_S`).
    max_backdate_s = SENDAT_MAX_BACKDATE_S
    #: Frames one client may have waiting for the bus before the hub stops reading it
    #: (its TCP send then blocks: back-pressure like a full CAN controller TX queue).
    max_pending_per_client = 1024
    #: Output bytes buffered per client before frames for it are counted as overrun and lost.
    max_outbuf_bytes = 4 << 20
    #: Bad elements a client may send before the hub disconnects it.
    max_errors_per_client = 100
    #: A frame due for delivery waits up to this long (s) for the next frame on the bus when
    #: that one is already queued, so both reach each client in one write (see
    #: :meth:`_next_deadline`). Frames keep their exact bus timestamps; a lone frame (an SDO
    #: request or reply) is never held. 0: every frame is delivered when it is due.
    delivery_batch_s = 0.0003

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 0,
        bitrate: int = 1_000_000,
        drop_rate: float = 0.0,
        delay_s: float = 0.0,
        seed: int | None = 0,
        jitter_s: float = 0.0,
    ) -> None:
        if host not in _LOOPBACK_NAMES:
            raise ValueError(f"the hub binds 127.0.0.1 only; refusing host {host!r}")
        if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
            raise ValueError(f"port must be an integer 0..65535, got {port!r}")
        if isinstance(bitrate, bool) or not isinstance(bitrate, int):
            raise ValueError(f"bitrate must be an integer in bit/s, got {bitrate!r}")
        if not 1 <= bitrate <= 1_000_000_000:
            raise ValueError(f"bitrate must be 1 .. 1e9 bit/s, got {bitrate}")
        self._check_faults(drop_rate, delay_s, jitter_s)
        self._requested_port = port
        self._bitrate = bitrate
        self._drop_rate = float(drop_rate)
        self._delay_s = float(delay_s)
        self._jitter_s = float(jitter_s)
        self._rng = random.Random(seed)
        self._jitter_rng = random.Random(None if seed is None else f"jitter-{seed}")
        self._listener: socket.socket | None = None
        self._wake_r: socket.socket | None = None
        self._wake_w: socket.socket | None = None
        self._poll: select.epoll | None = None
        self._by_fd: dict[int, _Client] = {}
        self._thread: threading.Thread | None = None
        self._stopping = False
        self._clients: dict[socket.socket, _Client] = {}
        self._buses: dict[str, _Bus] = {}
        self._mono0 = time.monotonic()
        self._wall0 = time.time()
        self._seq = 0
        self._failure: BaseException | None = None
        # counters (written by the hub thread only)
        self._n_clients_total = 0
        self._n_clients_dropped = 0
        self._n_received = 0
        self._n_forwarded = 0
        self._n_dropped = 0
        self._n_overrun = 0
        self._n_errors = 0
        self._busy_s = 0.0

    # ---------------------------------------------------------------- public API

    @property
    def port(self) -> int:
        """The TCP port the hub listens on (valid after :meth:`start`)."""
        if self._listener is None:
            raise RuntimeError("hub not started")
        return self._listener.getsockname()[1]

    @property
    def host(self) -> str:
        """Always "127.0.0.1"."""
        return _BIND_ADDRESS

    @property
    def bitrate(self) -> int:
        """Emulated bit rate, bit/s."""
        return self._bitrate

    @property
    def drop_rate(self) -> float:
        """Current drop probability (0..1)."""
        return self._drop_rate

    @property
    def delay_s(self) -> float:
        """Current extra delivery delay, s."""
        return self._delay_s

    @property
    def jitter_s(self) -> float:
        """Current ± jitter of the delivery delay, s."""
        return self._jitter_s

    @property
    def running(self) -> bool:
        """True while the hub thread serves clients."""
        return self._thread is not None and self._thread.is_alive()

    @property
    def stats(self) -> HubStats:
        """A snapshot of the hub's counters."""
        pending = 0
        for b in list(self._buses.values()):
            pending += len(b.deliveries) + sum(len(c.queue) for c in list(b.senders))
        return HubStats(
            clients=len(self._clients),
            clients_total=self._n_clients_total,
            clients_dropped=self._n_clients_dropped,
            frames_received=self._n_received,
            frames_forwarded=self._n_forwarded,
            frames_dropped=self._n_dropped,
            frames_overrun=self._n_overrun,
            frames_pending=pending,
            protocol_errors=self._n_errors,
            bus_busy_s=self._busy_s,
        )

    def join_kwargs(self, channel: str = "vcan0", tcp_tune: bool = True) -> dict:
        """Keyword arguments for ``can.Bus(**hub.join_kwargs())`` to join this hub."""
        return {
            "interface": "socketcand",
            "host": _BIND_ADDRESS,
            "port": self.port,
            "channel": channel,
            "tcp_tune": tcp_tune,
        }

    def join_line(self, channel: str = "vcan0") -> str:
        """The python-can line that joins this hub, as text."""
        return (
            f'can.Bus(interface="socketcand", host="{_BIND_ADDRESS}", port={self.port}, '
            f'channel="{channel}", tcp_tune=True)'
        )

    def set_faults(
        self,
        drop_rate: float | None = None,
        delay_s: float | None = None,
        jitter_s: float | None = None,
    ) -> None:
        """Change fault injection at run time; applies to frames not yet on the bus.

        drop_rate: probability 0..1 that a frame is lost. delay_s: extra delay, s (≥ 0).
        jitter_s: ± uniform jitter of the delay per frame, s (≥ 0). None keeps a setting.
        Raises ValueError (and changes nothing) for out-of-range values.
        """
        new_drop = self._drop_rate if drop_rate is None else drop_rate
        new_delay = self._delay_s if delay_s is None else delay_s
        new_jitter = self._jitter_s if jitter_s is None else jitter_s
        self._check_faults(new_drop, new_delay, new_jitter)
        self._drop_rate = float(new_drop)
        self._delay_s = float(new_delay)
        self._jitter_s = float(new_jitter)

    def start(self) -> Hub:
        """Bind 127.0.0.1:port and start serving in a background thread.

        Raises OSError (errno EADDRINUSE) if the port is busy, RuntimeError if already started.
        """
        if self._listener is not None:
            raise RuntimeError("hub already started")
        listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            listener.bind((_BIND_ADDRESS, self._requested_port))
            listener.listen(64)
            listener.setblocking(False)
        except OSError:
            listener.close()
            raise
        self._listener = listener
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._poll = select.epoll()
        self._poll.register(listener.fileno(), select.EPOLLIN)
        self._poll.register(self._wake_r.fileno(), select.EPOLLIN)
        self._stopping = False
        self._thread = threading.Thread(target=self._serve, name="can-hub", daemon=True)
        self._thread.start()
        return self

    def stop(self, timeout: float = 5.0) -> None:
        """Stop serving, close every client connection and the listening socket."""
        if self._listener is None:
            return
        self._stopping = True
        if self._wake_w is not None:
            try:
                self._wake_w.send(b"x")
            except OSError:
                pass
        if self._thread is not None:
            self._thread.join(timeout)
        for client in list(self._clients.values()):
            self._close(client)
        for s in (self._listener, self._wake_r, self._wake_w, self._poll):
            if s is not None:
                s.close()
        self._listener = self._wake_r = self._wake_w = self._poll = None
        self._thread = None
        self._buses.clear()  # frames still in flight are lost with the bus

    def __enter__(self) -> Hub:
        if self._listener is None:
            self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # ---------------------------------------------------------------- internals

    @staticmethod
    def _check_faults(drop_rate: float, delay_s: float, jitter_s: float = 0.0) -> None:
        for name, v in (("drop_rate", drop_rate), ("delay_s", delay_s), ("jitter_s", jitter_s)):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"{name} must be a finite number, got {v!r}")
        if not 0.0 <= drop_rate <= 1.0:
            raise ValueError(f"drop_rate must be in 0..1, got {drop_rate}")
        if not 0.0 <= delay_s <= 3600.0:
            raise ValueError(f"delay_s must be in 0..3600 s, got {delay_s}")
        if not 0.0 <= jitter_s <= 3600.0:
            raise ValueError(f"jitter_s must be in 0..3600 s, got {jitter_s}")

    def _delivery_due(self, end: float, last_due: float) -> float:
        """Delivery time of a frame that completed on the bus at ``end`` (monotonic s) when the
        previous frame on its bus is due at ``last_due``: end + delay_s + U(−jitter_s, jitter_s),
        never before ``end`` nor before ``last_due`` (CAN keeps the order of frames)."""
        if self._jitter_s == 0.0:
            due = end + self._delay_s
            return due if due > last_due else last_due
        delay = self._delay_s
        if self._jitter_s > 0.0:
            delay = max(0.0, delay + self._jitter_rng.uniform(-self._jitter_s, self._jitter_s))
        return max(end + delay, last_due)

    def _wall(self, mono: float) -> float:
        return self._wall0 + (mono - self._mono0)

    def _serve(self) -> None:
        try:
            while not self._stopping:
                self._iterate()
        except BaseException as exc:  # keep the reason for whoever looks at the hub
            self._failure = exc
            raise

    def _iterate(self) -> None:
        now = time.monotonic()
        deadline = self._next_deadline(now)
        timeout = None if deadline is None else max(0.0, deadline - now)
        poll = self._poll
        for c in self._by_fd.values():  # level-triggered interest: read unless its queue is
            events = _EPOLLIN if len(c.queue) < self.max_pending_per_client else 0  # full,
            if c.outbuf and c.ready_at <= now:  # write while output waits for room
                events |= _EPOLLOUT
            if events != c.events:
                poll.modify(c.fd, events)
                c.events = events
        if timeout is None:
            ready = poll.poll()
        else:  # epoll_wait counts whole ms (a 0.12 ms wait would take 1 ms): select waits
            # on the epoll descriptor to the microsecond, then the events are fetched
            woke, _, _ = select.select([poll], [], [], timeout)
            ready = poll.poll(0) if woke else []
        now = time.monotonic()
        writable = []
        for fd, events in ready:
            client = self._by_fd.get(fd)
            if client is None:
                if fd == self._listener.fileno():
                    self._accept(now)
                elif fd == self._wake_r.fileno():
                    try:
                        self._wake_r.recv(4096)
                    except OSError:
                        pass
                continue
            if events & _EPOLLOUT:
                writable.append(client)
            if events & ~_EPOLLOUT:  # data, end of stream or an error: recv tells which
                try:
                    self._read(client, now)
                except Exception:  # a bug triggered by one client must not stop the bus
                    _log.exception("hub: dropping client %s (internal error)", client.peer)
                    self._drop(client)
        now = time.monotonic()
        for bus in self._buses.values():
            self._advance(bus, now)
        for client in writable:
            self._flush(client, now)

    def _next_deadline(self, now: float) -> float | None:
        """When the hub must wake next (monotonic s), or None.

        A bus needs a wake when its first pending delivery is due. If the next frame waiting for
        the bus will be due within :attr:`delivery_batch_s` after that, the wake waits for it, so
        both go out in one write per client (frames back to back, e.g. a node's TPDOs of one
        tick). Arbitration needs no wake of its own: :meth:`_advance` computes each frame's start
        from the bus's free time and the arrivals, not from the time it runs.
        """
        deadline = None
        batch = self.delivery_batch_s
        for bus in self._buses.values():
            t = None
            senders = bus.senders
            if senders:
                head = senders[0] if len(senders) == 1 else min(senders, key=_head_arrival)
                start = max(bus.free_at, head.queue[0][0])
                t = start + head.queue[0][6] / self._bitrate + self._delay_s
            if bus.deliveries:
                due = bus.deliveries[0][0]
                if t is None or t > due + batch:
                    t = due
            if t is not None and (deadline is None or t < deadline):
                deadline = t
        for c in self._clients.values():
            if c.outbuf and c.ready_at > now and (deadline is None or c.ready_at < deadline):
                deadline = c.ready_at
        return deadline

    def _accept(self, now: float) -> None:
        while True:
            try:
                sock, peer = self._listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                return
            sock.setblocking(False)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            client = _Client(sock, peer)
            self._clients[sock] = client
            self._by_fd[client.fd] = client
            self._poll.register(client.fd, _EPOLLIN)
            client.events = _EPOLLIN
            self._n_clients_total += 1
            client.outbuf += b"< hi >"
            self._flush(client, now)

    def _read(self, client: _Client, now: float) -> None:
        try:
            chunk = client.sock.recv(65536)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self._close(client)
            return
        if not chunk:  # peer closed; an unfinished element is discarded
            self._close(client)
            return
        if _QUICKACK is not None:
            # ACK at once: a client without tcp_tune (Nagle on) then sends its next small
            # segment without waiting ~40 ms for our delayed ACK
            try:
                client.sock.setsockopt(socket.IPPROTO_TCP, _QUICKACK, 1)
            except OSError:
                pass
        if client.state == _RAW:  # it speaks after its handshake: it has read its < ok >,
            client.ready_at = 0.0  # so the hold ends (an answer to its first request waits not)
        if client.state == _RAW and not client.splitter.pending_bytes:
            while chunk:  # the common case: only well-formed sends (or sendats)
                frames, used = scan_sends(chunk)
                if frames:
                    self._enqueue(client, frames, now)
                else:
                    timed, used = scan_sendats(chunk)
                    if not timed:
                        break
                    self._enqueue_timed(client, timed, now)
                chunk = chunk[used:]
        for item in client.splitter.feed(chunk):
            if isinstance(item, ProtocolError):
                self._reject(client, str(item), now)
            else:
                try:
                    self._handle(client, item, now)
                except ProtocolError as exc:
                    self._reject(client, str(exc), now)
            if client.state == _CLOSED:
                return
        if client.splitter.overflow:
            self._reject(client, "element too long", now)
            self._drop(client)
            return
        self._flush(client, now)

    def _enqueue(
        self, client: _Client, frames: list[tuple[int, bytes, bool]], now: float
    ) -> None:
        """Queue ``frames`` (id, data, is_extended) of ``client`` for the bus, arrived ``now``."""
        self._queue(client, [(now, can_id, data, ext) for can_id, data, ext in frames])

    def _enqueue_timed(
        self, client: _Client, frames: list[tuple[float, int, bytes, bool]], now: float
    ) -> None:
        """Queue ``sendat`` frames ``(unix_time, id, data, is_extended)``: each arrives at its
        stated time, but never before a frame of this client still waiting for the bus (its
        order is kept), never more than :attr:`max_backdate_s` ago and never after ``now``
        (see :mod:`hub_protocol`). A frame of the client that is already on the bus does not
        hold it back: it starts when the bus is free, as a CAN controller's other transmit
        mailbox would."""
        queue = client.queue
        lo = now - self.max_backdate_s
        if queue and queue[-1][0] > lo:
            lo = queue[-1][0]
        mono_offset = self._mono0 - self._wall0
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

    def _queue(self, client: _Client, frames: list[tuple[float, int, bytes, bool]]) -> None:
        """Append ``(arrival, id, data, is_extended)`` to ``client``'s queue for the bus."""
        queue = client.queue
        if not queue:
            client.bus.senders.append(client)
        seq = self._seq
        for arrival, can_id, data, ext, *stated in frames:
            seq += 1
            rtr = data.__class__ is int  # a remote frame: data is its DLC
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
                    frame_bits_fast(can_id, b"" if rtr else data, ext),
                    # the time its sender stated (a sendat moved up to the backdate limit
                    # keeps it: its spacing to the next one is the sender's)
                    stated[0] if stated else arrival,
                )
            )
        self._seq = seq
        self._n_received += len(frames)

    def _handle(self, client: _Client, words: list[str], now: float) -> None:
        cmd = words[0]
        if client.state == _RAW and cmd == "send":
            self._enqueue(client, [parse_send_fields(words)], now)
        elif client.state == _RAW and cmd == "sendrtr":
            self._enqueue(client, [parse_sendrtr_fields(words)], now)  # (id, DLC, ext)
        elif client.state == _RAW and cmd == "sendat":
            self._enqueue_timed(client, [parse_sendat_fields(words)], now)
        elif cmd == "echo":
            client.outbuf += b"< echo >"
        elif cmd == "features":
            client.outbuf += FEATURES_REPLY
            client.parses_elements = True
        elif client.state == _WAIT_OPEN:
            if cmd != "open":
                raise ProtocolError(f"expected '< open BUS >', got {cmd!r}")
            name = parse_channel(words)
            bus = self._buses.get(name)
            if bus is None:
                bus = self._buses[name] = _Bus(name)
            client.bus = bus
            client.state = _WAIT_MODE
            client.outbuf += b"< ok >"
        elif client.state == _WAIT_MODE:
            if cmd != "rawmode":
                raise ProtocolError(f"only rawmode is supported, got {cmd!r}")
            client.outbuf += b"< ok >"
            self._flush(client, now)
            client.state = _RAW
            client.ready_at = now + (0.0 if client.parses_elements else self.handshake_hold_s)
            client.bus.receivers.append(client)
        elif cmd == "rawmode":
            client.outbuf += b"< ok >"
        else:
            raise ProtocolError(f"unknown or unsupported command {cmd!r}")

    def _reject(self, client: _Client, reason: str, now: float) -> None:
        self._n_errors += 1
        client.errors += 1
        if len(client.outbuf) < self.max_outbuf_bytes:
            client.outbuf += format_error(reason, self._wall(now))
        if client.errors > self.max_errors_per_client:
            self._drop(client)

    def _drop(self, client: _Client) -> None:
        if client.state == _CLOSED:
            return
        self._n_clients_dropped += 1
        try:  # best effort: let it see why
            client.sock.send(bytes(client.outbuf))
        except OSError:
            pass
        self._close(client)

    def _close(self, client: _Client) -> None:
        if client.state == _CLOSED:
            return
        client.state = _CLOSED
        self._clients.pop(client.sock, None)
        if self._by_fd.pop(client.fd, None) is not None and self._poll is not None:
            try:
                self._poll.unregister(client.fd)
            except (OSError, ValueError):
                pass
        bus = client.bus
        if bus is not None and client in bus.receivers:
            bus.receivers.remove(client)
        # frames it already sent stay queued: they were on their way to the bus
        try:
            client.sock.close()
        except OSError:
            pass

    def _flush(self, client: _Client, now: float) -> None:
        if not client.outbuf or client.ready_at > now or client.state == _CLOSED:
            return
        try:
            sent = client.sock.send(client.outbuf)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self._close(client)
            return
        del client.outbuf[:sent]

    def _advance(self, bus: _Bus, now: float) -> None:
        """Run the bus up to ``now``: arbitrate, occupy, schedule delivery, deliver what is due."""
        senders = bus.senders
        deliveries = bus.deliveries
        if not senders and (not deliveries or deliveries[0][0] > now):
            return  # most wakes: nothing on this bus to do
        bitrate = self._bitrate
        old = now - self.max_backdate_s
        if bus.busy_end and bus.busy_end[0] < old - 0.25:  # forget what no sendat reaches
            k = bisect_right(bus.busy_end, old)  # (a quarter second at a time)
            del bus.busy_start[:k], bus.busy_end[:k]
        while senders:
            if len(senders) == 1:  # the usual case: no arbitration to decide
                winner = senders[0]
                start = winner.queue[0][0]
                if start < bus.free_at:
                    start = bus.free_at
                if start > now:
                    break
            else:
                start = max(bus.free_at, min(c.queue[0][0] for c in senders))
                if start > now:
                    break
                winner = None
                best = None
                for c in senders:
                    arrival, key, seq = c.queue[0][:3]
                    if arrival <= start and (best is None or (key, seq) < best):
                        best = (key, seq)
                        winner = c
            head = winner.queue[0]
            floor = _spacing_floor(winner, head, bitrate)
            if start < floor - 1e-9:  # its spacing is not over: compete again from then
                winner.queue[0] = (floor, *head[1:])
                continue
            arrival, _, _, can_id, data, ext, bits, stated = winner.queue.popleft()
            if not winner.queue:
                senders.remove(winner)
            duration = bits / bitrate
            gap = None
            if start > arrival and start > winner.bus_end and bus.busy_end:
                # the bus was taken at its stated time by a frame that reached the hub first
                # (a batch stated in the past arrives after frames sent meanwhile): an idle
                # gap since then is where it was on the bus, as its sender stated; its own
                # earlier frames stay before it
                gap = _idle_gap(bus, max(arrival, winner.bus_end), duration)
            if gap is not None:
                i, start = gap
                end = start + duration
                bus.busy_start.insert(i, start)
                bus.busy_end.insert(i, end)
            else:
                end = start + duration
                bus.free_at = end
                bus.busy_start.append(start)
                bus.busy_end.append(end)
            winner.bus_end = end
            last = winner.spacing.get(can_id)
            winner.spacing[can_id] = (stated, end, None if last is None else stated - last[0])
            self._busy_s += duration
            if self._drop_rate > 0.0 and self._rng.random() < self._drop_rate:
                self._n_dropped += 1
                continue
            due = self._delivery_due(end, bus.last_due)
            bus.last_due = due
            deliveries.append((due, winner, can_id, data, ext))
        touched: list[_Client] = []
        wall_offset = self._wall0 - self._mono0
        max_outbuf = self.max_outbuf_bytes
        receivers = bus.receivers
        while deliveries and deliveries[0][0] <= now:
            due, sender, can_id, data, ext = deliveries.popleft()
            if data.__class__ is int:  # a remote frame (its DLC)
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
                    self._n_overrun += 1
                    continue
                outbuf += line
            self._n_forwarded += 1
        for c in touched:
            self._flush(c, now)
