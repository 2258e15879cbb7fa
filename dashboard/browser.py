"""Headless Chromium and a child ``drive-dashboard`` for the e2e test, the screenshot command
and the benchmark (one copy of the launch flags and of the start/stop code).

Uses Debian's /usr/bin/chromium through Playwright (never a downloaded browser) with the flags
from the field notes: without the background-networking flags it tries to reach other hosts.
"""

from __future__ import annotations

import contextlib
import re
import socket
import subprocess
import sys
import time
from collections.abc import Iterator, Sequence
from typing import Any, NamedTuple

__all__ = [
    "CHROMIUM",
    "FLAGS",
    "Dashboard",
    "click",
    "dismiss_notifications",
    "free_port",
    "launch",
    "open_bench",
    "renderer_pids",
    "run_dashboard",
    "select_tab",
    "stop_process",
    "text_input",
]

CHROMIUM = "/usr/bin/chromium"
FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
)


def free_port() -> int:
    """A TCP port that is free on 127.0.0.1 right now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]  # typeshed: the address is Any
        return port


def launch(playwright: Any) -> Any:
    """Headless /usr/bin/chromium from a ``sync_playwright()`` handle; returns the Browser."""
    return playwright.chromium.launch(executable_path=CHROMIUM, args=list(FLAGS), headless=True)


def open_bench(page: Any, url: str, timeout: float = 240.0) -> float:
    """Open the bench page at ``url`` and wait until it is usable (the Enable button shown).

    ``timeout`` in s. A starved host (load 20 on two cores: software WebGL, the viser bundle
    parsed at a tenth of a core) has kept a page past 60 s; if the button is not there half-way,
    the page is loaded again once (a page whose first websocket attempt timed out stays blank).
    Returns the s it took; raises ``TimeoutError`` with what the page shows otherwise."""
    t0 = time.monotonic()
    enable = page.get_by_role("button", name="Enable")
    last: Exception | None = None
    for k in (1, 2):
        until = t0 + timeout * k / 2  # first load: half the time; the second: the rest
        try:
            page.goto(url, timeout=max(until - time.monotonic(), 1.0) * 1000)
            enable.wait_for(timeout=max(until - time.monotonic(), 1.0) * 1000)
            return time.monotonic() - t0
        except Exception as exc:  # Playwright's TimeoutError
            last = exc
    shown = page.evaluate("() => document.body ? document.body.innerText.slice(0, 300) : ''")
    raise TimeoutError(
        f"bench page {url} not usable after {time.monotonic() - t0:.0f} s (two loads); "
        f"it shows: {shown!r}"
    ) from last


def renderer_pids(page: Any) -> list[int]:
    """The renderer processes of the browser that shows ``page`` (Chromium's own list, by the
    DevTools protocol): what a test measures the CPU and run-queue time of."""
    cdp = page.context.browser.new_browser_cdp_session()
    try:
        info = cdp.send("SystemInfo.getProcessInfo")["processInfo"]
    finally:
        cdp.detach()
    return [p["id"] for p in info if p["type"] == "renderer"]


def stop_process(proc: subprocess.Popen[Any], timeout: float = 10.0) -> None:
    """SIGTERM, wait up to ``timeout`` s, then SIGKILL."""
    if proc.poll() is None:
        proc.terminate()
    try:
        proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


class Dashboard(NamedTuple):
    """A running child ``drive-dashboard``: its GUI and API URLs and its process."""

    gui_url: str
    api_url: str
    proc: subprocess.Popen[str]


@contextlib.contextmanager
def run_dashboard(args: Sequence[str], timeout: float = 60.0) -> Iterator[Dashboard]:
    """``drive-dashboard <args> --port P --gui-port 0`` in a child process.

    Yields a :class:`Dashboard` once it printed its ``open http://...`` line; stops it
    (SIGTERM, then SIGKILL) on exit.
    :raises RuntimeError: it exited or printed no URL within ``timeout`` s.
    """
    api_port = free_port()
    cmd = [sys.executable, "-m", "dashboard.cli", *args, "--port", str(api_port)]
    cmd += ["--gui-port", "0"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    assert proc.stdout is not None  # stdout=PIPE
    try:
        line = ""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and not line.startswith("open "):
            line = proc.stdout.readline()
            if not line and proc.poll() is not None:
                raise RuntimeError(f"drive-dashboard exited with {proc.returncode}")
        m = re.match(r"open (http://127\.0\.0\.1:\d+/)", line)
        if not m:
            raise RuntimeError(f"drive-dashboard printed no URL: {line!r}")
        yield Dashboard(m.group(1), f"http://127.0.0.1:{api_port}", proc)
    finally:
        stop_process(proc)


_ARM = """e => {
    e.scrollIntoView({block: 'center'});
    window.__benchHit = null;
    document.addEventListener('click', ev => { window.__benchHit = ev.target; },
                              {capture: true, once: true});
}"""
# Did the click reach the element? A node React replaced meanwhile (detached) counts as reached:
# the click went to the panel being re-rendered, and repeating it could act twice.
_REACHED = """e => {
    const hit = window.__benchHit;
    if (hit === null) return false;
    if (!hit.isConnected || e === hit || e.contains(hit)) return true;
    const label = hit.closest ? hit.closest('label') : null;
    return label !== null && label.control === e;
}"""


def click(page: Any, locator: Any, attempts: int = 5) -> None:
    """A real mouse click on the element, without Playwright's wait for a "stable" element:
    viser re-renders the panel several times a second, and on a busy host that wait can time
    out. The element is scrolled to the middle of the view first.

    A forced click goes to whatever is under the element's centre when the browser gets it; if
    the panel moved meanwhile (a status line grew, a notice slid in) it reaches something else
    (seen in CI at load 7: a tab, a Run button). So a capturing listener records what the click
    hit, and only a click that did not reach the element is repeated (``attempts`` in all)."""
    el = locator.first
    el.wait_for(state="attached", timeout=60_000)
    for _ in range(attempts):
        el.evaluate(_ARM)
        el.click(force=True, timeout=60_000)
        if el.evaluate(_REACHED):
            break
        time.sleep(0.2)
    else:
        raise AssertionError(f"{attempts} clicks on {locator} reached something else")
    time.sleep(0.1)  # viser batches GUI messages in 50 ms windows


def click_until(page: Any, locator: Any, done: Any, timeout: float = 20.0) -> None:
    """:func:`click`, then wait ``timeout`` s for ``done(timeout)`` (which raises
    AssertionError when it did not come); click again, at most 3 clicks in all. A forced click
    that lands while viser re-renders the panel, or under a notification sliding in, reaches
    nothing. Only for idempotent buttons (Enable, Apply)."""
    for attempt in range(3):
        click(page, locator)
        try:
            done(timeout)
            return
        except AssertionError:
            if attempt == 2:
                raise


def select_tab(page: Any, name: str, exact: bool = False, timeout: float = 20.0) -> None:
    """Click the tab ``name`` until the page marks it selected (``aria-selected="true"``).

    A forced click that lands while viser re-renders the panel reaches nothing, and the tab's
    content then never appears (seen once in CI: a "Tuning" click lost at load 7): the tab's
    own state is the proof, so the click is repeated, at most 3 clicks in all."""
    tab = page.get_by_role("tab", name=name, exact=exact)

    def selected(t: float) -> None:
        deadline = time.monotonic() + t
        while time.monotonic() < deadline:
            if tab.first.get_attribute("aria-selected", timeout=60_000) == "true":
                return
            time.sleep(0.1)
        raise AssertionError(f"tab {name!r} not selected within {t:g} s")

    click_until(page, tab, selected, timeout=timeout)


def dismiss_notifications(page: Any) -> None:
    """Close viser's notifications (e.g. the "software WebGL" notice) so they hide nothing.

    The close buttons are clicked from the page's script: viser re-renders often enough that a
    Playwright click can keep waiting for a stable target."""
    sel = ".mantine-Notification-root button"
    for _ in range(10):
        page.evaluate(f"() => document.querySelectorAll('{sel}').forEach(b => b.click())")
        if not page.evaluate(f"() => document.querySelectorAll('{sel}').length"):
            return
        time.sleep(0.3)  # the close animation


def text_input(page: Any, label: str) -> Any:
    """The input of a viser text field by its label. viser 1.1's text input carries no id for
    its label's ``for`` (number inputs do), so ``get_by_label`` cannot find it: take the input
    in the row of the label whose text is exactly ``label``."""
    return page.locator(
        f"xpath=//label[normalize-space()='{label}']/ancestor::div[.//input][1]//input"
    ).first
