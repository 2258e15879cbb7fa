"""Safety rails around viser (1.1): who may open the GUI, and one lock for every send.

viser checks neither the Host nor the Origin of its HTTP page and WebSocket, handles a
share-URL request (a public tunnel) from any client even with the share button hidden, and its
handles may be written from any thread. This module:

- checks Host (and, for the WebSocket, Origin) in the opening handshake, before viser handles
  any message: a foreign Host gets 421, a foreign Origin 403 (the socket never opens);
- replaces viser's share-URL handlers with refusals;
- serialises every message viser queues (``queue_message``) under one process-wide lock, so
  that the plot thread, the status thread, viser's callbacks and the REST threads never push
  into viser's buffers at the same time.

Private viser/websockets API used (checked against viser 1.1.1, websockets 16): the asyncio
``Server`` object of the running server (found by its bound port), its ``process_request``
attribute, ``WebsockServer.register_handler/unregister_handler`` and
``WebsockMessageHandler.queue_message``.
"""

from __future__ import annotations

import gc
import threading
from collections.abc import Callable
from typing import Any

from dashboard.security import host_ok, origin_ok

#: One lock for every message queued into viser (see module docstring).
SEND_LOCK = threading.RLock()


def install_send_lock() -> None:
    """Wrap viser's ``WebsockMessageHandler.queue_message`` in :data:`SEND_LOCK` (once)."""
    from viser.infra import _infra

    cls = _infra.WebsockMessageHandler
    if getattr(cls.queue_message, "_dashboard_locked", False):
        return
    original = cls.queue_message

    def queue_message(self: Any, message: Any) -> None:
        with SEND_LOCK:
            original(self, message)

    queue_message._dashboard_locked = True  # type: ignore[attr-defined]
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
    port: int, hosts: Callable[[], set[str]], origins: Callable[[], set[str]]
) -> None:
    """Check Host (every HTTP request and WebSocket) and Origin (WebSocket) in the handshake of
    the viser server bound to ``port``. ``hosts``/``origins`` give the allowed sets at call
    time. :raises RuntimeError: no websockets server found on that port."""
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
            return original(conn, request) if original is not None else None

        srv.process_request = process_request


def refuse_share_url(server: Any, notify: Callable[[int], None] | None = None) -> None:
    """Replace viser's share-URL handlers (they open a public tunnel) by refusals."""
    from viser import _messages

    ws = server._websock_server
    for cls in (_messages.ShareUrlRequest, _messages.ShareUrlDisconnect):
        if cls in ws._incoming_handlers:
            ws.unregister_handler(cls)

    def refused(client_id: int, message: Any) -> None:
        if notify is not None:
            notify(client_id)

    ws.register_handler(_messages.ShareUrlRequest, refused)
    server.request_share_url = lambda *a, **k: None  # belt and braces: never a tunnel
