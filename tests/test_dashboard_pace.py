"""The per-page flow control of the live view (dashboard._gui_pace) against a stand-in page that
applies what it is sent in order and answers viser's localStorage read (as viser's page does:
MessageHandler.tsx answers LocalStorageGetItemRequestMessage after the messages before it).

Truths: the messages the stand-in page received, in order, and when it answers.
"""

from __future__ import annotations

from viser import _messages

from dashboard import _gui_pace
from dashboard._gui_pace import AHEAD, PagePace


class _Page:
    """A viser connection stand-in: keeps queued messages; ``apply()`` plays the page."""

    def __init__(self) -> None:
        self.queue: list[object] = []
        self.handlers: list = []

    def register_handler(self, cls, cb) -> None:
        assert cls is _messages.LocalStorageGetItemResponseMessage
        self.handlers.append(cb)

    def queue_message(self, msg) -> None:
        self.queue.append(msg)

    def apply(self, n: int | None = None) -> int:
        """Apply the first ``n`` queued messages (all by default), answering markers."""
        done, self.queue = self.queue[:n], self.queue[len(self.queue[:n]) :]
        for m in done:
            if isinstance(m, _messages.LocalStorageGetItemRequestMessage):
                ans = _messages.LocalStorageGetItemResponseMessage(
                    value=None, error=None, request_uuid=m.request_uuid
                )
                for cb in self.handlers:
                    cb(7, ans)
        return len(done)


class _Client:
    def __init__(self) -> None:
        self._websock_connection = _Page()


def _send(pace: PagePace, page: _Page) -> None:
    page.queue_message("update")
    pace.sent_update()


def test_a_page_that_applies_nothing_gets_at_most_AHEAD_updates():
    client = _Client()
    page, pace = client._websock_connection, PagePace(client)
    sent = 0
    for _ in range(1000):  # the plot loop ticking while the page is starved
        if pace.ready():
            _send(pace, page)
            sent += 1
    assert sent == AHEAD
    assert sum(m == "update" for m in page.queue) == AHEAD
    markers = [m for m in page.queue if m != "update"]
    assert markers and page.queue[-1] is markers[-1]  # the window's last update is confirmable
    page.apply()  # the page runs again and applies its backlog
    assert pace.ready() and pace.acked == pace.sent == AHEAD


def test_a_page_that_keeps_up_is_never_held_back():
    client = _Client()
    page, pace = client._websock_connection, PagePace(client)
    for _ in range(500):
        assert pace.ready()
        _send(pace, page)
        page.apply()  # applied before the next tick (and markers answered)
    assert pace.sent == 500 and pace.sent - pace.acked < AHEAD
    assert pace.markers <= 500 // (AHEAD - 1) + 2  # markers only when due, not per update


def test_answers_confirm_in_order_and_a_stalled_marker_lets_one_more_through(monkeypatch):
    client = _Client()
    page, pace = client._websock_connection, PagePace(client)
    while pace.ready():
        _send(pace, page)
    assert pace.markers == 2  # after the first update, and after the one that filled the window
    page.apply(2)  # the page applied the first update and answered the marker behind it
    assert pace.acked == 1 and pace.ready()
    _send(pace, page)
    assert not pace.ready()
    page.handlers[0](7, _messages.LocalStorageGetItemResponseMessage(None, None, "other-1"))
    assert not pace.ready()  # someone else's localStorage answer confirms nothing
    monkeypatch.setattr(_gui_pace, "STALL_S", 0.0)  # a page that stopped answering
    assert pace.ready()
    _send(pace, page)
    assert page.queue[-1] != "update"  # a new marker follows the extra update
    page.apply()
    assert pace.acked == pace.sent == AHEAD + 2 and not pace._pending


def test_a_client_without_a_connection_is_not_paced():
    pace = PagePace(object())
    for _ in range(3 * AHEAD):
        assert pace.ready()
        pace.sent_update()
