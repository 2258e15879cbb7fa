"""Two real browsers (two headless /usr/bin/chromium processes through Playwright) and a REST
client on one bench at the same time.

Truths: what each browser's page shows (its own DOM), what the drive holds (read through the
REST API / drive_link, not through the GUI), and the plot thread's counters.

- Inputs are per browser: what B types never appears in A, and A's "+ step" applies A's step.
- A watching browser cannot change anything; a REST client without the lease gets 409.
- Typed values are parsed strictly: −0.5 in L_c/L and "abc" in L_c show a message at the field
  and nothing reaches the drive; after Apply the fields show the drive's read-back.
- The live view cannot die silently: failing sends are survived, a killed plot thread is
  restarted, and a frozen data source shows "STALE" with the data's age in the page.
- A page starved of CPU (its renderer run 10 % of the time) is sent no backlog: the server
  holds at most AHEAD unconfirmed updates for it while the other page streams on, and it is
  usable again as soon as it runs (the busy CI host kept both pages unresponsive for minutes).
- A closed tab loses the lease LEASE_GRACE_S after its socket closed (not at once).
"""

from __future__ import annotations

import os
import re
import signal
import threading
import time

import pytest
from fastapi.testclient import TestClient

from dashboard import _gui_pace
from dashboard._gui import LEASE_GRACE_S
from dashboard._gui_pace import AHEAD
from dashboard.app import create_app
from dashboard.browser import CHROMIUM, click, launch, open_bench, text_input
from dashboard.config import BenchConfig

pytestmark = [
    pytest.mark.timeout(600),  # two Chromium start-ups take minutes at load 20-30
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium"),
]

L = 14.8e-6
VIEWPORT = {"width": 1400, "height": 900}  # the README screenshot's size
SCROLL_TOP = "() => document.querySelectorAll('*').forEach(e => { e.scrollTop = 0; })"


@pytest.fixture(scope="module")
def api():
    cfg = BenchConfig(virtual=True, speed_factor=1.0, gui_port=0, scene_3d=False)
    with TestClient(create_app(cfg), base_url="http://127.0.0.1:8000") as c:
        yield c


@pytest.fixture(scope="module")
def pages(api):
    from playwright.sync_api import sync_playwright

    url = f"http://127.0.0.1:{api.app.state.gui.port}/"
    with sync_playwright() as p:
        browsers = [launch(p), launch(p)]  # two Chromium processes: two real browsers
        out = []
        for b in browsers:
            pg = b.new_page(viewport=VIEWPORT)
            pg.set_default_timeout(90_000)  # a busy host stalls the pages for tens of seconds
            open_bench(pg, url)
            out.append(pg)
        yield out
        for b in browsers:
            b.close()


def text(page) -> str:
    return page.inner_text("body")


def wait_text(page, pattern: str, timeout: float = 60.0) -> re.Match:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = re.search(pattern, text(page))
        if m:
            return m
        time.sleep(0.1)
    raise AssertionError(f"page never showed {pattern!r}; it shows:\n{text(page)[:2000]}")


def wait_until(cond, timeout: float = 30.0, what: str = "condition") -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if cond():
            return
        time.sleep(0.1)
    raise AssertionError(f"{what} not met within {timeout} s")


def type_into(page, label: str, value: str) -> None:
    box = text_input(page, label)
    box.wait_for(state="attached", timeout=60_000)
    box.evaluate("e => { e.scrollIntoView({block: 'center'}); e.focus(); e.select(); }")
    page.keyboard.type(value)
    page.keyboard.press("Tab")
    time.sleep(0.3)  # viser batches GUI messages in 50 ms windows


def field(page, label: str) -> str:
    return text_input(page, label).input_value()


