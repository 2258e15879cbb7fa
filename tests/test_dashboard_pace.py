"""The per-page flow control of the live view (dashboard._gui_pace) against a stand-in page that
applies what it is sent in order; applying a marker's HTML makes it request the marker's image
from the viser port (as Chromium does for an <img hidden> put into the page), which the port
hands to dashboard._gui_pace.answer.

Truths: the messages the stand-in page received, in order, and when it applies them.
"""

from __future__ import annotations

import re

import pytest

from dashboard import _gui_pace
from dashboard._gui_pace import AHEAD, PATH_PREFIX, PagePace, answer

pytestmark = pytest.mark.unit


class _Page:
    """A browser's page stand-in: keeps what it is sent; ``apply()`` plays the page."""

    def __init__(self) -> None:
        self.queue: list[str] = []

    def apply(self, n: int | None = None) -> int:
        """Apply the first ``n`` queued updates (all by default), loading marker images."""
        done, self.queue = self.queue[:n], self.queue[len(self.queue[:n]) :]
        for m in done:
            src = re.search(r'<img src="([^"]+)"', m)
            if src:
                assert answer(src.group(1))  # the viser port recognises a marker's address
        return len(done)


class _Html:
    def __init__(self, page: _Page) -> None:
        self.page = page

    @property
    def content(self) -> str:
        return ""

    @content.setter
    def content(self, value: str) -> None:
        self.page.queue.append(value)


class _Client:
    """A viser ClientHandle stand-in with a connection and a per-client GUI."""

    def __init__(self) -> None:
        self._websock_connection = object()
        self.page = _Page()
        self.gui = self

    def add_html(self, content: str) -> _Html:
        return _Html(self.page)


def _paced() -> tuple[_Page, PagePace]:
    client = _Client()
    return client.page, PagePace(client)


def _send(pace: PagePace, page: _Page) -> None:
    page.queue.append("update")
    pace.sent_update()


def test_a_page_that_applies_nothing_gets_at_most_AHEAD_updates():
    page, pace = _paced()
    sent = 0
    for _ in range(1000):  # the plot loop ticking while the page is starved
        if pace.ready():
            _send(pace, page)
            sent += 1
    assert sent == AHEAD
    assert page.queue.count("update") == AHEAD
    assert page.queue[-1].startswith("<img")  # the window's last update is confirmable
    page.apply()  # the page runs again and applies its backlog
    assert pace.ready() and pace.acked == pace.sent == AHEAD


def test_a_page_that_keeps_up_is_never_held_back():
    page, pace = _paced()
    for _ in range(500):
        assert pace.ready()
        _send(pace, page)
        page.apply()  # applied before the next tick
    assert pace.sent == 500 and pace.sent - pace.acked < AHEAD
    assert pace.markers <= 500 // (AHEAD - 1) + 2  # markers only when due, not per update


def test_markers_confirm_in_order_and_a_stalled_marker_lets_one_more_through(monkeypatch):
    page, pace = _paced()
    while pace.ready():
        _send(pace, page)
    assert pace.markers == 2  # after the first update, and after the one that filled the window
    page.apply(2)  # the page applied the first update and the marker behind it
    assert pace.acked == 1 and pace.ready()
    _send(pace, page)
    assert not pace.ready()
    assert answer(f"{PATH_PREFIX}999999-1")  # a marker of a page gone: answered, changes nothing
    assert not answer("/index.html") and not answer(f"{PATH_PREFIX}x")
    assert not pace.ready()
    monkeypatch.setattr(_gui_pace, "STALL_S", 0.0)  # a page that stopped answering
    assert pace.ready()
    _send(pace, page)
    assert page.queue[-1].startswith("<img")  # a new marker follows the extra update
    page.apply()
    assert pace.acked == pace.sent == AHEAD + 2 and not pace._pending


def test_a_client_without_a_connection_is_not_paced():
    pace = PagePace(object())
    for _ in range(3 * AHEAD):
        assert pace.ready()
        pace.sent_update()
