"""Safety rails around viser (1.1): who may open the GUI, and one lock for every send.

viser checks neither the Host nor the Origin of its HTTP page and WebSocket, handles a
share-URL request (a public tunnel) from any client even with the share button hidden, and its
handles may be written from any thread. This module:

- checks Host (and, for the WebSocket, Origin) in the opening handshake, before viser handles
  any message: a foreign Host gets 421, a foreign Origin 403 (the socket never opens);
- replaces viser's share-URL handlers with refusals;
- answers the live view's pace markers (an image address per marker, :mod:`dashboard._gui_pace`)
  with an empty 204, after the Host check;
- serialises every message viser queues (``queue_message``) under one process-wide lock, so
  that the plot thread, the status thread, viser's callbacks and the REST threads never push
  into viser's buffers at the same time;
- fixes the race that froze the live plots ("RuntimeError: deque mutated during iteration"):
  viser's ``AsyncMessageBuffer.push()`` calls ``message_event.set()`` on an ``asyncio.Event``
  directly from the calling thread; ``Event.set()`` iterates the event's waiter deque while the
  event loop's thread appends/removes waiters (every window generator does ``wait()`` →
  ``clear()`` → ``wait()``), so a push from a plain thread can raise in the pusher. The
  buffers' events are replaced by :class:`LoopSafeEvent`, whose ``set()`` off the loop's
  thread is handed to the loop (viser already schedules the same ``set`` thread-safely right
  after; nothing in viser reads ``is_set()`` synchronously).

Private viser/websockets API used (checked against viser 1.1.1, websockets 16): the asyncio
``Server`` object of the running server (found by its bound port), its ``process_request``
attribute, ``WebsockServer.register_handler/unregister_handler`` and
``WebsockMessageHandler.queue_message``.
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import threading
from collections.abc import Callable
from typing import Any

from dashboard._security import host_ok, origin_ok

__all__ = [
    "SEND_LOCK",
    "LoopSafeEvent",
    "guard_handshake",
    "install_loop_safe_events",
    "install_send_lock",
    "refuse_share_url",
    "send_lock_installed",
]

#: One lock for every message queued into viser (see module docstring).
SEND_LOCK = threading.RLock()
_PATCHED: set[Any] = set()  #: the viser functions replaced here (installed once)


class LoopSafeEvent(asyncio.Event):
    """An asyncio.Event that may be set from any thread: off its loop's thread, ``set()`` is
    scheduled on the loop (``call_soon_threadsafe``) instead of touching the waiters."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        super().__init__()
        self._home = loop

    def set(self) -> None:
        try:
            here = asyncio.get_running_loop()
        except RuntimeError:
            here = None
        if here is self._home:
            super().set()
            return
        with contextlib.suppress(RuntimeError):  # loop closed: nobody waits any more
            self._home.call_soon_threadsafe(super().set)


def install_loop_safe_events() -> None:
    """Give every viser message buffer created from now on :class:`LoopSafeEvent` s (once)."""
    from viser.infra._async_message_buffer import AsyncMessageBuffer

    if AsyncMessageBuffer.__init__ in _PATCHED:
        return
    original = AsyncMessageBuffer.__init__

    def init_with_safe_events(self: Any, *args: Any, **kwargs: Any) -> None:
        original(self, *args, **kwargs)
        self.message_event = LoopSafeEvent(self.event_loop)
        self.flush_event = LoopSafeEvent(self.event_loop)

    _PATCHED.add(init_with_safe_events)
    AsyncMessageBuffer.__init__ = init_with_safe_events  # type: ignore[method-assign]


def send_lock_installed() -> bool:
    """True once viser's sends go through :data:`SEND_LOCK` (:func:`install_send_lock`)."""
    from viser.infra import _infra

    return _infra.WebsockMessageHandler.queue_message in _PATCHED


def install_send_lock() -> None:
    """Wrap viser's ``WebsockMessageHandler.queue_message`` in :data:`SEND_LOCK` and make its
    buffers' events thread-safe (:func:`install_loop_safe_events`); idempotent."""
    from viser.infra import _infra

    install_loop_safe_events()

    cls = _infra.WebsockMessageHandler
    if send_lock_installed():
        return
    original = cls.queue_message

    def queue_message(self: Any, message: Any) -> None:
        with SEND_LOCK:
            original(self, message)

    _PATCHED.add(queue_message)
    cls.queue_message = queue_message  # type: ignore[method-assign]


def _ws_servers(port: int) -> list[Any]:
    import websockets.asyncio.server as wss

    out = []
    for obj in gc.get_objects():
        if issubclass(type(obj), wss.Server):  # type(): no __getattribute__ of odd objects
            try:
                socks = obj.server.sockets if obj.server is not None else ()
            except Exception:
                continue
            if any(s.getsockname()[1] == port for s in socks):
                out.append(obj)
    return out


def guard_handshake(
    port: int,
    hosts: Callable[[], set[str]],
    origins: Callable[[], set[str]],
    answer: Callable[[str], bool] | None = None,
) -> None:
    """Check Host (every HTTP request and WebSocket) and Origin (WebSocket) in the handshake of
    the viser server bound to ``port``. ``hosts``/``origins`` give the allowed sets at call
    time. ``answer(path)``, if given, sees every plain request with an allowed Host first; when
    it returns True the request gets an empty 204 (the live view's pace markers,
    :mod:`dashboard._gui_pace`). :raises RuntimeError: no websockets server found on that port."""
    servers = _ws_servers(port)
    if not servers:
        raise RuntimeError(f"no viser server on port {port} to guard")
    for srv in servers:
        original = srv.process_request

        def process_request(conn: Any, request: Any, original: Any = original) -> Any:
            given = request.headers.get_all("Host")
            if len(given) != 1:
                return conn.respond(400, "exactly one Host header required\n")
            host = given[0]
            if not host_ok(host, hosts()):
                return conn.respond(421, f"host {host!r} not served here\n")
            if request.headers.get("Upgrade", "").lower() == "websocket":
                origin = request.headers.get("Origin")
                if not origin_ok(origin, origins()):
                    return conn.respond(403, "origin not allowed\n")
            elif answer is not None and answer(request.path):
                return conn.respond(204, "")
            return original(conn, request) if original is not None else None

        srv.process_request = process_request


def refuse_share_url(server: Any, notify: Callable[[int], None] | None = None) -> None:
    """Replace viser's share-URL handlers (they open a public tunnel) by refusals."""
    from viser import _messages

    ws = server._websock_server
    for cls in (_messages.ShareUrlRequest, _messages.ShareUrlDisconnect):
        with contextlib.suppress(AssertionError, KeyError):  # it was not registered
            ws.unregister_handler(cls)

    def refused(client_id: int, message: Any) -> None:
        if notify is not None:
            notify(client_id)

    ws.register_handler(_messages.ShareUrlRequest, refused)
    server.request_share_url = lambda *a, **k: None  # belt and braces: never a tunnel