def test_inputs_are_per_browser_and_only_the_controller_applies(api, pages):
    a, b = pages
    click(a, a.get_by_role("button", name="Enable"))  # A's first action takes control
    wait_until(lambda: api.get("/api/control").json()["client"] is not None, what="A in control")
    holder = api.get("/api/control").json()["client"]
    assert holder.startswith("browser #")
    wait_text(a, r"In control: browser #\d+ \(you\)")
    type_into(b, "Step size (rpm)", "3000")  # B watches and types
    assert field(b, "Step size (rpm)") == "3000"
    assert field(a, "Step size (rpm)") == "500"  # A's own input did not change
    click(a, a.get_by_role("button", name="+ step"))
    wait_until(lambda: api.get("/api/state").json()["speed_setpoint"] == 500, what="setpoint 500")
    click(b, b.get_by_role("button", name="+ step"))
    wait_text(b, r"controls the bench")  # B is told, at the control
    time.sleep(0.5)
    assert api.get("/api/state").json()["speed_setpoint"] == 500  # B changed nothing
    r = api.put("/api/setpoints/speed", json={"rpm": 100})  # REST client without the lease
    assert r.status_code == 409
    click(b, b.get_by_role("tab", name="Tuning"))
    click(a, a.get_by_role("tab", name="Tuning"))
    type_into(b, "L_c / L", "1.9")  # B's tuning inputs stay B's
    assert field(a, "L_c / L") == "1"
    click(b, b.get_by_role("tab", name="Speed"))


def test_typed_values_are_strict_and_nothing_is_sent(api, pages):
    a, _ = pages
    click(a, a.get_by_role("tab", name="Tuning"))
    a.evaluate(SCROLL_TOP)  # the panel from its top: preview and Apply without scrolling
    time.sleep(0.3)
    for name in ("Apply gains", "Read back"):
        box = a.get_by_role("button", name=name).bounding_box()
        assert box is not None and box["y"] + box["height"] <= VIEWPORT["height"], (name, box)
    assert a.get_by_text("Before applying").bounding_box()["y"] < VIEWPORT["height"]
    before = api.get("/api/gains").json()["L_c"]
    type_into(a, "L_c / L", "-0.5")
    wait_text(a, r"L_c / L: -0\.5 is outside the range .* nothing sent")
    click(a, a.get_by_role("button", name="Apply gains"))
    wait_text(a, r"nothing sent ·")  # the notice under Apply
    assert api.get("/api/gains").json()["L_c"] == before  # the drive kept its value
    type_into(a, "L_c / L", "1")
    type_into(a, "L_c (µH)", "abc")
    wait_text(a, r"L_c \(µH\): 'abc' is not a number")
    click(a, a.get_by_role("button", name="Apply gains"))
    time.sleep(0.5)
    assert api.get("/api/gains").json()["L_c"] == before
    type_into(a, "L_c (µH)", "20")
    click(a, a.get_by_role("button", name="Apply gains"))
    wait_text(a, r"applied; the fields show the drive's read-back")
    g = api.get("/api/gains").json()
    assert g["L_c"] == pytest.approx(20e-6, rel=1e-6)
    assert float(field(a, "L_c (µH)")) == pytest.approx(g["L_c"] * 1e6, rel=1e-6)
    assert float(field(a, "L_c / L")) == pytest.approx(g["L_c"] / g["motor_L"], rel=1e-5)
    tok = api.post("/api/control", json={"client": "t", "take_over": True}).json()["token"]
    api.put("/api/gains", json={"L_c": L}, headers={"X-Control-Token": tok})
    click(a, a.get_by_role("button", name="Take control"))


def test_live_view_survives_failures_and_shows_stale(api, pages, monkeypatch):
    gui = api.app.state.gui
    _, b = pages
    wait_text(b, r"● live · data \d+ ms old")
    real_push = gui.push_plots

    def failing(*a, **k):
        raise RuntimeError("deque mutated during iteration")  # what viser's buffer raised

    errors0 = gui.stream_errors
    monkeypatch.setattr(gui, "push_plots", failing)
    wait_until(lambda: gui.stream_errors >= errors0 + 3, what="failing sends survived")
    assert gui._threads["plots"].is_alive()  # the same thread carries on
    wait_text(b, r"STALE · plots not refreshed")  # the page says so while it fails
    monkeypatch.setattr(gui, "push_plots", real_push)
    sent = gui.frames_sent
    wait_until(lambda: gui.frames_sent > sent + 5, what="plots flowing again")

    def killer(*a, **k):  # kills the plot thread outright (not an Exception)
        gui.push_plots = real_push
        raise SystemExit("plot thread killed by the test")

    restarts = gui.plot_restarts
    old = gui._threads["plots"]
    gui.push_plots = killer
    wait_until(lambda: not old.is_alive(), what="plot thread dead")
    wait_until(lambda: gui.plot_restarts > restarts, timeout=20, what="watchdog restart")
    sent = gui.frames_sent
    wait_until(lambda: gui.frames_sent > sent + 5, what="plots after the restart")
    wait_text(b, r"● live · data \d+ ms old")

    live = api.app.state.bench.drive.live
    frozen = live.window(gui.config.live_window_s)
    monkeypatch.setattr(live, "window", lambda seconds, names=None: frozen)  # no new data
    m = wait_text(b, r"STALE · newest data ([\d.]+) s old")
    assert float(m.group(1)) >= 1.0  # stale after 1 s; the page rounds the age to 0.1 s
    monkeypatch.undo()
    wait_text(b, r"● live · data \d+ ms old")


