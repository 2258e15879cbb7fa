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
import select
import socket
import threading
import time
from collections import deque
from collections.abc import Container, Iterable

import can

__all__ = ["HubBus", "format_send"]

logger = logging.getLogger(__name__)

_QUICKACK = getattr(socket, "TCP_QUICKACK", None)
_MAX_PARTIAL = 4096  #: bytes of an unfinished element kept before the buffer is discarded


def format_send(cob_id: int, data: bytes, is_extended: bool = False) -> bytes:
    """``< send <id> <len> <b0> ... >`` as bytes (ids: 3 hex digits standard, 8 extended)."""
    ident = f"{cob_id:08X}" if is_extended else f"{cob_id:03X}"
    if data:
        return f"< send {ident} {len(data):X} {data.hex(' ')} >".encode("ascii")
    return f"< send {ident} 0 >".encode("ascii")


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
        can_filters=None,
        connect_timeout: float = 10.0,
        **kwargs,
    ) -> None:
        if port is None:
            raise can.CanInitializationError("vdhub needs the server's port")
        self._tcp_tune = bool(tcp_tune)
        self._buf = b""
        self._queue: deque[can.Message] = deque()
        self._send_lock = threading.Lock()
        self._eof = False
        #: CAN-IDs to deliver (None: all). Consulted per frame, so a live dict works.
        self.rx_wanted: Container[int] | None = None
        self.rx_dropped = 0  #: frames not delivered because nobody wanted them
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
    def _expect(self, word: str, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while True:
            end = self._buf.find(b">")
            if end >= 0:
                element = self._buf[: end + 1].decode("ascii", "replace").split()
                self._buf = self._buf[end + 1 :]
                if element[1:2] == [word]:
                    return
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
        """Send one frame (``timeout`` is ignored, as in python-can's socketcand)."""
        line = format_send(msg.arbitration_id, bytes(msg.data), msg.is_extended_id)
        with self._send_lock:
            self._sock.sendall(line)

    def send_many(self, frames: Iterable[tuple[int, bytes]]) -> int:
        """Send standard frames ``(cob_id, data)`` with one ``sendall``; returns how many."""
        lines = [format_send(cob_id, data) for cob_id, data in frames]
        if lines:
            with self._send_lock:
                self._sock.sendall(b"".join(lines))
        return len(lines)

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
