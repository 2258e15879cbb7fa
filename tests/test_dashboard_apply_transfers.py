"""What a GUI action costs on the bus, counted by a listener of our own on the loopback hub
(issue 25): SDO transfers are the initiate requests a client sends on 0x600 + node (CiA 301
§7.2.4.3: ccs 1 download, 2 upload, 5/6 block; segments and aborts belong to their transfer).
An "Apply gains" click costs at most 20, the same with a second page open; the preview of an
edit none; a speed setpoint of an enabled drive goes as one RPDO1 frame (0x200 + node), no SDO.
"""

from __future__ import annotations

import struct
import threading
import time

import can
import pytest
from fastapi.testclient import TestClient

from dashboard.app import create_app
from dashboard.config import BenchConfig
from drive_link.link.bus import open_bus
from firmware_protocol.entry import f32


class _Client:
    """A browser's handle stand-in: the panel's GUI goes to the server-wide GUI."""

    def __init__(self, gui, client_id: int) -> None:
        self.gui, self.client_id = gui, client_id


class _Bus(can.Listener):
    """SDO transfers started on 0x600 + node, and RPDO1 frames."""

    def __init__(self, node: int) -> None:
        self.node, self.sdo, self.rpdo1 = node, 0, []
        self.lock = threading.Lock()

    def on_message_received(self, msg: can.Message) -> None:
        b0 = msg.data[0] if msg.data else 0
        with self.lock:
            if msg.arbitration_id == 0x600 + self.node and (
                b0 >> 5 in (1, 2) or b0 & 0xE1 == 0xC0 or b0 & 0xE3 == 0xA0
            ):
                self.sdo += 1
            elif msg.arbitration_id == 0x200 + self.node:
                self.rpdo1.append(bytes(msg.data))


@pytest.fixture(scope="module")
def bench_bus():
    cfg = BenchConfig(virtual=True, speed_factor=2.0, gui_port=0, scene_3d=False)
    with TestClient(create_app(cfg), base_url="http://127.0.0.1:8000") as c:
        gui, bench = c.app.state.gui, c.app.state.bench
        bus = open_bus(host="127.0.0.1", port=bench.hub_port, bitrate=1_000_000)
        seen = _Bus(bench.node_id)
        notifier = can.Notifier(bus, [seen], timeout=0.1)
        try:
            yield gui, bench, seen
        finally:
            notifier.stop(1.0)
            bus.shutdown()


def _counted(seen: _Bus, action) -> int:
    time.sleep(0.3)  # frames of what came before are in
    with seen.lock:
        n0 = seen.sdo
    action()
    time.sleep(0.3)
    with seen.lock:
        return seen.sdo - n0


def _page(gui, cid: int):
    """A page as a connecting browser gets it (the GUI's bench events reach it)."""
    from dashboard._gui_panel import Panel

    panel = Panel(gui, _Client(gui.server.gui, cid))  # reads the gains once
    gui.panels[cid] = panel
    return panel.tuning


def test_apply_costs_at_most_20_transfers_and_the_preview_none(bench_bus):
    gui, bench, seen = bench_bus
    page = _page(gui, 995)
    bench.watch.stop()  # its mode poll (every 0.5 s) would be counted too
    try:
        page.Lc_uH.input.value = "16"
        assert _counted(seen, page.preview) == 0
        assert "L_c/L = 1.081" in page.preview_md.content  # 16 / 14.8: the typed set's verdict
        one = _counted(seen, page.apply)
        assert one <= 20, one
        assert bench.drive.read("current_controller.L_c") == f32(16e-6)  # read after counting
        assert "L_c 16 µH" in page.readback_md.content
        other = _page(gui, 996)  # a second page on this node
        other.Lc_uH.input.value = "14.8"
        two = _counted(seen, other.apply)
        assert two == one  # no page reads the set again after an Apply
        assert "L_c 14.8 µH" in page.readback_md.content  # the first page follows
    finally:
        bench.watch.start()
        gui.panels.clear()


def test_a_speed_setpoint_goes_by_rpdo1_without_a_read(bench_bus):
    _gui, bench, seen = bench_bus
    bench.command("enable")
    time.sleep(0.5)  # the statusword TPDO shows OPERATION ENABLED
    bench.set_speed(100)  # the mode known, the 0x6080 limit read once here
    bench.watch.stop()
    try:
        time.sleep(0.3)  # the 100 rpm frame is in
        with seen.lock:
            frames0 = len(seen.rpdo1)
        assert _counted(seen, lambda: bench.set_speed(321)) == 0
        with seen.lock:
            frames = seen.rpdo1[frames0:]
        assert [struct.unpack("<Hi", f) for f in frames] == [(0x000F, 321)]  # controlword, rpm
        assert bench.drive.read("target_velocity") == 321
    finally:
        bench.watch.start()
        bench.set_speed(0)
