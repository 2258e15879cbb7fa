"""GUI texts speak GUI (issue 24): the Config tab's DCF dry run names the GUI's own checkbox,
never the CLI's ``--force``, and lists its diff in the unit of the GUI's fields; a REST body
with a key given twice is refused (422) and changes nothing.

Truths: drive_link's own refusal of a poor-margin gain set (L_c = 1.6 L: stable, GM below
the 2 dB policy; CLI ``config load`` says "--force"), the drive's values read back through
drive_link, and the SI prefixes (1 µH = 1e-6 H, 1 mΩ = 1e-3 Ω).
"""

from __future__ import annotations

import re
import types

import pytest
from fastapi.testclient import TestClient

from dashboard._gui_words import CONFIG_FORCE_LABEL, diff_rows, gui_text, shown
from dashboard.app import create_app
from dashboard.config import BenchConfig
from drive_link.workflows.config_dcf import dcf_text, read_config

pytestmark = pytest.mark.timeout(120)


class _FakeClient:
    """A browser's handle stand-in: the panel's GUI goes to the server-wide GUI."""

    def __init__(self, gui, client_id: int) -> None:
        self.gui, self.client_id = gui, client_id


@pytest.fixture(scope="module")
def bench_panel():
    """(TestClient, a real Panel whose GUI is the server-wide one)."""
    from dashboard._gui_panel import Panel

    cfg = BenchConfig(virtual=True, speed_factor=2.0, gui_port=0, scene_3d=False)
    with TestClient(create_app(cfg), base_url="http://127.0.0.1:8000") as c:
        gui = c.app.state.gui
        yield c, Panel(gui, _FakeClient(gui.server.gui, 991))


def _upload(text: str, name: str = "bench.dcf"):
    f = types.SimpleNamespace(name=name, content=text.encode())
    return types.SimpleNamespace(target=types.SimpleNamespace(value=f))


def _with(text: str, index_sub: str, value: str) -> str:
    return re.sub(rf"(\[{index_sub}\]\n(?:.*\n)*?ParameterValue=).*", rf"\g<1>{value}", text)


def test_values_in_the_fields_unit():
    assert shown(1.48e-05, "H") == "14.8 µH"
    assert shown(0.0062, "Ohm") == "6.2 mΩ"
    assert shown(1000.0, "rpm") == "1000 rpm"
    assert diff_rows([{"name": "L_c", "unit": "H", "drive": 1.48e-5, "file": 2.0e-5}]) == (
        "L_c: 14.8 µH → 20 µH"
    )


def test_dcf_dry_run_in_the_gui_names_the_gui_checkbox_and_shows_field_units(bench_panel):
    c, panel = bench_panel
    d = c.app.state.bench.drive
    L = float(d.read("motor.L"))
    L_c = float(d.read("current_controller.L_c"))
    text = dcf_text(read_config(d), d.node_id)
    poor = _with(text, "2010sub2", repr(1.6 * L))  # stable, margins below the policy
    # drive_link itself (the CLI's path) names --force
    import io

    from drive_link.workflows.config_dcf import load

    with pytest.raises(Exception, match="--force"):
        load(d, io.StringIO(poor), dry_run=True)
    tab = panel.config_tab
    tab.dcf_dry.value = True
    tab.dcf_force.value = False
    cb = panel.page.action(tab.load_dcf, tab.cfg_md, needs_control=False)
    cb(_upload(poor))
    msg = tab.cfg_md.content
    assert "--force" not in msg and CONFIG_FORCE_LABEL in msg, msg
    # the GUI's own control does what --force does: the dry run passes and lists the diff
    tab.dcf_force.value = True
    cb(_upload(poor))
    msg = tab.cfg_md.content
    want = f"{1.6 * L * 1e6:.6g} µH"
    assert f"current_controller.L_c: {L_c * 1e6:.6g} µH → {want}" in msg, msg
    assert "dry run, nothing written" in msg
    assert float(d.read("current_controller.L_c")) == L_c  # a dry run wrote nothing
    tab.dcf_force.value = False


def test_cli_words_become_gui_words():
    m = gui_text("nothing written: gain set refused: GM 1.2 dB < 2 dB (--force loads it anyway)")
    assert "--force" not in m and CONFIG_FORCE_LABEL in m
    m = gui_text("nothing written: motor.L is written only with the power stage off: run "
                 "`drive-link disable` first")
    assert "drive-link" not in m and "press Disable first" in m


def test_duplicate_json_keys_are_refused_and_nothing_changes(bench_panel):
    c, _ = bench_panel
    tok = c.post("/api/control", json={"client": "words", "take_over": True}).json()["token"]
    hdr = {"X-Control-Token": tok, "Content-Type": "application/json"}
    before = c.get("/api/state").json()["speed_setpoint"]
    r = c.put("/api/setpoints/speed", content=b'{"rpm": 100, "rpm": 3000}', headers=hdr)
    assert r.status_code == 422 and "duplicate key 'rpm'" in r.json()["detail"], r.text
    assert c.get("/api/state").json()["speed_setpoint"] == before
    g0 = c.get("/api/gains").json()
    r = c.put("/api/gains", content=b'{"L_c": 2e-5, "R_c": 0.006, "L_c": 3e-5}', headers=hdr)
    assert r.status_code == 422, r.text
    assert c.get("/api/gains").json()["L_c"] == g0["L_c"]
    nested = b'{"steps": [{"at_s": 0, "rpm": 10, "rpm": 20}]}'
    assert c.post("/api/steps/sequence", content=nested, headers=hdr).status_code == 422
    ok = c.put("/api/setpoints/speed", content=b'{"rpm": 100}', headers=hdr)
    assert ok.status_code == 200 and ok.json()["rpm"] == 100.0
    c.delete("/api/control", headers={"X-Control-Token": tok})
