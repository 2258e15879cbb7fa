"""End to end in a real headless Chromium (/usr/bin/chromium, never a downloaded browser).

Starts ``drive-dashboard --virtual`` as a user would, opens the printed URL, enables the drive,
presses the speed step button, sees the speed plot move and the speed reach the setpoint, then
changes L_c and sees the drive's read-back and the margins change; the margins shown are checked
against python-control (test-only oracle). Screenshot: artifacts/dashboard_e2e.png only (the
README's picture is made on purpose with ``python -m dashboard.screenshot docs/bench.png``).
"""

from __future__ import annotations

import math
import os
import re
import time
from pathlib import Path

import control as ct
import httpx
import pytest

from dashboard.browser import (
    CHROMIUM,
    click,
    dismiss_notifications,
    launch,
    run_dashboard,
    text_input,
)

ROOT = Path(__file__).resolve().parents[1]
SPEED_FACTOR = 1.0
TS, R, L = 20e-6, 6.2e-3, 14.8e-6

pytestmark = [
    pytest.mark.timeout(180),
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium"),
]


@pytest.fixture(scope="module")
def bench():
    """``drive-dashboard --virtual`` in a child process; yields (gui_url, api_url)."""
    args = ["--virtual", "--speed-factor", str(SPEED_FACTOR), "--no-3d"]
    with run_dashboard(args) as urls:
        yield urls


@pytest.fixture(scope="module")
def page(bench):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = launch(p)
        pg = browser.new_page(viewport={"width": 1400, "height": 1000})
        pg.requested = []
        pg.on("request", lambda r: pg.requested.append(r.url))
        pg.on("websocket", lambda ws: pg.requested.append(ws.url))
        pg.goto(bench[0])
        pg.get_by_role("button", name="Enable").wait_for(timeout=30_000)
        yield pg
        browser.close()


def status(page) -> str:
    return page.inner_text("body")


def wait_text(page, pattern: str, timeout: float = 20.0) -> re.Match:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = re.search(pattern, status(page))
        if m:
            return m
        time.sleep(0.1)
    raise AssertionError(f"page never showed {pattern!r}; it shows:\n{status(page)[:1500]}")


def test_speed_step_in_the_browser(page):
    click(page, page.get_by_role("button", name="Enable"))
    wait_text(page, r"OPERATION ENABLED")
    plot = page.locator(".uplot").first
    before = plot.screenshot(timeout=60_000)
    click(page, page.get_by_role("button", name="+ step"))
    seen: list[float] = []
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        m = re.search(r"speed ([-\d.]+) rpm \(set (-?\d+)\)", status(page))
        if m and m.group(2) == "500":
            seen.append(float(m.group(1)))
            if abs(seen[-1] - 500.0) < 5.0:
                break
        time.sleep(0.1)
    assert seen and abs(seen[-1] - 500.0) < 5.0, f"speed never reached 500 rpm: {seen[-5:]}"
    assert any(20.0 < s < 480.0 for s in seen), f"no intermediate speed seen: {seen}"
    after = plot.screenshot(timeout=60_000)
    assert after != before  # the speed plot moved
    time.sleep(0.5)
    assert plot.screenshot(timeout=60_000) != after  # and keeps scrolling (live)


def test_one_controller_and_visible_take_over(page, bench):
    api = bench[1]
    tok = httpx.post(f"{api}/api/control", json={"client": "script", "take_over": True})
    tok = tok.json()["token"]
    wait_text(page, r"In control: script since")  # the browser sees who took over
    wait_text(page, r"script took control from you")  # shown under the control buttons
    click(page, page.get_by_role("button", name="+ step"))
    wait_text(page, r"script controls the bench")  # watching: the click changed nothing
    assert httpx.get(f"{api}/api/state").json()["speed_setpoint"] == 500
    click(page, page.get_by_role("button", name="Take control"))
    wait_text(page, r"In control: browser #\d+ \(you\) since")
    r = httpx.post(
        f"{api}/api/command", json={"command": "enable"}, headers={"X-Control-Token": tok}
    )
    assert r.status_code == 409  # the script now only watches


def current_margins(ratio: float) -> tuple[float, float, float]:
    """GM (dB), PM (°), ‖S‖∞ of the deadbeat loop with L_c = ratio·L (python-control)."""
    Phi, Gamma = math.exp(-R * TS / L), (1 - math.exp(-R * TS / L)) / (2 * R)
    Lc = ratio * L
    Phi_c, Gamma_c = math.exp(-R * TS / Lc), (1 - math.exp(-R * TS / Lc)) / (2 * R)
    loop = ct.minreal(
        ct.tf([1, -Phi_c, 0], [Gamma_c, 0, -Gamma_c], TS) * ct.tf([Gamma], [1, -Phi, 0], TS),
        verbose=False,
    )
    gm, pm, _, _ = ct.margin(loop)
    return 20 * math.log10(gm), abs(pm)  # PM: the smallest margin, a positive angle


def test_change_L_c_and_see_readback_and_margins(page, bench):
    click(page, page.get_by_role("tab", name="Tuning"))
    pattern = r"Current \(deadbeat, L_c/L = ([\d.]+)\): stable · GM ([\d.]+) dB · PM ([-\d.]+)°"
    m0 = wait_text(page, pattern)
    assert float(m0.group(1)) == pytest.approx(1.0, abs=1e-3)
    assert float(m0.group(3)) == pytest.approx(60.0, abs=0.2)
    box = text_input(page, "L_c (µH)")
    click(page, box)
    page.keyboard.press("Control+A")
    page.keyboard.type("22.2")
    page.keyboard.press("Tab")
    m1 = wait_text(
        page, r"Current \(deadbeat, L_c/L = 1\.500\): stable · GM ([\d.]+) dB · PM ([-\d.]+)°"
    )
    gm, pm = current_margins(1.5)
    assert float(m1.group(1)) == pytest.approx(gm, abs=0.01)
    assert float(m1.group(2)) == pytest.approx(pm, abs=0.1)
    assert float(m1.group(2)) != pytest.approx(float(m0.group(3)), abs=1.0)  # margins changed
    click(page, page.get_by_role("button", name="Apply gains"))
    wait_text(page, r"L_c 22\.2 µH \(L_c/L 1\.5000\)")  # read back from the drive
    g = httpx.get(f"{bench[1]}/api/gains").json()
    assert g["L_c"] == pytest.approx(22.2e-6, rel=1e-6)
    click(page, page.get_by_role("tab", name="Speed"))
    dismiss_notifications(page)  # viser's "software WebGL" notice
    page.get_by_text("In control:").scroll_into_view_if_needed()
    time.sleep(0.5)
    out = ROOT / "artifacts"
    out.mkdir(exist_ok=True)
    page.screenshot(path=str(out / "dashboard_e2e.png"))


def test_nothing_leaves_the_machine(page, bench):
    """The GUI and the API docs load no asset from a CDN or any other host."""
    page.goto(f"{bench[1]}/docs")
    page.get_by_text("/api/gains").first.wait_for(timeout=10_000)  # rendered from /openapi.json
    urls = [u for u in page.requested if not u.startswith(("data:", "blob:"))]
    assert urls and all(re.match(r"(http|ws)://127\.0\.0\.1:\d+/", u) for u in urls), urls
