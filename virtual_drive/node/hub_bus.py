"""Lean socketcand "rawmode" client for the virtual drive: a python-can bus (``can.BusABC``).

The drive sends about 2,200 frames/s at its default PDO rates. python-can's ``socketcand``
interface formats each frame with a generator, sends it alone and sets TCP_QUICKACK after every
send (about 34 µs per frame here); its receive loop builds a ``can.Message`` for every frame on
the bus, whoever it is for. This client speaks the same protocol (``< send ... >`` /
``< frame ... >``, see :mod:`virtual_drive.hub_protocol`) to the loopback hub or a socketcand
daemon, and

- :meth:`HubBus.send_many` writes all frames of a pacing tick in one ``sendall``;
- :attr:`HubBus.rx_wanted` (a container of CAN-IDs, e.g. the canopen network's ``subscribers``
  dict, consulted live) drops frames nobody on this node listens to before any ``can.Message``
  is built: four drives in one process then do not parse each other's TPDOs;
- :meth:`HubBus.lost` tells a connection closed by the server (end-of-file) from an idle one.

Registered as python-can interface ``vdhub`` (entry point ``can.interface``), so
``can.Bus(interface="vdhub", channel="vcan0", host="127.0.0.1", port=N)`` works anywhere;
``virtual-drive run --interface socketcand`` uses it for the drive's own connection.
"""

from __future__ import annotations

import logging
import operator
import os
import select
import socket
import threading
import time
from collections import deque
from collections.abc import Callable, Container, Iterable, Sequence
from typing import Any

import can

from virtual_drive.node.hub_elements import (
    WALL_OFFSET,
    format_held,
    format_send,
    format_sendat,
    format_sendat_batch,
    sendat_head,
    sendat_tail,
)

__all__ = ["HubBus", "HubConnection", "HubPort", "format_send", "format_sendat"]

logger = logging.getLogger(__name__)

_QUICKACK = getattr(socket, "TCP_QUICKACK", None)
_FIRST = operator.itemgetter(0)
_MAX_PARTIAL = 4096  #: bytes of an unfinished element kept before the buffer is discarded


