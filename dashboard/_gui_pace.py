"""Flow control per browser: send a page the next live update only when it has caught up.

Why: viser's page reads its WebSocket in a worker thread that hands every batch to the page's
main thread, however far behind that thread is; nothing pushes back on the server. A page
starved of CPU (a busy host: load 20 on two cores) then queues plot and status updates faster
than it applies them, and its backlog grows without bound. Measured: page B of two, run 10 % of
the time for 40 s, needed 18 s at full speed to answer a script call afterwards; in CI both
pages stayed unresponsive for minutes (Playwright's waits queue behind the backlog).

How: every update sent to a page counts (``sent``). Now and then (one marker in flight at a
time, at most one per MARKER_PERIOD_S), and always after the update that makes AHEAD updates
unconfirmed, a marker follows the update: a hidden HTML element of the page's panel gets an
``<img hidden>`` whose address (PATH_PREFIX + marker id) is served by the viser port itself
(:func:`dashboard._gui_guard.guard_handshake` calls :func:`answer`). The page requests it only
once its main thread applied that update, in order after everything queued before it, so the
request confirms all updates up to the marker (``acked``). :meth:`PagePace.ready` says whether
the page may get another update: fewer than AHEAD unconfirmed. So a slow page gets fewer, newer
updates (the plots and status always carry the whole current state, so skipping one loses
nothing) and its backlog stays below AHEAD updates; a page that keeps up is not slowed.

Why an image and not a viser request/answer (its localStorage read): a message that is not
GUI-only makes viser's page render its WebGL canvas for 250 ms (RENDER_SETTLE_MS in App.tsx);
with two markers a second that more than doubled Chromium's CPU (32.6 -> 75.3 % of a core).
A GUI update costs no canvas frame; the image request is one loopback HTTP request per marker.

Private viser API used (viser 1.1.1): ``ClientHandle._websock_connection`` (present for a real
browser's client) and ``client.gui.add_html``.
"""

from __future__ import annotations

import itertools
import re
import threading
import time
import weakref
from typing import Any

__all__ = ["AHEAD", "MARKER_PERIOD_S", "PATH_PREFIX", "STALL_S", "PagePace", "answer"]

AHEAD = 12  #: updates a page may have unconfirmed (≈ 0.4 s of plots at 24 Hz plus status)
MARKER_PERIOD_S = 0.5  #: at most one marker per this many s while the window is not full
STALL_S = 10.0  #: a marker unanswered this long: allow one more update (and a new marker)
PATH_PREFIX = "/dashboard-pace/"  #: the markers' image addresses on the viser port
_PATH = re.compile(re.escape(PATH_PREFIX) + r"(\d+)-(\d+)$")
_ids = itertools.count(1)
_paces: weakref.WeakValueDictionary[int, PagePace] = weakref.WeakValueDictionary()


def answer(path: str) -> bool:
    """A request for ``path`` reached the viser port: True if it was a marker's image (then
    the page it belongs to has applied everything up to that marker)."""
    m = _PATH.match(path.split("?", 1)[0])
    if m is None:
        return False
    pace = _paces.get(int(m.group(1)))
    if pace is not None:
        pace.confirm(int(m.group(2)))
    return True


class PagePace:
    """What one browser's page has applied of what the server sent it (see module docstring).

    A client without a viser connection (a test's stand-in) is never held back."""

    def __init__(self, client: Any) -> None:
        self._id = next(_ids)
        self._lock = threading.Lock()
        self.sent = 0  #: updates sent to the page
        self.acked = 0  #: updates the page confirmed it applied
        self.markers = 0  #: markers sent
        self.lag_s = 0.0  #: round-trip time of the last answered marker (s)
        self._pending: dict[int, tuple[int, float]] = {}  # marker → (sent count, monotonic)
        self._last_marker = -float("inf")
        self._html: Any = None
        if getattr(client, "_websock_connection", None) is not None:
            self._html = client.gui.add_html("")
            _paces[self._id] = self

    def ready(self) -> bool:
        """Whether the page may get another update now."""
        if self._html is None:
            return True
        with self._lock:
            if self.sent - self.acked < AHEAD:
                return True
            oldest = min((t for _, t in self._pending.values()), default=None)
        return oldest is None or time.monotonic() - oldest > STALL_S

    def sent_update(self) -> None:
        """Count one update just queued for the page; queue a marker after it when due."""
        if self._html is None:
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
            n = self.markers
            self._pending[n] = (self.sent, now)
            self._last_marker = now
        self._html.content = f'<img src="{PATH_PREFIX}{self._id}-{n}" alt="" hidden>'

    def confirm(self, marker: int) -> None:
        """The page applied everything up to ``marker`` (any thread)."""
        with self._lock:
            got = self._pending.pop(marker, None)
            if got is None:
                return
            seq, t = got
            self.acked = max(self.acked, seq)
            self.lag_s = time.monotonic() - t
            for k, (s, _) in list(self._pending.items()):
                if s <= seq:
                    del self._pending[k]
