"""The Report tab in a real headless Chromium (/usr/bin/chromium): run the commissioning report
on the virtual drive from the page with one experiment ticked, see its verdict, download the
HTML (self-contained: the figure embedded) and the JSON (the issue's schema); the drive is left
as the page found it (the REST API's state before and after), also when the run is cancelled
during a speed step. While the report runs (issue 26 item 7) the dashboard stays responsive:
GET /api/state at 10 Hz answers within 100 ms (median, and nine calls in ten), counted beyond the
run-queue wait the host gave the dashboard during each call, and the live speed
plot keeps moving (successive screenshots differ)."""

from __future__ import annotations

import itertools
import json
import os
import re
import statistics
import threading
import time

import httpx
import pytest
from conftest import PLOT_RATE_ARGS, RunQueueProbe

from dashboard.browser import (
    CHROMIUM,
    click,
    dismiss_notifications,
    launch,
    open_bench,
    run_dashboard,
    select_tab,
)

pytestmark = [
    pytest.mark.timeout(420),
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium"),
]


class StateSampler(threading.Thread):
    """GET /api/state every 0.1 s until stopped; ``latencies`` gets the s each call took
    while a long action ran (``running`` says whether one runs now), less the time the host
    kept the dashboard's threads waiting for a CPU during that call (its run-queue wait, at
    most the call's own time): what the product added, not the host."""

    def __init__(self, api_url: str, pid: int) -> None:
        super().__init__(daemon=True)
        self.api_url = api_url
        self.pid = pid
        self.latencies: list[float] = []
        self.host_s: list[float] = []
        self.running = False
        self.stop = threading.Event()

    def run(self) -> None:
        with httpx.Client(base_url=self.api_url, timeout=30) as api:
            while not self.stop.wait(0.1):
                probe = RunQueueProbe(self.pid)
                t0 = time.monotonic()
                self.running = api.get("/api/state").json()["action"] is not None
                took = time.monotonic() - t0
                probe.stop()
                if self.running:
                    host = min(took, probe.waited)
                    self.latencies.append(took - host)
                    self.host_s.append(host)


def _known_state(api_url: str, timeout: float = 10.0) -> dict:
    """``GET /api/state`` once the drive watch knows the mode again: right after a long action
    the dashboard shows the mode as unknown (None) until its next poll (0.5 s) reads it, rather
    than a mode the action may have changed (seen in an idle run: mode None just after Cancel)."""
    deadline = time.monotonic() + timeout
    while True:
        st = httpx.get(f"{api_url}/api/state", timeout=30).json()
        if st.get("mode") is not None or time.monotonic() > deadline:
            return st
        time.sleep(0.2)