class HubBus(can.BusABC):
    """A socketcand rawmode connection (python-can interface ``vdhub``).

    :param channel: bus name on the server (the hub's ``vcan0``).
    :param host: server address (127.0.0.1 for the loopback hub).
    :param port: server TCP port.
    :param tcp_tune: TCP_NODELAY on the socket and TCP_QUICKACK after each read (low latency).
    :param connect_timeout: s for the TCP connection and each handshake reply.
    :raises can.CanInitializationError: no server, or the handshake failed (one-line reason).
    """

    def __init__(
        self,
        channel: str = "vcan0",
        host: str = "127.0.0.1",
        port: int | None = None,
        tcp_tune: bool = True,
        can_filters: can.typechecking.CanFilters | None = None,
        connect_timeout: float = 10.0,
        **kwargs: Any,
    ) -> None:
        if port is None:
            raise can.CanInitializationError("vdhub needs the server's port")
        self._tcp_tune = bool(tcp_tune)
        self._buf = b""
        self._queue: deque[can.Message] = deque()
        self._send_lock = threading.Lock()
        #: timed frames waiting for flush(): (ready time, frames) per send_many call
        self._held: list[tuple[float, Sequence[tuple[int, bytes]]]] = []
        self._prefixes: dict[tuple[int, int], bytes] = {}  #: b"<id> <len> " per (id, len)
        self._eof = False
        #: CAN-IDs to deliver (None: all). Consulted per frame, so a live dict works.
        self.rx_wanted: Container[int] | None = None
        self.rx_dropped = 0  #: frames not delivered because nobody wanted them
        #: if set, called as (can_id, data, stamp, is_extended) for each wanted data frame
        #: instead of building a can.Message (drive_link's receive path, issue 11)
        self.rx_direct: Callable[[int, bytes, float, bool], None] | None = None
        try:
            sock = socket.create_connection((host, int(port)), timeout=connect_timeout)
        except OSError as exc:
            reason = getattr(exc, "strerror", None) or str(exc)
            raise can.CanInitializationError(
                f"cannot connect to {host}:{port}: {reason}"
            ) from exc
        self._sock = sock
        try:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self._expect("hi", connect_timeout)
            sock.sendall(f"< open {channel} >".encode("ascii"))
            self._expect("ok", connect_timeout)
            self.timed_sends = self._probe_features(min(connect_timeout, 2.0))
            sock.sendall(b"< rawmode >")
            self._expect("ok", connect_timeout)
        except (OSError, can.CanError) as exc:
            sock.close()
            if isinstance(exc, can.CanInitializationError):
                raise
            raise can.CanInitializationError(f"socketcand handshake failed: {exc}") from exc
        sock.settimeout(None)
        sock.setblocking(True)
        self.channel = channel
        self.channel_info = f"socketcand on {channel}@{host}:{port}"
        super().__init__(channel=channel, can_filters=can_filters, **kwargs)

    # -- handshake --------------------------------------------------------------------------
    def _probe_features(self, timeout: float) -> bool:
        """Ask ``< features >`` (before rawmode, so no frame can come first): True when the
        server is the loopback hub and takes ``< sendat ... >``; a socketcand daemon answers
        ``< error ... >`` (or nothing): plain sends. ``VIRTUAL_DRIVE_SENDAT=0`` in the
        environment keeps plain sends (and the drive's 1 ms ticks) on the hub too."""
        if os.environ.get("VIRTUAL_DRIVE_SENDAT", "1") == "0":
            return False
        self._sock.sendall(b"< features >")
        try:
            words = self._expect("features", timeout, strict=False)
        except (OSError, can.CanError):
            return False
        return words is not None and "sendat" in words

    def _expect(self, word: str, timeout: float, strict: bool = True) -> list[str] | None:
        """Read one element; it must be ``< word ... >`` (its words are returned). Otherwise
        CanInitializationError, or None when not ``strict``."""
        deadline = time.monotonic() + timeout
        while True:
            end = self._buf.find(b">")
            if end >= 0:
                element = self._buf[: end + 1].decode("ascii", "replace").split()
                self._buf = self._buf[end + 1 :]
                if element[1:2] == [word]:
                    return element[2:-1]
                if not strict:
                    return None
                raise can.CanInitializationError(
                    f"socketcand handshake: expected '< {word} >', got {' '.join(element)!r}"
                )
            left = deadline - time.monotonic()
            if left <= 0:
                raise can.CanInitializationError(f"socketcand handshake: no '< {word} >'")
            self._sock.settimeout(left)
            chunk = self._sock.recv(4096)
            if not chunk:
                raise can.CanInitializationError("socketcand server closed the connection")
            self._buf += chunk

    # -- sending ----------------------------------------------------------------------------
    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        """Send one frame (``timeout`` is ignored, as in python-can's socketcand); a remote
        frame as socketcand's ``< sendrtr <id> <dlc> >``."""
        if msg.is_remote_frame:
            ident = b"%08X" % msg.arbitration_id if msg.is_extended_id else b"%03X" % (
                msg.arbitration_id
            )
            line = b"< sendrtr %s %d >" % (ident, msg.dlc)
        elif self.timed_sends:  # with the time it was sent: see send_many
            line = format_sendat(
                time.monotonic(), msg.arbitration_id, bytes(msg.data), msg.is_extended_id
            )
        else:
            line = format_send(msg.arbitration_id, bytes(msg.data), msg.is_extended_id)
        with self._send_lock:
            self._sock.sendall(line)

    def send_many(self, frames: Sequence[tuple[int, bytes]], at: float | None = None) -> int:
        """Send standard frames ``(cob_id, data)`` with one ``sendall``; returns how many.

        :param at: the ``time.monotonic()`` at which the frames were ready for the bus (the
            TPDO due time of a drive that runs its ticks in batches); when the server takes it
            (:attr:`timed_sends`) they are held as ``< sendat >`` elements until
            :meth:`flush` (the end of the drive's tick: one write per tick), else ``at`` is
            ignored and they are sent now. Frames sent now go to such a server as ``sendat``
            with the time they were sent: a plain send takes the time the server reads it,
            later, on a busy host, than a batch stated before it, whose frames then had to
            follow it and were squeezed together (TPDO2 below its inhibit time at load 8).
        """
        if self.timed_sends:
            if at is not None:
                self._held.append((at, frames))  # (formatted in flush: one pass per tick)
                return len(frames)
            if frames:
                data = format_sendat_batch(time.monotonic(), frames)
                with self._send_lock:
                    self._sock.sendall(data)
            return len(frames)
        lines = [
            b"< send %03X %X %s >" % (cob_id, len(data), data.hex(" ").encode())
            if data
            else b"< send %03X 0 >" % cob_id
            for cob_id, data in frames
        ]  # format_send inlined (the pacing loop's path)
        if lines:
            with self._send_lock:
                self._sock.sendall(b"".join(lines))
        return len(lines)

    def send_lines(self, data: bytes) -> None:
        """Write already formatted socketcand elements (one ``sendall``, under the send
        lock): a :class:`HubConnection` sends its nodes' frames through it."""
        with self._send_lock:
            self._sock.sendall(data)

    def flush(self) -> None:
        """Write the frames held by :meth:`send_many` (``at`` given) in one ``sendall``."""
        if self._held:
            held, self._held = self._held, []
            data = format_held(held, self._prefixes)
            with self._send_lock:
                self._sock.sendall(data)

    # -- receiving --------------------------------------------------------------------------
    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        queue = self._queue
        if queue:
            return queue.popleft(), False
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            if self._eof:
                if timeout:
                    time.sleep(min(timeout, 0.05))  # no busy loop on a dead connection
                return None, False
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            try:
                ready, _, _ = select.select([self._sock], [], [], left)
            except (OSError, ValueError) as exc:
                raise can.CanOperationError(f"socketcand receive failed: {exc}") from exc
            if not ready:
                return None, False
            try:
                chunk = self._sock.recv(65536)
            except OSError as exc:
                raise can.CanOperationError(f"socketcand receive failed: {exc}") from exc
            if not chunk:
                self._eof = True
                continue
            if self._tcp_tune and _QUICKACK is not None:
                try:
                    self._sock.setsockopt(socket.IPPROTO_TCP, _QUICKACK, 1)
                except OSError:
                    pass
            self._parse(chunk)
            if queue:
                return queue.popleft(), False
            if deadline is not None and time.monotonic() >= deadline:
                return None, False

    def _parse(self, chunk: bytes) -> None:
        buf = self._buf + chunk if self._buf else chunk
        parts = buf.split(b">")
        rest = parts.pop()
        self._buf = rest if len(rest) <= _MAX_PARTIAL else b""
        wanted = self.rx_wanted
        direct = self.rx_direct
        queue = self._queue
        channel = self.channel
        for part in parts:
            words = part.split()
            if len(words) < 4 or words[0] != b"<":
                continue  # "< ok >", "< echo >", padding, garbage
            kind = words[1]
            if kind == b"frame":
                ident = words[2]
                try:
                    can_id = int(ident, 16)
                except ValueError:
                    continue
                if wanted is not None and can_id not in wanted:
                    self.rx_dropped += 1
                    continue
                try:
                    data = bytes.fromhex(words[4].decode("ascii")) if len(words) > 4 else b""
                    stamp = float(words[3])
                except ValueError:
                    logger.warning("bad frame element from the server: %r", part[:80])
                    continue
                if direct is not None:
                    direct(can_id, data, stamp, len(ident) != 3)
                    continue
                queue.append(
                    can.Message(
                        timestamp=stamp,
                        arbitration_id=can_id,
                        data=data,
                        is_extended_id=len(ident) != 3,
                        is_rx=True,
                        channel=channel,
                    )
                )
            elif kind == b"rtr":  # a remote frame (socketcand): rare, never filtered
                try:
                    can_id, stamp, dlc = int(words[2], 16), float(words[3]), int(words[4])
                except (IndexError, ValueError):
                    continue
                queue.append(
                    can.Message(
                        timestamp=stamp,
                        arbitration_id=can_id,
                        is_remote_frame=True,
                        dlc=dlc,
                        is_extended_id=len(words[2]) != 3,
                        is_rx=True,
                        channel=channel,
                    )
                )
            elif kind == b"error":
                try:
                    can_id, stamp = int(words[2], 16), float(words[3])
                except ValueError:
                    continue
                queue.append(
                    can.Message(
                        timestamp=stamp,
                        arbitration_id=can_id & 0x1FFFFFFF,
                        is_error_frame=True,
                        data=b"\x00",
                        is_extended_id=True,
                        is_rx=True,
                        channel=channel,
                    )
                )

    # -- lifetime ---------------------------------------------------------------------------
    def lost(self) -> str | None:
        """Why the connection is gone (the server closed it or it failed), or None."""
        if self._eof:
            return "the socketcand server closed the connection"
        try:
            if self._sock.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT) == b"":
                return "the socketcand server closed the connection"
        except BlockingIOError:
            pass
        except OSError as exc:
            return f"socketcand connection failed: {exc}"
        return None

    def fileno(self) -> int:
        return self._sock.fileno()

    def shutdown(self) -> None:
        super().shutdown()
        try:
            self._sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self._sock.close()


