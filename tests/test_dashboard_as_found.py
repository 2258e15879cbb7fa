"""The dashboard's REST API leaves the drive as found after a current step and an
identification (issue 24 deliverable 2: the API like the CLI), with drive_link doing it
(drive_link.workflows.steps): from speed mode at 1000 rpm, enabled, back to speed mode at 1000 rpm,
enabled, with the i_p* it had. The truth is the drive's own objects read through drive_link."""

from __future__ import annotations

import time

import pytest
from fastapi.testclient import TestClient

from dashboard.app import create_app
from dashboard.config import BenchConfig

pytestmark = pytest.mark.timeout(150)


@pytest.fixture(scope="module")
def client():
    cfg = BenchConfig(virtual=True, speed_factor=2.0, gui_port=0)
    with TestClient(create_app(cfg, gui=False), base_url="http://127.0.0.1:8000") as c:
        yield c


def found(client) -> tuple:
    d = client.app.state.bench.drive
    return d.state, d.mode, d.read("target_velocity"), d.read("setpoints.i_p_ref")


def test_current_step_and_identification_leave_speed_mode_at_1000rpm(client):
    r = client.post("/api/control", json={"client": "pytest", "take_over": True})
    hdr = {"X-Control-Token": r.json()["token"]}
    assert client.put("/api/setpoints/speed", json={"rpm": 1000}, headers=hdr).status_code == 200
    assert client.post("/api/command", json={"command": "enable"}, headers=hdr).status_code == 200
    d = client.app.state.bench.drive
    deadline = time.monotonic() + 30
    while abs(float(d.read("measurements.speed")) - 1000) > 30:
        assert time.monotonic() < deadline
        time.sleep(0.1)
    before = found(client)
    assert before[:3] == ("OPERATION ENABLED", "speed", 1000)
    r = client.post("/api/steps/current", json={"from_A": 15, "to_A": 20, "duration_ms": 1.0},
                    headers=hdr)
    assert r.status_code == 200, r.text
    assert found(client) == before
    r = client.post("/api/identify", json={"from_A": 15, "to_A": 30, "duration_s": 0.5},
                    headers=hdr)
    assert r.status_code == 200, r.text
    assert found(client) == before
