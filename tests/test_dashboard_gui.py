"""The viser side without a browser: the handshake refuses a foreign Origin (403) and a foreign
Host (421) before viser handles anything, the share-URL request (a public tunnel) is refused,
and every message viser queues goes through one lock.
"""

from __future__ import annotations

import re
import tempfile
import time
from pathlib import Path

import httpx
import msgspec
import pytest
import viser
from fastapi.testclient import TestClient
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from dashboard._gui_guard import SEND_LOCK
from dashboard.app import create_app
from dashboard.config import BenchConfig

pytestmark = pytest.mark.timeout(90)


@pytest.fixture(scope="module")
def app_client():
    cfg = BenchConfig(virtual=True, speed_factor=2.0, gui_port=0, scene_3d=False)
    with TestClient(create_app(cfg), base_url="http://127.0.0.1:8000") as c:
        yield c


def viser_ws(port: int, origin: str | None, host: str | None = None):
    headers = {"Host": host} if host else None
    return connect(
        f"ws://127.0.0.1:{port}/",
        origin=origin,
        additional_headers=headers,
        subprotocols=[f"viser-v{viser.__version__}"],
        open_timeout=10,
    )


def test_foreign_origin_is_refused_in_the_handshake(app_client):
    port = app_client.app.state.gui.port
    with pytest.raises(InvalidStatus) as exc:
        viser_ws(port, "http://evil.example")
    assert exc.value.response.status_code == 403  # the socket never opened: nothing handled
    with viser_ws(port, f"http://127.0.0.1:{port}") as ws:
        assert ws.recv(timeout=10)  # the page's own origin receives GUI state


def test_foreign_host_is_refused(app_client):
    port = app_client.app.state.gui.port
    r = httpx.get(f"http://127.0.0.1:{port}/", headers={"Host": f"evil.example:{port}"})
    assert r.status_code == 421
    assert httpx.get(f"http://127.0.0.1:{port}/").status_code == 200
    with pytest.raises(InvalidStatus) as exc:  # the client adds its own Host too: 400
        viser_ws(port, None, host=f"evil.example:{port}")
    assert exc.value.response.status_code in (400, 421)
    r = app_client.get("/api/state", headers={"Host": "evil.example:8000"})
    assert r.status_code == 421
    assert app_client.get("/openapi.json", headers={"Host": "evil.example"}).status_code == 421


def test_share_url_request_is_refused(app_client):
    gui = app_client.app.state.gui
    called = []
    gui.server.request_share_url = lambda *a, **k: called.append(1)  # would open a tunnel
    port = gui.port
    with viser_ws(port, f"http://127.0.0.1:{port}") as ws:
        ws.send(msgspec.msgpack.encode({"type": "ShareUrlRequest"}))
        time.sleep(1.0)
    assert not called
    assert getattr(gui.server, "_share_tunnel", None) is None


def test_viser_sends_go_through_one_lock(app_client):
    from dashboard._gui_guard import send_lock_installed

    assert send_lock_installed()
    # while the lock is held elsewhere, a send from the plot thread waits (no interleaving)
    gui = app_client.app.state.gui
    before = gui.frames_sent
    with SEND_LOCK:
        gui.server.gui.add_markdown("x")  # re-entrant on the same thread
        time.sleep(0.3)
    assert gui.frames_sent >= before


class _FakeClient:
    """A browser's handle stand-in: the panel's GUI goes to the server-wide GUI."""

    def __init__(self, gui, client_id: int) -> None:
        self.gui, self.client_id = gui, client_id


def test_with_a_token_the_gui_must_sign_in_before_it_changes_anything(app_client):
    from dashboard._gui_panel import Panel

    gui = app_client.app.state.gui
    bench = app_client.app.state.bench
    cfg = gui.config
    cfg.token = "secret-token-1234"  # as with --allow-remote --token
    try:
        p = Panel(gui, _FakeClient(gui.server.gui, 990))
        page = p.page
        assert not page.control(p.control_md)
        assert "access token" in p.control_md.content
        assert bench.lease.holder is None or not p.holds_control()
        p.token_in.value = "wrong-token-0000"
        p.sign_in()
        assert not page.authenticated and not page.control(p.control_md)
        p.token_in.value = "secret-token-1234"
        p.sign_in()
        assert page.authenticated and p.token_in.value == ""  # the token is not kept on the page
        if bench.lease.holder is not None:
            page.take_control()
        assert page.control(p.control_md) and p.holds_control()
    finally:
        cfg.token = None


