"""Flow control per browser: send a page the next live update only when it has caught up.

Why: viser's page reads its WebSocket in a worker thread that hands every batch to the page's
main thread, however far behind that thread is; nothing pushes back on the server. A page
starved of CPU (a busy host: load 20 on two cores) then queues plot and status updates faster
than it applies them, and its backlog grows without bound. Measured: page B of two, run 10 % of
the time for 40 s, needed 18 s at full speed to answer a script call afterwards; in CI both
pages stayed unresponsive for minutes (Playwright's waits queue behind the backlog).

How: every update sent to a page counts (``sent``). Now and then (one marker in flight at a
time, at most one per MARKER_PERIOD_S), and always after the update that makes AHEAD updates
unconfirmed, a marker follows the update: viser's localStorage read request
(``LocalStorageGetItemRequestMessage``), which the page answers from its main thread's message
handler, in order, after it applied everything queued before it. The answer confirms all updates
up to the marker (``acked``). :meth:`PagePace.ready` says whether the page may get another
update: fewer than AHEAD unconfirmed. So a slow page gets fewer, newer updates (the plots and
status always carry the whole current state, so skipping one loses nothing) and its backlog
stays below AHEAD updates; a fast page is not slowed. A marker costs the page one frame of its
(software-WebGL) canvas, hence at most one every MARKER_PERIOD_S unless the window is full.

Private viser API used (viser 1.1.1): ``ClientHandle._websock_connection`` (``queue_message``,
``register_handler``) and the two localStorage messages.
"""

from __future__ import annotations

import itertools
import threading
import time
from typing import Any

__all__ = ["AHEAD", "MARKER_PERIOD_S", "STALL_S", "PagePace"]

AHEAD = 12  #: updates a page may have unconfirmed (≈ 0.4 s of plots at 24 Hz plus status)
MARKER_PERIOD_S = 0.5  #: at most one marker per this many s while the window is not full
STALL_S = 10.0  #: a marker unanswered this long: allow one more update (and a new marker)
_KEY = "dashboard-pace"  #: the localStorage key read (never written: the answer is null)
_ids = itertools.count(1)


class PagePace:
    """What one browser's page has applied of what the server sent it (see module docstring).

    A client without a viser connection (a test's stand-in) is never held back."""

    def __init__(self, client: Any) -> None:
        self._conn = getattr(client, "_websock_connection", None)
        self._prefix = f"{_KEY}-{next(_ids)}-"
        self._lock = threading.Lock()
        self.sent = 0  #: updates sent to the page
        self.acked = 0  #: updates the page confirmed it applied
        self.markers = 0  #: markers sent
        self.lag_s = 0.0  #: round-trip time of the last answered marker (s)
        self._pending: dict[str, tuple[int, float]] = {}  # marker id → (sent count, monotonic)
        self._last_marker = -float("inf")
        if self._conn is not None:
            from viser import _messages

            self._request = _messages.LocalStorageGetItemRequestMessage
            self._conn.register_handler(
                _messages.LocalStorageGetItemResponseMessage, self._on_answer
            )

    def ready(self) -> bool:
        """Whether the page may get another update now."""
        if self._conn is None:
            return True
        with self._lock:
            if self.sent - self.acked < AHEAD:
                return True
            oldest = min((t for _, t in self._pending.values()), default=None)
        return oldest is None or time.monotonic() - oldest > STALL_S

    def sent_update(self) -> None:
        """Count one update just queued for the page; queue a marker after it when due."""
        if self._conn is None:
            return
        now = time.monotonic()
        with self._lock:
            self.sent += 1
            full = self.sent - self.acked >= AHEAD  # this update fills the window
            if self._pending:  # one marker in flight; another only for a full window
                stalled = all(now - t > STALL_S for _, t in self._pending.values())
                due = full or stalled
            else:
                due = full or now - self._last_marker >= MARKER_PERIOD_S
            if not due:
                return
            self.markers += 1
            uuid = f"{self._prefix}{self.markers}"
            self._pending[uuid] = (self.sent, now)
            self._last_marker = now
        self._conn.queue_message(self._request(key=_KEY, request_uuid=uuid))

    def _on_answer(self, client_id: int, message: Any) -> None:
        """viser's event loop: the page applied everything up to this marker."""
        del client_id
        uuid = getattr(message, "request_uuid", "")
        if not uuid.startswith(self._prefix):
            return
        with self._lock:
            got = self._pending.pop(uuid, None)
            if got is None:
                return
            seq, t = got
            self.acked = max(self.acked, seq)
            self.lag_s = time.monotonic() - t
            for k, (s, _) in list(self._pending.items()):
                if s <= seq:
                    del self._pending[k]
