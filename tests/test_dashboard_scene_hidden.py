"""The 3D rotor costs nothing while a browser hides it, in a real headless Chromium
(/usr/bin/chromium through Playwright).

Truths: the WebSocket frames the page received (Playwright's ``framereceived``, decoded from
viser's wire format: zstd msgpack), the WebGL draw calls the page made (counted by an init
script), and the drive's electrical angle θ_e read by SDO (0x2040:0E) by the test itself.

- Shown, the rotor's nodes arrive and turn while the drive turns.
- "3D rotor" unchecked: the rotor's nodes are removed; then, while the drive turns and the live
  plots keep arriving, the page receives no message for any rotor node and draws next to
  nothing (viser renders on demand: a heartbeat of the empty scene, against hundreds of draw
  calls per second with the rotor turning). Per browser: a second viser client (a plain
  WebSocket speaking viser's protocol, rotor shown) receives the turning rotor meanwhile,
  which also shows that the server was producing rotor updates during that window.
- Checked again at standstill: the rotor comes back at the drive's present angle
  (mechanical angle × pole pairs = θ_e), not where it was hidden.
"""

from __future__ import annotations

import math
import os
import sys
import threading
import time
from pathlib import Path

import msgspec
import pytest
import viser
from conftest import TEST_PLOT_RATE_HZ
from fastapi.testclient import TestClient
from websockets.sync.client import connect

from dashboard._gui_scene import ROOT, TOGGLE_LABEL
from dashboard.app import create_app
from dashboard.browser import CHROMIUM, click, launch, open_bench
from dashboard.config import BenchConfig

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from bench_dashboard import GL_COUNT_JS, decode_frame  # the wire format's one home

pytestmark = [
    pytest.mark.timeout(420),  # one Chromium start-up and page load take up to ~70 s at load 20-30
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium"),
]

POLE_PAIRS = 4  #: the virtual drive's motor.pole_pairs (EDS default) and the view's
WAIT_S = 90.0  #: bound of every wait for the page (a busy host stalls it for tens of seconds)


class Frames:
    """Every viser message the page received, in order, with its arrival (time.monotonic())."""

    def __init__(self) -> None:
        self.messages: list[tuple[float, dict]] = []

    def on_websocket(self, ws) -> None:
        if "/api/" in ws.url:
            return
        ws.on("framereceived", self._frame)

    def _frame(self, payload) -> None:
        if isinstance(payload, (bytes, bytearray)):
            now = time.monotonic()
            self.messages.extend((now, m) for m in decode_frame(bytes(payload)))

    def rotor(self, start: int = 0) -> list[dict]:
        """Messages from index ``start`` on that create, change or remove a rotor node."""
        return [m for _, m in self.messages[start:] if str(m.get("name", "")).startswith(ROOT)]

    def plot_updates(self, start: int = 0) -> int:
        """Live-plot data updates received from index ``start`` on."""
        return sum(
            1
            for _, m in self.messages[start:]
            if m.get("type") == "GuiUpdateMessage" and "data" in m.get("updates", {})
        )


class RawViewer:
    """A second viser client: a WebSocket with viser's subprotocol that decodes what it is sent
    and renders nothing (it shows the rotor: the checkbox's default)."""

    def __init__(self, port: int) -> None:
        url = f"http://127.0.0.1:{port}"
        self.ws = connect(
            f"ws://127.0.0.1:{port}",
            subprotocols=[f"viser-v{viser.__version__}"],
            origin=url,
            open_timeout=WAIT_S,
            max_size=None,
        )
        # viser counts a client as connected from its first camera report
        camera = {
            "type": "ViewerCameraMessage",
            "wxyz": (1.0, 0.0, 0.0, 0.0),
            "position": (0.0, 0.0, 3.0),
            "fov": 1.0,
            "near": 0.01,
            "far": 100.0,
            "image_height": 600,
            "image_width": 400,
            "look_at": (0.0, 0.0, 0.0),
            "up_direction": (0.0, 0.0, 1.0),
        }
        self.ws.send(msgspec.msgpack.encode(camera))
        self.seen = Frames()
        self._th = threading.Thread(target=self._run, name="raw-viewer", daemon=True)
        self._th.start()

    def _run(self) -> None:
        try:
            for payload in self.ws:
                self.seen._frame(payload)
        except Exception:  # closed
            pass

    def close(self) -> None:
        self.ws.close()
        self._th.join(timeout=10)


def rotor_angle(messages: list[dict]) -> float | None:
    """The rotor frame's last orientation in ``messages``, as its angle about z (rad)."""
    for m in reversed(messages):
        if m.get("name") == f"{ROOT}/rotor" and "wxyz" in m:
            w = m["wxyz"]
            return 2 * math.atan2(w[3], w[0]) % (2 * math.pi)
    return None


def wrap(a: float) -> float:
    """An angle difference wrapped into (-π, π]."""
    return (a + math.pi) % (2 * math.pi) - math.pi


@pytest.fixture(scope="module")
def bench():
    cfg = BenchConfig(
        virtual=True,
        speed_factor=1.0,
        gui_port=0,
        scene_3d=True,
        scene_3d_shown=True,
        gui_rate_hz=TEST_PLOT_RATE_HZ,
    )
    with TestClient(create_app(cfg), base_url="http://127.0.0.1:8000") as c:
        yield c.app.state.gui, c.app.state.bench


@pytest.fixture(scope="module")
def page(bench):
    from playwright.sync_api import sync_playwright

    gui, _ = bench
    with sync_playwright() as p:
        browser = launch(p)
        pg = browser.new_page(viewport={"width": 1280, "height": 800})
        pg.set_default_timeout(WAIT_S * 1000)
        pg.add_init_script(GL_COUNT_JS)
        pg.frames_seen = Frames()
        pg.on("websocket", pg.frames_seen.on_websocket)
        open_bench(pg, f"http://127.0.0.1:{gui.port}/")
        yield pg
        browser.close()


