"""Regenerate the README picture: ``python -m dashboard.screenshot docs/bench.png``.

Starts the real ``drive-dashboard --virtual`` on free ports, opens it in headless
/usr/bin/chromium (1400x900), enables the drive, makes a +500 rpm step, waits until the page
shows the speed half-way to the setpoint (the rise and the settling are both in
the plot), hides viser's notifications, takes the screenshot and stops everything.
``--no-3d`` leaves out the rotor view.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from dashboard.browser import click, dismiss_notifications, launch, open_bench, run_dashboard

if TYPE_CHECKING:
    from playwright.sync_api import Page

__all__ = ["SCROLL_TOP", "VIEWPORT", "main", "take"]

VIEWPORT = {"width": 1400, "height": 900}
SCROLL_TOP = (
    "() => document.querySelectorAll('*').forEach(e => { if (e.scrollTop) e.scrollTop = 0; })"
)


def _wait_speed(page: Page, target: float, tol: float = 5.0, timeout: float = 30.0) -> float:
    """Wait until the status line shows the speed within ``tol`` rpm of ``target``; returns it
    (rpm)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = re.search(r"speed ([-\d.]+) rpm \(set (-?\d+)\)", page.inner_text("body"))
        if m and float(m.group(2)) == target and abs(float(m.group(1)) - target) < tol:
            return float(m.group(1))
        time.sleep(0.1)
    raise RuntimeError(f"the speed never reached {target:.0f} rpm on the page")


def take(out: Path, scene_3d: bool = True, settle_s: float = 0.2) -> None:
    """Write the bench screenshot (PNG) to ``out``."""
    from playwright.sync_api import sync_playwright

    args = ["--virtual"] + (["--show-3d"] if scene_3d else ["--no-3d"])
    with run_dashboard(args) as dash, sync_playwright() as p:
        browser = launch(p)
        try:
            page = browser.new_page(viewport=VIEWPORT)
            open_bench(page, dash.gui_url)
            click(page, page.get_by_role("button", name="Enable"))
            page.get_by_text("OPERATION ENABLED").first.wait_for(timeout=20_000)
            time.sleep(0.5)
            dismiss_notifications(page)
            # and hide any notice that arrives later
            page.add_style_tag(content=".mantine-Notifications-root { display: none; }")
            click(page, page.get_by_role("button", name="+ step"))
            _wait_speed(page, 500.0, tol=250.0)  # half-way: the rise is in the plot
            time.sleep(settle_s)  # and the settling too, inside the 4 s window
            page.evaluate(SCROLL_TOP)  # the panel from its top (status)
            page.mouse.move(5, VIEWPORT["height"] - 5)
            time.sleep(0.3)
            out.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(out))
        finally:
            browser.close()


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m dashboard.screenshot", description=__doc__, allow_abbrev=False
    )
    ap.add_argument("out", type=Path, help="PNG file to write (e.g. docs/bench.png)")
    ap.add_argument("--no-3d", action="store_true", help="without the 3D rotor view")
    args = ap.parse_args(argv)
    if args.out.suffix.lower() != ".png":
        print("dashboard.screenshot: error: the output must be a .png file", file=sys.stderr)
        return 2
    try:
        take(args.out, scene_3d=not args.no_3d)
    except Exception as exc:  # one line, non-zero exit
        print(f"dashboard.screenshot: error: {exc}", file=sys.stderr)
        return 1
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