def test_report_tab_runs_and_downloads(tmp_path):
    from playwright.sync_api import TimeoutError as PlaywrightTimeoutError
    from playwright.sync_api import sync_playwright

    with run_dashboard(["--virtual", "--no-3d", *PLOT_RATE_ARGS]) as dash, sync_playwright() as p:
        browser = launch(p)
        page = browser.new_page(viewport={"width": 1400, "height": 900}, accept_downloads=True)
        page.set_default_timeout(90_000)
        requested: list[str] = []
        page.on("request", lambda r: requested.append(r.url))
        open_bench(page, dash.gui_url)
        dismiss_notifications(page)
        before = _known_state(dash.api_url)
        select_tab(page, "Report")
        for label in ("lc sweep", "current step pi", "current step predictive", "pwm ripple",
                      "identify electrical", "identify speed model", "speed step", "load step"):
            click(page, page.get_by_label(label, exact=True))
        click(page, page.get_by_role("button", name="Run report"))
        # issue 26 item 7: while it runs, /api/state answers in <= 100 ms and the plots move
        sampler = StateSampler(dash.api_url, dash.proc.pid)  # GET /api/state at 10 Hz while it runs
        sampler.start()
        shots: list[bytes] = []  # the speed plot while the report runs: it must move
        plot = page.locator(".uplot").first
        deadline = time.monotonic() + 180
        body = ""
        while time.monotonic() < deadline:
            if sampler.running:
                shots.append(plot.screenshot(timeout=60_000))
            body = page.inner_text("body")
            if re.search(r"report done in [\d.]+ s", body) or re.search(r"⚠ (?!STALE)", body):
                break
            time.sleep(0.2)
        assert re.search(r"report done in [\d.]+ s: 1 of 1 not failed", body), body[-600:]
        assert re.search(r"current_step_deadbeat\s*\|?\s*pass", body), body[-600:]
        with page.expect_download() as dl:
            click(page, page.get_by_role("button", name="HTML"))
        html = (tmp_path / "r.html")
        dl.value.save_as(html)
        text = html.read_text()
        assert "Commissioning report" in text and "data:image/png;base64," in text
        assert "<script" not in text and "src='http" not in text
        with page.expect_download() as dl:
            click(page, page.get_by_role("button", name="JSON"))
        dl.value.save_as(tmp_path / "r.json")
        rep = json.loads((tmp_path / "r.json").read_text())
        (e,) = rep["experiments"]
        assert e["id"] == "current_step_deadbeat" and e["verdict"] == "pass"
        assert e["metrics"]["settling_samples"]["measured"] == 2
        after = _known_state(dash.api_url)
        for key in ("state", "mode"):
            if key in before:
                assert after[key] == before[key], (before, after)
        # Cancel during a speed step: the drive is put back as found
        click(page, page.get_by_label("current step deadbeat", exact=True))
        click(page, page.get_by_label("speed step", exact=True))
        click(page, page.get_by_role("button", name="Run report"))
        page.get_by_role("button", name="Cancel action").wait_for(timeout=60_000)
        t_min, t_end = time.monotonic() + 2.0, time.monotonic() + 5.0
        # 2 s of shots, longer until 4 (one shot took over 0.6 s at load 16). Each shot gets
        # only the time left, so Cancel is pressed while the step still runs (ci27, load 10: a
        # shot with 60 s outlasted the whole speed step, and Cancel was gone)
        while time.monotonic() < t_min or (len(shots) < 4 and time.monotonic() < t_end):
            left = (t_end if len(shots) < 4 else t_min) - time.monotonic()
            if sampler.running:
                try:
                    shots.append(plot.screenshot(timeout=max(500.0, 1e3 * left)))
                except PlaywrightTimeoutError:
                    break
            time.sleep(0.2)
        click(page, page.get_by_role("button", name="Cancel action"))
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and "report cancelled" not in page.inner_text("body"):
            time.sleep(0.5)
        assert "report cancelled" in page.inner_text("body")
        sampler.stop.set()
        sampler.join(timeout=10)
        lat, load = sampler.latencies, os.getloadavg()
        print(f"while the report ran: GET /api/state median {statistics.median(lat) * 1e3:.0f} "
              f"ms, max {max(lat) * 1e3:.0f} ms over {len(lat)} calls beyond the host's run-queue "
              f"wait (which was {sum(sampler.host_s):.2f} s in all); {len(shots)} plot shots "
              f"(load {load[0]:.1f})")
        assert len(lat) >= 20 and len(shots) >= 4, "the report ended before it was seen"
        # as the freshness test: the median within 100 ms, none near an SDO timeout (0.3 s);
        # and nine calls in ten within 100 ms (a loaded 2-core host delays a few)
        assert statistics.median(lat) <= 0.100, (sorted(lat)[-5:], load)
        assert sum(x <= 0.100 for x in lat) >= 0.9 * len(lat), (sorted(lat)[-5:], load)
        assert max(lat) < 0.300, (sorted(lat)[-5:], load)
        moved = sum(a != b for a, b in itertools.pairwise(shots))
        assert moved >= len(shots) - 2, f"the live plot stood still: {moved} of {len(shots) - 1}"
        after = _known_state(dash.api_url)
        for key in ("state", "mode", "speed_setpoint", "current_setpoint"):
            assert after[key] == before[key], (key, before, after)
        assert all(u.startswith(("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:"))
                   for u in requested), requested
        browser.close()