def wait_for(page, cond, what: str, timeout: float = WAIT_S) -> None:
    """Wait (letting Playwright deliver the page's frames) until ``cond()``."""
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            load = os.getloadavg()[0]
            raise AssertionError(f"{what}: not within {timeout:g} s (load {load:.1f})")
        page.wait_for_timeout(100)


def test_hidden_rotor_is_sent_nothing_and_comes_back_at_the_present_angle(bench, page):
    gui, drive_bench = bench
    seen: Frames = page.frames_seen
    drive = drive_bench.drive
    wait_for(page, lambda: any(m.get("name") == f"{ROOT}/rotor" for m in seen.rotor()),
             "the rotor's nodes reach the page")
    drive_bench.command("enable")
    drive_bench.set_speed(300.0)
    start = len(seen.messages)
    wait_for(page, lambda: len({rotor_angle([m]) for m in seen.rotor(start)} - {None}) >= 3,
             "the rotor turns in the page")
    other = RawViewer(gui.port)
    try:
        hidden_angle = hide_and_watch(page, drive_bench, other)
    finally:
        other.close()

    # --- shown again at standstill: at the drive's present angle
    drive_bench.set_speed(0.0)
    wait_for(page, lambda: abs(drive.live.latest()["measurements.speed"]) < 1.0,
             "the drive stands still")
    page.wait_for_timeout(300)
    shown_at = len(seen.messages)
    click(page, page.get_by_label(TOGGLE_LABEL, exact=True))
    wait_for(page, lambda: rotor_angle(seen.rotor(shown_at)) is not None,
             "the rotor comes back in the page")
    angle = rotor_angle(seen.rotor(shown_at))
    theta_e = float(drive.read("measurements.theta_e"))
    drive_bench.command("disable")
    err = wrap(angle * POLE_PAIRS - theta_e)
    assert abs(err) < 0.1, (
        f"rotor shown at θ_e {angle * POLE_PAIRS % (2 * math.pi):.3f} rad, the drive is at "
        f"{theta_e:.3f} rad (hidden at {hidden_angle})"
    )


def hide_and_watch(page, drive_bench, other: RawViewer) -> float | None:
    """Hide the rotor in ``page``; check that it is sent nothing for it while the drive turns
    and ``other`` keeps getting it. Returns the rotor's angle the page saw last (rad)."""
    seen: Frames = page.frames_seen
    drive = drive_bench.drive
    start = len(seen.messages)
    wait_for(page, lambda: rotor_angle(other.seen.rotor()) is not None,
             "the other viewer gets the rotor")
    # --- hidden: the removal arrives, then nothing for the rotor while the plots stream on
    click(page, page.get_by_label(TOGGLE_LABEL, exact=True))
    wait_for(page, lambda: any(m.get("type") == "RemoveSceneNodeMessage"
                               and m.get("name") == ROOT for m in seen.rotor(start)),
             "the rotor's removal reaches the page")
    page.wait_for_timeout(500)  # the removal's own re-render settles (250 ms)
    hidden_at = len(seen.messages)
    hidden_angle = rotor_angle(seen.rotor(0))
    gl0, t0 = page.evaluate("window.__gl"), time.monotonic()
    n_other = len(other.seen.messages)

    def other_turns() -> int:
        return len({rotor_angle([m]) for m in other.seen.rotor(n_other)} - {None})

    wait_for(page, lambda: seen.plot_updates(hidden_at) >= 20 and other_turns() >= 5
             and time.monotonic() - t0 >= 2.0,
             "live plots keep arriving in the page and the rotor in the other viewer")
    draws, dt = page.evaluate("window.__gl") - gl0, time.monotonic() - t0
    assert abs(drive.live.latest()["measurements.speed"]) > 100.0  # the drive kept turning
    assert seen.rotor(hidden_at) == [], "rotor messages sent to a page that hides it"
    # the empty scene's heartbeat (~1 render/s); the turning rotor drew ~800 calls/s here
    assert draws <= 5 * dt + 20, f"{draws} WebGL draws in {dt:.1f} s with the rotor hidden"
    return hidden_angle


def test_by_default_a_page_opens_with_the_rotor_hidden_and_is_sent_none():
    """``drive-dashboard`` as users start it (``BenchConfig()`` defaults, no ``--show-3d``): a
    new viser client gets the "3D rotor" checkbox unchecked and, while the live plots stream,
    no message for any rotor node."""
    cfg = BenchConfig(virtual=True, speed_factor=1.0, gui_port=0)
    assert cfg.scene_3d and not cfg.scene_3d_shown
    with TestClient(create_app(cfg), base_url="http://127.0.0.1:8000") as c:
        gui = c.app.state.gui
        viewer = RawViewer(gui.port)
        try:
            seen = viewer.seen

            def toggle() -> dict | None:
                """The checkbox's creation message (``value``: checked, ``props``: label...)."""
                for _, m in list(seen.messages):
                    if (m.get("props") or {}).get("label") == TOGGLE_LABEL:
                        return m
                return None

            deadline = time.monotonic() + WAIT_S
            while (toggle() is None or seen.plot_updates() < 10) and time.monotonic() < deadline:
                time.sleep(0.1)
            box = toggle()
            assert box is not None, "no '3D rotor' checkbox reached the client"
            assert box.get("value") is False
            assert seen.plot_updates() >= 10, "the live plots did not stream"
            assert seen.rotor() == [], "rotor messages sent to a client that did not ask"
        finally:
            viewer.close()