def _renderer_pids(page) -> list[int]:
    """The renderer processes of the browser that shows ``page`` (Chromium's own list)."""
    cdp = page.context.browser.new_browser_cdp_session()
    try:
        info = cdp.send("SystemInfo.getProcessInfo")["processInfo"]
    finally:
        cdp.detach()
    return [p["id"] for p in info if p["type"] == "renderer"]


def _starve(pids: list[int], seconds: float, duty: float, stop: threading.Event) -> None:
    """Let ``pids`` run ``duty`` of every 0.5 s (SIGSTOP/SIGCONT) for ``seconds``."""
    until = time.monotonic() + seconds
    try:
        while time.monotonic() < until and not stop.is_set():
            for pid in pids:
                os.kill(pid, signal.SIGSTOP)
            time.sleep(0.5 * (1 - duty))
            for pid in pids:
                os.kill(pid, signal.SIGCONT)
            time.sleep(0.5 * duty)
    finally:
        for pid in pids:
            os.kill(pid, signal.SIGCONT)


def test_a_starved_page_gets_no_backlog_and_is_usable_when_it_runs(api, pages):
    gui = api.app.state.gui
    a, b = pages
    click(a, a.get_by_role("button", name="Take control"))  # to tell A's panel from B's
    wait_text(a, r"In control: browser #\d+ \(you\)")
    wait_text(b, r"● live · data \d+ ms old")
    panels = gui.panel_list()
    assert len(panels) == 2
    pa = next(p for p in panels if p.holds_control())
    pb = next(p for p in panels if p is not pa)
    pids = _renderer_pids(b)
    assert pids
    stop = threading.Event()
    th = threading.Thread(target=_starve, args=(pids, 12.0, 0.1, stop), daemon=True)
    acked_a, sent_b = pa.pace.acked, pb.pace.sent
    behind = 0
    th.start()
    try:
        while th.is_alive():
            behind = max(behind, pb.pace.sent - pb.pace.acked)
            time.sleep(0.02)
    finally:
        stop.set()
        th.join()
    print(f"starved page: {pb.pace.sent - sent_b} updates sent in 12 s, at most {behind} queued")
    # at most AHEAD updates queued for the starved page, plus one per STALL_S (a marker its
    # page had not answered for that long)
    assert behind <= AHEAD + int(12.0 / _gui_pace.STALL_S)
    assert pb.pace.sent - sent_b < 12 * (gui.config.gui_rate_hz + 4)  # not the full stream
    assert pa.pace.acked > acked_a  # page A applied (and confirmed) updates meanwhile
    t0 = time.monotonic()
    b.evaluate("1")  # the page runs scripts again at once: no backlog in front of them
    wait_text(b, r"● live · data \d+ ms old", timeout=30)
    b.get_by_role("button", name="Enable").first.wait_for(timeout=30_000)
    print(f"page B usable {time.monotonic() - t0:.1f} s after the starvation")


def test_closed_tab_loses_the_lease_after_the_grace_time(api, pages):
    a, b = pages
    click(a, a.get_by_role("button", name="Take control"))
    wait_text(a, r"In control: browser #\d+ \(you\)")
    holder = api.get("/api/control").json()["client"]
    a.close()
    wait_text(b, r"its page closed: control frees in", timeout=30)
    assert api.get("/api/control").json()["client"] == holder  # kept through a reload's time
    wait_until(
        lambda: api.get("/api/control").json()["client"] is None,
        timeout=LEASE_GRACE_S + 30,
        what="lease released",
    )
    click(b, b.get_by_role("button", name="+ step"))  # nobody holds it: B's action takes it
    wait_text(b, r"In control: browser #\d+ \(you\)")
