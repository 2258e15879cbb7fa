"""The dashboard's Bus tab without a browser: the panel's own connection to the bench's bus,
the table it draws, its filters and pause. Truth: the EDS read by configparser (the names of
TPDO2's default mapping) and CiA 301's heartbeat state code of the drive the bench started."""

from __future__ import annotations

import configparser
import re
import time

import pytest
from fastapi.testclient import TestClient

from dashboard.app import create_app
from dashboard.config import BenchConfig
from firmware_protocol import EDS_PATH

pytestmark = pytest.mark.timeout(90)


class _FakeClient:
    def __init__(self, gui, client_id: int) -> None:
        self.gui, self.client_id = gui, client_id


@pytest.fixture(scope="module")
def app_client():
    cfg = BenchConfig(virtual=True, gui_port=0, scene_3d=False)
    with TestClient(create_app(cfg), base_url="http://127.0.0.1:8000") as c:
        yield c


def _tpdo2_names() -> list[str]:
    cp = configparser.RawConfigParser(strict=False, interpolation=None)
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    cp.read(EDS_PATH, encoding="utf-8")
    out = []
    for i in (1, 2):
        ref = int(cp[f"1A01sub{i}"]["DefaultValue"], 0)
        idx, sub = ref >> 16, (ref >> 8) & 0xFF
        out.append(
            f"{cp[f'{idx:04X}']['ParameterName']}.{cp[f'{idx:04X}sub{sub:X}']['ParameterName']}"
        )
    return out


def _rows(content: str) -> dict[str, list[str]]:
    rows = re.findall(r"<tr>(.*?)</tr>", content)
    cells = [re.findall(r"<td>(.*?)</td>", r) for r in rows]
    return {c[0]: c for c in cells if c}


def test_bus_tab_shows_the_bench_bus_decoded_filtered_and_paused(app_client):
    from dashboard._gui_panel import Panel

    gui = app_client.app.state.gui
    p = Panel(gui, _FakeClient(gui.server.gui, 993)).bus_tab
    assert p.table is None  # unchecked: no connection, no cost
    p.bus_on.value = True
    p.on_toggle()
    try:
        time.sleep(1.6)
        rows = _rows(p.bus_html.content)
        assert rows["0x701"][1] == "heartbeat" and rows["0x701"][6] == "OPERATIONAL"
        i_p, speed = _tpdo2_names()
        assert rows["0x281"][6].startswith(f"TPDO2: {i_p}=") and f", {speed}=" in rows["0x281"][6]
        # 1 kHz (the event timer), measured; a drive starved of CPU sends fewer (README)
        assert 300 < float(rows["0x281"][3]) < 1300
        p.bus_ids.value = "0x700-0x77F"
        p.on_filter()
        time.sleep(0.8)
        shown = {int(i, 16) for i in _rows(p.bus_html.content)}
        assert 0x701 in shown and all(0x700 <= i <= 0x77F for i in shown)  # (0x77F: the host)
        p.bus_ids.value = "0xZZ"  # refused in one line; the filter stays
        p.on_filter()
        assert "0xZZ" in p.bus_md.content and p.table.keep.ids == set(range(0x700, 0x780))
        p.bus_pause.value = True
        p.on_pause()
        time.sleep(0.6)
        frozen = p.bus_html.content
        time.sleep(1.0)
        assert p.bus_html.content == frozen and "paused" in frozen
    finally:
        p.bus_on.value = False
        p.on_toggle()
    assert p.table is None
