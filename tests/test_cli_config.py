"""`drive-link config save|diff|load FILE.dcf`, `objects`, `read`/`write` by index, `--json`
errors, against the virtual drive in this process (python-can "virtual" bus).

Oracles: canopen's own DCF import (``canopen.import_od``, CiA 306) for the saved file and the
drive's values read back over SDO; the EDS view (firmware_protocol) for the object listing."""

from __future__ import annotations

import json
import re
import uuid

import can
import canopen
import pytest

from drive_link import cli
from drive_link.errors import InvalidValue
from firmware_protocol import load_od

pytestmark = [pytest.mark.timeout(120), pytest.mark.unit]


@pytest.fixture(scope="module")
def node(tmp_path_factory):
    from virtual_drive.node import VirtualDrive

    ch = f"cfg-{uuid.uuid4().hex}"
    bus = can.Bus(interface="virtual", channel=ch)
    vd = VirtualDrive(bus, node_id=7, store_path=tmp_path_factory.mktemp("s") / "p.json").start()
    yield ch
    vd.stop()
    bus.shutdown()


def dl(ch, capsys, *args: str, json_out: bool = True) -> tuple[int, object]:
    argv = [args[0], "--interface", "virtual", "--channel", ch, "--node", "7", *args[1:]]
    rc = cli.main([*argv, "--json"] if json_out else argv)
    out = capsys.readouterr()
    if json_out:
        assert out.err == "", out.err
        return rc, json.loads(out.out)
    return rc, out.out + out.err


def set_param(path, index: int, sub: int, value: str) -> None:
    """Change one ParameterValue in the DCF text (section [IIIIsubS], or [IIII] for a
    variable)."""
    text = path.read_text()
    sec = f"[{index:04X}sub{sub:X}]"
    if sec not in text:
        sec = f"[{index:04X}]"
    head, _, rest = text.partition(sec + "\n")
    assert rest, sec
    body, sep, tail = rest.partition("\n\n")
    body = re.sub(r"^ParameterValue=.*$", f"ParameterValue={value}", body, flags=re.M)
    path.write_text(head + sec + "\n" + body + sep + tail)


def test_config_save_loads_in_canopen_and_matches_the_drive(node, capsys, tmp_path):
    f = tmp_path / "drive.dcf"
    rc, out = dl(node, capsys, "config", "save", str(f), "--bitrate", "500000")
    assert rc == 0 and out["objects"] >= 30 and out["node_id"] == 7
    od = canopen.import_od(str(f))
    assert od.node_id == 7 and od.bitrate == 500000  # [DeviceComissioning] NodeID, Baudrate
    saved = [v for v in _variables(od) if v.value is not None]
    assert len(saved) == out["objects"]
    # what the drive reports, read by index in one command (JSON keyed by OD name, in order)
    rc, got = dl(node, capsys, "read", *[f"0x{v.index:04X}:{v.subindex:X}" for v in saved])
    assert rc == 0, got
    assert len(got) == len(saved)
    for var, value in zip(saved, got.values(), strict=True):
        assert var.value == pytest.approx(value, rel=1e-7), var.name
    checked = len(saved)
    rc, out = dl(node, capsys, "config", "diff", str(f))
    assert rc == 0 and out["changes"] == [] and out["same"] == checked


def _variables(od):
    for obj in od.values():
        if isinstance(obj, canopen.objectdictionary.ODVariable):
            yield obj
        else:
            yield from obj.values()


