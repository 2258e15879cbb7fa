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

A failure explains itself: it carries what :class:`Watch` saw every 5 s (load, CPU/memory/IO
pressure, each Chromium process's CPU s, state and major faults, how long each renderer's main
thread ran and waited for a CPU, the pace counters of each page, viser connections opened and
closed, the last text of each page). A page that did not answer in time because the host gave
its renderer no CPU (its main thread waited for one ≥ STARVED of that time) skips the test with
those figures; a renderer that ran or slept meanwhile fails it.
"""

from __future__ import annotations

import functools
import os
import re
import signal
import threading
import time

import pytest
from conftest import main_thread_times
from fastapi.testclient import TestClient

from dashboard import _gui_pace
from dashboard._gui import LEASE_GRACE_S
from dashboard._gui_pace import AHEAD
from dashboard.app import create_app
from dashboard.browser import CHROMIUM, launch, open_bench, renderer_pids, text_input
from dashboard.browser import click as _click
from dashboard.browser import click_until as _click_until
from dashboard.browser import select_tab as _select_tab
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


class Watch:
    """What the module's two pages did, for a failure message that explains itself: every
    SAMPLE_S the host (load, CPU and memory pressure, free memory), each browser's processes
    (CPU s, state, major page faults; for the renderers' main threads the s they ran and the s
    they waited for a CPU), the pace counters of each page's panel, the viser connections
    opened and closed, and the last text each page showed."""

    SAMPLE_S = 5.0

    def __init__(self, gui) -> None:
        self.gui = gui
        self.pids: dict[str, dict[int, str]] = {}  # page name → {pid: Chromium process type}
        self.names: dict[int, str] = {}  # id(page) → page name
        self.last_text: dict[str, tuple[float, str]] = {}  # page name → (monotonic, text)
        self.samples: list[str] = []
        self.events: list[str] = []  # viser connections opened and closed, page crashes
        self._conns: dict[int, object] = {}
        self._stop = threading.Event()
        self._t0 = time.monotonic()
        self._th = threading.Thread(target=self._run, name="browser-watch", daemon=True)

    def add(self, name: str, page) -> None:
        cdp = page.context.browser.new_browser_cdp_session()
        try:
            info = cdp.send("SystemInfo.getProcessInfo")["processInfo"]
        finally:
            cdp.detach()
        self.pids[name] = {p["id"]: p["type"] for p in info}
        self.names[id(page)] = name
        page.on("crash", lambda _: self.event(f"page {name} crashed"))

    def event(self, what: str) -> None:
        self.events.append(f"t={time.monotonic() - self._t0:.0f}s {what}")

    def start(self) -> None:
        ws = self.gui.server._websock_server
        self._conns.update(ws._live_connections)
        self.gui.server.on_client_connect(self._opened)
        self.gui.server.on_client_disconnect(self._closed)
        self._th.start()

    def _opened(self, client) -> None:
        ws = self.gui.server._websock_server
        self._conns[client.client_id] = ws._live_connections.get(client.client_id)
        self.event(f"viser client #{client.client_id} opened")

    def _closed(self, client) -> None:
        conn = self._conns.pop(client.client_id, None)
        how = "?"
        if conn is not None:
            how = f"code {conn.close_code} {conn.close_reason!r}"
            if conn.protocol.close_rcvd is None:
                how += " (no close frame from the page)"
        self.event(f"viser client #{client.client_id} closed: {how}")

    def stop(self) -> None:
        self._stop.set()
        self._th.join(timeout=5)

    def _run(self) -> None:
        while not self._stop.wait(self.SAMPLE_S):
            self.samples.append(self.sample())
            del self.samples[:-24]

    def sched(self, page) -> tuple[float, float]:
        """(s run, s waited for a CPU) so far by the main threads of ``page``'s renderers."""
        name = self.names.get(id(page), "?")
        ran = waited = 0.0
        for pid, typ in self.pids.get(name, {}).items():
            if typ == "renderer":
                r, w = main_thread_times(pid)
                ran, waited = ran + r, waited + w
        return ran, waited

    def sample(self) -> str:
        out = [f"t={time.monotonic() - self._t0:.0f}s load {os.getloadavg()[0]:.1f} {_host()}"]
        for name, pids in self.pids.items():
            procs = " ".join(f"{typ[:3]}:{_proc(pid)}" for pid, typ in pids.items())
            out.append(f"{name}[{procs}]")
        for p in self.gui.panel_list():
            pending = ",".join(f"{time.monotonic() - t:.0f}s" for _, t in p.pace._pending.values())
            out.append(
                f"#{p.cid}{'*' if p.holds_control() else ''}(sent {p.pace.sent} acked "
                f"{p.pace.acked} lag {p.pace.lag_s:.1f}s pending {pending or '-'})"
            )
        return " ".join(out)

    def report(self) -> str:
        now = time.monotonic()
        seen = "\n".join(
            f"page {n} showed ({now - t:.0f} s ago): {txt[:300]!r}"
            for n, (t, txt) in self.last_text.items()
        )
        return (
            "\n--- browser watch: per Chromium process (bro/ren/GPU/net/sto) CPU s, state, major"
            " faults, a renderer's main thread ran/waited-for-CPU s; #client(*: in control) the"
            " pace of each page ---\n"
            + "\n".join([*self.samples[-12:], "now: " + self.sample(), *self.events[-6:]])
            + "\n"
            + seen
        )


