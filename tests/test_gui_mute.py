"""The page's echo guard is per thread (dashboard._gui_page.Page.mute).

viser calls a field's callbacks in the thread that sets its value (checked here on a real
viser server), so the echo of a value the page sets is muted in that thread. An update the
browser sends meanwhile is handled in another of viser's threads and must not be dropped: with
one shared count, a keystroke that came in while another callback was muted was lost, and the
Loop tab kept drawing the L_c of an earlier keystroke (22 µH) under a box showing 22.2 (ci29).
"""

from __future__ import annotations

import threading
import types

import pytest
import viser

from dashboard._gui_page import Page
from dashboard.config import BenchConfig


def _page(gui=None) -> Page:
    client = types.SimpleNamespace(client_id=1, gui=gui)
    return Page(owner=None, client=client, bench=None, config=BenchConfig(virtual=True))


@pytest.mark.unit
def test_a_mute_in_one_thread_leaves_other_threads_heard():
    page = _page()
    inside, release = threading.Event(), threading.Event()
    seen: dict[str, bool] = {}

    def muter() -> None:
        with page.mute():
            seen["muting thread"] = page.muted
            inside.set()
            release.wait(10)

    t = threading.Thread(target=muter)
    t.start()
    assert inside.wait(10)
    seen["other thread"] = page.muted
    release.set()
    t.join(10)
    assert seen == {"muting thread": True, "other thread": False}
    assert not page.muted


def test_viser_calls_a_set_fields_callback_in_the_setting_thread_where_it_is_muted():
    srv = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        page = _page(srv.gui)
        box = srv.gui.add_text("L_c (µH)", "14.8")
        heard: list[tuple[str, str]] = []

        @box.on_update
        def _(event) -> None:
            if not page.muted:
                heard.append((threading.current_thread().name, box.value))

        def set_muted() -> None:
            with page.mute():
                box.value = "22"  # the page shows a value: its echo is muted

        t = threading.Thread(target=set_muted, name="page")
        t.start()
        t.join(10)
        assert heard == []
        box.value = "22.2"  # not muted here: heard, in this thread
        assert heard == [(threading.current_thread().name, "22.2")]
    finally:
        srv.stop()
