"""REST strictness and long actions against the virtual drive (in process, no GUI).

Truths: JSON (RFC 8259 has no NaN/Infinity; 1e400 is not a finite double), pydantic strict mode
(no coercion), HTTP (421 for a Host the server does not serve, 401 without the Bearer token),
and the drive's own objects read through drive_link for "nothing changed" / "put back".
"""

from __future__ import annotations

import threading
import time

import pytest
from fastapi.testclient import TestClient
from starlette.websockets import WebSocketDisconnect

from dashboard.app import create_app
from dashboard.config import BenchConfig

pytestmark = pytest.mark.timeout(120)
BASE = "http://127.0.0.1:8000"


@pytest.fixture(scope="module")
def client():
    cfg = BenchConfig(virtual=True, speed_factor=4.0, gui_port=0)
    with TestClient(create_app(cfg, gui=False), base_url=BASE) as c:
        yield c


@pytest.fixture()
def hdr(client):
    r = client.post("/api/control", json={"client": "pytest", "take_over": True})
    return {"X-Control-Token": r.json()["token"]}


def raw(client, method: str, path: str, body: str, hdr: dict) -> int:
    h = {**hdr, "Content-Type": "application/json"}
    return client.request(method, path, content=body.encode(), headers=h).status_code


@pytest.mark.parametrize(
    "body",
    [
        '{"rpm": NaN}',
        '{"rpm": Infinity}',
        '{"rpm": 1e400}',
        '{"rpm": true}',
        '{"rpm": "300"}',
        '{"rpm": 300, "extra": 1}',
    ],
)
def test_speed_body_is_strict(client, hdr, body):
    before = client.app.state.bench.speed_setpoint
    assert raw(client, "PUT", "/api/setpoints/speed", body, hdr) == 422
    assert client.app.state.bench.speed_setpoint == before


def test_gains_strict_force_and_numbers(client, hdr):
    d = client.app.state.bench.drive
    L_c = float(d.read("current_controller.L_c"))
    assert raw(client, "PUT", "/api/gains", '{"L_c": 2.8e-5, "force": "yes"}', hdr) == 422
    assert raw(client, "PUT", "/api/gains", '{"L_c": NaN}', hdr) == 422
    assert raw(client, "PUT", "/api/gains", '{"L_c": "1.4e-5"}', hdr) == 422
    assert float(d.read("current_controller.L_c")) == L_c  # nothing applied


def test_trace_channels_and_trigger_level(client, hdr):
    ok = client.get("/api/trace/config").json()
    bad = {**ok, "channels": ["measurements.no_such_signal"]}
    assert client.put("/api/trace/config", json=bad, headers=hdr).status_code == 422
    nan_level = '{"trigger": "signal", "trigger_level": NaN}'
    assert raw(client, "PUT", "/api/trace/config", nan_level, hdr) == 422
    assert client.get("/api/trace/config").json() == ok  # nothing stored
    good = {**ok, "channels": ["i_p"]}
    r = client.put("/api/trace/config", json=good, headers=hdr)
    assert r.status_code == 200 and r.json()["channels"] == ["measurements.i_p"]


def test_body_less_actions_need_no_body(client, hdr):
    assert client.post("/api/gains/store", headers=hdr).status_code == 200
    assert client.request("DELETE", "/api/steps/sequence", headers=hdr).status_code == 200
    assert raw(client, "DELETE", "/api/steps/sequence", '{"x": 1}', hdr) == 422
    assert client.request("DELETE", "/api/control", headers=hdr).status_code == 200
    assert client.get("/api/control").json()["client"] is None


def test_host_header_and_bearer_only(client):
    assert client.get("/api/state", headers={"Host": "evil.example:8000"}).status_code == 421
    assert client.get("/api/state", headers={"Host": "localhost:8000"}).status_code == 200
    cfg = client.app.state.config
    cfg.token = "secret-token-1234"
    try:
        assert client.get("/api/state?token=secret-token-1234").status_code == 401  # not in URLs
        ok = client.get("/api/state", headers={"Authorization": "Bearer secret-token-1234"})
        assert ok.status_code == 200
        with client.websocket_connect("ws://127.0.0.1:8000/api/stream") as ws:
            ws.send_json({"type": "auth", "token": "secret-token-1234"})
            assert ws.receive_json()["type"] in ("live", "state")
        with client.websocket_connect("ws://127.0.0.1:8000/api/stream") as ws:
            ws.send_json({"type": "auth", "token": "wrong-token-00000"})
            with pytest.raises(WebSocketDisconnect):  # closed 1008, nothing sent
                ws.receive_json()
    finally:
        cfg.token = None


def test_cancelled_identification_puts_the_drive_back(client, hdr):
    bench = client.app.state.bench
    d = bench.drive
    client.post("/api/command", json={"command": "disable"}, headers=hdr)
    client.put("/api/mode", json={"mode": "speed"}, headers=hdr)
    mode0, state0 = d.mode, d.state
    i0 = float(d.read("setpoints.i_p_ref"))
    result = {}

    def run():
        result["r"] = client.post(
            "/api/identify", json={"from_A": 10, "to_A": 20, "duration_s": 20}, headers=hdr
        )

    th = threading.Thread(target=run)
    th.start()
    deadline = time.monotonic() + 30
    while bench.action is None and time.monotonic() < deadline:
        time.sleep(0.02)
    assert bench.action is not None
    time.sleep(0.5)
    assert client.get("/api/state").json()["action"]["what"] == "identification"
    assert client.post("/api/action/cancel", headers=hdr).json()["cancelled"] is True
    th.join(60)
    assert result["r"].status_code != 200 and "put back" in result["r"].text
    assert state0 != "OPERATION ENABLED"
    assert d.mode == mode0 and d.state != "OPERATION ENABLED"  # as found: speed, power off
    assert float(d.read("setpoints.i_p_ref")) == pytest.approx(i0, abs=1e-6)  # i_p* as found


def test_action_past_its_deadline_restores_and_frees_the_bench(client, hdr):
    from dashboard._actions import ActionTimeoutError

    bench = client.app.state.bench
    d = bench.drive
    client.put("/api/mode", json={"mode": "speed"}, headers=hdr)
    mode0 = d.mode
    with pytest.raises(ActionTimeoutError, match="put back"):
        with bench.long_action("test action", deadline_s=0.3) as act:
            bench.set_current(12.0)  # switches to current mode, like a step test
            act.sleep(5.0)  # a stuck action: the deadline ends it
    assert d.mode == mode0
    assert bench.action is None and bench.busy is None
    assert client.get("/api/state").json()["action"] is None