def test_config_load_checks_first_then_writes_all(node, capsys, tmp_path):
    f = tmp_path / "d.dcf"
    assert dl(node, capsys, "config", "save", str(f))[0] == 0
    rc, before = dl(node, capsys, "read", "current_controller.R_c", "velocity_window")
    set_param(f, 0x2010, 3, "0.005")  # R_c, Ohm (limits 0..1)
    set_param(f, 0x606D, 0, "0x0020")  # velocity_window, rpm
    rc, out = dl(node, capsys, "config", "load", str(f), "--dry-run")
    assert rc == 0 and out["written"] == 0 and len(out["changes"]) == 2
    assert dl(node, capsys, "read", "current_controller.R_c", "velocity_window")[1] == before
    # one value outside its limits: one line naming it, nothing written (R_c neither)
    bad = tmp_path / "bad.dcf"
    bad.write_text(f.read_text())
    set_param(bad, 0x2010, 2, "0.5")  # L_c = 0.5 H > HighLimit 0.002
    rc, err = dl(node, capsys, "config", "load", str(bad), json_out=False)
    assert rc == 7 and err.count("\n") == 1 and "current_controller.L_c" in err, err
    assert "nothing written" in err
    assert dl(node, capsys, "read", "current_controller.R_c", "velocity_window")[1] == before
    # the good file: both written (R_c through the gain set), read back equal
    rc, out = dl(node, capsys, "config", "load", str(f))
    assert rc == 0 and out["written"] == 2, out
    rc, got = dl(node, capsys, "read", "current_controller.R_c", "velocity_window")
    assert got["current_controller.R_c"] == pytest.approx(0.005, rel=1e-6)
    assert got["velocity_window"] == 0x20
    assert dl(node, capsys, "config", "diff", str(f))[1]["changes"] == []


def test_config_load_gains_follow_the_gain_policy(node, capsys, tmp_path):
    """L_c = 1.6 L has poor margins (drive_link.workflows.gains: refused without --force, exit 8 in
    set-gains); a DCF with it is refused the same way, nothing written, and loads with --force
    through the gain set."""
    f = tmp_path / "g.dcf"
    assert dl(node, capsys, "config", "save", str(f))[0] == 0
    L = dl(node, capsys, "read", "motor.L")[1]["motor.L"]
    set_param(f, 0x2010, 2, repr(1.6 * L))
    set_param(f, 0x606D, 0, "0x0021")  # velocity_window: not written either when refused
    before = dl(node, capsys, "read", "current_controller.L_c", "velocity_window")[1]
    rc, err = dl(node, capsys, "config", "load", str(f), json_out=False)
    assert rc == 7 and "--force" in err and err.count("\n") == 1, err
    assert dl(node, capsys, "read", "current_controller.L_c", "velocity_window")[1] == before
    try:
        rc, out = dl(node, capsys, "config", "load", str(f), "--force")
        assert rc == 0 and out["written"] == 2, out
        got = dl(node, capsys, "read", "current_controller.L_c")[1]["current_controller.L_c"]
        assert got == pytest.approx(1.6 * L, rel=1e-6)
    finally:
        dl(node, capsys, "write", "current_controller.L_c", repr(before["current_controller.L_c"]))


def test_config_load_of_motor_data_needs_the_power_stage_off(node, capsys, tmp_path):
    f = tmp_path / "m.dcf"
    assert dl(node, capsys, "config", "save", str(f))[0] == 0
    set_param(f, 0x2000, 2, "1.5e-05")  # motor.L (ConfigOnly)
    dl(node, capsys, "nmt", "start")
    assert dl(node, capsys, "enable")[0] == 0
    try:
        rc, err = dl(node, capsys, "config", "load", str(f), json_out=False)
        assert rc == 1 and "disable" in err and err.count("\n") == 1, err
        assert dl(node, capsys, "read", "motor.L")[1]["motor.L"] == pytest.approx(14.8e-6)
    finally:
        dl(node, capsys, "disable")


