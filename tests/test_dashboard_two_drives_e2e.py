"""Two drives, two browsers, one bench: ``drive-dashboard --virtual --nodes 1,2`` (the console
script, as a user starts it) in real headless Chromium (/usr/bin/chromium).

Browser A takes node 1 and sets 1000 rpm, browser B picks node 2 in the node selector, takes it
(one control lease per node: both hold control at once) and sets -500 rpm. Truth: canopen's own
master on a separate connection to the hub reads target_velocity (0x60FF, CiA 402) of each drive
by SDO: each drive got only its own setpoint. Then the REST API per node (``/api/nodes``,
``?node=N``) and a watcher: B, switched to node 1, sees node 1's setpoint and controller and its
step is refused (A holds node 1).
"""

from __future__ import annotations

import contextlib
import os
import re
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import canopen
import httpx
import pytest
from conftest import PLOT_RATE_ARGS

from dashboard.browser import (
    CHROMIUM,
    click,
    click_until,
    dismiss_notifications,
    free_port,
    launch,
    open_bench,
    stop_process,
    text_input,
)
from firmware_protocol import EDS_PATH

VIEWPORT = {"width": 1280, "height": 800}
DASHBOARD = Path(sys.executable).parent / "drive-dashboard"  # the console script

pytestmark = [
    pytest.mark.timeout(420),  # two Chromium pages on a loaded host take minutes
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium"),
]