WATCH: Watch | None = None


def _stat(pid: int) -> list[str] | None:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()
    except OSError:
        return None


def _proc(pid: int) -> str:
    """CPU s, state and major faults of process ``pid`` (and ran/waited s of a renderer's main
    thread), or "gone"."""
    st = _stat(pid)
    if st is None:
        return "gone"
    cpu = (int(st[11]) + int(st[12])) / os.sysconf("SC_CLK_TCK")
    ran, waited = main_thread_times(pid)
    return f"{cpu:.0f}s{st[0]}{st[9]}({ran:.0f}/{waited:.0f})"


def _host() -> str:
    """CPU and memory pressure (PSI some avg10, %) and available memory (MB)."""
    out = []
    for kind in ("cpu", "memory", "io"):
        try:
            with open(f"/proc/pressure/{kind}") as f:
                out.append(f"{kind} {f.readline().split()[1].split('=')[1]}%")
        except (OSError, IndexError):
            pass
    try:
        with open("/proc/meminfo") as f:
            avail = next(ln for ln in f if ln.startswith("MemAvailable"))
        out.append(f"avail {int(avail.split()[1]) // 1024} MB")
    except (OSError, StopIteration):
        pass
    return " ".join(out)


def explain(exc: BaseException) -> AssertionError:
    """``exc`` with what the browser watch saw (see :class:`Watch`)."""
    extra = WATCH.report() if WATCH is not None else ""
    out = AssertionError(f"{type(exc).__name__}: {exc}{extra}")
    out.explained = True  # type: ignore[attr-defined]
    return out


STARVED = 0.5  #: a page whose renderer waited for a CPU this share of a wait was starved


