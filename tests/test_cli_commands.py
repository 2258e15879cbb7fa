"""The remaining `drive-link` commands in one process against the virtual drive (python-can
"virtual" bus): mode, quick-stop, fault-reset, faults, nmt, live, store/restore, identify-drive."""

from __future__ import annotations

import json
import time
import uuid

import can
import pytest

from drive_link import cli

pytestmark = [pytest.mark.timeout(90), pytest.mark.unit]


@pytest.fixture(scope="module")
def node(tmp_path_factory):
    from virtual_drive.node import VirtualDrive

    ch = f"cli-{uuid.uuid4().hex}"
    bus = can.Bus(interface="virtual", channel=ch)
    vd = VirtualDrive(bus, node_id=6, store_path=tmp_path_factory.mktemp("s") / "p.json").start()
    yield vd, ch
    vd.stop()
    bus.shutdown()


def dl(node, capsys, *args: str) -> tuple[int, object]:
    _, ch = node
    rc = cli.main(
        [args[0], "--interface", "virtual", "--channel", ch, "--node", "6", "--json", *args[1:]]
    )
    out = capsys.readouterr()
    return rc, (json.loads(out.out) if out.out.strip() else out.err)


def test_state_commands(node, capsys):
    assert dl(node, capsys, "nmt", "start") == (0, {"sent": "start"})
    assert dl(node, capsys, "mode", "speed") == (
        0,
        {"mode": "speed", "state": "SWITCH ON DISABLED"},
    )
    assert dl(node, capsys, "enable")[1] == {"state": "OPERATION ENABLED"}
    rc, out = dl(node, capsys, "quick-stop")
    assert rc == 0 and out["state"] in ("QUICK STOP ACTIVE", "SWITCH ON DISABLED")
    dl(node, capsys, "enable")
    dl(node, capsys, "write", "sim_fault.V_dc_supply", "70")  # > 60 V trip (virtual-only)
    time.sleep(0.2)
    rc, out = dl(node, capsys, "faults")
    assert rc == 0 and out["history"][0]["code"] == 0x3210 and out["error_register"] & 0x04
    assert out["history"][0]["description"] == "DC-link overvoltage"
    rc, err = dl(node, capsys, "fault-reset")  # the overvoltage persists: refused
    # with --json the error is JSON on stdout, with the exit code
    assert rc == 1 and err["exit_code"] == 1 and "fault reset refused" in err["error"]
    dl(node, capsys, "write", "sim_fault.V_dc_supply", "48")
    rc, out = dl(node, capsys, "fault-reset")
    assert rc == 0 and out == {"state": "SWITCH ON DISABLED"}


def test_live_reports_rates(node, capsys):
    """TPDO1's event timer is 10 ms: 100 frames/s (CiA 301 §7.5.2.35). ``live --seconds 0.5``
    rates the frames over the time it listened, not over a second it did not (it said 50 Hz)."""
    from conftest import RunQueueProbe

    dl(node, capsys, "nmt", "start")
    probe = RunQueueProbe()  # (drive and host are this process)
    rc, out = dl(node, capsys, "live", "--seconds", "0.5")
    wait = probe.stop()
    assert rc == 0
    tpdo1 = out["stats"]["tpdo"]["TPDO1"]
    assert tpdo1["expected_hz"] == 100.0
    assert 0 < tpdo1["rate_hz"] <= 130, tpdo1
    if wait < 0.2:  # a host that kept the process waiting delivers fewer frames in the window
        assert tpdo1["rate_hz"] >= 75, (tpdo1, repr(probe))
    assert "measurements.i_p" in out["latest"]


def test_store_and_restore(node, capsys):
    rc, out = dl(node, capsys, "write", "current_controller.R_c", "0.005")
    assert rc == 0 and out["current_controller.R_c"] == pytest.approx(0.005)
    assert dl(node, capsys, "store") == (0, {"stored": True})
    assert dl(node, capsys, "restore", "--reset") == (0, {"restored": True, "reset": True})
    rc, out = dl(node, capsys, "read", "current_controller.R_c")
    assert out["current_controller.R_c"] == pytest.approx(0.0062)  # contract default


def test_identify_drive(node, capsys, tmp_path):
    dl(node, capsys, "nmt", "start")
    rc, out = dl(
        node,
        capsys,
        "identify-drive",
        "--to",
        "10",
        "--divider",
        "20",
        "--length",
        "1000",
        "--pre-trigger",
        "50",
        "--csv",
        str(tmp_path / "id.csv"),
    )
    assert rc == 0, out
    # the virtual drive's shaft reproduces the paper's model (a = 0.9999785, b = 3.33715e-4)
    assert out["fit"]["a"] == pytest.approx(0.9999785, abs=5e-6)
    assert out["fit"]["b"] == pytest.approx(3.33715e-4, rel=0.1)
    assert out["ip_gains"]["speed_k_p"] == pytest.approx(0.2113, rel=0.15)
    assert (tmp_path / "id.csv").exists()
    dl(node, capsys, "disable")