class _DownloadClient(_FakeClient):
    """A browser stand-in that keeps what the panel sends it as file downloads."""

    def __init__(self, gui, client_id: int) -> None:
        super().__init__(gui, client_id)
        self.files: dict[str, bytes] = {}

    def send_file_download(self, name: str, data: bytes, **kw) -> None:
        self.files[name] = data


def _event(value):
    from types import SimpleNamespace

    return SimpleNamespace(target=SimpleNamespace(value=value))


def test_config_tab_saves_a_dcf_canopen_reads_and_loads_it_back(app_client, tmp_path):
    """Truths: canopen's own DCF import (values of the file) and the drive's read-back."""
    import canopen
    from viser._gui_handles import UploadedFile

    from dashboard._gui_panel import Panel

    gui = app_client.app.state.gui
    drive = app_client.app.state.bench.drive
    client = _DownloadClient(gui.server.gui, 991)
    p = Panel(gui, client)
    tab = p.config_tab
    assert tab.save_dcf(None).startswith("saved ")
    (name, data), = client.files.items()
    assert name.endswith(".dcf")
    path = tmp_path / name
    path.write_bytes(data)
    od = canopen.objectdictionary.import_od(str(path), node_id=1)
    R_c = drive.read("current_controller.R_c")
    var = next(v for v in _od_vars(od) if v.name.endswith("R_c") and 0x2000 <= v.index)
    assert float(var.value) == pytest.approx(R_c, rel=1e-6)  # the file holds the drive's value
    text = data.decode()
    text = re.sub(
        rf"(\[{var.index:04X}sub{var.subindex:X}\][^\[]*?ParameterValue=)[^\r\n]*",
        lambda m: m.group(1) + repr(R_c * 2),
        text,
        flags=re.IGNORECASE,
    )
    upload = UploadedFile(name, text.encode())
    tab.dcf_dry.value = True
    msg = tab.load_dcf(_event(upload))
    assert "1 change(s) (dry run, nothing written)" in msg, msg
    assert drive.read("current_controller.R_c") == pytest.approx(R_c)  # nothing written
    tab.dcf_dry.value = False
    if app_client.app.state.bench.lease.holder is not None:
        p.page.take_control()
    msg = tab.load_dcf(_event(upload))
    assert "1 object(s) written" in msg, msg
    assert drive.read("current_controller.R_c") == pytest.approx(R_c * 2, rel=1e-6)
    tab.load_dcf(_event(UploadedFile(name, data)))  # the saved file puts it back
    assert drive.read("current_controller.R_c") == pytest.approx(R_c, rel=1e-6)


def _od_vars(od):
    import canopen

    for obj in od.values():
        if isinstance(obj, canopen.objectdictionary.ODVariable):
            yield obj
        else:
            yield from obj.values()


def test_config_tab_records_the_bus_for_other_can_tools(app_client):
    """Truth: python-can's own reader opens the downloaded .asc and finds the drive's TPDOs."""
    import can

    from dashboard._gui_panel import Panel

    gui = app_client.app.state.gui
    client = _DownloadClient(gui.server.gui, 992)
    tab = Panel(gui, client).config_tab
    tab.rec_fmt.value = ".asc"
    assert "recording the bus" in tab.record_button(_event("Start recording"))
    time.sleep(1.5)
    msg = tab.record_button(_event("Stop and download"))
    (name, data), = client.files.items()
    assert name.endswith(".asc") and "downloaded" in msg
    path = Path(tempfile.mkdtemp()) / name
    path.write_bytes(data)
    ids = {m.arbitration_id for m in can.LogReader(str(path))}
    assert 0x701 in ids or any(0x181 <= i <= 0x4FF for i in ids), ids  # heartbeat or TPDOs
