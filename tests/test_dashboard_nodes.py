"""``drive-dashboard --virtual --nodes 1,2``: one command starts two drives on the bench's hub;
the dashboard controls ``--node`` and the other drive is on the same bus. Truth: canopen's own
network scanner and SDO client on a separate connection to the hub."""

from __future__ import annotations

import time

import canopen
import pytest
from fastapi.testclient import TestClient

from dashboard import cli
from dashboard.app import create_app
from dashboard.config import BenchConfig
from firmware_protocol import EDS_PATH

pytestmark = pytest.mark.timeout(90)


@pytest.mark.unit
def test_nodes_needs_virtual_and_must_hold_node(capsys):
    for argv, needle in (
        (["--nodes", "1,2", "--interface", "virtual"], "needs --virtual"),
        (["--virtual", "--nodes", "1,2", "--node", "3"], "not one of --nodes"),
        (["--virtual", "--nodes", "1,1"], "names a node twice"),
    ):
        assert cli.main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and needle in err, err


def test_two_drives_from_one_command_the_bench_controls_its_node():
    cfg = BenchConfig(virtual=True, nodes=(1, 2), node_id=2, gui_port=0, scene_3d=False)
    cfg.validate()
    with TestClient(create_app(cfg), base_url="http://127.0.0.1:8000") as c:
        bench = c.app.state.bench
        assert bench.drive.node_id == 2
        net = canopen.Network()
        net.connect(interface="socketcand", host="127.0.0.1", port=bench.hub_port,
                    channel="vcan0")  # fmt: skip
        try:
            net.scanner.search()
            time.sleep(1.0)
            assert {1, 2} <= set(net.scanner.nodes)
            one = net.add_node(1, canopen.import_od(str(EDS_PATH), 1))
            assert one.sdo["device_type"].raw == 0x00020192  # the other drive answers too
            bench.drive.write("target_velocity", 77)
            assert one.sdo["target_velocity"].raw == 0  # the bench wrote to node 2 only
        finally:
            net.disconnect()
