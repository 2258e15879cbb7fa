"""The REST API per node: ``GET /api/nodes``, ``POST /api/nodes/scan`` and ``?node=N`` on the
routes, with one control lease per node. Two drives started by the bench (``--virtual --nodes
1,2``); truth: canopen's own SDO client on a separate connection to the hub (0x60FF
target_velocity of each drive, CiA 402)."""

from __future__ import annotations

import json
import time

import canopen
import pytest
from fastapi.testclient import TestClient

from dashboard.app import create_app
from dashboard.config import BenchConfig
from firmware_protocol import EDS_PATH

pytestmark = pytest.mark.timeout(120)


@pytest.fixture(scope="module")
def client():
    cfg = BenchConfig(virtual=True, nodes=(1, 2), node_id=1, gui_port=0, scene_3d=False)
    with TestClient(create_app(cfg, gui=False), base_url="http://127.0.0.1:8000") as c:
        yield c


def trace_channel(net: canopen.Network, node_id: int) -> canopen.sdo.SdoClient:
    """canopen's SDO client on the drive's second SDO server (0x1201: 0x680 + N / 0x6B0 + N,
    the EDS defaults): the dashboard's own reads use the first server, and two clients on one
    SDO channel would take each other's answers."""
    node = canopen.RemoteNode(node_id, canopen.import_od(str(EDS_PATH), node_id))
    sdo = node.add_sdo(0x680 + node_id, 0x6B0 + node_id)  # before add_node (canopen)
    net.add_node(node)
    sdo.network = net  # canopen leaves it unset on an added client
    sdo.RESPONSE_TIMEOUT = 2.0
    sdo.MAX_RETRIES = 3  # canopen resends an unanswered request (a starved hub at load 16)
    return sdo


@pytest.fixture(scope="module")
def master(client):
    net = canopen.Network()
    port = client.app.state.bench.hub_port
    net.connect(interface="socketcand", host="127.0.0.1", port=port, channel="vcan0")
    try:
        yield {n: trace_channel(net, n) for n in (1, 2)}
    finally:
        net.disconnect()


def nodes(client) -> dict[int, dict]:
    return {r["node_id"]: r for r in client.get("/api/nodes").json()}


def test_nodes_lists_both_drives_by_their_heartbeats(client):
    deadline = time.monotonic() + 10
    while {n for n, r in nodes(client).items() if r["nmt_state"]} != {1, 2}:
        assert time.monotonic() < deadline, nodes(client)
        time.sleep(0.1)
    rows = nodes(client)
    assert rows[1]["default"] and rows[1]["open"] and rows[1]["nmt_state"] == "OPERATIONAL"
    assert not rows[2]["default"] and rows[2]["nmt_state"] in ("PRE-OPERATIONAL", "OPERATIONAL")
    assert {r["node_id"] for r in client.post("/api/nodes/scan").json()} == {1, 2}


def test_one_lease_per_node_and_each_drive_gets_only_its_setpoint(client, master):
    one = client.post("/api/control", json={"client": "A"}).json()["token"]
    two = client.post("/api/control?node=2", json={"client": "B"}).json()["token"]
    # each lease is held: a third client is refused on either node, A's token is not B's
    assert client.post("/api/control", json={"client": "C"}).status_code == 409
    assert client.post("/api/control?node=2", json={"client": "C"}).status_code == 409
    r = client.put("/api/setpoints/speed?node=2", json={"rpm": 100},
                   headers={"X-Control-Token": one})  # fmt: skip
    assert r.status_code == 409
    assert master[2]["target_velocity"].raw == 0  # refused: nothing sent
    r = client.put("/api/setpoints/speed", json={"rpm": 1000}, headers={"X-Control-Token": one})
    assert r.status_code == 200, r.text
    r = client.put("/api/setpoints/speed?node=2", json={"rpm": -500},
                   headers={"X-Control-Token": two})  # fmt: skip
    assert r.status_code == 200, r.text
    assert master[1]["target_velocity"].raw == 1000
    assert master[2]["target_velocity"].raw == -500
    s1, s2 = client.get("/api/state").json(), client.get("/api/state?node=2").json()
    assert (s1["node_id"], s1["speed_setpoint"], s1["controller"]["client"]) == (1, 1000, "A")
    assert (s2["node_id"], s2["speed_setpoint"], s2["controller"]["client"]) == (2, -500, "B")
    rows = nodes(client)
    assert (rows[1]["controller"], rows[2]["controller"]) == ("A", "B")
    assert rows[2]["open"] and rows[2]["nmt_state"] == "OPERATIONAL"  # started when opened
    # giving node 2 back leaves node 1's lease alone
    r = client.request("DELETE", "/api/control?node=2", headers={"X-Control-Token": two})
    assert r.status_code == 200, r.text
    assert client.get("/api/control?node=2").json()["client"] is None
    assert client.get("/api/control").json()["client"] == "A"


def test_unknown_and_invalid_nodes(client):
    t0 = time.monotonic()
    r = client.get("/api/state?node=9")
    assert r.status_code == 404 and "node 9" in r.json()["detail"]
    assert time.monotonic() - t0 < 1.0  # not seen on the bus: no SDO probe to wait for
    for bad in ("0", "128", "x"):
        assert client.get(f"/api/state?node={bad}").status_code == 422


def test_stream_of_one_node(client):
    """``/api/stream?node=2``: the state messages are node 2's."""
    with client.websocket_connect("ws://127.0.0.1:8000/api/stream?node=2") as ws:
        for _ in range(200):
            msg = json.loads(ws.receive_text())
            if msg["type"] == "state":
                break
        assert msg["type"] == "state" and msg["node_id"] == 2, msg
