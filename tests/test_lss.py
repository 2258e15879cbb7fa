"""LSS (CiA 305) on both sides: two virtual drives out of the box (no node-ID, 0xFF; distinct
serial numbers in 0x1018:4) in one ``virtual-drive run --unconfigured 2`` process on the hub,
found by fast scan and given distinct node-IDs.

Truth: canopen's own :class:`canopen.lss.LssMaster` (fast scan, configure node-ID, inquire) and
canopen's SDO client reading 0x1018 of the node that booted with the new ID."""

from __future__ import annotations

import contextlib
import io
import json
import subprocess
import sys
import time
from pathlib import Path

import canopen
import pytest

from drive_link import cli
from virtual_drive.hub import Hub

pytestmark = pytest.mark.timeout(120)

BIN = Path(sys.executable).parent
SERIALS = (0x00A5, 0x0042)  # the fast scan finds the lowest LSS address first: 0x42


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    store = tmp_path_factory.mktemp("lss") / "drive.json"
    hub = Hub(port=0).start()
    proc = subprocess.Popen(
        [str(BIN / "virtual-drive"), "run", "-i", "socketcand", "--host", "127.0.0.1",
         "--port", str(hub.port), "--unconfigured", "2", "--serial-base", "0x42",
         "--store", str(store)],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )  # fmt: skip
    try:
        line = proc.stdout.readline()
        assert "2 unconfigured drive(s) (serial 66,67)" in line, line
        yield hub, store
    finally:
        proc.terminate()
        proc.wait(10)
        hub.stop()


def _network(hub: Hub) -> canopen.Network:
    net = canopen.Network()
    net.connect(interface="socketcand", host="127.0.0.1", port=hub.port, channel="vcan0")
    net.lss.RESPONSE_TIMEOUT = 0.2
    return net


def test_fast_scan_with_canopens_lss_master_gives_distinct_ids(bench):
    hub, store = bench
    net = _network(hub)
    try:
        net.lss.send_switch_state_global(net.lss.WAITING_STATE)
        found, address = net.lss.fast_scan()
        assert found and address == [0, 0x5048, 0x00010000, 0x42]  # vendor, product, rev, serial
        assert net.lss.inquire_node_id() == 0xFF  # in configuration state, still unconfigured
        net.lss.configure_node_id(10)
        net.lss.store_configuration()
        net.lss.send_switch_state_global(net.lss.WAITING_STATE)  # boots as node 10
        node = net.add_node(10, canopen.import_od(_eds(), 10))
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            try:
                serial = node.sdo.upload(0x1018, 4)
                break
            except canopen.SdoCommunicationError:
                time.sleep(0.2)
        assert int.from_bytes(serial, "little") == 0x42
        # the configured drive keeps out of the next fast scan: the other one answers
        found, address = net.lss.fast_scan()
        assert found and address[3] == 0x43
        net.lss.configure_node_id(11)
        net.lss.send_switch_state_global(net.lss.WAITING_STATE)
        time.sleep(1.0)
        assert net.lss.fast_scan() == (False, None)  # nobody unconfigured is left
        net.scanner.search()
        time.sleep(1.0)
        assert {10, 11} <= set(net.scanner.nodes)
        stored = store.with_name("drive-serial66.lss.json")  # 0x17 wrote it; 0x43 was not stored
        assert json.loads(stored.read_text())["node_id"] == 10
        assert not store.with_name("drive-serial67.lss.json").exists()
    finally:
        net.disconnect()


def test_drive_link_lss_configures_what_is_unconfigured(bench):
    """After the first test both drives have IDs: reset node 11 to 0xFF by LSS (selective
    switch by its address, configure 0xFF, reset communication), then ``drive-link lss``."""
    hub, _store = bench
    net = _network(hub)
    try:
        assert net.lss.send_switch_state_selective(0, 0x5048, 0x00010000, 0x43)
        net.lss.configure_node_id(0xFF)
        net.lss.send_switch_state_global(net.lss.WAITING_STATE)
        net.nmt.send_command(0x82)  # reset communication: the pending 0xFF takes effect
        time.sleep(1.0)
    finally:
        net.disconnect()
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = cli.main(["lss", "--host", "127.0.0.1", "--port", str(hub.port), "--first-id",
                       "10", "--json"])  # fmt: skip
    assert rc == 0
    done = json.loads(out.getvalue())
    # after the first test: 10 is in use (node 10 answers the scan), 0x43 gets the next free ID
    # and boots with it (run alone, both drives are unconfigured and get 10 and 11)
    assert all(d["booted"] for d in done) and 0x43 in {d["serial"] for d in done}
    ids = [d["node_id"] for d in done]
    assert len(set(ids)) == len(ids) and all(i >= 10 for i in ids)
    if len(done) == 1:
        assert ids == [11]


def _eds() -> str:
    from firmware_protocol import EDS_PATH

    return str(EDS_PATH)
