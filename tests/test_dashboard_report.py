"""The Report tab in a real headless Chromium (/usr/bin/chromium): run the commissioning report
on the virtual drive from the page with one experiment ticked, see its verdict, download the
HTML (self-contained: the figure embedded) and the JSON (the issue's schema); the drive is left
as the page found it (the REST API's state before and after), also when the run is cancelled
during a speed step."""

from __future__ import annotations

import json
import os
import re
import time

import httpx
import pytest

from dashboard.browser import (
    CHROMIUM,
    click,
    dismiss_notifications,
    launch,
    open_bench,
    run_dashboard,
)

pytestmark = [
    pytest.mark.timeout(420),
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium"),
]


def test_report_tab_runs_and_downloads(tmp_path):
    from playwright.sync_api import sync_playwright

    with run_dashboard(["--virtual", "--no-3d"]) as dash, sync_playwright() as p:
        browser = launch(p)
        page = browser.new_page(viewport={"width": 1400, "height": 900}, accept_downloads=True)
        page.set_default_timeout(90_000)
        requested: list[str] = []
        page.on("request", lambda r: requested.append(r.url))
        open_bench(page, dash.gui_url)
        dismiss_notifications(page)
        before = httpx.get(f"{dash.api_url}/api/state", timeout=30).json()
        click(page, page.get_by_role("tab", name="Report"))
        for label in ("lc sweep", "current step pi", "current step predictive", "pwm ripple",
                      "identify electrical", "identify speed model", "speed step", "load step"):
            click(page, page.get_by_label(label, exact=True))
        click(page, page.get_by_role("button", name="Run report"))
        deadline = time.monotonic() + 180
        body = ""
        while time.monotonic() < deadline:
            body = page.inner_text("body")
            if re.search(r"report done in [\d.]+ s", body) or "⚠" in body:
                break
            time.sleep(0.5)
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
        after = httpx.get(f"{dash.api_url}/api/state", timeout=30).json()
        for key in ("state", "mode"):
            if key in before:
                assert after[key] == before[key], (before, after)
        # Cancel during a speed step: the drive is put back as found
        click(page, page.get_by_label("current step deadbeat", exact=True))
        click(page, page.get_by_label("speed step", exact=True))
        click(page, page.get_by_role("button", name="Run report"))
        page.get_by_role("button", name="Cancel action").wait_for(timeout=60_000)
        time.sleep(1.0)
        click(page, page.get_by_role("button", name="Cancel action"))
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and "report cancelled" not in page.inner_text("body"):
            time.sleep(0.5)
        assert "report cancelled" in page.inner_text("body")
        after = httpx.get(f"{dash.api_url}/api/state", timeout=30).json()
        for key in ("state", "mode", "speed_setpoint", "current_setpoint"):
            assert after[key] == before[key], (key, before, after)
        assert all(u.startswith(("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:"))
                   for u in requested), requested
        browser.close()