def explained(fn):
    """``fn`` whose failures carry the browser watch's report. When ``fn(page, ...)`` timed out
    because the host gave ``page``'s renderer no CPU (its main thread waited for one at least
    STARVED of the time, /proc schedstat), the test is skipped with those figures instead: the
    page then cannot show anything, whatever the product does. A renderer that ran, or slept
    (blocked), while the page did not answer fails the test."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        page = args[0] if args and hasattr(args[0], "inner_text") else None
        t0 = time.monotonic()
        s0 = WATCH.sched(page) if WATCH is not None and page is not None else None
        try:
            return fn(*args, **kwargs)
        except Exception as exc:  # Playwright's TimeoutError, a failed assert
            if getattr(exc, "explained", False):
                raise
            if s0 is not None and type(exc).__name__ == "TimeoutError":
                dt = time.monotonic() - t0
                ran, waited = (b - a for a, b in zip(s0, WATCH.sched(page), strict=True))
                if waited >= STARVED * dt:
                    pytest.skip(
                        f"page {WATCH.names.get(id(page))} did not answer in {dt:.0f} s: the "
                        f"host starved it (its renderer ran {ran:.1f} s and waited {waited:.1f}"
                        f" s for a CPU; load {os.getloadavg()[0]:.1f}): {exc}"
                        + WATCH.report()
                    )
            raise explain(exc) from exc

    return wrapper


click = explained(_click)
click_until = explained(_click_until)
select_tab = explained(_select_tab)


@pytest.fixture(scope="module")
def pages(api):
    global WATCH
    from playwright.sync_api import sync_playwright

    url = f"http://127.0.0.1:{api.app.state.gui.port}/"
    WATCH = Watch(api.app.state.gui)
    with sync_playwright() as p:
        browsers = [launch(p), launch(p)]  # two Chromium processes: two real browsers
        out = []
        for name, b in zip("AB", browsers, strict=True):
            pg = b.new_page(viewport=VIEWPORT)
            pg.set_default_timeout(90_000)  # a busy host stalls the pages for tens of seconds
            open_bench(pg, url)
            WATCH.add(name, pg)
            out.append(pg)
        WATCH.start()
        yield out
        WATCH.stop()
        print(WATCH.report())  # shown with -s or on a teardown error
        for b in browsers:
            b.close()


def text(page, timeout: float = 90.0) -> str:
    """The page's text (``timeout`` s for the page to answer)."""
    txt = page.inner_text("body", timeout=timeout * 1000)
    if WATCH is not None:
        WATCH.last_text[WATCH.names.get(id(page), "?")] = (time.monotonic(), txt)
    return txt


@explained
def wait_text(page, pattern: str, timeout: float = 90.0) -> re.Match:
    """The first match of ``pattern`` in the page's text within ``timeout`` s (a page that
    does not answer counts against the same time)."""
    deadline = time.monotonic() + timeout
    while True:
        m = re.search(pattern, text(page, max(deadline - time.monotonic(), 1.0)))
        if m:
            return m
        if time.monotonic() >= deadline:
            raise AssertionError(f"page never showed {pattern!r} in {timeout:g} s")
        time.sleep(0.1)


def wait_until(cond, timeout: float = 30.0, what: str = "condition") -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if cond():
            return
        time.sleep(0.1)
    raise AssertionError(f"{what} not met within {timeout} s")


@explained
def type_into(page, label: str, value: str) -> None:
    box = text_input(page, label)
    box.wait_for(state="attached", timeout=60_000)
    box.evaluate("e => { e.scrollIntoView({block: 'center'}); e.focus(); e.select(); }")
    page.keyboard.type(value)
    page.keyboard.press("Tab")
    time.sleep(0.3)  # viser batches GUI messages in 50 ms windows


@explained
def field(page, label: str) -> str:
    return text_input(page, label).input_value()


