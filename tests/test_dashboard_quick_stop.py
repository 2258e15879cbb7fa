"""Quick stop is a safety control: it acts at once, from any client, and wins over "as found".

While a long action runs (identification from the REST API; the report from browser A in a real
Chromium), a client that does NOT hold the control lease (a watching script; browser B) presses
Quick stop. The truth is the drive's own statusword as it goes out on the bus in TPDO1
(0x6041, mapped first by the EDS default 0x1A00), received by a second, independent CAN client
on the virtual drive's hub and decoded with the CiA 402-2 table (not drive_link's decoder):

- within 0.5 s of the press the statusword shows QUICK STOP ACTIVE (then SWITCH ON DISABLED,
  with the default quick_stop_option_code 2);
- it never shows OPERATION ENABLED again afterwards, although the drive was found enabled in
  speed mode at 1000 rpm (the action's "leave as found" must not re-enable it);
- the mode and the speed setpoint are put back (speed mode, 1000 rpm).

On the old code (efa426e..03f8860) the watcher's quick stop was refused (409 / "controls the
bench") and, from the holder, waited behind the bench lock for the whole action; the restore
then enabled the drive again.
"""

from __future__ import annotations

import contextlib
import os
import re
import threading
import time

import can
import httpx
import pytest
from conftest import PLOT_RATE_ARGS, HostDelay, cia402_state
from fastapi.testclient import TestClient

from dashboard.app import create_app
from dashboard.browser import (
    CHROMIUM,
    click,
    click_until,
    dismiss_notifications,
    free_port,
    launch,
    open_bench,
    renderer_pids,
    run_dashboard,
    select_tab,
)
from dashboard.config import BenchConfig

NODE = 1
MAX_REACTION_S = 0.5

pytestmark = pytest.mark.timeout(300)


