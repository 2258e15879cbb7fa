"""`drive-link monitor` against raw frames this test puts on the loopback hub with python-can
(cansend-like), its decoded texts compared with the EDS as Python's configparser reads it
(names, units, default PDO mappings), CiA 301's NMT and heartbeat codes and canopen's own EMCY
descriptions."""

from __future__ import annotations

import configparser
import contextlib
import io
import json
import struct
import threading
import time

import can
import pytest
from canopen.emcy import EmcyError

from drive_link import cli
from drive_link.link.monitor import BusTable, IdFilter, parse_ids
from firmware_protocol import EDS_PATH
from virtual_drive.hub import Hub

pytestmark = pytest.mark.timeout(60)

N = 3  # the node the frames speak for


def _eds() -> configparser.RawConfigParser:
    cp = configparser.RawConfigParser(strict=False, interpolation=None)
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    cp.read(EDS_PATH, encoding="utf-8")
    return cp


def _name_unit(cp, index: int, sub: int) -> tuple[str, str]:
    """OD name as the project writes it (record.member) and the Unit key, from the EDS text."""
    sec = f"{index:04X}sub{sub:X}"
    if cp.has_section(sec):
        name = f"{cp[f'{index:04X}']['ParameterName']}.{cp[sec]['ParameterName']}"
        return name, cp[sec].get("Unit", "")
    return cp[f"{index:04X}"]["ParameterName"], cp[f"{index:04X}"].get("Unit", "")


def _msg(cob: int, data: bytes) -> can.Message:
    return can.Message(arbitration_id=cob, data=data, is_extended_id=False)


def _run_monitor(hub, send, *extra: str) -> dict:
    """``drive-link monitor`` on ``hub`` while ``send`` puts frames on it (after the monitor
    has joined: the hub counts its connection and its rawmode hold has passed)."""
    port = hub.port
    before = hub.stats.clients_total
    out = io.StringIO()
    box = {}

    def run() -> None:
        with contextlib.redirect_stdout(out):
            box["rc"] = cli.main(["monitor", "--host", "127.0.0.1", "--port", str(port),
                                  "--seconds", "4", "--json", *extra])  # fmt: skip

    th = threading.Thread(target=run)
    th.start()
    deadline = time.monotonic() + 30.0
    while hub.stats.clients_total == before and time.monotonic() < deadline:
        time.sleep(0.02)  # a loaded host took over 1 s to start the monitor
    time.sleep(Hub.handshake_hold_s + 0.3)
    with can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="vcan0") as tx:
        send(tx)
    th.join(20)
    assert box["rc"] == 0
    return json.loads(out.getvalue())