class HubConnection:
    """One socketcand connection shared by several nodes of this process (``--nodes``).

    Each node gets a :class:`HubPort` (a python-can bus of its own, ``port()``). Frames from the
    server are read by one thread and handed to the ports whose ``rx_wanted`` has their ID;
    frames a port sends go to the server and, as on a real bus, to the other ports that want
    them. The hub then forwards each drive frame once (to the other clients) instead of to every
    drive connection, and no drive parses the others' PDOs. Frames sent on the thread named by
    :meth:`batch_on` (the pacing thread) are collected and written in one ``sendall`` at
    :meth:`flush` (the pacer calls it after its TPDO passes and at the end of each wake-up).

    Parameters as :class:`HubBus`.
    """

    def __init__(
        self,
        channel: str = "vcan0",
        host: str = "127.0.0.1",
        port: int | None = None,
        tcp_tune: bool = True,
        connect_timeout: float = 10.0,
        **kwargs: Any,
    ) -> None:
        self._bus = HubBus(channel, host, port, tcp_tune, connect_timeout=connect_timeout)
        self.channel_info = self._bus.channel_info
        self.channel = channel
        self._ports: list[HubPort] = []
        self._lock = threading.Lock()
        #: (time the frames were ready, monotonic s; their lines) held for flush()
        self._held: list[tuple[float, list[bytes]]] = []
        self._batch_ident: int | None = None
        self._broken: str | None = None
        self._closed = False
        self._reader = threading.Thread(target=self._read, name="hub-connection", daemon=True)
        self._reader.start()

    def port(self) -> HubPort:
        """A new node-side bus on this connection."""
        p = HubPort(self)
        with self._lock:
            self._ports = [*self._ports, p]
        return p

    def batch_on(self, ident: int | None) -> None:
        """Collect the frames sent by thread ``ident`` until :meth:`flush` (None: never)."""
        self._batch_ident = ident

    def flush(self) -> None:
        """Write the collected frames in one ``sendall``, in the order of their times (the
        hub keeps a sender's order: one node's frames stated earlier must not follow another
        node's stated later, nor a heartbeat held after them)."""
        if self._held:
            held, self._held = self._held, []
            if len(held) > 1:
                held.sort(key=_FIRST)
            data = b"".join([b"".join(lines) for _, lines in held])
            try:
                self._bus.send_lines(data)
            except OSError as exc:  # reported once; lost() says why
                if self._broken is None:
                    self._broken = f"socketcand connection failed: {exc}"
                    logger.warning("hub connection: %s", exc)

    def send_from(
        self, src: HubPort, frames: list[tuple[int, bytes, bool]], at: float | None = None
    ) -> None:
        """Frames ``(cob_id, data, extended)`` port ``src`` sends (due at ``at``, monotonic s):
        to the server (held for :meth:`flush` on the batching thread) and to the sibling
        ports that want them."""
        if self._bus.timed_sends:
            # every frame with its time, those sent now too (heartbeat, SDO answer, EMCY): a
            # plain send takes the time the hub reads it, later than the batch stated before
            # it, whose frames then had to follow it and were squeezed (TPDO2 below its
            # inhibit time at load 8)
            if at is None:
                at = time.monotonic()
            head = sendat_head(at)
            lines = [head + sendat_tail(cob_id, data, ext) for cob_id, data, ext in frames]
        else:
            lines = [format_send(cob_id, data, ext) for cob_id, data, ext in frames]
        if threading.get_ident() == self._batch_ident:
            self._held.append((time.monotonic() if at is None else at, lines))
        else:
            self._bus.send_lines(b"".join(lines))
        ports = self._ports
        if len(ports) > 1:  # local delivery: the other nodes of this process see them too
            stamp = time.time() if at is None else at + WALL_OFFSET
            for p in ports:
                if p is src:
                    continue
                wanted = p.rx_wanted
                for cob_id, data, ext in frames:
                    if wanted is None or cob_id in wanted:
                        msg = can.Message(
                            timestamp=stamp,
                            arbitration_id=cob_id,
                            data=data,
                            is_extended_id=ext,
                            is_rx=True,
                            channel=self.channel,
                        )
                        p.deliver(msg)

    def _read(self) -> None:
        bus = self._bus
        while not self._closed:
            try:
                msg = bus.recv(0.2)
            except can.CanError:
                if self._closed:
                    return
                time.sleep(0.05)
                continue
            if msg is None:
                continue
            cob_id = msg.arbitration_id
            for p in self._ports:
                wanted = p.rx_wanted
                if (
                    wanted is None
                    or cob_id in wanted
                    or msg.is_error_frame
                    or msg.is_remote_frame
                ):
                    p.deliver(msg)

    @property
    def timed_sends(self) -> bool:
        """The server takes ``< sendat >`` (see :meth:`HubBus.send_many`)."""
        return self._bus.timed_sends

    def lost(self) -> str | None:
        """Why the shared connection is gone, or None (as :meth:`HubBus.lost`)."""
        return self._bus.lost() or self._broken

    def detach(self, p: HubPort) -> None:
        """Port ``p`` shut down: the connection closes with its last port."""
        with self._lock:
            self._ports = [q for q in self._ports if q is not p]
            last = not self._ports
        if last:
            self.close()

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._bus.shutdown()
        self._reader.join(2.0)