def test_objects_lists_what_the_eds_says(capsys):
    assert cli.main(["objects", "0x2010", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    eds = {(e.index, e.subindex): e for e in load_od().entries if e.index == 0x2010}
    assert len(rows) == len(eds)
    row = next(r for r in rows if r["name"] == "current_controller.L_c")
    e = eds[(0x2010, 2)]
    assert row["index"] == "0x2010:02" and row["type"] == "REAL32" and row["unit"] == "H"
    assert (row["low"], row["high"], row["access"]) == (e.low, e.high, "rw")
    assert cli.main(["objects", "velocity"]) == 0
    text = capsys.readouterr().out
    assert "target_velocity" in text and "0x60FF:00" in text and "INTEGER32" in text
    assert cli.main(["objects", "no_such_thing", "--json"]) == 7
    assert json.loads(capsys.readouterr().out)["exit_code"] == 7


def test_read_write_by_index_with_units_and_json_errors(node, capsys):
    rc, out = dl(node, capsys, "read", "0x6041", "0x2010:2")
    assert rc == 0 and set(out) == {"statusword", "current_controller.L_c"}
    rc, out = dl(node, capsys, "write", "0x2010:3", "4.5 mOhm")
    assert rc == 0 and out["current_controller.R_c"] == pytest.approx(4.5e-3, rel=1e-6)
    rc, out = dl(node, capsys, "write", "consumer_heartbeat_time.consumer_4", "-1e30")
    assert rc == 7 and out["exit_code"] == 7 and "below" in out["error"]
    rc, out = dl(node, capsys, "write", "0x2010:3", "5 A")
    assert rc == 7 and "wrong dimension" in out["error"]
    rc, out = dl(node, capsys, "read", "0x6041:7")
    assert rc == 7 and "no sub-index 7" in out["error"]  # an unknown object: invalid value
    # an argument's invalid value with --json is JSON too, exit 7 as for `write` (README table)
    rc, out = dl(node, capsys, "set-speed", "nan")
    assert rc == 7 and out["exit_code"] == 7 and "nan and inf are refused" in out["error"]
    # -inf / -nan are values (refused as such), not -i / -n short options
    for text in ("-inf", "-nan", "-inf A"):
        rc, out = dl(node, capsys, "set-current", text)
        assert rc == 7 and "nan and inf are refused" in out["error"], text


def test_set_gains_takes_units(node, capsys):
    before = dl(node, capsys, "gains")[1]
    try:
        rc, out = dl(node, capsys, "set-gains", "L_c=20uH", "R_c=5 mOhm")
        assert rc == 0, out
        assert out["gains"]["L_c"] == pytest.approx(20e-6, rel=1e-7)
        assert out["gains"]["R_c"] == pytest.approx(5e-3, rel=1e-7)
        rc, out = dl(node, capsys, "set-gains", "L_c=5A")
        assert rc == 7 and "wrong dimension" in out["error"]
    finally:
        dl(node, capsys, "set-gains", f"L_c={before['L_c']!r}", f"R_c={before['R_c']!r}")


def test_dashboard_path_text_in_text_out(node):
    """The functions the dashboard calls: the DCF as text (download) and back from text
    (upload), through the same checks."""
    import io

    from drive_link import Drive
    from drive_link.workflows.config_dcf import dcf_text, diff, load, read_config

    with Drive.connect(interface="virtual", channel=node, node_id=7) as d:
        text = dcf_text(read_config(d), d.node_id)
        up = io.StringIO(text)
        up.name = "drive.dcf"  # canopen picks the format by the name
        assert canopen.import_od(up).node_id == 7
        assert diff(d, io.StringIO(text)).changes == []
        bad = re.sub(r"(\[2010sub3\]\n(?:.*\n)*?ParameterValue=).*", r"\g<1>7.5", text)
        with pytest.raises(InvalidValue, match=r"nothing written: .*R_c"):
            load(d, io.StringIO(bad))


def test_config_save_without_bitrate_names_the_eds_default_with_a_warning(node, capsys, tmp_path):
    """No -b and a bus that does not say its bit rate: the DCF names the EDS default (not the
    Baudrate=0 of old, which no CANopen tool accepts) and the CLI says so in one line."""
    f = tmp_path / "nob.dcf"
    rc, text = dl(node, capsys, "config", "save", str(f), json_out=False)
    assert rc == 0
    warning = [ln for ln in text.splitlines() if ln.startswith("warning:")]
    assert len(warning) == 1 and "1000 kbit/s" in warning[0]
    assert canopen.import_od(str(f)).bitrate == 1_000_000  # BaudRate_1000=1 in the EDS
    rc, out = dl(node, capsys, "config", "save", str(f))  # --json: the warning in the object
    assert rc == 0 and len(out["warnings"]) == 1