class StatuswordWatch:
    """A second CAN client on the hub: every TPDO1 of the node as (time.monotonic(), state)."""

    def __init__(self, hub_port: int) -> None:
        self.bus = can.Bus(interface="socketcand", host="127.0.0.1", port=hub_port,
                           channel="vcan0")
        self.seen: list[tuple[float, str]] = []
        self._stop = threading.Event()
        self._th = threading.Thread(target=self._run, daemon=True)
        self._th.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            msg = self.bus.recv(0.1)
            if msg is not None and msg.arbitration_id == 0x180 + NODE and len(msg.data) >= 2:
                sw = int.from_bytes(bytes(msg.data[:2]), "little")
                self.seen.append((time.monotonic(), cia402_state(sw)))

    def last(self) -> str | None:
        return self.seen[-1][1] if self.seen else None

    def first_stopped_after(self, t0: float, timeout: float = 5.0) -> float:
        """s from ``t0`` to the first statusword after it showing QUICK STOP ACTIVE or SWITCH
        ON DISABLED (an experiment's own mode switch coasts to SWITCHED ON, never to these:
        only the quick stop can show them here, the drive being found enabled)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for t, state in list(self.seen):
                if t >= t0 and state in ("QUICK STOP ACTIVE", "SWITCH ON DISABLED"):
                    return t - t0
            time.sleep(0.01)
        raise AssertionError(f"still enabled {timeout} s after the quick stop: {self.seen[-3:]}")

    def enabled_after(self, t0: float) -> list[float]:
        """s after ``t0`` of every OPERATION ENABLED statusword once the drive had stopped
        (frames already on the way at ``t0`` do not count)."""
        t_stop = t0 + self.first_stopped_after(t0)
        return [t - t0 for t, s in list(self.seen) if t >= t_stop and s == "OPERATION ENABLED"]

    def close(self) -> None:
        self._stop.set()
        self._th.join(timeout=2.0)
        self.bus.shutdown()


@contextlib.contextmanager
def watching(hub_port: int):
    w = StatuswordWatch(hub_port)
    try:
        yield w
    finally:
        w.close()


def wait_for(cond, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.02)


def test_watcher_quick_stop_over_rest_during_identification():
    cfg = BenchConfig(virtual=True, speed_factor=2.0, gui_port=0)
    with TestClient(create_app(cfg, gui=False), base_url="http://127.0.0.1:8000") as c:
        bench = c.app.state.bench
        d = bench.drive
        hdr = {"X-Control-Token": c.post("/api/control", json={"client": "holder"}).json()["token"]}
        assert c.put("/api/setpoints/speed", json={"rpm": 1000}, headers=hdr).status_code == 200
        assert c.post("/api/command", json={"command": "enable"}, headers=hdr).status_code == 200
        wait_for(lambda: abs(float(d.read("measurements.speed")) - 1000) < 30, 30, "1000 rpm")
        with watching(bench.hub_port) as w:
            result: dict = {}

            def identify() -> None:
                r = c.post("/api/identify", json={"from_A": 15, "to_A": 30, "duration_s": 3.0},
                           headers=hdr)
                result["status"], result["text"] = r.status_code, r.text

            th = threading.Thread(target=identify)
            th.start()
            wait_for(lambda: bench.action is not None and time.monotonic()
                     - bench.action.started > 0.5 and w.last() == "OPERATION ENABLED", 30,
                     "the identification running with the drive enabled")
            # a watcher (no control token): once through /api/command, once /api/quick_stop
            t0 = time.monotonic()
            r = c.post("/api/command", json={"command": "quick_stop"})
            assert r.status_code == 200, r.text
            dt = w.first_stopped_after(t0)
            assert dt < MAX_REACTION_S, f"quick stop took {dt:.3f} s (load {os.getloadavg()})"
            th.join(timeout=60)
            assert not th.is_alive()
            assert result["status"] >= 400 and "quick stop" in result["text"], result
            time.sleep(1.0)  # the restore is done: would it have enabled the drive again?
            assert w.enabled_after(t0) == [], "the drive was enabled again after a quick stop"
            assert cia402_state(int(d.read("statusword"))) != "OPERATION ENABLED"
            assert d.mode == "speed" and int(d.read("target_velocity")) == 1000
            assert c.post("/api/quick_stop").status_code == 200  # the short route, no token
            assert c.post("/api/command", json={"command": "enable"}).status_code == 409


def _hub_port_arg() -> tuple[list[str], int]:
    port = free_port()
    return ["--virtual", "--no-3d", "--hub-port", str(port), *PLOT_RATE_ARGS], port


@pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")
@pytest.mark.timeout(420)
def test_watching_browser_quick_stops_a_report_at_once():
    from playwright.sync_api import sync_playwright

    args, hub_port = _hub_port_arg()
    with run_dashboard(args) as dash, sync_playwright() as p, watching(hub_port) as w:
        api = dash.api_url
        browser = launch(p)
        a = browser.new_page(viewport={"width": 1400, "height": 900})
        b = browser.new_page(viewport={"width": 1400, "height": 900})
        for page in (a, b):
            page.set_default_timeout(90_000)
            open_bench(page, dash.gui_url)
            dismiss_notifications(page)
        # browser A: speed mode at 1000 rpm, enabled (it takes control by its first action)
        select_tab(a, "Speed")
        click_until(a, a.get_by_role("button", name="Enable"),
                    lambda t: wait_for(lambda: w.last() == "OPERATION ENABLED", t, "enabled"))
        holder = httpx.get(f"{api}/api/state", timeout=30).json()["controller"]
        assert holder is not None
        # 1000 rpm over the speed field of A's Speed tab is a typed entry; two + steps of 500
        for _ in range(2):
            click(a, a.get_by_role("button", name="+ step"))
        wait_for(lambda: httpx.get(f"{api}/api/state", timeout=30).json()["speed_setpoint"]
                 == 1000, 30, "the 1000 rpm setpoint")
        before = httpx.get(f"{api}/api/state", timeout=30).json()
        assert before["mode"] == "speed" and before["state"] == "OPERATION ENABLED"
        # browser A runs the whole report (about 40 s); B watches
        select_tab(a, "Report")
        click(a, a.get_by_role("button", name="Run report"))

        def running() -> bool:
            act = httpx.get(f"{api}/api/state", timeout=30).json()["action"]
            return bool(act) and act["elapsed_s"] > 1.0 and w.last() == "OPERATION ENABLED"

        wait_for(running, 90, "the report running with the drive enabled")
        quick = b.get_by_role("button", name="Quick stop")
        quick.first.evaluate("e => e.scrollIntoView({block: 'center'})")
        host = HostDelay(dash.proc.pid, *renderer_pids(b))
        t0 = time.monotonic()
        quick.first.click(force=True, timeout=60_000)
        dt = w.first_stopped_after(t0)
        extra = host.allowance()
        load = os.getloadavg()
        print(f"quick stop from the watching browser: {dt * 1000:.0f} ms (load {load})")
        # the product's part 0.5 s; the host's part: the run-queue time it gave the dashboard
        # and B's renderer meanwhile (0.88 s at load 8.3 in a fresh-clone run)
        assert dt < MAX_REACTION_S + extra, (
            f"quick stop took {dt:.3f} s (host allowance {extra:.3f} s: {host!r}; load {load})"
        )
        body_b = b.inner_text("body")
        assert "controls the bench" not in body_b, body_b[-500:]
        wait_for(lambda: httpx.get(f"{api}/api/state", timeout=30).json()["action"] is None,
                 60, "the report to end")
        time.sleep(1.5)
        assert w.enabled_after(t0) == [], "the drive was enabled again after the quick stop"
        after = httpx.get(f"{api}/api/state", timeout=30).json()
        assert after["state"] != "OPERATION ENABLED" and after["mode"] == "speed", after
        assert after["speed_setpoint"] == 1000
        wait_for(lambda: re.search(r"quick stop", a.inner_text("body")) is not None, 20,
                 "browser A told why its report stopped")
        browser.close()