class HubPort(can.BusABC):
    """One node's bus on a shared :class:`HubConnection` (``rx_wanted`` as on HubBus)."""

    def __init__(self, conn: HubConnection) -> None:
        self._conn = conn
        self._queue: deque[can.Message] = deque()
        self._ready = threading.Condition()
        self.rx_wanted: Container[int] | None = None
        self.channel = conn.channel
        self.channel_info = conn.channel_info
        super().__init__(channel=conn.channel)

    def deliver(self, msg: can.Message) -> None:
        """A frame for this node (from the server or a sibling port on the connection)."""
        with self._ready:
            self._queue.append(msg)
            self._ready.notify()

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        with self._ready:
            if not self._queue:
                self._ready.wait(timeout)
            if self._queue:
                return self._queue.popleft(), False
        return None, False

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        self._conn.send_from(self, [(msg.arbitration_id, bytes(msg.data), msg.is_extended_id)])

    @property
    def timed_sends(self) -> bool:
        """The server takes ``< sendat >`` (see :meth:`HubBus.send_many`)."""
        return self._conn.timed_sends

    def flush(self) -> None:
        """Nothing: frames are sent at once, or held by the connection for the pacer's
        flush hook (:meth:`HubConnection.batch_on`)."""

    def send_many(self, frames: Iterable[tuple[int, bytes]], at: float | None = None) -> int:
        batch = [(cob_id, data, False) for cob_id, data in frames]
        if batch:
            self._conn.send_from(self, batch, at)
        return len(batch)

    def lost(self) -> str | None:
        return self._conn.lost()

    def shutdown(self) -> None:
        super().shutdown()
        self._conn.detach(self)