@explained
def test_inputs_are_per_browser_and_only_the_controller_applies(api, pages):
    a, b = pages
    # A's first action takes control
    click_until(
        a,
        a.get_by_role("button", name="Enable"),
        lambda t: wait_until(
            lambda: api.get("/api/control").json()["client"] is not None, t, "A in control"
        ),
    )
    holder = api.get("/api/control").json()["client"]
    assert holder.startswith("browser #")
    wait_text(a, r"In control: browser #\d+ \(you\)")
    type_into(b, "Step size (rpm)", "3000")  # B watches and types
    assert field(b, "Step size (rpm)") == "3000"
    assert field(a, "Step size (rpm)") == "500"  # A's own input did not change
    click(a, a.get_by_role("button", name="+ step"))
    wait_until(lambda: api.get("/api/state").json()["speed_setpoint"] == 500, what="setpoint 500")
    click_until(  # B is told, at the control (B's click changes nothing: safe to repeat)
        b,
        b.get_by_role("button", name="+ step"),
        lambda t: wait_text(b, r"controls the bench", t),
        timeout=30.0,
    )
    time.sleep(0.5)
    assert api.get("/api/state").json()["speed_setpoint"] == 500  # B changed nothing
    r = api.put("/api/setpoints/speed", json={"rpm": 100})  # REST client without the lease
    assert r.status_code == 409
    select_tab(b, "Tuning")
    select_tab(a, "Tuning")
    type_into(b, "L_c / L", "1.9")  # B's tuning inputs stay B's
    assert field(a, "L_c / L") == "1"
    select_tab(b, "Speed")


@explained
def test_typed_values_are_strict_and_nothing_is_sent(api, pages):
    a, _ = pages
    select_tab(a, "Tuning")
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
    click_until(
        a,
        a.get_by_role("button", name="Apply gains"),
        lambda t: wait_text(a, r"applied; the fields show the drive's read-back", t),
        timeout=30.0,
    )
    g = api.get("/api/gains").json()
    assert g["L_c"] == pytest.approx(20e-6, rel=1e-6)
    assert float(field(a, "L_c (µH)")) == pytest.approx(g["L_c"] * 1e6, rel=1e-6)
    assert float(field(a, "L_c / L")) == pytest.approx(g["L_c"] / g["motor_L"], rel=1e-5)
    tok = api.post("/api/control", json={"client": "t", "take_over": True}).json()["token"]
    api.put("/api/gains", json={"L_c": L}, headers={"X-Control-Token": tok})
    click(a, a.get_by_role("button", name="Take control"))


@explained
def test_live_view_survives_failures_and_shows_stale(api, pages, monkeypatch):
    gui = api.app.state.gui
    _, b = pages
    wait_text(b, r"● live · data [\d.]+ s old")
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
    wait_text(b, r"● live · data [\d.]+ s old")

    live = api.app.state.bench.drive.live
    frozen = live.window(gui.config.live_window_s)
    frozen_newest = live.streams(0.0)  # what the bench's state reads (newest of each signal)
    monkeypatch.setattr(live, "window", lambda seconds, names=None: frozen)  # no new data
    monkeypatch.setattr(live, "streams", lambda seconds=None: frozen_newest)
    m = wait_text(b, r"STALE · newest data ([\d.]+) s old")
    assert float(m.group(1)) >= 0.5  # stale after 0.5 s; the page rounds the age to 0.1 s
    monkeypatch.undo()
    wait_text(b, r"● live · data [\d.]+ s old")


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


@explained
def test_a_starved_page_gets_no_backlog_and_is_usable_when_it_runs(api, pages):
    gui = api.app.state.gui
    a, b = pages
    click(a, a.get_by_role("button", name="Take control"))  # to tell A's panel from B's
    wait_text(a, r"In control: browser #\d+ \(you\)")
    wait_text(b, r"● live · data [\d.]+ s old")
    panels = gui.panel_list()
    assert len(panels) == 2
    pa = next(p for p in panels if p.holds_control())
    pb = next(p for p in panels if p is not pa)
    pids = renderer_pids(b)
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
    wait_text(b, r"● live · data [\d.]+ s old", timeout=30)
    b.get_by_role("button", name="Enable").first.wait_for(timeout=30_000)
    print(f"page B usable {time.monotonic() - t0:.1f} s after the starvation")


@explained
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
    # (B shows the Speed tab, whatever an earlier test of this module left it on)
    select_tab(b, "Speed")
    click(b, b.get_by_role("button", name="+ step"))  # nobody holds it: B's action takes it
    wait_text(b, r"In control: browser #\d+ \(you\)")
