"""End to end in a real headless Chromium (/usr/bin/chromium, never a downloaded browser).

Starts ``drive-dashboard --virtual`` as a user would, opens the printed URL, enables the drive,
presses the speed step button, sees the speed plot move and the speed reach the setpoint, then
changes L_c and sees the drive's read-back and the margins change; the margins shown are checked
against python-control (test-only oracle). Layout at 1280×800: the live plots are the main area
(each ≥ 40 % of the width and ≥ 200 px tall, measured on screen); the Bode plot of the typed
L_c (read from the page's cursor legend) matches python-control before anything is applied,
and the z-plane redraws. Screenshots: artifacts/dashboard_e2e*.png only (the README's picture
is made on purpose with ``python -m dashboard.screenshot docs/bench.png``).
"""

from __future__ import annotations

import contextlib
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
    click_until,
    dismiss_notifications,
    launch,
    open_bench,
    run_dashboard,
    select_tab,
    text_input,
)

ROOT = Path(__file__).resolve().parents[1]
SPEED_FACTOR = 1.0
TS, R, L = 20e-6, 6.2e-3, 14.8e-6
VIEWPORT = {"width": 1280, "height": 800}

pytestmark = [
    pytest.mark.timeout(420),  # one Chromium start-up and page load take up to ~70 s at load 20-30
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
        pg = browser.new_page(viewport=VIEWPORT)
        pg.set_default_timeout(90_000)  # a busy host starves the page for tens of seconds
        pg.requested = []
        pg.on("request", lambda r: pg.requested.append(r.url))
        pg.on("websocket", lambda ws: pg.requested.append(ws.url))
        open_bench(pg, bench[0])
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
    # (Enable is idempotent: a click that reached nothing while viser re-rendered is repeated)
    click_until(
        page, page.get_by_role("button", name="Enable"),
        lambda t: wait_text(page, r"OPERATION ENABLED", t),
    )
    plot = page.locator(".uplot").first
    before = plot.screenshot(timeout=60_000)
    click(page, page.get_by_role("button", name="+ step"))
    t_click = time.monotonic()
    seen: list[tuple[float, float]] = []  # (s after the click, rpm shown)
    deadline = t_click + 30
    while time.monotonic() < deadline:
        m = re.search(r"speed ([-\d.]+) rpm \(set (-?\d+)\)", status(page))
        if m and m.group(2) == "500":
            seen.append((time.monotonic() - t_click, float(m.group(1))))
            if abs(seen[-1][1] - 500.0) < 5.0:
                break
        time.sleep(0.1)
    assert seen and abs(seen[-1][1] - 500.0) < 5.0, f"speed never reached 500 rpm: {seen[-5:]}"
    # the IP loop eq. (27) with the paper's gains passes 4 % at 0.14 s and 50 % at 0.73 s: a
    # page read within 1 s of the click shows the rise (a busy host may delay the first read
    # past it; then only the end state is checked)
    if seen[0][0] < 1.0:
        assert any(20.0 < s < 480.0 for _, s in seen), f"no intermediate speed seen: {seen}"
    rising = plot.screenshot(timeout=60_000)
    time.sleep(0.5)
    assert plot.screenshot(timeout=60_000) != rising  # live: the plot keeps scrolling
    assert plot.screenshot(timeout=60_000) != before  # the speed plot moved


def test_plots_are_the_main_area(page):
    """Measured on screen: both live plots wide and tall, fully in view, left of the controls."""
    plots = page.locator(".uplot:visible")
    boxes = [plots.nth(i).bounding_box() for i in range(plots.count())]
    assert len(boxes) == 2, boxes  # speed and i_p (the Live tab)
    enable = page.get_by_role("button", name="Enable").bounding_box()
    for b in boxes:
        assert b["width"] >= 0.4 * VIEWPORT["width"], boxes
        assert b["height"] >= 200, boxes
        assert b["y"] >= 0 and b["y"] + b["height"] <= VIEWPORT["height"] + 1, boxes
        assert b["x"] + b["width"] <= enable["x"], (b, enable)  # plots beside the controls
    out = ROOT / "artifacts"
    out.mkdir(exist_ok=True)
    page.screenshot(path=str(out / "dashboard_e2e_live.png"))


def test_one_controller_and_visible_take_over(page, bench):
    api = bench[1]
    # premise: this browser holds control (it clicked before; on a busy host its websocket may
    # have reconnected since, as a new client without the lease)
    if not re.search(r"In control: browser #\d+ \(you\)", status(page)):
        click(page, page.get_by_role("button", name="Take control"))
        wait_text(page, r"In control: browser #\d+ \(you\) since")
    tok = httpx.post(f"{api}/api/control", json={"client": "script", "take_over": True})
    tok = tok.json()["token"]
    wait_text(page, r"In control: script since")  # the browser sees who took over
    wait_text(page, r"script took control from you")  # shown under the control buttons
    sp0 = httpx.get(f"{api}/api/state").json()["speed_setpoint"]
    click(page, page.get_by_role("button", name="+ step"))
    wait_text(page, r"script controls the bench")  # watching: the click changed nothing
    assert httpx.get(f"{api}/api/state").json()["speed_setpoint"] == sp0
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


def loop_legend(page, at: float = 0.55) -> dict[str, float]:
    """Hover the Bode magnitude plot at ``at`` of its width; the cursor legend's values."""
    over = page.locator(".uplot:visible").nth(0).locator(".u-over")
    over.evaluate("e => e.scrollIntoView({block: 'center'})")  # the z-plane shot scrolled
    box = over.bounding_box()
    page.mouse.move(box["x"] + 5, box["y"] + 5)  # enter the plot, then move to the spot
    page.mouse.move(box["x"] + at * box["width"], box["y"] + box["height"] / 2, steps=5)
    time.sleep(0.3)
    rows = page.locator(".uplot:visible").nth(0).evaluate(
        "u => [...u.querySelectorAll('.u-legend .u-series')].map("
        "r => [r.querySelector('.u-label').innerText, r.querySelector('.u-value').innerText])"
    )
    vals: dict = {"_rows": rows, "_box": box}
    for label, value in rows:
        with contextlib.suppress(ValueError):
            vals[label.strip()] = float(value.replace(",", ""))
    return vals


def deadbeat_db(ratio: float, f_hz: float) -> float:
    """|C P| (dB) of the deadbeat loop with L_c = ratio·L at f_hz (python-control)."""
    Phi, Gamma = math.exp(-R * TS / L), (1 - math.exp(-R * TS / L)) / (2 * R)
    Lc = ratio * L
    Phi_c, Gamma_c = math.exp(-R * TS / Lc), (1 - math.exp(-R * TS / Lc)) / (2 * R)
    loop = ct.tf([1, -Phi_c, 0], [Gamma_c, 0, -Gamma_c], TS) * ct.tf([Gamma], [1, -Phi, 0], TS)
    h = ct.frequency_response(loop, [2 * math.pi * f_hz]).complex.ravel()[0]
    return 20 * math.log10(abs(h))


def test_change_L_c_and_see_readback_and_margins(page, bench):
    select_tab(page, "Tuning")
    select_tab(page, "Loop", exact=True)  # Bode and z-plane beside
    pattern = r"Current \(deadbeat, L_c/L = ([\d.]+)\): stable · GM ([\d.]+) dB · PM ([-\d.]+)°"
    m0 = wait_text(page, pattern)
    assert float(m0.group(1)) == pytest.approx(1.0, abs=1e-3)
    assert float(m0.group(3)) == pytest.approx(60.0, abs=0.2)
    wait_text(page, r"Typed set \(deadbeat")
    time.sleep(0.5)
    z_plane = page.locator(".uplot:visible").nth(2)
    z_before = z_plane.screenshot(timeout=60_000)
    box = text_input(page, "L_c (µH)")
    shown = []
    for _ in range(4):  # what the box shows is what was typed (at load 18 one typing arrived
        # as "22", one as "2": a click that landed during a re-render left the focus elsewhere;
        # focused and selected in the page itself, as the other browser tests do)
        box.wait_for(state="attached", timeout=60_000)
        box.evaluate("e => { e.scrollIntoView({block: 'center'}); e.focus(); e.select(); }")
        page.keyboard.type("22.2")
        page.keyboard.press("Tab")
        time.sleep(0.3)  # viser batches GUI messages in 50 ms windows
        shown.append(box.input_value(timeout=30_000))
        if shown[-1] == "22.2":
            break
    assert shown[-1] == "22.2", f"the L_c box showed {shown} after typing 22.2"
    m1 = wait_text(
        page,
        r"Current \(deadbeat, L_c/L = 1\.500\): stable · GM ([\d.]+) dB · PM ([-\d.]+)°",
        timeout=60,
    )
    gm, pm = current_margins(1.5)
    assert float(m1.group(1)) == pytest.approx(gm, abs=0.01)
    assert float(m1.group(2)) == pytest.approx(pm, abs=0.1)
    assert float(m1.group(2)) != pytest.approx(float(m0.group(3)), abs=1.0)  # margins changed
    # the Bode plot shows the typed set (1.5 L) against the applied one (L), before Apply
    deadline = time.monotonic() + 20
    while True:
        v = loop_legend(page)
        f = v.get("f (Hz)")
        typed, applied = v.get("current, typed"), v.get("current, applied")
        if f and typed is not None and abs(typed - deadbeat_db(1.5, f)) < 0.02:
            break
        assert time.monotonic() < deadline, f"Bode legend never showed the typed set: {v}"
        time.sleep(0.3)
    assert applied == pytest.approx(deadbeat_db(1.0, f), abs=0.02)
    assert abs(typed - applied) > 0.05  # two curves, not one
    assert z_plane.screenshot(timeout=60_000) != z_before  # the poles moved
    out = ROOT / "artifacts"
    out.mkdir(exist_ok=True)
    page.screenshot(path=str(out / "dashboard_e2e_loop.png"))
    click(page, page.get_by_role("button", name="Apply gains"))
    wait_text(page, r"L_c 22\.2 µH \(L_c/L 1\.5000\)")  # read back from the drive
    g = httpx.get(f"{bench[1]}/api/gains").json()
    assert g["L_c"] == pytest.approx(22.2e-6, rel=1e-6)
    deadline = time.monotonic() + 20  # the grey reference follows the drive's new set
    while abs(loop_legend(page).get("current, applied", 0.0) - deadbeat_db(1.5, f)) > 0.02:
        assert time.monotonic() < deadline, "applied curve did not follow the read-back"
        time.sleep(0.3)
    select_tab(page, "Speed")
    select_tab(page, "Live", exact=True)
    dismiss_notifications(page)  # viser's "software WebGL" notice
    page.get_by_text("In control:").scroll_into_view_if_needed()
    time.sleep(0.5)
    page.screenshot(path=str(out / "dashboard_e2e.png"))


STATUS_BAR = """() => {
  const inView = (el) => {
    if (!el) return {top: -1, bottom: -1, onTop: false};  // not on the page at all
    const r = el.getBoundingClientRect();
    const hit = document.elementFromPoint(r.x + r.width / 2, r.y + r.height / 2);
    return {top: r.top, bottom: r.bottom, onTop: !!hit && el.contains(hit)};
  };
  const quick = [...document.querySelectorAll('button')]
    .find(b => b.innerText.trim() === 'Quick stop');
  const badge = [...document.querySelectorAll('.bench-statusbar .bench-badge')]
    .find(b => /OPERATION ENABLED|SWITCH|FAULT|QUICK STOP|READY/.test(b.innerText));
  const scrolled = Math.max(...[...document.querySelectorAll('.mantine-ScrollArea-viewport')]
    .map(e => e.scrollTop));
  const boxes = (sel) => [...document.querySelectorAll(sel)].map(e => e.getBoundingClientRect());
  const notices = boxes('.mantine-Notification-root');
  const covered = [...boxes('.uplot'), ...[...document.querySelectorAll('button, input')]
      .filter(e => !e.closest('.mantine-Notification-root'))
      .map(e => e.getBoundingClientRect()).filter(r => r.width && r.height)]
    .filter(r => notices.some(n => n.left < r.right && r.left < n.right
                                   && n.top < r.bottom && r.top < n.bottom));
  return {quick: inView(quick), quickBg: getComputedStyle(quick).backgroundColor,
          badge: inView(badge), scrolled, notices: notices.length, covered: covered.length};
}"""


def test_status_bar_stays_in_view_and_uncovered_while_the_tuning_tab_scrolls(page):
    """1280×800 (issue 24): with the Tuning tab scrolled to its end, the CiA 402 badge and
    Quick stop are in view and on top (the element at their centre is theirs), Quick stop is
    red, and viser's notices (software WebGL here) cover no plot and no control."""
    select_tab(page, "Tuning")
    time.sleep(0.3)
    page.evaluate(
        "() => document.querySelectorAll('.mantine-ScrollArea-viewport')"
        ".forEach(e => { e.scrollTop = e.scrollHeight; })"
    )
    time.sleep(0.5)
    got = page.evaluate(STATUS_BAR)
    assert got["scrolled"] > 100, got  # the panel did scroll: the premise of the test
    for name in ("quick", "badge"):  # Quick stop first: the old page scrolled it away
        box = got[name]
        assert 0 <= box["top"] and box["bottom"] <= VIEWPORT["height"], (name, got)
        assert box["onTop"], (name, got)
    r, g, b = map(int, re.findall(r"\d+", got["quickBg"])[:3])
    assert r > 180 and g < 120 and b < 120, got["quickBg"]  # red: the safety control
    assert got["covered"] == 0, got
    out = ROOT / "artifacts"
    out.mkdir(exist_ok=True)
    page.screenshot(path=str(out / "dashboard_e2e_status_bar.png"))
    page.evaluate(
        "() => document.querySelectorAll('.mantine-ScrollArea-viewport')"
        ".forEach(e => { e.scrollTop = 0; })"
    )
    select_tab(page, "Speed")


def test_nothing_leaves_the_machine(page, bench):
    """The GUI and the API docs load no asset from a CDN or any other host."""
    page.goto(f"{bench[1]}/docs")
    page.get_by_text("/api/gains").first.wait_for(timeout=10_000)  # rendered from /openapi.json
    urls = [u for u in page.requested if not u.startswith(("data:", "blob:"))]
    assert urls and all(re.match(r"(http|ws)://127\.0\.0\.1:\d+/", u) for u in urls), urls