def test_monitor_decodes_raw_frames_as_the_eds_says(hub):
    cp = _eds()
    map_ref = [int(cp[f"1A01sub{i}"]["DefaultValue"], 0) for i in (1, 2)]  # TPDO2's default
    (n1, u1), (n2, u2) = (_name_unit(cp, r >> 16, (r >> 8) & 0xFF) for r in map_ref)
    new_ref = int(cp["1A02sub1"]["DefaultValue"], 0)  # remap TPDO2:1 to TPDO3's first object
    n3, u3 = _name_unit(cp, new_ref >> 16, (new_ref >> 8) & 0xFF)

    def send(tx: can.Bus) -> None:
        tx.send(_msg(0x000, bytes([0x01, N])))
        for _ in range(10):
            tx.send(_msg(0x700 + N, b"\x7f"))
            time.sleep(0.01)
        tx.send(_msg(0x700 + 4, b"\x05"))  # another node: filtered out below
        tx.send(_msg(0x080 + N, struct.pack("<HB5x", 0x2310, 0x03)))
        tx.send(_msg(0x600 + N, bytes([0x40, 0x10, 0x20, 0x02, 0, 0, 0, 0])))
        tx.send(_msg(0x580 + N, bytes([0x43, 0x10, 0x20, 0x02]) + struct.pack("<f", 1.48e-5)))
        time.sleep(0.05)
        tx.send(_msg(0x280 + N, struct.pack("<ff", 12.5, 1000.0)))
        time.sleep(0.2)
        # remap by SDO (expedited download, confirmed), then the same PDO again
        tx.send(_msg(0x600 + N, bytes([0x23, 0x01, 0x1A, 0x01]) + struct.pack("<I", new_ref)))
        tx.send(_msg(0x580 + N, bytes([0x60, 0x01, 0x1A, 0x01, 0, 0, 0, 0])))
        time.sleep(0.05)
        tx.send(_msg(0x280 + N, struct.pack("<ff", -7.25, 1000.0)))

    res = _run_monitor(hub, send, "--show-nodes", str(N))
    rows = {r["id"]: r for r in res["rows"]}
    assert f"0x{0x704:03X}" not in rows  # --show-nodes 3
    assert rows["0x000"]["text"] == f"start node {N}"
    hb = rows[f"0x{0x700 + N:03X}"]
    assert hb["text"] == "PRE-OPERATIONAL" and hb["count"] == 10 and hb["kind"] == "heartbeat"
    emcy = rows[f"0x{0x80 + N:03X}"]["text"]
    assert (
        emcy.startswith("0x2310 ") and EmcyError(0x2310, 3, b"", 0).get_desc().lower() in emcy
    )  # its class
    assert "register 0x03" in emcy
    map_name = f"{cp['1A01']['ParameterName']}.{cp['1A01sub1']['ParameterName']}"
    assert rows[f"0x{0x600 + N:03X}"]["text"] == f"write 0x1A01:01 {map_name} = 0x{new_ref:08X}"
    answer = rows[f"0x{0x580 + N:03X}"]["text"]  # the last answer: the remap confirmed
    assert (
        answer
        == f"0x1A01:01 {cp['1A01']['ParameterName']}.{cp['1A01sub1']['ParameterName']} written"
    )
    pdo = rows[f"0x{0x280 + N:03X}"]["text"]
    assert pdo == f"TPDO2: {n3}=-7.25 {u3}".rstrip() + f", {n2}=1000 {u2}".rstrip(), pdo
    del n1, u1  # the default mapping's text: the unit test below


@pytest.fixture(scope="module")
def hub():
    h = Hub(port=0).start()
    yield h
    h.stop()


@pytest.mark.unit
def test_table_decodes_the_sdo_answer_with_the_eds_unit_and_filters_by_id():
    cp = _eds()
    name, unit = _name_unit(cp, 0x2010, 2)
    table = BusTable(keep=IdFilter(ids=parse_ids("0x580-0x5FF,0x283,0x603")))
    table.on_frame(0x603, bytes([0x40, 0x10, 0x20, 0x02, 0, 0, 0, 0]), 1.0)
    table.on_frame(0x583, bytes([0x43, 0x10, 0x20, 0x02]) + struct.pack("<f", 1.48e-5), 1.0)
    table.on_frame(0x703, b"\x05", 1.0)
    ref = [int(cp[f"1A01sub{i}"]["DefaultValue"], 0) for i in (1, 2)]
    (n1, u1), (n2, u2) = (_name_unit(cp, r >> 16, (r >> 8) & 0xFF) for r in ref)
    for k in range(5):
        table.on_frame(0x283, struct.pack("<ff", 12.5, 1000.0), 1.0 + 0.001 * k)
    rows = {r["id"]: r for r in table.rows()}
    assert set(rows) == {"0x583", "0x283", "0x603"}
    assert rows["0x603"]["text"] == f"read 0x2010:02 {name}"
    assert rows["0x583"]["text"] == f"0x2010:02 {name} = 1.48e-05 {unit}"
    assert rows["0x283"]["text"] == f"TPDO2: {n1}=12.5 {u1}, {n2}=1000 {u2}"
    assert rows["0x283"]["count"] == 5 and rows["0x283"]["rate_hz"] == pytest.approx(1000, rel=0.01)
    table.pause(True)
    table.on_frame(0x283, struct.pack("<ff", 1.0, 2.0), 2.0)
    assert {r["id"]: r for r in table.rows()}["0x283"]["count"] == 5  # frozen while paused
    table.pause(False)
    assert {r["id"]: r for r in table.rows()}["0x283"]["count"] == 6