@pytest.fixture(scope="module")
def bench() -> Iterator[tuple[str, str, int]]:
    """``drive-dashboard --virtual --nodes 1,2``; yields (gui_url, api_url, hub_port)."""
    api_port = free_port()
    cmd = [str(DASHBOARD), "--virtual", "--nodes", "1,2", "--no-3d", *PLOT_RATE_ARGS]
    cmd += ["--port", str(api_port), "--gui-port", "0"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        lines: list[str] = []
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline and len(lines) < 2:
            line = proc.stdout.readline()
            if not line and proc.poll() is not None:
                raise RuntimeError(f"drive-dashboard exited with {proc.returncode}: {lines}")
            lines.append(line)
        gui = re.search(r"open (http://127\.0\.0\.1:\d+/)", lines[0])
        hub = re.search(r"loopback hub 127\.0\.0\.1:(\d+)", lines[1])
        assert gui and hub, lines
        yield gui.group(1), f"http://127.0.0.1:{api_port}", int(hub.group(1))
    finally:
        stop_process(proc)


def trace_channel(net: canopen.Network, node_id: int) -> canopen.sdo.SdoClient:
    """canopen's SDO client on the drive's second SDO server (0x1201: 0x680 + N / 0x6B0 + N,
    the EDS defaults): the dashboard's own reads use the first server, and two clients on one
    SDO channel would take each other's answers."""
    node = canopen.RemoteNode(node_id, canopen.import_od(str(EDS_PATH), node_id))
    sdo = node.add_sdo(0x680 + node_id, 0x6B0 + node_id)  # before add_node (canopen)
    net.add_node(node)
    sdo.network = net  # canopen leaves it unset on an added client
    sdo.RESPONSE_TIMEOUT = 2.0
    return sdo


@pytest.fixture(scope="module")
def master(bench) -> Iterator[dict[int, canopen.sdo.SdoClient]]:
    """canopen's own master on its own connection to the hub: nodes 1 and 2."""
    net = canopen.Network()
    net.connect(interface="socketcand", host="127.0.0.1", port=bench[2], channel="vcan0")
    try:
        yield {n: trace_channel(net, n) for n in (1, 2)}
    finally:
        net.disconnect()


@pytest.fixture(scope="module")
def pages(bench):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = launch(p)
        out = []
        for _ in range(2):  # two contexts: two independent browsers (own websocket, own lease)
            pg = browser.new_context(viewport=VIEWPORT).new_page()
            pg.set_default_timeout(90_000)
            open_bench(pg, bench[0])
            dismiss_notifications(pg)
            out.append(pg)
        yield out
        browser.close()


def body(page) -> str:
    return page.inner_text("body")


def wait_text(page, pattern: str, timeout: float = 30.0) -> re.Match:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = re.search(pattern, body(page))
        if m:
            return m
        time.sleep(0.1)
    raise AssertionError(f"page never showed {pattern!r}; it shows:\n{body(page)[:1500]}")


def select_node(page, node: int) -> None:
    """Pick ``node`` in the page's "Node" dropdown (a Mantine select: open it, click the
    option), as a user does."""
    for attempt in range(3):
        click(page, text_input(page, "Node"))
        opt = page.get_by_role("option", name=str(node), exact=True)
        try:
            opt.first.wait_for(state="visible", timeout=20_000)
            opt.first.click(force=True, timeout=20_000)
            wait_text(page, rf"this page shows node {node}", 20)
            return
        except Exception:
            if attempt == 2:
                raise
            page.keyboard.press("Escape")


def set_speed(page, rpm: int) -> None:
    box = text_input(page, "Speed setpoint (rpm)")
    box.wait_for(state="attached", timeout=60_000)
    box.evaluate("e => { e.scrollIntoView({block: 'center'}); e.focus(); e.select(); }")
    page.keyboard.type(str(rpm))
    page.keyboard.press("Tab")
    time.sleep(0.3)  # viser batches GUI messages in 50 ms windows
    click_until(
        page,
        page.get_by_role("button", name="Set speed"),
        lambda t: wait_text(page, rf"\(set {rpm}\)", t),
    )


def test_two_browsers_control_two_drives_each_gets_only_its_setpoint(bench, pages, master):
    a, b = pages
    api = bench[1]
    # both pages list the two drives the dashboard sees (heartbeats) and start on node 1
    for pg in pages:
        wait_text(pg, r"node 1\s+OPERATIONAL")
        wait_text(pg, r"node 2\s+(OPERATIONAL|PRE-OPERATIONAL)")
    click(a, a.get_by_role("button", name="Take control"))
    wait_text(a, r"In control: browser #\d+ \(you\)")
    set_speed(a, 1000)
    select_node(b, 2)
    click(b, b.get_by_role("button", name="Take control"))  # node 2: nobody holds it
    wait_text(b, r"In control: browser #\d+ \(you\)")
    set_speed(b, -500)
    # A still holds node 1: the two leases are independent
    wait_text(a, r"In control: browser #\d+ \(you\)")
    wait_text(a, r"\(set 1000\)")
    # the truth, by canopen's own SDO client: each drive got only its own setpoint
    assert master[1]["target_velocity"].raw == 1000
    assert master[2]["target_velocity"].raw == -500

    # REST per node: the same picture, and node 2's lease is B's
    rows = {r["node_id"]: r for r in httpx.get(f"{api}/api/nodes").json()}
    assert set(rows) == {1, 2}
    assert rows[1]["controller"] and rows[2]["controller"]
    assert rows[1]["controller"] != rows[2]["controller"]
    assert httpx.get(f"{api}/api/state").json()["speed_setpoint"] == 1000
    s2 = httpx.get(f"{api}/api/state", params={"node": 2}).json()
    assert (s2["node_id"], s2["speed_setpoint"]) == (2, -500)
    r = httpx.post(f"{api}/api/control", params={"node": 2}, json={"client": "script"})
    assert r.status_code == 409  # B holds node 2
    assert httpx.get(f"{api}/api/state", params={"node": 9}).status_code == 404
    assert httpx.get(f"{api}/api/state", params={"node": 0}).status_code == 422

    # a watcher: B switches to node 1 and sees node 1 (its setpoint, A in control); its
    # step is refused and node 1 keeps A's setpoint
    select_node(b, 1)
    wait_text(b, r"\(set 1000\)")
    ctl = wait_text(b, r"In control: (browser #\d+)( \(you\))?")
    assert ctl.group(2) is None, ctl.group(0)
    click(b, b.get_by_role("button", name="+ step"))
    wait_text(b, r"controls the bench")
    time.sleep(0.5)
    assert master[1]["target_velocity"].raw == 1000
    assert master[2]["target_velocity"].raw == -500
    with contextlib.suppress(Exception):
        out = Path(__file__).resolve().parents[1] / "artifacts"
        out.mkdir(exist_ok=True)
        a.screenshot(path=str(out / "dashboard_two_drives.png"))
