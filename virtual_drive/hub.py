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
import select
import socket
import threading
import time
from dataclasses import dataclass
from typing import Any

from virtual_drive.hub_bus import CLOSED, RAW, WAIT_MODE, WAIT_OPEN, Bus, Client, HubCounters
from virtual_drive.hub_faults import FaultInjection
from virtual_drive.hub_protocol import (
    FEATURES_REPLY,
    SENDAT_MAX_BACKDATE_S,
    ProtocolError,
    format_error,
    parse_channel,
    parse_send_fields,
    parse_sendat_fields,
    parse_sendrtr_fields,
    scan_sendats,
    scan_sends,
    wall_offset,
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
    #: ``sendat`` frames that reached the hub more than 5 ms (``hub_bus.SPACING_HOLD_S``) after
    #: their stated time: the host stalled their sender or the hub, and a sender's spacing
    #: (a TPDO's inhibit time) may show shortened on the bus after it
    frames_late: int
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
        self._faults = FaultInjection(drop_rate, delay_s, jitter_s, seed)
        self._requested_port = port
        self._bitrate = bitrate
        self._listener: socket.socket | None = None
        self._wake_r: socket.socket | None = None
        self._wake_w: socket.socket | None = None
        self._poll: select.epoll | None = None
        self._by_fd: dict[int, Client] = {}
        self._thread: threading.Thread | None = None
        self._stopping = False
        self._clients: dict[socket.socket, Client] = {}
        self._buses: dict[str, Bus] = {}
        self._mono0 = time.monotonic()
        self._wall0 = self._mono0 + wall_offset()  # (not time.time(): see wall_offset)
        self._failure: BaseException | None = None
        # counters (written by the hub thread only)
        self._n_clients_total = 0
        self._n_clients_dropped = 0
        self._n_errors = 0
        self._frames = HubCounters()  # added to by the buses

    # ---------------------------------------------------------------- public API

    @property
    def port(self) -> int:
        """The TCP port the hub listens on (valid after :meth:`start`)."""
        if self._listener is None:
            raise RuntimeError("hub not started")
        port: int = self._listener.getsockname()[1]
        return port

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
        return self._faults.drop_rate

    @property
    def delay_s(self) -> float:
        """Current extra delivery delay, s."""
        return self._faults.delay_s

    @property
    def jitter_s(self) -> float:
        """Current ± jitter of the delivery delay, s."""
        return self._faults.jitter_s

    @property
    def running(self) -> bool:
        """True while the hub thread serves clients."""
        return self._thread is not None and self._thread.is_alive()

    @property
    def stats(self) -> HubStats:
        """A snapshot of the hub's counters."""
        pending = sum(b.pending() for b in list(self._buses.values()))
        frames = self._frames
        return HubStats(
            clients=len(self._clients),
            clients_total=self._n_clients_total,
            clients_dropped=self._n_clients_dropped,
            frames_received=frames.received,
            frames_forwarded=frames.forwarded,
            frames_dropped=frames.dropped,
            frames_overrun=frames.overrun,
            frames_late=frames.late,
            frames_pending=pending,
            protocol_errors=self._n_errors,
            bus_busy_s=frames.busy_s,
        )

    def join_kwargs(self, channel: str = "vcan0", tcp_tune: bool = True) -> dict[str, Any]:
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
        self._faults.set(drop_rate, delay_s, jitter_s)

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
        poll, listener, wake_r = self._poll, self._listener, self._wake_r
        assert poll is not None and listener is not None and wake_r is not None  # (start())
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
                if fd == listener.fileno():
                    self._accept(listener, poll, now)
                elif fd == wake_r.fileno():
                    try:
                        wake_r.recv(4096)
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
        backdate, max_outbuf = self.max_backdate_s, self.max_outbuf_bytes
        for bus in self._buses.values():
            for c in bus.advance(now, backdate, max_outbuf):
                self._flush(c, now)
        for client in writable:
            self._flush(client, now)

    def _next_deadline(self, now: float) -> float | None:
        """When the hub must wake next (monotonic s), or None.

        A bus needs a wake when its first pending delivery is due. If the next frame waiting for
        the bus will be due within :attr:`delivery_batch_s` after that, the wake waits for it, so
        both go out in one write per client (frames back to back, e.g. a node's TPDOs of one
        tick). Arbitration needs no wake of its own: :meth:`Bus.advance` computes each frame's start
        from the bus's free time and the arrivals, not from the time it runs.
        """
        deadline = None
        batch = self.delivery_batch_s
        for bus in self._buses.values():
            t = bus.next_wake(batch)
            if t is not None and (deadline is None or t < deadline):
                deadline = t
        for c in self._clients.values():
            if c.outbuf and c.ready_at > now and (deadline is None or c.ready_at < deadline):
                deadline = c.ready_at
        return deadline

    def _accept(self, listener: socket.socket, poll: select.epoll, now: float) -> None:
        while True:
            try:
                sock, peer = listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                return
            sock.setblocking(False)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            client = Client(sock, peer)
            self._clients[sock] = client
            self._by_fd[client.fd] = client
            poll.register(client.fd, _EPOLLIN)
            client.events = _EPOLLIN
            self._n_clients_total += 1
            client.outbuf += b"< hi >"
            self._flush(client, now)

    def _read(self, client: Client, now: float) -> None:
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
        # the time the bytes were read, not the iteration's: this thread may have waited for
        # the GIL in between, and a sender's sendat times, stated before it sent, then looked
        # like the future (put on the bus at once, their spacing squeezed: TPDO2 below its
        # inhibit time at load 8)
        now = time.monotonic()
        if _QUICKACK is not None:
            # ACK at once: a client without tcp_tune (Nagle on) then sends its next small
            # segment without waiting ~40 ms for our delayed ACK
            try:
                client.sock.setsockopt(socket.IPPROTO_TCP, _QUICKACK, 1)
            except OSError:
                pass
        if client.state == RAW:  # it speaks after its handshake: it has read its < ok >,
            client.ready_at = 0.0  # so the hold ends (an answer to its first request waits not)
        if client.state == RAW and not client.splitter.pending_bytes:
            bus, backdate = client.on_bus(), self.max_backdate_s
            while chunk:  # the common case: only well-formed sends (or sendats)
                frames, used = scan_sends(chunk)
                if frames:
                    bus.enqueue(client, frames, now)
                else:
                    timed, used = scan_sendats(chunk)
                    if not timed:
                        break
                    bus.enqueue_timed(client, timed, now, backdate)
                chunk = chunk[used:]
        for item in client.splitter.feed(chunk):
            if isinstance(item, ProtocolError):
                self._reject(client, str(item), now)
            else:
                try:
                    self._handle(client, item, now)
                except ProtocolError as exc:
                    self._reject(client, str(exc), now)
            if client.state == CLOSED:
                return
        if client.splitter.overflow:
            self._reject(client, "element too long", now)
            self._drop(client)
            return
        self._flush(client, now)

    def _handle(self, client: Client, words: list[str], now: float) -> None:
        cmd = words[0]
        if client.state == RAW and cmd == "send":
            client.on_bus().enqueue(client, [parse_send_fields(words)], now)
        elif client.state == RAW and cmd == "sendrtr":
            client.on_bus().enqueue(client, [parse_sendrtr_fields(words)], now)  # (id, DLC, ext)
        elif client.state == RAW and cmd == "sendat":
            timed = [parse_sendat_fields(words)]
            client.on_bus().enqueue_timed(client, timed, now, self.max_backdate_s)
        elif cmd == "echo":
            client.outbuf += b"< echo >"
        elif cmd == "features":
            client.outbuf += FEATURES_REPLY
            client.parses_elements = True
        elif client.state == WAIT_OPEN:
            if cmd != "open":
                raise ProtocolError(f"expected '< open BUS >', got {cmd!r}")
            name = parse_channel(words)
            bus = self._buses.get(name)
            if bus is None:
                bus = self._buses[name] = Bus(
                    name,
                    self._bitrate,
                    self._faults,
                    self._frames,
                    wall_offset=self._wall0 - self._mono0,
                    mono_offset=self._mono0 - self._wall0,
                )
            client.bus = bus
            client.state = WAIT_MODE
            client.outbuf += b"< ok >"
        elif client.state == WAIT_MODE:
            if cmd != "rawmode":
                raise ProtocolError(f"only rawmode is supported, got {cmd!r}")
            client.outbuf += b"< ok >"
            self._flush(client, now)
            client.state = RAW
            client.ready_at = now + (0.0 if client.parses_elements else self.handshake_hold_s)
            client.on_bus().join(client)
        elif cmd == "rawmode":
            client.outbuf += b"< ok >"
        else:
            raise ProtocolError(f"unknown or unsupported command {cmd!r}")

    def _reject(self, client: Client, reason: str, now: float) -> None:
        self._n_errors += 1
        client.errors += 1
        if len(client.outbuf) < self.max_outbuf_bytes:
            client.outbuf += format_error(reason, self._wall(now))
        if client.errors > self.max_errors_per_client:
            self._drop(client)

    def _drop(self, client: Client) -> None:
        if client.state == CLOSED:
            return
        self._n_clients_dropped += 1
        try:  # best effort: let it see why
            client.sock.send(bytes(client.outbuf))
        except OSError:
            pass
        self._close(client)

    def _close(self, client: Client) -> None:
        if client.state == CLOSED:
            return
        client.state = CLOSED
        self._clients.pop(client.sock, None)
        if self._by_fd.pop(client.fd, None) is not None and self._poll is not None:
            try:
                self._poll.unregister(client.fd)
            except (OSError, ValueError):
                pass
        bus = client.bus
        if bus is not None:
            bus.leave(client)  # frames it already sent stay queued
        try:
            client.sock.close()
        except OSError:
            pass

    def _flush(self, client: Client, now: float) -> None:
        if not client.outbuf or client.ready_at > now or client.state == CLOSED:
            return
        try:
            sent = client.sock.send(client.outbuf)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            self._close(client)
            return
        del client.outbuf[:sent]
