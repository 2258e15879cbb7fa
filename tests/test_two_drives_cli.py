"""Two drives on one hub from the CLI: ``scan`` lists both with their own NMT state and
``--node`` picks the drive. Truth: canopen's own heartbeat consumer (RemoteNode.nmt.state) on a
separate connection to the hub, and an SDO read by canopen's client."""

from __future__ import annotations

import contextlib
import io
import json
import time

import canopen
import pytest

from drive_link import cli
from firmware_protocol import EDS_PATH

pytestmark = pytest.mark.timeout(90)


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    from virtual_drive.launch import virtual_bench

    with virtual_bench(nodes=(1, 2), store_dir=tmp_path_factory.mktemp("s")) as bus:
        yield bus


def dl(port: int, *args: str) -> tuple[int, object]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = cli.main([*args, "--host", "127.0.0.1", "--port", str(port), "--json"])
    return rc, json.loads(out.getvalue())


def test_scan_lists_every_node_with_its_state_and_node_picks_the_drive(bench):
    net = canopen.Network()
    net.connect(interface="socketcand", host="127.0.0.1", port=bench.port, channel="vcan0")
    try:
        nodes = {n: net.add_node(n, canopen.import_od(str(EDS_PATH), n)) for n in (1, 2)}
        assert dl(bench.port, "--node", "2", "nmt", "start")[0] == 0
        for node in nodes.values():
            node.nmt.wait_for_heartbeat(3.0)
        time.sleep(0.3)
        truth = {n: node.nmt.state for n, node in nodes.items()}
        assert truth == {1: "PRE-OPERATIONAL", 2: "OPERATIONAL"}
        rc, found = dl(bench.port, "scan")
        assert rc == 0
        assert {f["node_id"]: f["nmt_state"] for f in found} == truth
        assert all(f["device_type"] == 0x00020192 for f in found)
        rc, _ = dl(bench.port, "--node", "2", "write", "target_velocity", "123")
        assert rc == 0
        raw = {n: nodes[n].sdo["target_velocity"].raw for n in (1, 2)}
        assert raw == {1: 0, 2: 123}  # only node 2 took it
    finally:
        net.disconnect()
