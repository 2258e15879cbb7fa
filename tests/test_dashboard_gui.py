"""The viser side without a browser: its WebSocket refuses foreign Origins (viser itself checks
none), a take-over through the API is shown in the GUI, and the GUI's read-back follows the drive.
"""

from __future__ import annotations

import time

import pytest
import viser
from fastapi.testclient import TestClient
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from dashboard.app import create_app
from dashboard.config import BenchConfig

pytestmark = pytest.mark.timeout(90)


@pytest.fixture(scope="module")
def app_client():
    cfg = BenchConfig(virtual=True, speed_factor=2.0, gui_port=0, scene_3d=False)
    with TestClient(create_app(cfg)) as c:
        yield c


def viser_ws(port: int, origin: str):
    return connect(
        f"ws://127.0.0.1:{port}/",
        origin=origin,
        subprotocols=[f"viser-v{viser.__version__}"],
        open_timeout=10,
    )


def test_viser_websocket_refuses_foreign_origin(app_client):
    port = app_client.app.state.gui.port
    with viser_ws(port, "http://evil.example") as ws:
        with pytest.raises(ConnectionClosed) as exc:
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline:
                ws.recv(timeout=5)
        assert exc.value.rcvd is not None and exc.value.rcvd.code == 1008
    with viser_ws(port, f"http://127.0.0.1:{port}") as ws:
        got = 0
        deadline = time.monotonic() + 3
        while time.monotonic() < deadline:
            ws.recv(timeout=5)  # the page's own origin keeps receiving GUI state
            got += 1
        assert got > 0


def test_take_over_is_visible_in_the_gui(app_client):
    gui = app_client.app.state.gui
    a = app_client.post("/api/control", json={"client": "script-A", "take_over": True})
    assert a.status_code == 200
    deadline = time.monotonic() + 5
    while "script-A" not in gui.controller_md.content and time.monotonic() < deadline:
        time.sleep(0.05)
    assert "In control:** script-A" in gui.controller_md.content
    app_client.post("/api/control", json={"client": "script-B", "take_over": True})
    assert "In control:** script-B" in gui.controller_md.content


def test_gui_read_back_follows_the_drive(app_client):
    gui = app_client.app.state.gui
    tok = app_client.post("/api/control", json={"client": "t", "take_over": True}).json()["token"]
    r = app_client.put("/api/gains", json={"L_c": 20e-6}, headers={"X-Control-Token": tok})
    assert r.status_code == 200
    deadline = time.monotonic() + 5
    while "L_c 20 µH" not in gui.readback_md.content and time.monotonic() < deadline:
        time.sleep(0.05)
    assert "L_c 20 µH" in gui.readback_md.content
    assert gui.Lc_uH.value == pytest.approx(20.0, abs=1e-4)
    assert gui.Lc_ratio.value == pytest.approx(20.0 / 14.8, abs=1e-5)
