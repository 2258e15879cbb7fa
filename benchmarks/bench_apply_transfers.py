"""SDO transfers on the bus per dashboard action: an "Apply gains" click with 1 and with 3
browsers, one preview field edit, one speed setpoint. Prints figures; no pass/fail.

How:
  - ``drive-dashboard --virtual --no-3d --hub-port P`` runs as a child; this process joins the
    loopback hub on P with a python-can listener (:mod:`_sdo_transfers`) that counts the SDO
    transfers started on 0x600 + node (expedited, segmented and block transfers each count
    once, whatever their number of frames).
  - RPDO frames (0x200/0x300/0x400/0x500 + node) are counted beside the SDO transfers.
  - The clicks are real: headless /usr/bin/chromium (:mod:`dashboard.browser`) types L_c in the
    Tuning tab (the preview) and presses "Apply gains"; the speed setpoint is one
    ``PUT /api/setpoints/speed`` with the drive enabled (OPERATION ENABLED).
  - The dashboard's own background reads go on meanwhile: the drive watch uploads the mode
    display 0x6061 every 0.5 s. The figure is the action's transfers without those uploads
    (counted by object, listed below each figure); the raw count and the background rate
    measured over a quiet window first are printed beside it.
  - Load average (/proc/loadavg) printed beside every figure.

Run: python benchmarks/bench_apply_transfers.py [--browsers 1,3]
"""

from __future__ import annotations

import argparse
import re
import time
from collections.abc import Callable
from typing import Any

import can
import httpx
from _sdo_transfers import SdoTransfers

from dashboard.browser import click as real_click
from dashboard.browser import free_port, launch, open_bench, run_dashboard, select_tab, text_input
from drive_link.link.bus import open_bus

NODE = 1
WATCH_POLL = ("upload", 0x6061, 0)  #: the drive watch's background read (mode display)
QUIET_S = 4.0  #: window over which the background rate is measured (s)
SETTLE_S = 1.0  #: after an action completed, transfers it caused may still come this long (s)


def loadavg() -> str:
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


def wait_text(page: Any, pattern: str, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while not re.search(pattern, page.inner_text("body")):
        if time.monotonic() > deadline:
            raise TimeoutError(f"{pattern!r} not shown within {timeout:g} s")
        time.sleep(0.1)


class Meter:
    """Transfers caused by one action: the count over its window minus the background."""

    def __init__(self, counter: SdoTransfers) -> None:
        self.counter = counter
        n0 = counter.total
        time.sleep(QUIET_S)
        self.rate = (counter.total - n0) / QUIET_S  # background transfers per second

    def measure(self, label: str, action: Callable[[], None]) -> int:
        before, t0, pdo0 = self.counter.snapshot(), time.monotonic(), self.counter.rpdos
        action()
        time.sleep(SETTLE_S)
        after, dt = self.counter.snapshot(), time.monotonic() - t0
        rpdos = self.counter.rpdos - pdo0
        raw = sum((after - before).values())
        net = raw - (after - before)[WATCH_POLL]
        objs = ", ".join(
            f"{k[0][0]}{k[1]:04X}:{k[2]}×{v}" for k, v in sorted((after - before).items())
        )
        print(
            f"{label:<34} {net:4d} SDO transfers (raw {raw} in {dt:.1f} s, background "
            f"{self.rate:.1f}/s), {rpdos} RPDO frames · load {loadavg()}\n    {objs}",
            flush=True,
        )
        return net


def edit_Lc(page: Any, value: str) -> None:
    box = text_input(page, "L_c (µH)")
    real_click(page, box)
    page.keyboard.press("Control+A")
    page.keyboard.type(value)
    page.keyboard.press("Tab")
    ratio = float(value) / 14.8
    wait_text(page, rf"Current \(deadbeat, L_c/L = {ratio:.3f}\)")


def apply(page: Any, value: str) -> None:
    real_click(page, page.get_by_role("button", name="Apply gains"))
    wait_text(page, rf"L_c {re.escape(value)} µH \(L_c/L")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--browsers", default="1,3", help="browser counts to measure Apply with")
    args = ap.parse_args(argv)
    counts = [int(n) for n in args.browsers.split(",")]
    from playwright.sync_api import sync_playwright

    hub = free_port()
    print(f"load average at start: {loadavg()}", flush=True)
    with run_dashboard(["--virtual", "--no-3d", "--hub-port", str(hub)]) as dash:
        bus = open_bus(host="127.0.0.1", port=hub, bitrate=1_000_000)
        counter = SdoTransfers(NODE)
        notifier = can.Notifier(bus, [counter], timeout=0.1)
        try:
            meter = Meter(counter)
            api = f"{dash.api_url}/api"
            tok = httpx.post(f"{api}/control", json={"client": "bench"}).json()["token"]
            hdr = {"X-Control-Token": tok}
            cmd = httpx.post(f"{api}/command", json={"command": "enable"}, headers=hdr)
            cmd.raise_for_status()
            time.sleep(1.0)  # the statusword TPDO shows OPERATION ENABLED
            httpx.put(f"{api}/setpoints/speed", json={"rpm": 200}, headers=hdr).raise_for_status()
            time.sleep(0.5)
            meter.measure(
                "speed setpoint (API)",
                lambda: httpx.put(
                    f"{api}/setpoints/speed", json={"rpm": 300}, headers=hdr
                ).raise_for_status(),
            )
            httpx.delete(f"{api}/control", headers=hdr)
            with sync_playwright() as p:
                browser = launch(p)
                pages: list[Any] = []
                value = "14.8"
                for n in counts:
                    while len(pages) < n:
                        pg = browser.new_page(viewport={"width": 1280, "height": 900})
                        pg.set_default_timeout(90_000)
                        open_bench(pg, dash.gui_url)
                        pages.append(pg)
                    main_page = pages[0]
                    select_tab(main_page, "Tuning")
                    time.sleep(2.0)  # the pages' first read-backs are done
                    meter = Meter(counter)
                    value = "16" if value != "16" else "14.8"
                    meter.measure(
                        f"preview: one L_c edit ({n} browser{'s' if n > 1 else ''})",
                        lambda v=value, pg=main_page: edit_Lc(pg, v),
                    )
                    meter.measure(
                        f"Apply gains click ({n} browser{'s' if n > 1 else ''})",
                        lambda v=value, pg=main_page: apply(pg, v),
                    )
                browser.close()
        finally:
            notifier.stop(1.0)
            bus.shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
